"""``pa10-dnbs simulate``: in-process closed loop, metrics, figures and report."""
from __future__ import annotations

import math
from pathlib import Path

from ..config import ConfigError, default_config_path, load_config
from ..kinematics.urdf_chain import UrdfChain
from ..report.metrics_file import effective_window, metrics_dict
from ..report.outputs import atomic_output_dir, check_output_dir, write_report
from ..sim.closed_loop import simulate


def run_simulate(config_path: Path | None, controller: str, duration_s: float | None, out: Path,
                 force: bool, progress: bool) -> int:
    """Run one or both controllers; write everything into ``out`` atomically. Returns the exit code."""
    config_path = Path(config_path) if config_path else default_config_path()
    cfg = load_config(config_path)
    if duration_s is None:
        duration_s = cfg["simulation"]["duration_s"]
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ConfigError(f"--duration: must be a positive finite number of seconds, got {duration_s}")
    n_steps = int(round(duration_s / cfg["simulation"]["dt_s"]))
    if n_steps < 2:
        raise ConfigError(f"--duration: {duration_s} s is shorter than two steps")
    duration_s = n_steps * cfg["simulation"]["dt_s"]
    check_output_dir(out, force)
    window = effective_window(duration_s, cfg["simulation"]["window_s"])
    kinds = ("dnbs", "pid") if controller == "both" else (controller,)
    runs, metrics = [], []
    for kind in kinds:
        run = simulate(cfg, kind, duration_s, progress=progress)
        runs.append(run)
        metrics.append(metrics_dict(run, window, source="in-process", config_file=str(config_path.resolve()),
                                    seed=cfg["simulation"]["seed"], limit_hits=run.extra["limit_hits"]))
    notes = [f"config: `{config_path}`", "source: in-process simulation (no ROS)"]
    if tuple(window) != tuple(cfg["simulation"]["window_s"]):
        notes.append(f"run shorter than the configured window {cfg['simulation']['window_s']}: "
                     f"metrics over the second half instead")
    with atomic_output_dir(out, force) as tmp:
        write_report(tmp, runs, metrics, title="PA10-7CE closed-loop run", notes=notes,
                     chain=UrdfChain.from_file(cfg["plant"]["urdf"]))
    for m in metrics:
        print(f"{m['controller']}: worst-joint RMS error {m['worst_rms_error_rad']:.3e} rad over "
              f"{m['window_s']} s, {m['real_time_factor']:.1f}x real time")
    print(f"wrote {out}/report.md")
    ok = all(m["all_finite"] and m["torques_within_limits"] for m in metrics)
    return 0 if ok else 1
