"""What each command is asked to do: one frozen dataclass per command, built by ``cli.py`` from its flags.

The values are already checked, each once, by the parser's ``type=`` validators (cli_values.py); a command
checks only what depends on its settings (a duration against the step, a clock rate against dt). A field's
unit is in its name; None: the config's value (or the command's default, as its flag's help says).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .fault_flags import FaultFlags
from ..supervisor.robot_options import RobotOptions
from ..loop.scheduling import DEFAULT_RT_PRIORITY
from ..tune.objective import TRAINING_SCENARIOS, TRAINING_SEEDS
from ..wire.clock_schedule import DEFAULT_CLOCK_HZ


@dataclass(frozen=True)
class SimulateOptions:
    """``pa10-dnbs simulate``: controller one of dnbs, pid, ctc, both, all; arm a preset's name, arm file or URDF
    (None: the config's); engine pybullet or mujoco; trajectory a JointTrajectory file followed from t = 0;
    init_from the checkpoints of an earlier run (a warm start)."""

    out: Path
    config_path: Path | None = None
    controller: str = "dnbs"
    duration_s: float | None = None
    force: bool = False
    progress: bool = False
    init_from: Path | None = None
    figures: bool = True
    arm: str | None = None
    engine: str = "pybullet"
    trajectory: Path | None = None


@dataclass(frozen=True)
class LaunchOptions:
    """``pa10-dnbs launch``: one run of the node graph.

    mode: lockstep or realtime; real_time_factor and deadline_fraction pace realtime (docs/timing.md);
    effort_timeout_s [s of wall time] bounds lockstep's wait for an effort, on_missing_effort (hold or zero)
    replaces a missing one. reliability: the joint topics' QoS (None: the mode's default). domain_id: None: a
    leased free one (with an external robot: this shell's ROS_DOMAIN_ID). record: a bag directory
    (bag_compression zstd or none). faults: the fault flags, applied to the settings' faults section.
    restart: resume or fresh (None: a dead controller is not restarted). netns: GROUP=NAMESPACE items.
    init_from: the checkpoints of an earlier run (a warm start of DNBS). live_port: serve the live view on
    live_host:live_port (0: a free port; None: off), live_hz frames per second at most. rt_priority: SCHED_FIFO
    priority of every node where the OS grants it (0: off); sched_batch: every node but the plant under
    SCHED_BATCH. namespace: the arm's ROS namespace (None: /<the arm's name>). clock_hz: /clock rate [Hz of
    simulated time] (None: not given, DEFAULT_CLOCK_HZ). robot: ``--robot external`` and its topics (None: the
    project's plant, docs/your_robot.md); plant: pybullet (the plant node) or mujoco (the MuJoCo robot node
    behind the joint bus, docs/engines.md). trajectory: a JointTrajectory file the reference node follows from
    step 0 instead of eq. 27."""

    out: Path
    config_path: Path | None = None
    mode: str = "lockstep"
    controller: str = "dnbs"
    duration_s: float | None = None
    force: bool = False
    progress: bool = False
    domain_id: int | None = None
    reliability: str | None = None
    effort_timeout_s: float = 1.0
    on_missing_effort: str = "hold"
    record: Path | None = None
    faults: FaultFlags = field(default_factory=FaultFlags)
    restart: str | None = None
    netns: tuple[str, ...] = ()
    init_from: Path | None = None
    bag_compression: str = "zstd"
    live_port: int | None = None
    live_host: str = "127.0.0.1"
    live_hz: float = 50.0
    real_time_factor: float = 1.0
    deadline_fraction: float = 0.9
    rt_priority: int = DEFAULT_RT_PRIORITY
    sched_batch: bool = False
    namespace: str | None = None
    clock_hz: float | None = None
    figures: bool = True
    arm: str | None = None
    robot: RobotOptions | None = None
    trajectory: Path | None = None
    plant: str = "pybullet"


@dataclass(frozen=True)
class StudyOptions:
    """``pa10-dnbs study``: scenarios and controllers as comma-separated lists; seeds 0..seeds-1; jobs local
    processes (None: one per core); scheduler a Dask scheduler's address instead."""

    out: Path
    scenarios: str = "nominal"
    controllers: str = "dnbs,pid"
    seeds: int = 1
    duration_s: float | None = None      # None: the config's simulation.duration_s
    force: bool = False
    config_path: Path | None = None
    jobs: int | None = None
    progress: bool = False
    arm: str | None = None
    scheduler: str | None = None


@dataclass(frozen=True)
class TuneOptions:
    """``pa10-dnbs tune``: the controller's search (docs/tuning.md): trials completed trials; storage an Optuna
    URL (None: DIR/tune.db); seed the sampler's; scenarios, seeds, held_out_seeds the runs of each trial;
    params the parameters searched (None: all of the controller's space)."""

    controller: str
    out: Path
    trials: int = 20
    arm: str | None = None
    config_path: Path | None = None
    storage: str | None = None
    seed: int = 0
    jobs: int | None = None
    scheduler: str | None = None
    scenarios: str = TRAINING_SCENARIOS
    seeds: int = TRAINING_SEEDS
    held_out_seeds: int = 3
    duration_s: float | None = None      # None: the config's simulation.duration_s
    params: str | None = None
    progress: bool = False


@dataclass(frozen=True)
class ArmInfoOptions:
    """``pa10-dnbs arm``: the arm (None: the config's) and the config."""

    config_path: Path | None = None
    arm: str | None = None


@dataclass(frozen=True)
class AnalyseOptions:
    """``pa10-dnbs analyse``: a recorded bag's metrics, figures and report into out (config None: the bag's)."""

    bag_path: Path
    out: Path
    force: bool = False
    config_path: Path | None = None
    progress: bool = False
    figures: bool = True


@dataclass(frozen=True)
class ReplayOptions:
    """``pa10-dnbs replay``: rate the playback speed factor; start_offset_s [s of the bag's timeline]; clock_hz
    /clock from the bag's timeline (0: the recorded /clock); wait_for_subscribers_s [s]; live_port the live view
    (None: off); namespace the arm's topics under it (None: as recorded)."""

    bag_path: Path
    rate: float = 1.0
    topics: list[str] | None = None
    start_offset_s: float = 0.0
    loop: bool = False
    clock_hz: float = 0.0
    wait_for_subscribers_s: float = 0.0
    queue_depth: int = 1000
    live_port: int | None = None
    live_host: str = "127.0.0.1"
    live_hz: float = 50.0
    config_path: Path | None = None
    namespace: str | None = None


@dataclass(frozen=True)
class RobotCommandOptions:
    """``pa10-dnbs robot``: the arm in MuJoCo as an external robot; mode lockstep or paced; duration_s [s of
    robot time] (None: until Ctrl-C); clock_hz [Hz of robot time] (0: no /clock; None: not given,
    DEFAULT_CLOCK_HZ)."""

    config_path: Path | None = None
    arm: str | None = None
    mode: str = "lockstep"
    duration_s: float | None = None
    state_topic: str = "/robot_joint_states"
    command_topic: str = "/robot_joint_command"
    clock_hz: float | None = None
