"""``pa10-dnbs`` command line: simulate (in-process), launch (ROS 2 node graph), analyse and replay bags.

Exit codes: 0 success, 1 run failure, 2 bad input (config, arguments, existing output).
"""
from __future__ import annotations

import argparse
import errno
import sys

from . import interrupt
_startup_sigint = interrupt.quiet_start()   # Ctrl-C while the modules load: one line, exit 130

from .config import ConfigError, default_config_path
from .config_error import said_as
from .console_stream import forgive_stderr, forgive_stdout
from .commands.fault_flags import add_fault_arguments
from .loop.scheduling import DEFAULT_RT_PRIORITY
from .cli_values import (EFFORT_TIMEOUT_MAX_S, MAX_REPLAY_CLOCK_HZ, REPLAY_RATE_MAX, REPLAY_RATE_MIN, RTF_MAX,
                         RTF_MIN, WAIT_FOR_SUBSCRIBERS_MAX_S, OneLineParser, nonnegative,
                         number_in, path_arg, plain_int, positive, seconds, utf8_text, whole_in)
from .output_lock import held, release_all
from .refused import Refused
from .setting_flags import SETTING_FLAGS
from .tune.objective import TRAINING_SCENARIOS, TRAINING_SEEDS

if __name__ != "__main__" and not sys.argv[0].endswith("pa10-dnbs"):   # imported by a caller: its own Ctrl-C
    interrupt.end_quiet_start(_startup_sigint)

LIVE_PORT = 8765  # Foxglove's default WebSocket port


#: errors of a write that name no file (a full disk, a quota, a read-only file system): the line names --out
WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS})

#: the commands that write no output folder (their Ctrl-C line says nothing about outputs)
NO_OUTPUTS = frozenset({"robot", "replay", "arm"})


def _progress(args: argparse.Namespace) -> bool:
    return not args.no_progress and sys.stderr is not None and sys.stderr.isatty()


def _simulate_options(args: argparse.Namespace):
    """The ``simulate`` command's options from its parsed flags."""
    from .commands.options import SimulateOptions

    return SimulateOptions(
        out=args.out, config_path=args.config, controller=args.controller, duration_s=args.duration,
        force=args.force, progress=_progress(args), init_from=args.init_from, figures=not args.no_figures,
        arm=args.arm, engine=args.engine, trajectory=args.trajectory)


def _unused_flags(args: argparse.Namespace, rules) -> None:
    """Refuse a flag that has no effect in the chosen mode: ``rules`` are (dest, applies, why) triples."""
    for dest, applies, why in rules:
        if getattr(args, dest) is not None and not applies:
            raise ConfigError(f"--{dest.replace('_', '-')}: {why}")


def _live_defaults(args: argparse.Namespace) -> None:
    _unused_flags(args, [(d, args.live is not None, "only with --live") for d in ("live_host", "live_hz")])
    args.live_host = "127.0.0.1" if args.live_host is None else args.live_host
    args.live_hz = 50.0 if args.live_hz is None else args.live_hz


def _launch_options(args: argparse.Namespace):
    """The ``launch`` command's options from its parsed flags."""
    from .commands.options import LaunchOptions
    from .commands.fault_flags import FaultFlags

    realtime = args.mode == "realtime"
    _unused_flags(args, [("rtf", realtime, "only with --mode realtime (lockstep runs as fast as the graph answers)"),
                         ("deadline_fraction", realtime, "only with --mode realtime (lockstep has no deadlines)"),
                         ("bag_compression", args.record is not None, "only with --record")])
    paced_by_robot = "not with --robot external (a paced robot runs at its own rate: its next state is the deadline)"
    _unused_flags(args, [("rtf", args.robot is None, paced_by_robot),
                         ("deadline_fraction", args.robot is None, paced_by_robot)])
    _live_defaults(args)
    return LaunchOptions(
        out=args.out, config_path=args.config, mode=args.mode, controller=args.controller, duration_s=args.duration,
        force=args.force, progress=_progress(args), domain_id=args.domain_id, reliability=args.reliability,
        effort_timeout_s=1.0 if args.effort_timeout is None else args.effort_timeout,
        on_missing_effort=args.on_missing_effort, record=args.record, faults=FaultFlags.of(args),
        restart=args.restart, netns=tuple(args.netns), init_from=args.init_from,
        bag_compression=args.bag_compression or "zstd", live_port=args.live, live_host=args.live_host,
        live_hz=args.live_hz, real_time_factor=1.0 if args.rtf is None else args.rtf,
        deadline_fraction=0.9 if args.deadline_fraction is None else args.deadline_fraction,
        rt_priority=args.rt_priority, sched_batch=args.sched_batch, namespace=args.namespace,
        clock_hz=args.clock_hz, figures=not args.no_figures, arm=args.arm, robot=_robot_options(args),
        trajectory=args.trajectory, plant=args.plant)


def _robot_options(args: argparse.Namespace):
    """``--robot external`` and its flags (docs/your_robot.md), or None (the project's plant)."""
    _unused_flags(args, [(d, args.robot is not None, "only with --robot external")
                         for d in ("robot_command", "robot_state_topic", "robot_command_topic", "robot_timeout")])
    if args.robot is None:
        return None
    from .supervisor.robot_options import RobotOptions

    return RobotOptions(args.robot, args.robot_command or "joint_state", args.robot_state_topic,
                        args.robot_command_topic, 1.0 if args.robot_timeout is None else args.robot_timeout)


def _robot_command_options(args: argparse.Namespace):
    """The ``robot`` command's options from its parsed flags."""
    from .commands.options import RobotCommandOptions

    return RobotCommandOptions(
        config_path=args.config, arm=args.arm, mode=args.mode, duration_s=args.duration,
        state_topic=args.state_topic, command_topic=args.command_topic, clock_hz=args.clock_hz)


def _jobs_only_local(args: argparse.Namespace) -> None:
    """--jobs counts local processes: with --scheduler the cluster's workers run everything, and it was ignored."""
    _unused_flags(args, [("jobs", args.scheduler is None,
                          "local worker processes only; with --scheduler the cluster's workers run the runs")])


def _study_options(args: argparse.Namespace):
    """The ``study`` command's options from its parsed flags."""
    from .commands.options import StudyOptions

    _jobs_only_local(args)
    return StudyOptions(
        out=args.out, scenarios=args.scenarios, controllers=args.controllers, seeds=args.seeds,
        duration_s=args.duration, force=args.force, config_path=args.config, jobs=args.jobs,
        progress=_progress(args), arm=args.arm, scheduler=args.scheduler)


def _tune_options(args: argparse.Namespace):
    """The ``tune`` command's options from its parsed flags."""
    from .commands.options import TuneOptions

    _jobs_only_local(args)
    return TuneOptions(
        controller=args.controller, out=args.out, trials=args.trials, arm=args.arm, config_path=args.config,
        storage=args.storage, seed=args.seed, jobs=args.jobs, scheduler=args.scheduler, scenarios=args.scenarios,
        seeds=args.seeds, held_out_seeds=args.held_out_seeds, duration_s=args.duration, params=args.params,
        progress=_progress(args))


def _arm_options(args: argparse.Namespace):
    """The ``arm`` command's options from its parsed flags."""
    from .commands.options import ArmInfoOptions

    return ArmInfoOptions(config_path=args.config, arm=args.arm)


def _analyse_options(args: argparse.Namespace):
    """The ``analyse`` command's options from its parsed flags."""
    from .commands.options import AnalyseOptions

    return AnalyseOptions(bag_path=args.bag, out=args.out, force=args.force, config_path=args.config,
                          progress=_progress(args), figures=not args.no_figures)


def _replay_options(args: argparse.Namespace):
    """The ``replay`` command's options from its parsed flags."""
    from .commands.options import ReplayOptions

    _unused_flags(args, [("config", args.live is not None, "only with --live (the live view's torque limits and step; "
                                                           "the bag is replayed as recorded)")])
    _live_defaults(args)
    return ReplayOptions(
        bag_path=args.bag, rate=args.rate, topics=args.topics, start_offset_s=args.start_offset, loop=args.loop,
        clock_hz=args.clock, wait_for_subscribers_s=args.wait_for_subscribers, queue_depth=args.queue_depth,
        live_port=args.live, live_host=args.live_host, live_hz=args.live_hz, config_path=args.config,
        namespace=args.namespace)


#: Each command: (its module in commands/, its run function, the builder of its options from the parsed flags).
COMMANDS = {
    "simulate": ("simulate", "run_simulate", _simulate_options),
    "launch": ("launch", "run_launch", _launch_options),
    "robot": ("robot", "run_robot", _robot_command_options),
    "study": ("study", "run_study_command", _study_options),
    "tune": ("tune", "run_tune", _tune_options),
    "arm": ("arm_info", "run_arm_info", _arm_options),
    "analyse": ("analyse", "run_analyse", _analyse_options),
    "replay": ("replay", "run_replay", _replay_options),
}


def command_options(args: argparse.Namespace):
    """The options dataclass of the parsed command (commands/options.py); ConfigError for a flag that does not apply."""
    return COMMANDS[args.func_name][2](args)


def _run(args: argparse.Namespace) -> int:
    """Build the command's options from its flags and run it (its module imported only now)."""
    import importlib

    module, run, _ = COMMANDS[args.func_name]
    options = command_options(args)
    return getattr(importlib.import_module(f".commands.{module}", __package__), run)(options)


def add_arm_argument(p: argparse.ArgumentParser) -> None:
    """``--arm NAME|PATH``: the same flag on every command that runs an arm."""
    p.add_argument("--arm", type=utf8_text, default=None, metavar="NAME|PATH",
                   help="the arm: a preset of urdf/ (pa10, iiwa, panda) or the path of an arm file (arm.yaml) or a "
                        "bare URDF (default: the config's arm, pa10; docs/arms.md)")


def add_parallel_arguments(p: argparse.ArgumentParser, what: str) -> None:
    """``--jobs N`` (alias ``--workers``) and ``--scheduler ADDRESS``: where the runs execute (docs/tuning.md)."""
    p.add_argument("--jobs", "--workers", dest="jobs", type=whole_in(1, 4096), default=None, metavar="N",
                   help=f"local worker processes for the {what} (default: one per core; 1: in this process)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help=f"run the {what} on a Dask distributed cluster (e.g. tcp://127.0.0.1:8786) instead of "
                        "local processes; its workers need the same pa10_dnbs (docs/tuning.md)")


def _add_run_args(p: argparse.ArgumentParser, controllers: tuple[str, ...], help_controller: str) -> None:
    p.add_argument("--config", type=path_arg, default=None, help=f"YAML config (default: {default_config_path()})")
    add_arm_argument(p)
    p.add_argument("--controller", choices=controllers, default="dnbs", help=help_controller)
    p.add_argument("--duration", type=seconds, default=None, metavar="SECONDS",
                   help="simulated time [s] (default: simulation.duration_s of the config, 20 s)")
    p.add_argument("--out", type=path_arg, required=True, metavar="DIR", help="output directory")
    p.add_argument("--force", action="store_true", help="replace an existing output (never one a running command writes)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-figures", action="store_true",
                   help="write metrics, time series and report.md without figures (batch runs; ~3 s less)")
    p.add_argument("--trajectory", type=path_arg, default=None, metavar="FILE",
                   help="follow this JointTrajectory (YAML or JSON) from t = 0 instead of eq. 27 "
                        "(docs/trajectories.md; example: config/trajectory_example.yaml)")


def _add_live_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--live", type=plain_int, nargs="?", const=LIVE_PORT, default=None, metavar="PORT",
                   help=f"serve a live view for Foxglove (WebSocket) on PORT (default {LIVE_PORT}; 0: any free port); "
                        "in Foxglove: Open connection, Foxglove WebSocket, ws://127.0.0.1:PORT (docs/live_view.md)")
    p.add_argument("--live-host", default=None, metavar="ADDRESS",
                   help="with --live: address the live view listens on (default 127.0.0.1: this machine only)")
    p.add_argument("--live-hz", type=positive, default=None, metavar="HZ",
                   help="with --live: live view frames per second of wall time, at most (default 50)")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="pa10-dnbs", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    sim = sub.add_parser("simulate", help="closed loop in one process (no ROS), with metrics, figures, report")
    _add_run_args(sim, ("dnbs", "pid", "ctc", "both", "all"),
                  "dnbs (the paper's, with the configured remedies), pid (decentralized baseline), ctc (centralized "
                  "computed torque with the plant's model: the reference), both (dnbs, pid), all (dnbs, pid, ctc)")
    sim.add_argument("--init-from", type=path_arg, default=None, metavar="CHECKPOINTS",
                     help="warm start: the DNBS weights and covariances of an earlier run (its output directory or "
                          "its checkpoints/ directory); reported as such")
    sim.add_argument("--engine", choices=("pybullet", "mujoco"), default="pybullet",
                     help="the plant's physics engine: pybullet (the project's plant) or mujoco (an independent "
                          "second engine on the same arm; docs/engines.md)")
    sim.set_defaults(func=_run, func_name="simulate")

    la = sub.add_parser("launch", help="the ROS 2 node graph (plant, one controller per joint, reference)")
    la.add_argument("--mode", choices=("lockstep", "realtime"), default="lockstep",
                    help="lockstep: the plant steps once every joint has answered (deterministic, as fast as the "
                         "graph goes); realtime: the plant steps on a wall-clock schedule with deadlines "
                         "(docs/timing.md)")
    la.add_argument("--rtf", type=number_in(RTF_MIN, RTF_MAX, low_open=False), default=None, metavar="R",
                    help="realtime only: real-time factor, as Gazebo's real_time_factor: a step of dt takes dt / R of "
                         "wall time (1.0: 1 kHz; 0.5: half speed, a 2 ms tick)")
    la.add_argument("--deadline-fraction", type=number_in(0, 1), default=None, metavar="F",
                    help="realtime only: an effort counts when it arrives within this fraction of its tick "
                         "(default 0.9); a missing one is held or zeroed (--on-missing-effort) and counted")
    la.add_argument("--rt-priority", type=whole_in(0, 99), default=DEFAULT_RT_PRIORITY, metavar="N",
                    help=f"SCHED_FIFO priority 1..99 for every node of the graph where the OS allows it (root, "
                         f"CAP_SYS_NICE or ulimit -r); otherwise one line and the default policy. Default "
                         f"{DEFAULT_RT_PRIORITY}, as ros2_control's controller manager; 0: off (docs/timing.md)")
    la.add_argument("--sched-batch", action="store_true",
                    help="run every node but the plant under SCHED_BATCH (any user may), so the nodes the "
                         "plant's messages wake do not preempt it while it publishes; opt-in: a small gain "
                         "within this machine's noise; a granted --rt-priority replaces it (docs/timing.md)")
    _add_run_args(la, ("dnbs", "pid"), "the joint controllers: dnbs or pid (ctc is centralized: in-process only)")
    la.add_argument("--namespace", default=None, metavar="NS",
                    help="the arm's ROS namespace (default /<arm name>, /pa10 for the PA10): every node runs in it, its "
                         "topics are NS/<joint>/state, "
                         "NS/joint_states, ...; /clock, /tf, /tf_static, /diagnostics stay global")
    la.add_argument("--clock-hz", type=positive, default=None, metavar="HZ",
                    help="/clock rate in Hz of simulated time (default 100, as `ros2 bag play --clock`); every node "
                         "but the plant runs with use_sim_time:=true")
    la.add_argument("--domain-id", type=whole_in(0, 232), default=None, help="ROS_DOMAIN_ID, 0..232 as ROS 2 accepts (default: a free one in 1..101, leased for the run so concurrent runs never share it; above 101 the DDS ports may meet Linux's ephemeral ones)")
    la.add_argument("--reliability", choices=("reliable", "best_effort"), default=None,
                    help="QoS of the per-joint state/effort topics (default: best_effort, depth 1 in realtime, "
                         "the sensor-data convention; in lockstep best_effort too, reliable when --record or "
                         "--netns is given; docs/timing.md)")
    la.add_argument("--effort-timeout", type=number_in(0, EFFORT_TIMEOUT_MAX_S), default=None, metavar="SECONDS",
                    help="wall time to wait for a joint's effort before holding/zeroing it: every step in "
                         "lockstep; in realtime, the handshake steps before the tick schedule starts (default 1)")
    la.add_argument("--on-missing-effort", choices=("hold", "zero"), default="hold",
                    help="what replaces a missing effort: the joint's last applied torque (hold) or zero")
    la.add_argument("--record", type=path_arg, default=None, metavar="BAG_DIR",
                    help="record every topic into a rosbag2 MCAP bag (replaced only with --force)")
    la.add_argument("--restart", nargs="?", const="resume", choices=("resume", "fresh"), default=None,
                    help="restart a joint controller that dies (up to 3 times per joint), resuming from its "
                         "last checkpoint (default) or fresh")
    la.add_argument("--netns", action="append", default=[], metavar="GROUP=NAMESPACE",
                    help="run a node group (observer, reference, controllers, plant) in a network namespace "
                         "(ip netns), with discovery range SUBNET: several hosts on one machine; repeatable")
    la.add_argument("--init-from", type=path_arg, default=None, metavar="CHECKPOINTS",
                    help="warm start: the DNBS weights and covariances of an earlier run (its output directory or "
                         "its checkpoints/ directory); reported as such")
    la.add_argument("--bag-compression", choices=("zstd", "none"), default=None,
                    help="with --record: zstd-compressed MCAP chunks (default, as `ros2 bag record -s mcap`) or none")
    _add_live_args(la)
    la.add_argument("--plant", choices=("pybullet", "mujoco"), default="pybullet",
                    help="pybullet: the project's plant node; mujoco: the arm in MuJoCo as an external robot behind "
                         "the joint bus (lockstep; docs/engines.md)")
    la.add_argument("--robot", choices=("external",), default=None,
                    help="external: no plant; the joint bus drives a robot already running that speaks the standard "
                         "interface, on this shell's ROS_DOMAIN_ID or --domain-id (docs/your_robot.md)")
    la.add_argument("--robot-command", default=None, metavar="FORM",
                    help="with --robot external: joint_state (stamped JointState efforts, the default) or "
                         "forward:<controller> (Float64MultiArray on /<controller>/commands)")
    la.add_argument("--robot-state-topic", default=None, metavar="TOPIC",
                    help="with --robot external: the robot's JointState topic (default /robot_joint_states; "
                         "/joint_states with forward:...)")
    la.add_argument("--robot-command-topic", default=None, metavar="TOPIC",
                    help="with --robot external and joint_state commands: the command topic (default "
                         "/robot_joint_command)")
    la.add_argument("--robot-timeout", type=positive, default=None, metavar="SECONDS",
                    help="with --robot external: wall time without a new robot state that makes it stale (default 1)")
    add_fault_arguments(la)
    la.set_defaults(func=_run, func_name="launch")

    rb = sub.add_parser("robot", help="the arm in MuJoCo as an external robot: a ROS 2 node on the standard robot "
                                      "interface (docs/engines.md, docs/your_robot.md)")
    rb.add_argument("--engine", choices=("mujoco",), default="mujoco", help="the simulator (mujoco)")
    rb.add_argument("--config", type=path_arg, default=None, help=f"YAML config (default: {default_config_path()})")
    add_arm_argument(rb)
    rb.add_argument("--mode", choices=("lockstep", "paced"), default="lockstep",
                    help="lockstep: publish state k, wait for the command stamped k, step once; paced: step every "
                         "simulation.dt_s of wall time with the latest command")
    rb.add_argument("--duration", type=seconds, default=None, metavar="SECONDS",
                    help="robot time to run [s], > 0 (default: until Ctrl-C)")
    rb.add_argument("--state-topic", default="/robot_joint_states", metavar="TOPIC",
                    help="the robot's JointState topic (default /robot_joint_states; a relative name resolves in the "
                         "arm's namespace, /pa10 for the PA10, as launch --robot external's)")
    rb.add_argument("--command-topic", default="/robot_joint_command", metavar="TOPIC",
                    help="its JointState effort command topic (default /robot_joint_command; relative: as "
                         "--state-topic)")
    rb.add_argument("--clock-hz", type=nonnegative, default=None, metavar="HZ",
                    help="/clock rate in Hz of robot time (default 100; 0: none)")
    rb.set_defaults(func=_run, func_name="robot")

    st = sub.add_parser("study", help="robustness study: scenarios x controllers x seeds, in parallel (in-process)")
    st.add_argument("--scenarios", default="nominal", metavar="LIST",
                    help="comma-separated: nominal, payload_2kg, payload_5kg, links_heavier_30pct, encoder_noise, "
                         "delay_1_tick, coulomb, fast_reference")
    st.add_argument("--controllers", default="dnbs,pid", metavar="LIST", help="comma-separated: dnbs, pid, ctc")
    st.add_argument("--seeds", type=whole_in(1, 100000), default=1, help="seeds 0..N-1 of the DNBS initial weights and the noise")
    st.add_argument("--duration", type=seconds, default=None, metavar="SECONDS",
                    help="simulated time per run (default: simulation.duration_s of the config, 20 s)")
    st.add_argument("--out", type=path_arg, required=True, metavar="DIR", help="output directory")
    st.add_argument("--config", type=path_arg, default=None, help="YAML config the scenarios start from")
    add_arm_argument(st)
    add_parallel_arguments(st, "runs")
    st.add_argument("--force", action="store_true", help="replace an existing output (never one a running command writes)")
    st.add_argument("--no-progress", action="store_true", help="no progress bar")
    st.set_defaults(func=_run, func_name="study")

    ar = sub.add_parser("arm", help="an arm's facts, sources, effective inertias and gains (docs/arms.md)")
    ar.add_argument("--config", type=path_arg, default=None, help="YAML config (default: the shipped default)")
    add_arm_argument(ar)
    ar.set_defaults(func=_run, func_name="arm")

    tu = sub.add_parser("tune", help="search a controller's settings on an arm with Optuna (docs/tuning.md)")
    tu.add_argument("--controller", required=True, metavar="NAME", help="dnbs, pid or ctc")
    tu.add_argument("--trials", type=whole_in(1, 1000000), default=20, metavar="N",
                    help="completed trials the study should hold (a resumed tune runs the rest; default 20)")
    tu.add_argument("--out", type=path_arg, required=True, metavar="DIR",
                    help="tuned.yaml, tune.md, tune.json, figures, and the study's SQLite storage tune.db")
    add_arm_argument(tu)
    tu.add_argument("--config", type=path_arg, default=None,
                    help="YAML config the search starts from (default: the shipped default)")
    tu.add_argument("--storage", default=None, metavar="URL",
                    help="Optuna storage URL (default: sqlite:///DIR/tune.db), e.g. postgresql://host/db")
    tu.add_argument("--seed", type=whole_in(0, 2**32 - 1), default=0, help="the sampler's seed (default 0)")
    tu.add_argument("--params", default=None, metavar="LIST",
                    help="search only these parameters of the controller's space (the rest stay at the start)")
    tu.add_argument("--scenarios", default=TRAINING_SCENARIOS, metavar="LIST",
                    help=f"training scenarios (default {TRAINING_SCENARIOS})")
    tu.add_argument("--seeds", type=whole_in(1, 100000), default=TRAINING_SEEDS, metavar="N",
                    help=f"training seeds 0..N-1 (default {TRAINING_SEEDS})")
    tu.add_argument("--held-out-seeds", type=whole_in(0, 100000), default=3, metavar="N",
                    help="held-out seeds 100..100+N-1 on every scenario, for the best and the start (default 3; "
                         "0: none)")
    tu.add_argument("--duration", type=seconds, default=None, metavar="SECONDS",
                    help="simulated time per run (default: simulation.duration_s of the config, 20 s)")
    add_parallel_arguments(tu, "runs of the trials")
    tu.add_argument("--no-progress", action="store_true", help="no progress line")
    tu.set_defaults(func=_run, func_name="tune")

    an = sub.add_parser("analyse", help="metrics, figures and report of a recorded run, from its bag alone")
    an.add_argument("bag", type=path_arg, metavar="BAG", help="rosbag2 bag directory (metadata.yaml + .mcap)")
    an.add_argument("--out", type=path_arg, required=True, metavar="DIR", help="output directory")
    an.add_argument("--config", type=path_arg, default=None,
                    help="YAML config (default: the one stored in the bag, else the shipped default)")
    an.add_argument("--force", action="store_true", help="replace an existing output (never one a running command writes)")
    an.add_argument("--no-progress", action="store_true", help="no progress bar")
    an.add_argument("--no-figures", action="store_true", help="metrics and report.md without figures")
    an.set_defaults(func=_run, func_name="analyse")

    rp = sub.add_parser("replay", help="publish a bag's topics with their recorded timing (like ros2 bag play)")
    rp.add_argument("bag", type=path_arg, metavar="BAG", help="rosbag2 bag directory")
    rp.add_argument("--rate", type=number_in(REPLAY_RATE_MIN, REPLAY_RATE_MAX, low_open=False), default=1.0,
                    help=f"playback speed factor in [{REPLAY_RATE_MIN:g}, {REPLAY_RATE_MAX:g}] (default 1)")
    rp.add_argument("--topics", nargs="+", default=None, metavar="TOPIC", help="only these topics (default: all)")
    rp.add_argument("--start-offset", type=nonnegative, default=0.0, metavar="SECONDS",
                    help="skip the bag's first SECONDS (of its own timeline; less than its length)")
    rp.add_argument("--loop", action="store_true", help="play again and again until Ctrl-C (each pass lasts until "
                    "the bag's end, whichever topics are played)")
    rp.add_argument("--clock", type=number_in(0.0, MAX_REPLAY_CLOCK_HZ), nargs="?", const=100.0,   # (0, 1000]
                    default=0.0, metavar="HZ",
                    help=f"publish /clock from the bag's timeline at HZ of wall time, in (0, {MAX_REPLAY_CLOCK_HZ:g}] "
                         "(default 100 when given); "
                         "the recorded /clock is then not replayed (without --clock it is)")
    rp.add_argument("--wait-for-subscribers", type=number_in(0, WAIT_FOR_SUBSCRIBERS_MAX_S, low_open=False),
                    default=0.0, metavar="SECONDS",
                    help=f"before playing, wait up to SECONDS (at most {WAIT_FOR_SUBSCRIBERS_MAX_S:g}; 0: no wait) "
                         f"until every topic has a subscriber (exit 1 if not)")
    rp.add_argument("--namespace", default=None, metavar="NS",
                    help="publish the arm's topics under NS (e.g. /arm2: /pa10/s1/state -> /arm2/s1/state); "
                         "/clock, /tf, /tf_static, /diagnostics stay global (default: as recorded)")
    rp.add_argument("--queue-depth", type=whole_in(1, 1000000), default=1000,
                    help="keep_last depth of each publisher, at least (default 1000)")
    _add_live_args(rp)
    rp.add_argument("--config", type=path_arg, default=None,
                    help="with --live: config for the torque limits (default: the one stored in the bag)")
    rp.set_defaults(func=_run, func_name="replay")
    return parser


def _lossless_streams() -> None:
    """stdout and stderr write what their encoding cannot (a path or joint name outside ASCII under LC_ALL=POSIX)
    as backslash escapes: a "wrote ..." line never fails the run it reports."""
    for stream in (sys.stdout, sys.stderr):
        if hasattr(stream, "reconfigure"):   # None when closed (>&-); a StringIO when redirected in-process
            stream.reconfigure(errors="backslashreplace")


def main(argv: list[str] | None = None) -> int:
    _lossless_streams()   # before the wrap below: it reconfigures the streams themselves
    if argv is None:   # this process is the command: a reader gone from its stdout does not end its run, nor a
        forgive_stdout()   # hung-up terminal its stop (a line that cannot be written does not change the exit code)
        forgive_stderr()
    args = build_parser().parse_args(argv)
    locked_before = held()   # a command run inside another (scripts/equal_budget.py) keeps its caller's locks
    try:
        with interrupt.two_stage_sigint():   # Ctrl-C: the command stops and says what it kept; twice: at once
            return args.func(args)
    except ConfigError as exc:
        print(f"pa10-dnbs: error: {exc.named(SETTING_FLAGS)}", file=sys.stderr)
        return 2
    except Refused as exc:   # an output in the way, a bag, a kernel (refused.py)
        print(f"pa10-dnbs: error: {said_as(str(exc), SETTING_FLAGS)}", file=sys.stderr)
        return 2
    except OSError as exc:
        out = getattr(args, "out", None)
        where = (f" (while writing the outputs for {out})"
                 if exc.filename is None and out is not None and exc.errno in WRITE_ERRNOS else "")
        print(f"pa10-dnbs: error: {exc}{where}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        writes = getattr(args, "func_name", None) not in NO_OUTPUTS
        print(interrupt.written_line() or ("pa10-dnbs: interrupted before it wrote anything (outputs are written "
              "whole, at the end): run the same command again" if writes else
              "pa10-dnbs: interrupted while starting, before any work: nothing changed"), file=sys.stderr)
        return 130
    finally:
        if argv is None:   # this process is the command (not a caller's in-process run): Ctrl-C while it exits
            interrupt.quiet_end()
        release_all(keep=locked_before)  # the output paths this command locked (output_lock.py)


if __name__ == "__main__":
    sys.exit(main())
