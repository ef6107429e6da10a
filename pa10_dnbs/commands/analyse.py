"""``pa10-dnbs analyse BAG --out DIR``: metrics, figures and report of a run, from its bag alone."""
from __future__ import annotations

import math
import sys
from pathlib import Path

from ..bag.analysis import bag_arm, bag_joint_names, robot_chain, run_info, wire_record_from_bag
from ..bag.bag_reader import Bag, BagError
from ..bag.run_config import run_config, stored_steps
from ..config import config_file
from .options import AnalyseOptions
from ..number_text import interval
from ..output_lock import lock_input
from ..report.metrics_file import diverged_text, metrics_dict, run_ok, window_settings
from ..report.outputs import atomic_output_dir, check_output_dir, write_report
from ..report.progress import ProgressBar

MIN_STEPS = 2   # a run of fewer steps has no sample in its metrics window (the second half of the run)


def _recorded_prefix_end(rec) -> int | None:
    """The last step of a bag whose joint states stop early without a gap before (a run stopped with Ctrl-C,
    whose bag is closed and readable), else None: states 0..end received, none after, at least 2 steps."""
    got = rec.got_state
    end = int(got.argmin()) - 1 if not got.all() else rec.n
    if end < 2 or got[end + 1:].any():
        return None
    return end


def run_analyse(options: AnalyseOptions) -> int:
    """Rebuild the run from the bag ``options.bag_path`` and write the report into ``options.out``. Raises
    BagError on a bad bag.

    ``options.progress``: a progress bar on stderr while the bag is read (report/progress.py; drawn on a terminal only).
    """
    o = options
    if o.config_path is not None:   # a folder given as --config is said so, not "--out lies inside --config"
        config_file(Path(o.config_path))
    check_output_dir(o.out, o.force, "out", inputs={"bag_path": o.bag_path, "config_path": o.config_path})
    lock_input(o.bag_path, "bag")  # a bag another run is still recording (or replacing) is refused, not misread
    with Bag(o.bag_path) as bag:
        info = run_info(bag)
        joints = bag_joint_names(bag)
        run_settings = run_config(bag, info, o.config_path, joints)
        dt = run_settings.dt_s
        n_steps = stored_steps(bag, info, dt, len(joints))
        bar = None
        if o.progress:
            js = bag_arm(bag).joint_states
            total = n_steps if n_steps is not None else bag.topics[js].count if js in bag.topics else 0
            bar = ProgressBar(total, dt, f"analyse {bag.path.name}")
        try:
            rec = wire_record_from_bag(bag, dt, n_steps, progress=bar.update if bar is not None else None)
        finally:
            if bar is not None:
                bar.close()
        if rec.malformed:
            raise BagError(f"{bag.path}: corrupt bag: {rec.malformed} messages on joint_states or the reference "
                           "topics could not be decoded")
        truncated = None
        missing = rec.missing()
        if missing and (end := _recorded_prefix_end(rec)) is not None:  # a stopped run: analyse what was recorded
            truncated = (f"the bag ends at step {end} ({end * dt:g} s) of the {rec.n}-step run ({rec.n * dt:g} s): "
                         f"the run was stopped; analysed the recorded part, [0, {end * dt:g}] s")
            rec = wire_record_from_bag(bag, dt, end)
            missing = rec.missing()
        if missing:
            raise BagError(f"{bag.path}: the bag does not hold the whole run: {missing}")
        if rec.n < MIN_STEPS:  # the metrics' window (the run's second half at least) needs a sample
            got = int(rec.got_state.sum())
            raise BagError(f"{bag.path}: the bag holds {got} joint state{'s' * (got != 1)}, a run of {rec.n} "
                           f"step{'s' * (rec.n != 1)}; at least {MIN_STEPS + 1} joint states ({MIN_STEPS} steps of "
                           f"{dt:g} s) are needed for the metrics")
        controller = info.get("controller", "unknown")
        run = rec.run_data(controller, joints, run_settings.torque_limit_nm, math.nan)
        measured = window_settings(run_settings.window_s, run_settings.settle_band_rad, run_settings.startup_s,
                                   rec.n * dt)
        metrics = metrics_dict(run, measured, source="bag", bag=str(bag.path.resolve()), mode=info.get("mode"),
                               seed=run_settings.seed, malformed_messages=rec.malformed)
        notes = [f"bag: `{bag.path}` ({bag.message_count} messages on {len(bag.topics)} topics; {bag.crc_note()})",
                 f"config: {run_settings.source}",
                 f"source: rebuilt from the bag's {bag_arm(bag).joint_states} and reference topics ({info.get('mode', '?')} run)"]
        if truncated:
            notes.append(truncated)
        chain = robot_chain(bag, run_settings.arm_file)
        with atomic_output_dir(o.out, o.force) as tmp:
            write_report(tmp, [run], [metrics], title="Run from a bag", notes=notes, chain=chain,
                         figures=o.figures)
    if truncated:
        print(f"analyse: {truncated}")
    print(f"{controller}: worst-joint RMS error {metrics['worst_rms_error_rad']:.3e} rad over "
          f"{interval(metrics['window_s'])} s "
          f"({rec.n} steps from {bag.path})")
    print(f"wrote {o.out}/report.md")
    if run_ok(metrics):
        return 0
    why = [what for ok, what in ((metrics["all_finite"], "non-finite values"),
                                 (metrics["torques_within_limits"], "torques beyond the limits"),
                                 (not metrics.get("diverged"), f"a diverged run ({diverged_text(metrics)})"))
           if not ok]
    print(f"analyse: exit 1: the recorded run holds {' and '.join(why)} ({o.out}/report.md)", file=sys.stderr)
    return 1
