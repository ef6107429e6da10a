"""The time series of a launched run rebuilt from the bag it recorded, every step checked to be there."""
from __future__ import annotations

from pathlib import Path

from ..bag.analysis import bag_arm, bag_joint_names, wire_record_from_bag
from ..bag.bag_reader import Bag, BagError
from ..supervisor.graph_run import GraphFailure
from ..wire.clock_schedule import DEFAULT_CLOCK_HZ, ClockSchedule
from ..wire.steps import StepClock
from ..wire.topics import CLOCK


def bag_run(bag_path: Path, dt: float, n_steps: int, controller: str, torque_limit_nm, wall_time_s: float,
             lockstep_stats: dict | None, clock_hz: float = DEFAULT_CLOCK_HZ):
    """(RunData, what is missing or None) rebuilt from the bag just recorded; a bad bag is a failed run.

    With ``lockstep_stats`` (the plant's stats of a lockstep run) every step 0..n_steps must be in the bag
    on the arm's joint_states and each joint's state topic, and on each effort topic except the steps the
    plant filled in after a timeout; /clock must hold the steps of ``ClockSchedule`` at ``clock_hz``. (Resent states and repeated answers add messages; none may be lost.)
    """
    clock = StepClock(dt)
    try:
        with Bag(bag_path) as bag:
            rec = wire_record_from_bag(bag, dt, n_steps)
            arm = bag_arm(bag)
            joint_names = bag_joint_names(bag, arm)
            steps = {}
            if lockstep_stats is not None:
                per_step = [CLOCK, arm.joint_states] + [t for j in joint_names for t in (arm.state(j), arm.effort(j))]
                steps = {t: set() for t in per_step}
                for topic, _, _, data in bag.messages([t for t in per_step if t in bag.topics]):
                    if len(data) >= 12:
                        steps[topic].add(clock.step_of_cdr(data))
    except BagError as exc:
        raise GraphFailure(f"the recorded bag is not readable: {exc}") from None
    problems = [rec.missing()] if rec.missing() else []
    if rec.malformed:
        problems.append(f"{rec.malformed} undecodable messages")
    everything = set(range(n_steps + 1))
    for topic, seen in steps.items():
        expected = everything
        if topic == CLOCK:
            expected = ClockSchedule.steps(clock_hz, dt, n_steps)
        elif topic.endswith("/effort"):
            joint = joint_names.index(topic.split("/")[-2])
            filled = {k for a, b in lockstep_stats["joints"][joint]["timeout_ranges"] for k in range(a, b + 1)}
            expected = everything - filled - {n_steps}  # the answer to the last state may come after the end
        lost = expected - seen
        if lost:
            problems.append(f"{topic} lacks {len(lost)} steps (first {min(lost)})")
    run = rec.run_data(controller, joint_names, torque_limit_nm, wall_time_s)
    return run, "; ".join(problems) or None


def bag_stamp(bag_path: Path | None) -> tuple[int, int] | None:
    """What identifies the bag at ``bag_path`` now: its metadata.yaml's (inode, modification time [ns]), None
    when it has none (a bag is finished by writing it)."""
    try:
        st = (Path(bag_path) / "metadata.yaml").stat()
    except (OSError, TypeError):
        return None
    return st.st_ino, st.st_mtime_ns


def failed_run_bag_note(bag_path: Path | None, before: tuple[int, int] | None) -> str | None:
    """The line a failed launch says of its ``--record`` bag (``before``: :func:`bag_stamp` at the start): the
    part recorded is readable, or nothing was recorded and what lies there is an earlier run's bag (``--force``
    replaces it only once this run's recorder opens it), or nothing (no bag there)."""
    now = bag_stamp(bag_path)
    if now is None:
        return None
    if now != before:
        return f"the bag recorded so far is closed and readable: {bag_path}"
    return f"this run recorded nothing: {bag_path} is still the earlier run's bag, untouched"
