"""PyBullet against MuJoCo on the same arm, reference and gains: in-process runs and their side-by-side table.

Each arm runs with its default config (``config/default.yaml`` and its arm file) on both engines; the figures
are those of ``pa10-dnbs simulate``: the worst joint's RMS error over the metrics window (10-20 s for a 20 s
run) and its settling time into the settle band (1e-2 rad).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..accel.choice import resolve_kernel
from ..config import default_config_path
from ..run_settings import build_settings
from ..report.metrics_file import metrics_dict, metrics_settings
from .closed_loop import simulate

ENGINE_PAIR = ("pybullet", "mujoco")
SETTLE_TARGET_S = 0.5  # the target: MuJoCo's DNBS settles by 0.5 s
RMS_RATIO_TARGET = 2.0  # ... and reaches a worst RMS within 2x of PyBullet's


@dataclass(frozen=True)
class EngineRun:
    """One run's figures: arm, engine, controller, worst RMS [rad] over ``window_s`` [s], worst settling [s]
    (None: never settled), and whether every value stayed finite and within the torque limits."""

    arm: str
    engine: str
    controller: str
    worst_rms_rad: float
    settle_s: float | None
    window_s: tuple[float, float]
    ok: bool


def run_engines(arms: list[str], controllers: list[str], duration_s: float, say=None) -> list[EngineRun]:
    """Every (arm, engine, controller) run in-process for ``duration_s`` s; ``say``: a line per run, or None."""
    runs = []
    for arm in arms:
        settings = resolve_kernel(build_settings(default_config_path(), arm=arm), say=lambda *_: None)
        measured = metrics_settings(settings, duration_s)
        for engine in ENGINE_PAIR:
            for kind in controllers:
                run = simulate(settings, kind, duration_s, engine=engine)
                m = metrics_dict(run, measured)
                r = EngineRun(arm, engine, kind, float(m["worst_rms_error_rad"]), m["worst_settling_time_s"],
                              tuple(m["window_s"]), bool(m["all_finite"] and m["torques_within_limits"]))
                runs.append(r)
                if say is not None:
                    say(f"{arm} {engine} {kind}: RMS {r.worst_rms_rad:.2e} rad, settled {_settle(r.settle_s)}")
    return runs


def _settle(s: float | None) -> str:
    return "never" if s is None else f"{s:.2f}"


def _find(runs: list[EngineRun], arm: str, engine: str, kind: str) -> EngineRun | None:
    return next((r for r in runs if (r.arm, r.engine, r.controller) == (arm, engine, kind)), None)


def engine_table(runs: list[EngineRun]) -> str:
    """A Markdown table: one row per arm and controller, PyBullet and MuJoCo side by side, the RMS ratio."""
    window = runs[0].window_s if runs else (0.0, 0.0)
    lines = [f"| arm | controller | RMS [{window[0]:g}, {window[1]:g}) s, PyBullet / MuJoCo [rad] | MuJoCo / PyBullet "
             f"| settled after, PyBullet / MuJoCo [s] |", "|---|---|---|---|---|"]
    for arm in dict.fromkeys(r.arm for r in runs):
        for kind in dict.fromkeys(r.controller for r in runs if r.arm == arm):
            pb, mj = _find(runs, arm, "pybullet", kind), _find(runs, arm, "mujoco", kind)
            lines.append(f"| {arm} | {kind.upper()} | {pb.worst_rms_rad:.2e} / {mj.worst_rms_rad:.2e} | "
                         f"{mj.worst_rms_rad / pb.worst_rms_rad:.2f} | {_settle(pb.settle_s)} / {_settle(mj.settle_s)} |")
    return "\n".join(lines) + "\n"


def target_lines(runs: list[EngineRun]) -> list[str]:
    """One line per arm on the target: MuJoCo's DNBS settles by 0.5 s with a worst RMS within 2x of
    PyBullet's; each line starts with "met" or "NOT met"."""
    out = []
    for arm in dict.fromkeys(r.arm for r in runs):
        pb, mj = _find(runs, arm, "pybullet", "dnbs"), _find(runs, arm, "mujoco", "dnbs")
        if pb is None or mj is None:
            continue
        ratio = mj.worst_rms_rad / pb.worst_rms_rad
        met = mj.ok and mj.settle_s is not None and mj.settle_s <= SETTLE_TARGET_S and ratio <= RMS_RATIO_TARGET
        out.append(f"{'met' if met else 'NOT met'}: {arm} MuJoCo DNBS settled after {_settle(mj.settle_s)} s "
                   f"(target <= {SETTLE_TARGET_S:g}), RMS {ratio:.2f}x PyBullet's (target <= {RMS_RATIO_TARGET:g}x)")
    return out
