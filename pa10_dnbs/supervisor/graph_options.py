"""What one run of the graph is given (``GraphOptions``) and what it gives back (``GraphResult``)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..wire.clock_schedule import DEFAULT_CLOCK_HZ
from ..wire.topics import DEFAULT_NS


class GraphFailure(RuntimeError):
    """A node failed, exited early, or the run did not complete."""

    def __init__(self, message: str, interrupted: bool = False):
        super().__init__(message)
        self.interrupted = interrupted


@dataclass
class GraphOptions:
    config_path: Path
    recorded_config: str = ""        # the config path a bag names ('' = config_path; launch: <out>/config_used.yaml,
                                     # where config_path is its temporary output folder's, gone after the run)
    mode: str = "lockstep"
    controller: str = "dnbs"
    duration_s: float = 20.0
    domain_id: int | None = None
    reliability: str | None = None   # per-joint state/effort QoS; None: the mode's default (``loop_reliability``)
    real_time_factor: float = 1.0    # realtime: a step of dt_s takes dt_s / real_time_factor of wall time
    deadline_fraction: float = 0.9   # realtime: efforts must arrive within this fraction of the tick
    rt_priority: int = 0             # SCHED_FIFO priority of every node, as granted (0: off; loop/scheduling.py)
    sched_batch: bool = False        # every node but the plant under SCHED_BATCH (loop/scheduling.py)
    effort_timeout_s: float = 1.0
    on_missing_effort: str = "hold"
    progress: bool = False
    dt_s: float = 1e-3
    record_bag: Path | None = None   # record every topic into this rosbag2 MCAP bag directory
    force_bag: bool = False
    restart: str | None = None       # 'resume' or 'fresh': restart a joint controller that died
    max_restarts: int = 3            # per joint
    netns: dict[str, str] = field(default_factory=dict)  # node group -> network namespace (multi-host)
    init_from: Path | None = None    # warm start: a directory of <joint>.npz controller checkpoints
    bag_compression: str = "zstd"    # 'zstd' (MCAP chunks, as `ros2 bag record -s mcap`) or 'none'
    live_port: int | None = None     # serve the live view (Foxglove WebSocket) on this port; 0: a free one
    live_host: str = "127.0.0.1"
    live_hz: float = 50.0            # live view frames per second of wall time, at most
    namespace: str = DEFAULT_NS      # the arm's ROS namespace: every node runs in it (topics relative to it)
    clock_hz: float = DEFAULT_CLOCK_HZ  # /clock rate [Hz of simulated time]; every node but the plant uses it
    joint_names: tuple[str, ...] = ()   # the arm's actuated joints, chain order: one controller process each
    trajectory_file: Path | None = None  # --trajectory: the reference node follows it from step 0 (not eq. 27)
    params_file: Path | None = None  # the run's ROS params file (supervisor/params_file.py): every node's settings
    robot: str = ""                     # '' = the project's plant; 'external': the joint bus to a running robot
    robot_command: str = "joint_state"  # external: joint_state or forward:<controller> (docs/your_robot.md)
    robot_state_topic: str = ""         # external: the robot's JointState topic; '' = the command form's default
    robot_command_topic: str = ""       # external, joint_state form: the command topic; '' = /robot_joint_command
    robot_timeout_s: float = 1.0        # external: wall time without a new robot state that makes it stale
    plant_engine: str = ""              # 'mujoco': the MuJoCo robot node runs behind the joint bus (supervisor/plant_engine.py)


@dataclass
class GraphResult:
    stats: dict
    exit_codes: dict[str, int]
    domain_id: int
    wall_total_s: float
    wire_file: Path | None   # the wire monitor's record; None when the run went into the bag
    bag: Path | None = None
    restarts: list[dict] = field(default_factory=list)   # joint, exit code, wall time, resumed step
    controllers: dict[str, dict] = field(default_factory=dict)  # joint -> counters of its last incarnation
    reference: dict | None = None  # the reference node's stats: trajectories taken from the topic (None: no file)


def loop_reliability(opt: GraphOptions) -> str:
    """QoS reliability of the per-joint state/effort topics: as given, else the run's default.

    Realtime: best effort, the sensor-data convention (a late sample is overwritten, not re-sent). Lockstep:
    best effort too while the loop stays on one host and nothing records it: at most one state and one effort per
    joint are in flight, the shared-memory queues never overflow, and a sample lost anyway is re-requested
    by the plant's resend (0.25 s), so the run stays the in-process run bit for bit; it saves the
    acknowledgements of reliable writers (lockstep 12 % faster here, docs/timing.md). Reliable when a bag
    records the run (the bag must hold every message, and a recorder that falls behind would lose best-effort
    samples) or nodes run in other network namespaces (UDP between hosts can drop what DDS would retransmit).
    """
    if opt.reliability is not None:
        return opt.reliability
    if opt.mode == "realtime":
        return "best_effort"
    return "reliable" if opt.record_bag is not None or opt.netns else "best_effort"
