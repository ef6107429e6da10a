"""What a launched run's report says beside its figures: its notes (config, arm, source, timing, trajectory, robot,
warm start, faults, window) and the timing part of metrics.json."""
from __future__ import annotations

import sys

from ..number_text import interval
from .fault_flags import faults_active
from ..supervisor.fault_report import detected_faults, fault_note
from .launch_plan import LaunchPlan
from .options import LaunchOptions


def report_notes(plan: LaunchPlan, o: LaunchOptions, stats: dict, result, source: str, metrics: dict) -> list[str]:
    """The report's notes of the run ``plan`` made from ``o``: the graph's ``stats`` and ``result``, the record
    the time series were rebuilt from (``source``), its ``metrics``; a lockstep run that stepped past a missing
    effort without an injected fault is also warned about on stderr."""
    settings, mode, config_path, the_arm = plan.settings, o.mode, plan.config_path, plan.settings.arm
    trajectory, init_from, robot, own_robot = plan.trajectory, plan.init_from, plan.robot, plan.own_robot
    reliability, window = plan.reliability, plan.measured["window_s"]
    notes = [f"config: `{config_path}`",
             f"arm: {the_arm.name} ({the_arm.description}), `{the_arm.file}`",
             f"source: ROS 2 node graph, {mode} mode, {reliability} QoS, domain {result.domain_id}; "
             f"time series rebuilt from {source}",
             _timing_note(stats)]
    if trajectory is not None or received_trajectories(result.reference):
        notes.append(reference_note(trajectory, result.reference, settings.simulation.dt_s))
    if own_robot:
        notes.append("plant: the arm in MuJoCo (`pa10-dnbs robot --engine mujoco`) behind the joint bus, "
                     "lockstep (docs/engines.md)")
    elif robot is not None:
        notes.append(f"plant: an external robot behind the joint bus ({robot.command} commands; "
                     "docs/your_robot.md)")
    if init_from is not None:
        notes.append(f"DNBS warm-started from the checkpoints in `{init_from}` (not a cold start)")
    if faults_active(settings.faults) or result.restarts:
        notes.append(fault_note(metrics["faults"]))
    else:
        if unforced := _unforced_faults(metrics["faults"]):  # effort timeouts: their own note, next
            notes.append(fault_note(metrics["faults"]))
            print(f"pa10-dnbs launch: warning: {unforced}", file=sys.stderr, flush=True)
        if mode == "lockstep" and (nondeterministic := _unforced_timeouts(stats, o.effort_timeout_s)):
            notes.append(nondeterministic)
            print(f"pa10-dnbs launch: warning: {nondeterministic}", file=sys.stderr, flush=True)
    if rivals := second_effort_publishers(stats, result.restarts):
        notes.append(rivals)
        print(f"pa10-dnbs launch: warning: {rivals}", file=sys.stderr, flush=True)
    if tuple(window) != tuple(settings.simulation.window_s):
        notes.append(f"run shorter than the configured window {interval(settings.simulation.window_s)} s: "
                     "metrics over the second half instead")
    return notes


def received_trajectories(reference: dict | None) -> bool:
    """Whether the reference node took (or refused) any trajectory from its topic (``reference``: its stats)."""
    return bool(reference and (reference["trajectories_accepted"] or reference["trajectories_refused"]))


def reference_note(trajectory, reference: dict | None, dt_s: float) -> str:
    """The report's line on the reference followed: eq. 27 or the file ``trajectory`` from t = 0, then each
    trajectory accepted from the topic from its start step (``reference``: the reference node's stats), and how many
    the node refused."""
    if trajectory is not None:
        note = f"reference: the trajectory of `{trajectory}` from t = 0, not eq. 27 (docs/trajectories.md)"
    else:
        note = "reference: eq. 27"
    if not received_trajectories(reference):
        return note
    topic = reference["trajectory_topic"]
    for a in reference["accepted"]:
        note += (f"; from step {a['start_step']} (t = {a['start_step'] * dt_s:.3f} s) the trajectory received on "
                 f"`{topic}` ({a['points']} points), its last point reached at step {a['end_step']} "
                 f"(t = {a['end_step'] * dt_s:.3f} s) and held")
    if len(reference["accepted"]) < reference["trajectories_accepted"]:
        more = reference["trajectories_accepted"] - len(reference["accepted"])
        note += f"; {more} more accepted (logs/reference.log)"
    if reference["trajectories_refused"]:
        note += (f"; {reference['trajectories_refused']} received on `{topic}` refused, changing nothing "
                 f"(the first: {reference['refused_reasons'][0]}; every reason in logs/reference.log)")
    return note


def _unforced_faults(faults: dict) -> str | None:
    """What to say when a run without injected faults counted some anyway (the report's faults line names them
    too), else None: a joint controller's guard refused states (a robot's joint beyond its URDF limit: a wrong
    zero, offset or URDF), the plant got non-finite, out-of-range or undecodable efforts."""
    parts = detected_faults(faults, skip=("effort_timeouts",))
    if not parts:
        return None
    return (f"faults detected with none injected: {'; '.join(parts)} (bad_states_*: a joint controller refused "
            "those states as beyond the joint's limits by more than guards.position_margin_rad, faster than "
            "guards.max_speed_rad_s or non-finite, and answered them with guards.on_bad_state instead of its "
            "law; a robot's joint zero, offset or URDF limits?)")


def second_effort_publishers(stats: dict, restarts: list[dict]) -> str | None:
    """What to say when a joint's effort topic had a second publisher (the plant's ``effort_publishers``, the most
    it saw at once: another controller answering that joint's states, whichever answer came first applied), else
    None. A restarted joint is left out: its killed process's publisher stays in the graph for a while (DDS
    forgets it after its lease, ~20 s). The run's numbers are then not those of its controller alone: the launcher
    exits 1."""
    restarted = {r["joint"] for r in restarts}
    joints = [(j["name"], j.get("effort_publishers", 0), j.get("stale_efforts", 0)) for j in stats["joints"]
              if j.get("effort_publishers", 0) > 1 and j["name"] not in restarted]
    if not joints:
        return None
    return ("a second publisher on an effort topic: " + ", ".join(
        f"{name}: {n} publishers, {stale} efforts for steps already applied" for name, n, stale in joints)
        + " (another controller answered those joints' states and the plant applied whichever answer came first: "
        "the run's numbers are not its controller's alone, nor, in lockstep, the in-process run's; the plant's "
        "log names the publishers)")


def _unforced_timeouts(stats: dict, effort_timeout_s: float) -> str | None:
    """What to say when a lockstep run without injected faults stepped past a missing effort, else None."""
    joints = [(j["name"], j["effort_timeouts"]) for j in stats["joints"] if j["effort_timeouts"]]
    if not joints:
        return None
    return (f"the plant stepped without an answer {sum(n for _, n in joints)} times "
            f"({', '.join(f'{name}: {n}' for name, n in joints)}; --effort-timeout {effort_timeout_s:g} s of wall "
            "time): no fault was injected, so a node stalled (a loaded machine?) and this lockstep run is not "
            "the in-process run bit for bit")


TIMING_KEYS = ("on_time_fraction", "late_start_ticks", "max_start_lateness_us", "target_real_time_factor",
               "real_time_factor", "tick_period_s", "deadline_fraction", "reliability", "state_qos_depth",
               "effort_qos_depth", "effort_timeout_s", "on_missing_effort", "rt_priority", "rt_priority_applied",
               "cpu", "effort_waits_per_step", "effort_wakeups_per_step", "on_time_fraction_per_bin")


def timing_summary(stats: dict, controllers: dict, sched_batch: bool) -> dict:
    """The timing part of metrics.json: the plant's pacing figures and, per joint, misses and latency; whether
    the nodes were asked for SCHED_BATCH and the policies the controllers ended with (their stats files)."""
    policies = sorted({c["sched_policy"] for c in controllers.values() if c and "sched_policy" in c})
    timing = ({k: stats.get(k) for k in TIMING_KEYS}
              | {"sched_batch": sched_batch, "controller_sched_policies": policies, "joints": stats["joints"]})
    if paced_by_robot(stats):  # no tick schedule of the graph's own: the robot's next state is the deadline
        timing |= {"target_real_time_factor": None, "tick_period_s": None, "deadline_fraction": None,
                   "paced_by": "robot"}
    return timing


def paced_by_robot(stats: dict) -> bool:
    """A realtime run of the joint bus (its stats carry ``robot``): paced by the robot's own states."""
    return stats["mode"] == "realtime" and "robot" in stats


def _timing_note(stats: dict) -> str:
    j = stats["joints"]
    med = max(x["latency_median_us"] or 0 for x in j)
    p99 = max(x["latency_p99_us"] or 0 for x in j)
    s = (f"plant: {stats['steps']} steps, real-time factor {stats['real_time_factor']:.2f}; state-to-effort latency "
         f"p50 up to {med:.0f} us, p99 up to {p99:.0f} us; effort timeouts "
         f"{sum(x['effort_timeouts'] for x in j)}")
    if paced_by_robot(stats):
        s += ("; paced by the robot (its next state is each state's deadline); states with every effort before the "
              f"next one {100 * stats['on_time_fraction']:.2f} %, missed states per joint "
              + ", ".join(f"{x['name']} {x['missed_ticks']}" for x in j))
    elif stats["mode"] == "realtime":
        s += (f"; target real-time factor {stats['target_real_time_factor']:g} (tick {1e3 * stats['tick_period_s']:.2f}"
              f" ms, deadline {100 * stats['deadline_fraction']:.0f} %); ticks with every effort on time "
              f"{100 * stats['on_time_fraction']:.2f} %, late tick starts {stats['late_start_ticks']}, missed ticks "
              "per joint " + ", ".join(f"{x['name']} {x['missed_ticks']}" for x in j))
    return s
