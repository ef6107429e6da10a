"""What to start: every node process of the graph as (name, argv), with its ROS arguments.

The plant is started last and told every other node's name but the live view's (``ready_nodes``): it
publishes step 0 only once each of them said ready on the ``ready`` topic (the start handshake,
``ros/ready.py``).

Every node runs in the arm's namespace (``-r __ns:=NS``) under its own name (``-r __node:=``), and every
node but the plant with ``use_sim_time:=true`` (the plant publishes /clock) and ``sched_batch`` as
``GraphOptions.sched_batch`` says; every node with ``rt_priority`` = ``GraphOptions.rt_priority`` (one
scheduling class for the whole graph, loop/scheduling.py). Never imports rclpy.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

from ..ros.param_overrides import override_value
from ..wire.topics import CLOCK, DEFAULT_NS, DIAGNOSTICS, REFERENCE_DEPTH, ArmTopics
from .graph_options import GraphOptions, loop_reliability

NODE_GROUPS = ("observer", "reference", "controllers", "plant")


LIVE_VIEW = "live_view"  # the live observer: display only, its failure does not fail the run
REFERENCE_STATS = "reference_stats.json"  # the reference node's stats file, beside the plant's
JOINT_BUS = "joint_bus"  # --robot external: in the plant's place, in front of the robot (docs/your_robot.md)


def node_group(name: str) -> str:
    if name.startswith("joint_controller_"):
        return "controllers"
    if name == JOINT_BUS:
        return "plant"
    return name if name in ("reference", "plant") else "observer"


def _ros_args(node: str, params: dict, ns: str = DEFAULT_NS) -> list[str]:
    args = ["--ros-args", "-r", f"__node:={node}", "-r", f"__ns:={ns}"]
    for k, v in params.items():
        args += ["-p", f"{k}:={override_value(v)}"]
    return args


def graph_topics(joint_names, ns: str = DEFAULT_NS) -> list[str]:
    """Every topic of the graph of the arm with ``joint_names`` in ``ns`` as recorder specs ('/name:pkg/msg/Type',
    resolved)."""
    arm = ArmTopics(ns)
    specs = [f"{CLOCK}:rosgraph_msgs/msg/Clock", f"{arm.joint_states}:sensor_msgs/msg/JointState",
             f"{arm.robot_description}:std_msgs/msg/String", f"{DIAGNOSTICS}:diagnostic_msgs/msg/DiagnosticArray"]
    for j in joint_names:
        specs += [f"{arm.state(j)}:sensor_msgs/msg/JointState", f"{arm.effort(j)}:sensor_msgs/msg/JointState",
                  f"{arm.reference(j)}:trajectory_msgs/msg/JointTrajectory"]
    return specs


REALTIME_REFERENCE_BATCH = 20  # reference points per message in realtime (smaller bursts of work in the controllers)


def reference_lookahead(opt: GraphOptions) -> int:
    """Steps the reference node keeps published beyond the latest /clock: 150, or more when /clock comes less
    often than every 100 steps (the plant must never need a reference past the next /clock)."""
    every = math.ceil(1.0 / (opt.clock_hz * opt.dt_s) - 1e-9)
    return max(150, every + 50)


def reference_batch(opt: GraphOptions) -> int:
    """Reference points per message: REALTIME_REFERENCE_BATCH in realtime, 100 in lockstep, or more where the
    lookahead would take more than REFERENCE_DEPTH - 2 messages (a /clock below ~0.5 Hz in lockstep, ~3 Hz in
    realtime): the reference endpoints keep REFERENCE_DEPTH, and the first batch, published with the whole
    lookahead at the start, must still be there when a controller matches."""
    batch = REALTIME_REFERENCE_BATCH if opt.mode == "realtime" else 100
    return max(batch, math.ceil(reference_lookahead(opt) / (REFERENCE_DEPTH - 2)))


def controller_command(opt: GraphOptions, workdir: Path, joint: str, incarnation: int = 0) -> list[str]:
    """argv of joint ``joint``'s controller; a restarted one (incarnation > 0) resumes unless opt.restart is
    'fresh', and is not killed again by faults.kill_controller_at_s."""
    params = {"config_file": Path(opt.config_path), "joint": joint, "controller": opt.controller,
              "reliability": loop_reliability(opt), "queue_depth": 1 if opt.mode == "realtime" else 2000,
              "rt_priority": opt.rt_priority, "sched_batch": str(opt.sched_batch).lower(),
              "stats_file": workdir / f"controller_{joint}.json", "incarnation": incarnation,
              "resume": str(incarnation > 0 and opt.restart != "fresh").lower(),
              "effort_subscribers": 1 + int(opt.record_bag is not None),  # the plant and the recorder
              "use_sim_time": "true"}
    if opt.controller == "dnbs":
        params["checkpoint_file"] = workdir / "checkpoints" / f"{joint}.npz"
        if opt.init_from is not None:
            params["init_file"] = opt.init_from / f"{joint}.npz"
    files = ["--params-file", str(opt.params_file)] if opt.params_file is not None else []
    return [sys.executable, "-m", "pa10_dnbs.ros.joint_controller_node"] + _ros_args(f"joint_controller_{joint}",
                                                                                    params, opt.namespace) + files


def node_commands(opt: GraphOptions, stats_file: Path, wire_file: Path) -> list[tuple[str, list[str]]]:
    """(name, argv) of every process: the wire monitor, the recorder (with --record), the nine nodes,
    the plant last (it starts stepping once the others are matched)."""
    py = [sys.executable, "-m"]
    # each node's settings: from the run's params file when there is one; config_file (the run's config_used.yaml)
    # is read only for a key the params file does not give, so a node never falls back to the shipped config
    files = ["--params-file", str(opt.params_file)] if opt.params_file is not None else []

    def ros(node: str, params: dict) -> list[str]:
        return _ros_args(node, {**params, "sched_batch": str(opt.sched_batch).lower(),
                                "use_sim_time": "true", "rt_priority": opt.rt_priority}, opt.namespace) + files

    config_file = Path(opt.config_path)
    if opt.record_bag is None:
        cmds = [("wire_monitor", py + ["pa10_dnbs.ros.wire_monitor"] + ros("wire_monitor", {
                    "config_file": config_file, "duration_s": opt.duration_s, "out_file": Path(wire_file)}))]
    else:  # the recorder is the observer: the run is rebuilt from the bag
        end_ns = int(round(opt.duration_s / opt.dt_s)) * int(round(opt.dt_s * 1e9))
        custom = [f"controller={opt.controller}", f"mode={opt.mode}", f"duration_s={opt.duration_s!r}",
                  f"reliability={loop_reliability(opt)}", f"config_file={opt.recorded_config or config_file}",
                  f"clock_hz={opt.clock_hz!r}",
                  f"namespace={opt.namespace}"]
        cmds = [("recorder", py + ["pa10_dnbs.ros.recorder_node"] + ros("recorder", {
            "config_file": config_file, "bag": Path(opt.record_bag), "force": str(opt.force_bag).lower(),
            "topics": graph_topics(opt.joint_names, opt.namespace), "custom_data": custom, "end_stamp_ns": end_ns,
            "compression": opt.bag_compression}))]
    if opt.live_port is not None:  # display only: started after the observer, never waited for by the plant
        cmds.append((LIVE_VIEW, py + ["pa10_dnbs.ros.live_observer_node"] + ros(LIVE_VIEW, {
            "config_file": config_file, "host": opt.live_host, "port": opt.live_port, "display_hz": opt.live_hz})))
    # realtime: smaller reference batches, so that decoding one (in each controller) never costs a tick its
    # deadline; lockstep keeps 100 points per message (fewer messages, and timing does not matter there)
    batch = reference_batch(opt)
    cmds.append(("reference", py + ["pa10_dnbs.ros.reference_node"] + ros(
        "reference", {"config_file": config_file, "duration_s": opt.duration_s, "batch_steps": batch,
                      "lookahead_steps": reference_lookahead(opt),
                      "reference_subscribers": 2,  # the joint's controller and the observer
                      "stats_file": Path(stats_file).parent / REFERENCE_STATS,  # the trajectories it took
                      **({"trajectory_file": Path(opt.trajectory_file)} if opt.trajectory_file else {})})))
    if not opt.joint_names:
        raise ValueError("GraphOptions.joint_names: the arm's joints are needed to start one controller each")
    for j in opt.joint_names:
        cmds.append((f"joint_controller_{j}", controller_command(opt, stats_file.parent, j)))
    # the start handshake: the plant publishes step 0 once every node but the live view (display only) said ready
    ready = [name for name, _ in cmds if name != LIVE_VIEW]
    if opt.plant_engine == "mujoco":  # --plant mujoco: our own external robot, before the bus (the last process)
        from .plant_engine import mujoco_robot_command

        cmds.append(mujoco_robot_command(opt, lambda node, params: _ros_args(node, params, opt.namespace) + files))
    plant, module, extra = "plant", "pa10_dnbs.ros.plant.node", {}
    if opt.robot == "external":  # the joint bus in the plant's place: same handshake, topics and stats file
        plant, module = JOINT_BUS, "pa10_dnbs.ros.joint_bus_node"
        extra = {"robot_command": opt.robot_command, "robot_state_topic": opt.robot_state_topic or "''",
                 "robot_command_topic": opt.robot_command_topic or "''", "robot_timeout_s": opt.robot_timeout_s}
    cmds.append((plant, py + [module] + _ros_args(plant, ({
        **extra, "ready_nodes": ready, "settle_s": 0.0,
        "config_file": config_file, "mode": opt.mode, "duration_s": opt.duration_s, "reliability": loop_reliability(opt),
        "effort_timeout_s": opt.effort_timeout_s, "on_missing_effort": opt.on_missing_effort,
        "real_time_factor": opt.real_time_factor, "deadline_fraction": opt.deadline_fraction,
        "rt_priority": opt.rt_priority,
        "stats_file": Path(stats_file), "min_joint_states_subscribers": int(opt.record_bag is None),
        "recorders": int(opt.record_bag is not None), "clock_hz": opt.clock_hz}), opt.namespace) + files))
    return cmds
