"""The live view: from the wire's raw messages to what a Foxglove client is shown, one frame per display period.

Fed with raw CDR messages as they arrive (``on_message``: cheap, the newest
/joint_states is only remembered) and ticked by the caller's wall-clock timer
(``tick``), it sends at most one frame per period of wall time:
<ns>/joint_states forwarded as it came off the wire, /tf from the URDF's
forward kinematics (what the recorder writes into bags), <ns>/tracking
(tracking error and torque per joint), and the simulated time. /diagnostics
goes out as it comes (1 Hz per node); <ns>/robot_description and /tf_static
are latched. Topics are the resolved names of the arm (``ArmTopics``, /pa10
by default), for input and output alike.
Work for a channel nobody is subscribed to is skipped. Used by the launcher's
live observer node and by ``replay --live``.
"""
from __future__ import annotations

import struct
import xml.etree.ElementTree as ET

from ..bag.tf_messages import tf_message_cdr
from ..kinematics.urdf_chain import UrdfChain
from ..wire import joint_state_cdr
from ..wire.reference_buffer import ReferenceBuffer
from ..wire.steps import NS_PER_S, StepClock, cdr_stamp_ns
from ..wire.topics import DIAGNOSTICS, TF, TF_STATIC, ArmTopics
from . import tracking
from .decimator import Decimator

DEFAULT_DISPLAY_HZ = 50.0
_U32 = struct.Struct("<I")


def string_cdr(data: bytes) -> str:
    """The text of a std_msgs/msg/String's CDR bytes."""
    if len(data) < 8:
        raise ValueError("too short for a String")
    (n,) = _U32.unpack_from(data, 4)
    if n == 0 or 8 + n > len(data):
        raise ValueError("bad String length")
    return bytes(data[8:8 + n - 1]).decode("utf-8")


class LiveView:
    def __init__(self, sink, torque_limit_nm, dt_s: float, display_hz: float = DEFAULT_DISPLAY_HZ, *,
                 joint_names, arm: ArmTopics = ArmTopics()):
        """``sink``: a LiveServer (log, wanted, resend_latched, broadcast_time); ``display_hz``: frames per
        second of wall time at most; ``torque_limit_nm``: the arm's torque limits, in ``joint_names`` order (the
        arm's joints, chain order); ``arm``: the topic names read and served."""
        if not display_hz > 0:
            raise ValueError(f"display_hz must be > 0, got {display_hz}")
        self.sink = sink
        self.arm = arm
        self.joint_names = tuple(joint_names)
        self.torque_limit_nm = [float(v) for v in torque_limit_nm]
        if len(self.torque_limit_nm) != len(self.joint_names):
            raise ValueError("torque_limit_nm needs one value per joint")
        self.clock = StepClock(dt_s)
        self.decimator = Decimator(1.0 / display_hz)
        self.refs = ReferenceBuffer(len(self.joint_names), self.clock)
        self._ref_topics = {arm.reference(j): i for i, j in enumerate(self.joint_names)}
        self.chain: UrdfChain | None = None
        self.last_stamp_ns = 0
        self.frames = 0
        self.malformed = 0

    def topics(self) -> list[str]:
        """The ROS topics the view reads."""
        return [self.arm.robot_description, self.arm.joint_states, DIAGNOSTICS] + list(self._ref_topics)

    # ------------------------------------------------------------ input
    def on_message(self, topic: str, data: bytes) -> None:
        """A raw message off the wire (or out of a bag)."""
        if topic == self.arm.joint_states:
            self.decimator.offer(data)
        elif topic in self._ref_topics:
            if not self.refs.add_cdr(self._ref_topics[topic], data):
                self.malformed += 1
        elif topic == DIAGNOSTICS:
            try:
                stamp = cdr_stamp_ns(data)
            except struct.error:
                self.malformed += 1
                return
            self.sink.log(DIAGNOSTICS, bytes(data), stamp)
        elif topic == self.arm.robot_description:
            self._on_description(bytes(data))

    def _on_description(self, data: bytes) -> None:
        try:
            chain = UrdfChain(string_cdr(data))
        except (ValueError, UnicodeDecodeError, ET.ParseError, AttributeError):
            self.malformed += 1
            return
        self.chain = chain
        sec, nanosec = divmod(self.last_stamp_ns, NS_PER_S)
        self.sink.log(self.arm.robot_description, data, self.last_stamp_ns)
        self.sink.log(TF_STATIC, tf_message_cdr(chain.fixed_transforms(), sec, nanosec), self.last_stamp_ns)

    # ------------------------------------------------------------ output
    def tick(self, now_s: float) -> bool:
        """Send a frame if one is due at wall time ``now_s`` [s] and a new state came; True if one was sent."""
        self.sink.resend_latched()
        data = self.decimator.take(now_s)
        if data is None:
            return False
        try:
            sec, nanosec, names, pos, _, eff = joint_state_cdr.decode(data)
        except (ValueError, struct.error, UnicodeDecodeError):
            self.malformed += 1
            return False
        stamp_ns = sec * NS_PER_S + nanosec
        step = self.clock.step_of_ns(stamp_ns)
        self.last_stamp_ns = stamp_ns
        self.sink.broadcast_time(stamp_ns)
        self.sink.log(self.arm.joint_states, bytes(data), stamp_ns)
        by_name = dict(zip(names or self.joint_names, pos))
        if self.chain is not None and self.sink.wanted(TF):
            self.sink.log(TF, tf_message_cdr(self.chain.moving_transforms(by_name), sec, nanosec), stamp_ns)
        positions = [float(by_name.get(j, float("nan"))) for j in self.joint_names]
        by_name_tau = dict(zip(names or self.joint_names, eff))
        torques = [float(by_name_tau.get(j, float("nan"))) for j in self.joint_names]
        self.refs.error(step, positions)  # updates the worst |e| so far
        if self.sink.wanted(self.arm.tracking):
            msg = tracking.tracking_message(stamp_ns, step, self.joint_names, positions, self.refs.at(step), torques,
                                            self.torque_limit_nm, self.refs.worst_abs_error)
            self.sink.log(self.arm.tracking, tracking.encode(msg), stamp_ns)
        self.refs.forget_before(step)
        self.frames += 1
        return True
