"""Plant-side effort bookkeeping: lockstep completion, timeouts, realtime misses."""
import math

import numpy as np
import pytest

from pa10_dnbs.loop.effort_gate import EffortGate


def test_lockstep_completes_only_with_all_joints():
    g = EffortGate(3)
    assert not g.offer(0, 0, 1.0)
    assert not g.offer(2, 0, 3.0)
    assert g.missing == [1]
    assert g.offer(1, 0, 2.0)
    np.testing.assert_array_equal(g.take_lockstep(), [1.0, 2.0, 3.0])
    assert g.step == 1 and g.missing == [0, 1, 2]


def test_stale_and_future_efforts_do_not_complete_a_step():
    g = EffortGate(2)
    for j in range(2):
        g.offer(j, 0, 1.0)
    g.take_lockstep()
    assert not g.offer(0, 0, 5.0)  # a resend answer for step 0
    assert g.stale[0] == 1
    assert not g.offer(1, 7, 5.0)  # not the current step either
    assert g.missing == [0, 1]


@pytest.mark.parametrize("mode,expected", [("hold", 4.0), ("zero", 0.0)])
def test_timeout_fills_missing_joint_and_counts(mode, expected):
    g = EffortGate(2, on_missing=mode)
    g.offer(0, 0, 1.0)
    g.offer(1, 0, 4.0)
    g.take_lockstep()
    g.offer(0, 1, 2.0)
    tau = g.take_lockstep(timed_out=True)
    assert tau.tolist() == [2.0, expected]
    assert g.timeouts.tolist() == [0, 1]
    with pytest.raises(RuntimeError):
        g.take_lockstep()


def test_nonfinite_effort_is_replaced_at_once_and_counted():
    g = EffortGate(2, on_missing="hold")
    g.offer(0, 0, 1.0)
    g.offer(1, 0, 2.0)
    g.take_lockstep()
    assert not g.offer(0, 1, math.nan)      # joint 0 answered (held), joint 1 not yet
    assert g.missing == [1]
    assert not g.offer(0, 1, math.inf)      # a second bad answer changes nothing
    assert g.offer(1, 1, 5.0)
    assert g.take_lockstep().tolist() == [1.0, 5.0]
    assert g.nonfinite.tolist() == [2, 0] and g.timeouts.tolist() == [0, 0]


def test_realtime_zero_order_hold_and_miss_count():
    g = EffortGate(2)
    g.offer(0, 0, 1.0)
    g.offer(1, 0, 2.0)
    assert g.take_realtime().tolist() == [1.0, 2.0]  # tick applying step 0: both answered state 0
    g.offer(0, 1, 3.0)                                # joint 1 late for state 1
    assert g.take_realtime().tolist() == [3.0, 2.0]  # held
    assert g.misses.tolist() == [0, 1]
    assert (g.ticks, g.ticks_all_on_time) == (2, 1)


def test_efforts_ahead_are_kept_until_their_step():
    """A player re-driving the plant sends efforts for later steps; each is applied at its own step."""
    gate = EffortGate(2)
    assert not gate.offer(0, 1, 10.0) and not gate.offer(1, 1, 11.0)   # step 1, early
    assert not gate.offer(0, 2, 20.0)
    assert not gate.ready
    gate.offer(0, 0, 1.0)
    assert gate.offer(1, 0, 2.0)
    np.testing.assert_array_equal(gate.take_lockstep(), [1.0, 2.0])
    assert gate.ready                      # step 1 was complete before it came
    np.testing.assert_array_equal(gate.take_lockstep(), [10.0, 11.0])
    assert gate.missing == [1]             # step 2: joint 1 still owes
    assert gate.offer(1, 2, 21.0)
    np.testing.assert_array_equal(gate.take_lockstep(), [20.0, 21.0])
    assert gate.timeouts.sum() == 0 and gate.stale.sum() == 0


def test_efforts_ahead_are_bounded():
    gate = EffortGate(1, max_pending=2)
    for k in (1, 2, 3, 4):
        gate.offer(0, k, float(k))
    assert gate.dropped_ahead.tolist() == [2]
