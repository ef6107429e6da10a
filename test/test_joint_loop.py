"""The controller node's loop: waits for references, answers each state once."""
import numpy as np

from pa10_dnbs.core.controller_bank import FixedGainBank
from pa10_dnbs.core.reference import ReferenceSample
from pa10_dnbs.loop.guarded_controllers import GuardedControllers
from pa10_dnbs.loop.joint_loop import JointLoop


class Recorder(FixedGainBank):
    """A bank of one row that answers 1, 2, 3, ... and records what it saw."""
    n_joints = 1

    def __init__(self):
        self.calls = []

    def answer(self, x1, x2, ref: ReferenceSample, active=None):
        self.calls.append((float(x1[0]), float(x2[0]), float(ref.position_rad[0]), float(ref.velocity_rad_s[0]),
                           float(ref.position_ahead_rad[0])))
        return np.array([float(len(self.calls))])


def _loop():
    ctrl = Recorder()
    return ctrl, JointLoop(GuardedControllers(ctrl, guard=None), preview_steps=2)


def test_state_waits_for_its_references_then_is_answered():
    ctrl, loop = _loop()
    assert loop.on_state(0, 0.1, 0.0) == []            # no reference yet
    assert loop.add_reference(0, [0.0, 0.5], [1.0, 1.5]) == []  # x_d(2) still missing
    assert loop.add_reference(2, [0.7, 0.8], [2.0, 2.0]) == [(0, 1.0)]
    assert ctrl.calls == [(0.1, 0.0, 0.0, 1.0, 0.7)]


def test_resent_state_gets_same_effort_without_retraining():
    ctrl, loop = _loop()
    loop.add_reference(0, [0.0] * 10, [0.0] * 10)
    assert loop.on_state(0, 0.1, 0.0) == [(0, 1.0)]
    assert loop.on_state(0, 0.1, 0.0) == [(0, 1.0)]
    assert len(ctrl.calls) == 1 and loop.duplicates == 1
    assert loop.on_state(1, 0.2, 0.0) == [(1, 2.0)]
    assert loop.on_state(0, 0.1, 0.0) == []  # older than the last answer: ignored
    assert loop.out_of_order == 1


def test_every_bad_state_message_is_counted_once_resends_and_stale_ones_too():
    """docs/faults.md: the controller's bad-state counters equal the corrupted states the plant sent. A resend
    draws its own fate, so a corrupted resend of an answered step (answered from the stored effort, untrained)
    and a corrupted stale or superseded state are counted too; the answers stay those of the first message."""
    from pa10_dnbs.core.state_guard import StateGuard

    ctrl = Recorder()
    guard = StateGuard(lower_rad=np.array([-1.0]), upper_rad=np.array([1.0]), margin_rad=0.0, max_speed_rad_s=10.0)
    loop = JointLoop(GuardedControllers(ctrl, guard=guard), preview_steps=2)
    loop.add_reference(0, [0.0] * 10, [0.0] * 10)
    nan = float("nan")
    assert loop.on_state(0, 0.1, 0.0) == [(0, 1.0)]
    assert loop.on_state(0, nan, 0.0) == [(0, 1.0)]        # corrupted resend: the stored answer, counted
    assert loop.on_state(1, 5.0, 0.0) == [(1, 1.0)]        # out of range: answered with the held torque, counted
    assert loop.on_state(0, float("inf"), 0.0) == []       # stale and corrupted: ignored, counted
    assert loop.on_state(20, nan, 0.0) == []               # waits for references ...
    assert loop.on_state(20, 0.3, 0.0) == []               # ... superseded by its resend: the first counted
    assert len(ctrl.calls) == 2 and loop.duplicates == 1 and loop.out_of_order == 1
    assert loop.bad_states == {"nonfinite": 3, "position": 1, "speed": 0}
