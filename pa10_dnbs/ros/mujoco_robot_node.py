"""mujoco_robot_node: the arm simulated by MuJoCo as an external robot speaking the standard robot interface
(docs/your_robot.md): what a user's simulator or ros2_control robot would be to the joint bus.

Publishes ``sensor_msgs/JointState`` (name, position [rad], velocity [rad/s], effort = the torque applied over
the step before [N m]; header.stamp = robot time k T) on ``state_topic`` and ``rosgraph_msgs/Clock`` on /clock
(reliable, transient-local: time 0 goes out at start and reaches late joiners; then one per 1 / ``clock_hz`` of
robot time). Takes ``sensor_msgs/JointState`` effort commands on ``command_topic``, matched by joint name,
header.stamp = the stamp of the state they answer. The stepping rule (lockstep or paced): ``loop/robot_stepper.py``;
the plant: ``plant/mujoco_plant.py`` (T = ``simulation.dt_s``, 1 ms). Lockstep re-sends the current state every
``resend_s`` while its command is missing. State 0 goes out once a command publisher and a state subscriber have
matched; paced, it is held (re-sent every ``resend_s``, /clock at 0) until the first command comes, so the robot's
time starts with the graph's first answer, not when the bus's endpoints appear (the graph's start handshake takes
seconds: a paced robot running meanwhile raced it). Runs ``duration_s`` of robot time, or until SIGINT (0); then
one summary line and exit 0.
"""
from __future__ import annotations

import struct
import time
from typing import NoReturn

from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState

from ..loop.robot_stepper import MODES, RobotStepper
from ..plant.engines import open_plant
from ..wire import joint_state_cdr
from ..wire.clock_schedule import DEFAULT_CLOCK_HZ, ClockSchedule, check_clock_hz
from .params import SETTINGS_DEFAULTS, Param, ParameterError, check_choice, declare, declare_settings, duration_steps
from .plant.endpoints import CLOCK_CDR
from .polled import PolledSubscription, SubscriptionWaitSet
from .runtime import announce_ready
from .settings_params import NODE_SECTIONS
from .endpoints import CLOCK

PARAMS = {
    "config_file": SETTINGS_DEFAULTS,
    "arm": Param("", "the arm of those defaults: a preset's name or an arm file or URDF; '' = the config's arm "
                     "(arm_file, when given, is the arm)"),
    "mode": Param("lockstep", "lockstep (step once the command for the current state is in) or paced (wall-clock "
                              "ticks of simulation.dt_s with the latest command)"),
    "duration_s": Param(0.0, "robot time to run [s]; 0 = until SIGINT", 0.0),
    "state_topic": Param("/robot_joint_states", "where the robot's JointState goes", topics=True),
    "command_topic": Param("/robot_joint_command", "where its JointState effort commands come from", topics=True),
    "clock_hz": Param(DEFAULT_CLOCK_HZ, "/clock rate [Hz of robot time]; 0 = no /clock", 0.0, 1e6),
    "resend_s": Param(0.25, "lockstep (and paced before the first command): wall time before the current state "
                            "is sent again [s]", 0.0),
}
STATE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.VOLATILE)
COMMAND_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.VOLATILE)
CLOCK_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
MATCH_POLL_S = 0.05  # wall time between two looks at the endpoints before state 0 [s]
NS = 1_000_000_000
FINAL_FLUSH_S = 2.0  # wall time the finished robot waits for its last state to be acknowledged [s]


class MuJoCoRobotNode(Node):
    def __init__(self):
        super().__init__("mujoco_robot")
        p = declare(self, PARAMS)
        check_choice("mode", p["mode"], MODES)
        if not p["resend_s"] > 0:
            raise ParameterError(f"parameter resend_s must be > 0, got {p['resend_s']}")
        settings = declare_settings(self, NODE_SECTIONS["mujoco_robot"], p["config_file"], p["arm"], "arm")
        self.dt = settings.simulation.dt_s
        try:
            check_clock_hz(p["clock_hz"], self.dt)
        except ValueError as exc:
            raise ParameterError(f"parameter clock_hz {exc}") from None
        self.p = p
        self.plant, self._close_plant = open_plant(settings, "mujoco")
        self.joint_names = self.plant.joint_names
        self.stepper = RobotStepper(self.plant, p["mode"], self.dt)
        self.last_step = duration_steps(p["duration_s"], self.dt) if p["duration_s"] > 0 else 2**62
        self._state_pub = self.create_publisher(JointState, p["state_topic"], STATE_QOS)
        self._clock_pub = self.create_publisher(Clock, CLOCK, CLOCK_QOS) if p["clock_hz"] > 0 else None
        self._schedule = ClockSchedule(p["clock_hz"], self.dt, self.last_step) if p["clock_hz"] > 0 else None
        self._commands = PolledSubscription(self, JointState, p["command_topic"], COMMAND_QOS)
        self._wait_set = SubscriptionWaitSet(self, [self._commands])
        self._index_of: dict[tuple, list[int] | None] = {}  # a command's names -> the arm's joints in it
        self.resends = self.malformed = self.late_ticks = 0
        self.wall_start = self.wall_end = None
        self.exit_code = 0
        self.get_logger().info(f"MuJoCo {self.plant.arm.name} ({len(self.joint_names)} joints), {p['mode']}, "
                               f"state {self._state_pub.topic_name}, commands "
                               f"{self.resolve_topic_name(p['command_topic'])}")
        announce_ready("mujoco_robot")

    # ---------------------------------------------------------------- wire
    def _publish_state(self) -> None:
        k = self.stepper.step
        t = self.stepper.stamp_ns
        q, qd = self.plant.state
        self._state_pub.publish(joint_state_cdr.encode(t // NS, t % NS, self.joint_names, q.tolist(), qd.tolist(),
                                                       self.plant.applied_torque_nm.tolist()))
        if self._schedule is not None and self._schedule.due(k):
            self._clock_pub.publish(CLOCK_CDR.pack(0x0100, 0, t // NS, t % NS))

    def _efforts(self, names, effort) -> list[float] | None:
        """The arm's efforts in chain order from a command's fields, or None (a joint or an effort missing)."""
        key = tuple(names)
        if key not in self._index_of:
            where = {n: i for i, n in enumerate(key)}
            self._index_of[key] = [where[j] for j in self.joint_names] if all(j in where for j in self.joint_names) \
                else None
            if self._index_of[key] is None:
                self.get_logger().warning(missing_joints_text(self.joint_names, key))
        idx = self._index_of[key]
        if idx is None or len(effort) < len(key):
            return None
        return [float(effort[i]) for i in idx]

    def _take_commands(self) -> bool:
        """Offer every queued command to the stepper; True when one stepped the plant (lockstep)."""
        stepped = False
        while (got := self._commands.take()) is not None:
            try:
                sec, nanosec, names, _, _, effort = joint_state_cdr.decode(got[0])
            except (ValueError, IndexError, struct.error, UnicodeDecodeError):
                self.malformed += 1
                continue
            u = self._efforts(names, effort)
            if u is None:
                self.malformed += 1
                continue
            if self.stepper.offer(sec * NS + nanosec, u):
                stepped = True
                if self.stepper.mode == "lockstep":
                    return True  # one step per command: the next one answers the next state
        return stepped

    # ---------------------------------------------------------------- loop
    def _wait_for_bus(self, stop) -> bool:
        """/clock at time 0 out (latched); then wait until a command publisher and a state subscriber matched."""
        if self._clock_pub is not None:
            self._schedule.due(0)
            self._clock_pub.publish(CLOCK_CDR.pack(0x0100, 0, 0, 0))
        said = False
        while not stop.done():
            if self._commands.get_publisher_count() > 0 and self._state_pub.get_subscription_count() > 0:
                return True
            if not said:
                print(f"WAITING for a controller on {self.resolve_topic_name(self.p['command_topic'])} and "
                      f"{self._state_pub.topic_name}",
                      flush=True)
                said = True
            time.sleep(MATCH_POLL_S)
        return False

    def loop(self, executor, stop) -> None:
        if not self._wait_for_bus(stop):
            return
        print("RUNNING mujoco_robot", flush=True)
        self.wall_start = time.perf_counter()
        if self.stepper.mode == "lockstep":
            self._run_lockstep(stop)
        else:
            self._run_paced(stop)
        self.wall_end = time.perf_counter()
        if not stop.done():  # the run's end: the last state reaches every reliable reader before the process goes
            self._state_pub.wait_for_all_acked(Duration(seconds=FINAL_FLUSH_S))

    def _run_lockstep(self, stop) -> None:
        self._publish_state()
        sent = time.monotonic()
        while not stop.done() and self.stepper.step < self.last_step:
            self._wait_set.wait(min(0.05, self.p["resend_s"]))
            if self._take_commands():
                self._publish_state()
                sent = time.monotonic()
            elif time.monotonic() - sent >= self.p["resend_s"]:
                self.resends += 1
                self._publish_state()
                sent = time.monotonic()

    def _run_paced(self, stop) -> None:
        tick_ns = int(round(self.dt * NS))
        self._publish_state()
        sent = time.monotonic()
        while not stop.done() and self.stepper.commands == 0:  # state 0 held until the graph's first answer
            self._wait_set.wait(0.05)
            self._take_commands()
            if self.stepper.commands == 0 and time.monotonic() - sent >= self.p["resend_s"]:
                self.resends += 1
                self._publish_state()
                sent = time.monotonic()
        next_ns = time.perf_counter_ns() + tick_ns
        while not stop.done() and self.stepper.step < self.last_step:
            left = next_ns - time.perf_counter_ns()
            if left > 0:
                self._wait_set.wait(left / NS)
                self._take_commands()
                if time.perf_counter_ns() < next_ns:
                    continue
            elif -left > tick_ns:  # more than a tick late: counted, not caught up
                self.late_ticks += 1
                next_ns = time.perf_counter_ns()
            self._take_commands()
            self.stepper.tick()
            self._publish_state()
            next_ns += tick_ns

    # ---------------------------------------------------------------- report
    def summary(self) -> str:
        s = self.stepper
        wall = (self.wall_end or time.perf_counter()) - self.wall_start if self.wall_start is not None else 0.0
        rate = f", {s.step / wall:.0f} steps/s of wall time" if wall > 0 else ""
        return (f"mujoco_robot: {s.step} steps ({s.step * self.dt:g} s of robot time) in {wall:.2f} s{rate}; "
                f"{s.commands} commands, {s.stale} for another state, {s.refused} non-finite, {self.malformed} "
                f"malformed; {self.resends} states re-sent; {self.late_ticks} late ticks; joint limit hits "
                f"{self.plant.limit_hits.tolist()}")

    def close(self) -> None:
        print(self.summary(), flush=True)
        self._wait_set.destroy()
        self._close_plant()


def missing_joints_text(arm_joints, command_joints) -> str:
    """The warning for a command lacking some of the arm's joints: the arm's, the command's, and which lack."""
    missing = [j for j in arm_joints if j not in set(command_joints)]
    return (f"a command without every joint of the arm: the arm's joints are {', '.join(arm_joints)}; the command "
            f"names {', '.join(command_joints) or 'none'} (missing {', '.join(missing)}): ignored")


def main(args=None) -> NoReturn:
    from .runtime import exit_process, run_node

    exit_process(run_node(MuJoCoRobotNode, args, params=PARAMS))


if __name__ == "__main__":
    main()
