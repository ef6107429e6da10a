"""Defensive controller: the state guard, the EKF guard, checkpoints; no non-finite torque gets out."""
import math

import numpy as np
import pytest

from pa10_dnbs.controller_factory import build_controller, build_reference
from pa10_dnbs.core.checkpoint import load_checkpoint, save_checkpoint
from pa10_dnbs.core.ekf import EKFParams, EKFTrainer
from pa10_dnbs.core.state_guard import StateGuard
from pa10_dnbs.loop.joint_loop import JointLoop

GUARD = StateGuard(lower_rad=-1.0, upper_rad=1.0, margin_rad=0.1, max_speed_rad_s=5.0)


class Constant:
    def __init__(self, u):
        self.u, self.calls = u, 0

    def step(self, x1, x2, ref):
        self.calls += 1
        return self.u


@pytest.mark.parametrize("x1, x2, reason", [
    (0.5, 1.0, None), (1.09, -4.9, None), (math.nan, 0.0, "nonfinite"), (0.0, math.inf, "nonfinite"),
    (1.11, 0.0, "position"), (-1.2, 0.0, "position"), (0.0, 5.01, "speed"), (0.0, -6.0, "speed")])
def test_state_guard(x1, x2, reason):
    assert GUARD.check(x1, x2) == reason


@pytest.mark.parametrize("on_bad, expected", [("hold", 3.0), ("zero", 0.0)])
def test_bad_states_are_answered_safely_and_counted(on_bad, expected):
    ctrl = Constant(3.0)
    loop = JointLoop(ctrl, preview_steps=2, guard=GUARD, on_bad_state=on_bad)
    loop.add_reference(0, [0.0] * 20, [0.0] * 20)
    assert loop.on_state(0, 0.1, 0.0) == [(0, 3.0)]
    answers = [loop.on_state(k, x1, x2)[0][1] for k, (x1, x2) in
               enumerate([(math.nan, 0.0), (math.inf, 0.0), (9.0, 0.0), (0.0, 50.0)], start=1)]
    assert answers == [expected] * 4
    assert loop.bad_states == {"nonfinite": 2, "position": 1, "speed": 1}
    assert ctrl.calls == 1  # the controller never saw a bad state


def test_nonfinite_torque_from_the_controller_never_leaves():
    loop = JointLoop(Constant(math.nan), preview_steps=2, guard=GUARD, on_bad_state="hold")
    loop.add_reference(0, [0.0] * 20, [0.0] * 20)
    out = [loop.on_state(k, 0.1, 0.0)[0][1] for k in range(5)]
    assert out == [0.0] * 5 and loop.nonfinite_torques == 5


def _ekf():
    return EKFTrainer(np.full(6, 0.01), EKFParams(p0=1.0, q=0.01, r=1.0, eta=1.0))


def test_ekf_guard_detects_nonfinite_and_indefinite_P_and_resets():
    ekf = _ekf()
    H = np.linspace(0.1, 0.6, 6)
    for _ in range(10):
        ekf.update(H, 0.3)
    assert ekf.healthy(full=True)
    ekf.P[2, 4] = ekf.P[4, 2] = math.nan
    ekf.update(H, 0.3)
    assert not ekf.healthy(full=False)  # NaN reaches H^T P H and w at once
    ekf.reset()
    assert ekf.healthy(full=True) and np.array_equal(ekf.w, ekf.w0) and np.array_equal(ekf.P, np.eye(6))
    ekf.P[0, 0] = -5.0  # symmetric, finite, not positive definite: only the full check sees it
    assert not ekf.healthy(full=True)


def test_dnbs_controller_resets_a_broken_network_and_keeps_a_finite_torque(cfg):
    ctrl = build_controller(cfg, "dnbs", 4)
    ref = build_reference(cfg)
    for k in range(50):
        ctrl.step(0.1, 0.0, ref.sample(4, k))
    ctrl.torque_ekf.P[:] = math.inf
    # seen at the next update (H^T P H), or at the latest by the full check every 100 steps
    torques = [ctrl.step(0.1, 0.0, ref.sample(4, k)) for k in range(50, 151)]
    assert ctrl.ekf_resets == {"alpha": 0, "torque": 1}
    assert ctrl.torque_ekf.healthy(full=True)
    assert all(math.isfinite(u) for u in torques[1:])  # the step that broke may not be (JointLoop holds then)


def test_checkpoint_resume_continues_exactly(cfg, tmp_path):
    """A controller restored from a checkpoint answers like the original would have."""
    ref = build_reference(cfg)
    a = build_controller(cfg, "dnbs", 1)
    for k in range(300):
        a.step(0.1 + 1e-4 * k, 0.01, ref.sample(1, k))
    save_checkpoint(tmp_path / "s2.npz", a.state_dict(), 299)
    state, step = load_checkpoint(tmp_path / "s2.npz")
    b = build_controller(cfg, "dnbs", 1)
    b.load_state_dict(state)
    assert step == 299 and b.steps == 300
    for k in range(300, 400):
        assert a.step(0.13, 0.02, ref.sample(1, k)) == b.step(0.13, 0.02, ref.sample(1, k))
    (tmp_path / "junk.npz").write_bytes(b"not a checkpoint")
    with pytest.raises(ValueError, match="not a readable checkpoint"):
        load_checkpoint(tmp_path / "junk.npz")
