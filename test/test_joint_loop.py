"""The controller node's loop: waits for references, answers each state once."""
from pa10_dnbs.core.reference import ReferenceSample
from pa10_dnbs.loop.joint_loop import JointLoop


class Recorder:
    def __init__(self):
        self.calls = []

    def step(self, x1, x2, ref: ReferenceSample):
        self.calls.append((x1, x2, ref))
        return float(len(self.calls))


def test_state_waits_for_its_references_then_is_answered():
    ctrl = Recorder()
    loop = JointLoop(ctrl, preview_steps=2)
    assert loop.on_state(0, 0.1, 0.0) == []            # no reference yet
    assert loop.add_reference(0, [0.0, 0.5], [1.0, 1.5]) == []  # x_d(2) still missing
    assert loop.add_reference(2, [0.7, 0.8], [2.0, 2.0]) == [(0, 1.0)]
    assert ctrl.calls == [(0.1, 0.0, ReferenceSample(0.0, 1.0, 0.7))]


def test_resent_state_gets_same_effort_without_retraining():
    ctrl = Recorder()
    loop = JointLoop(ctrl, preview_steps=2)
    loop.add_reference(0, [0.0] * 10, [0.0] * 10)
    assert loop.on_state(0, 0.1, 0.0) == [(0, 1.0)]
    assert loop.on_state(0, 0.1, 0.0) == [(0, 1.0)]
    assert len(ctrl.calls) == 1 and loop.duplicates == 1
    assert loop.on_state(1, 0.2, 0.0) == [(1, 2.0)]
    assert loop.on_state(0, 0.1, 0.0) == []  # older than the last answer: ignored
    assert loop.out_of_order == 1
