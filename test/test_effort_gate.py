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


def test_deadline_applies_exactly_the_efforts_that_came():
    g = EffortGate(2)
    g.offer(0, 0, 1.0)
    g.offer(1, 0, 2.0)
    assert g.take_deadline().tolist() == [1.0, 2.0]  # both answered state 0 in time
    g.offer(0, 1, 3.0)                                # joint 1 misses the deadline of state 1
    assert g.take_deadline().tolist() == [3.0, 2.0]  # held
    assert g.misses.tolist() == [0, 1] and g.miss_steps == [[], [1]]
    assert (g.ticks, g.ticks_all_on_time) == (2, 1)
    assert not g.offer(1, 1, 9.0)                     # its late answer: stale, never applied
    assert g.stale.tolist() == [0, 1]
    assert g.missing == [0, 1] and g.step == 2


@pytest.mark.parametrize("mode", ["hold", "zero"])
def test_lost_efforts_in_realtime_are_filled_in_and_counted_per_joint(mode):
    """A seeded 5 % of efforts never arrive (as --drop-efforts does on the wire): every loss is one miss of its
    joint at its step, the tick is not on time, the torque is the last applied one (hold) or zero, and every
    effort that did arrive is applied unchanged at its own step."""
    rng = np.random.default_rng(5)
    n, steps = 7, 2000
    sent = rng.normal(size=(steps, n))
    lost = rng.random((steps, n)) < 0.05
    g = EffortGate(n, on_missing=mode)
    applied = np.zeros((steps, n))
    for k in range(steps):
        for j in rng.permutation(n):
            if not lost[k, j]:
                g.offer(j, k, sent[k, j])
        applied[k] = g.take_deadline()
    assert g.misses.tolist() == lost.sum(axis=0).tolist()
    assert [s[0] if s else None for s in g.miss_steps] == [
        int(np.flatnonzero(lost[:, j])[0]) if lost[:, j].any() else None for j in range(n)]
    assert g.ticks == steps and g.ticks_all_on_time == int((~lost.any(axis=1)).sum())
    assert np.array_equal(applied[~lost], sent[~lost])
    for k, j in zip(*np.nonzero(lost)):
        expected = (applied[k - 1, j] if k > 0 else 0.0) if mode == "hold" else 0.0
        assert applied[k, j] == expected, (k, j)
    assert g.timeouts.sum() == 0 and g.stale.sum() == 0


def test_deadline_on_time_fraction_per_bin():
    g = EffortGate(1)
    g.bin_steps = 2
    for k, arrives in enumerate([True, False, True, True, False]):
        if arrives:
            g.offer(0, k, 1.0)
        g.take_deadline()
    assert g.ticks_per_bin == [2, 2, 1] and g.on_time_per_bin == [1, 2, 0]


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
