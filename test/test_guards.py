"""Defensive controllers: the state guard, the EKF guard, checkpoints; no non-finite torque gets out."""
import math

import numpy as np
import pytest

from pa10_dnbs.core.controller_bank import FixedGainBank
from pa10_dnbs.controller_factory import build_controllers, build_reference
from pa10_dnbs.core.checkpoint import checkpoint_due, checkpoint_phase, load_checkpoint, save_checkpoint
from pa10_dnbs.core.reference import ReferenceSample
from pa10_dnbs.core.state_guard import OK, REASONS, StateGuard
from pa10_dnbs.loop.guarded_controllers import GuardedControllers

GUARD = StateGuard(lower_rad=np.array([-1.0]), upper_rad=np.array([1.0]), margin_rad=0.1,
                   max_speed_rad_s=np.array([5.0]))
REF = ReferenceSample(np.zeros(1), np.zeros(1), np.zeros(1))


class Constant(FixedGainBank):
    """A bank of one row answering ``u`` (and recording the rows it was asked to train)."""
    n_joints = 1

    def __init__(self, u):
        self.u, self.trained = u, []

    def answer(self, x1, x2, ref, active=None):
        assert np.all(np.isfinite(x1)) and np.all(np.isfinite(x2))  # never fed an untrusted state
        self.trained.append(1.0 if active is None else float(active[0]))
        return np.array([self.u])


@pytest.mark.parametrize("x1, x2, reason", [
    (0.5, 1.0, None), (1.09, -4.9, None), (math.nan, 0.0, "nonfinite"), (0.0, math.inf, "nonfinite"),
    (1.11, 0.0, "position"), (-1.2, 0.0, "position"), (0.0, 5.01, "speed"), (0.0, -6.0, "speed"),
    (math.nan, 50.0, "nonfinite"), (9.0, 50.0, "position")])
def test_state_guard(x1, x2, reason):
    code = GUARD.check(np.array([x1]), np.array([x2]))[0]
    assert (None if code == OK else REASONS[code]) == reason


@pytest.mark.parametrize("on_bad, expected", [("hold", 3.0), ("zero", 0.0)])
def test_bad_states_are_answered_safely_counted_and_not_trained_on(on_bad, expected):
    ctrl = Constant(3.0)
    g = GuardedControllers(ctrl, GUARD, on_bad)
    assert g.step(np.array([0.1]), np.zeros(1), REF)[0] == 3.0
    answers = [g.step(np.array([x1]), np.array([x2]), REF)[0]
               for x1, x2 in [(math.nan, 0.0), (math.inf, 0.0), (9.0, 0.0), (0.0, 50.0)]]
    assert answers == [expected] * 4
    assert {r: int(c[0]) for r, c in g.bad_states.items()} == {"nonfinite": 2, "position": 1, "speed": 1}
    assert ctrl.trained == [1.0, 0.0, 0.0, 0.0, 0.0]


def test_a_bad_joint_does_not_disturb_the_others(cfg):
    """In a bank of seven, joint 2's NaN state is held; the other six answer exactly as without it."""
    ref = build_reference(cfg)
    a = GuardedControllers(build_controllers(cfg, "dnbs"), _guard7(), "hold")
    b = GuardedControllers(build_controllers(cfg, "dnbs"), _guard7(), "hold")
    x1, x2 = np.full(7, 0.05), np.zeros(7)
    ub_held = None
    for k in range(50):
        ua = a.step(x1, x2, ref.sample(k))
        y1 = x1.copy()
        if k >= 20:
            y1[2] = math.nan
        ub = b.step(y1, x2, ref.sample(k))
        assert np.array_equal(np.delete(ua, 2), np.delete(ub, 2))
        if k >= 20:
            assert ub[2] == ub_held
        ub_held = ub[2]
    assert int(b.bad_states["nonfinite"][2]) == 30 and np.isfinite(b.controllers.torque_ekf.w).all()


def _guard7():
    return StateGuard(np.full(7, -3.0), np.full(7, 3.0), 0.1, np.full(7, 10.0))


def test_nonfinite_torque_from_the_controller_never_leaves():
    g = GuardedControllers(Constant(math.nan), GUARD, "hold")
    out = [g.step(np.array([0.1]), np.zeros(1), REF)[0] for _ in range(5)]
    assert out == [0.0] * 5 and int(g.nonfinite_torques[0]) == 5


def test_dnbs_controller_resets_a_broken_network_and_keeps_a_finite_torque(cfg):
    ctrl = build_controllers(cfg, "dnbs", [4])
    ref = build_reference(cfg)
    x1, x2 = np.array([0.1]), np.zeros(1)
    for k in range(50):
        ctrl.step(x1, x2, ref.sample(k, [4]))
    ctrl.torque_ekf.P[:] = math.inf
    # seen at the next update (H^T P H), or at the latest by the full check every 100 steps
    torques = [ctrl.step(x1, x2, ref.sample(k, [4]))[0] for k in range(50, 151)]
    assert {k: int(v[0]) for k, v in ctrl.ekf_resets.items()} == {"alpha": 0, "torque": 1}
    assert not ctrl.torque_ekf.unhealthy(full=True).any()
    assert all(math.isfinite(u) for u in torques[1:])  # the step that broke may not be (the guard holds then)


def test_checkpoint_resume_continues_exactly(cfg, tmp_path):
    """A controller restored from a checkpoint answers like the original would have."""
    ref = build_reference(cfg)
    a = build_controllers(cfg, "dnbs", [1])
    for k in range(300):
        a.step(np.array([0.1 + 1e-4 * k]), np.array([0.01]), ref.sample(k, [1]))
    save_checkpoint(tmp_path / "s2.npz", a.state_dict(0), 299)
    state, step = load_checkpoint(tmp_path / "s2.npz")
    b = build_controllers(cfg, "dnbs", [1])
    b.load_state_dict(0, state)
    assert step == 299 and b.steps == 300
    for k in range(300, 400):
        x1, x2 = np.array([0.13]), np.array([0.02])
        assert a.step(x1, x2, ref.sample(k, [1]))[0] == b.step(x1, x2, ref.sample(k, [1]))[0]
    with pytest.raises(ValueError, match="joint index 1, expected 2"):
        build_controllers(cfg, "dnbs", [2]).load_state_dict(0, state)
    (tmp_path / "junk.npz").write_bytes(b"not a checkpoint")
    with pytest.raises(ValueError, match=r"not a checkpoint \(.npz\)"):
        load_checkpoint(tmp_path / "junk.npz")


@pytest.mark.parametrize("content,why", [("npy", "a single array (.npy, np.save's output)"), ("text", "it starts with b'step: '"),
                                         ("empty", "an empty file")])
def test_a_file_that_is_no_zip_archive_is_not_a_checkpoint(tmp_path, content, why):
    """A .npy renamed .npz made np.load return an array (TypeError: no context manager); a text file got numpy's
    advice about allow_pickle. Both: one line naming the file."""
    f = tmp_path / "s1.npz"
    if content == "npy":
        with open(f, "wb") as out:
            np.save(out, np.zeros(3))
    else:
        f.write_text("step: 3\n" if content == "text" else "")
    with pytest.raises(ValueError) as e:
        load_checkpoint(f)
    assert str(e.value) == f"{f}: not a checkpoint (.npz): not a zip archive: {why}"


def test_periodic_checkpoints_of_the_joints_are_spread_over_the_period():
    """Seven controllers saving on one step put a few ms of CPU into one tick: each joint has its own phase."""
    phases = [checkpoint_phase(j, 7, 1000) for j in range(7)]
    assert phases == [0, 142, 285, 428, 571, 714, 857]
    due = [[k for k in range(1, 3001) if checkpoint_due(k, 1000, ph)] for ph in phases]
    assert due[0] == [1000, 2000, 3000] and due[3] == [428, 1428, 2428]
    assert all(len(d) == 3 for d in due) and len({k for d in due for k in d}) == 21  # never two on one step
    assert not checkpoint_due(0, 1000, 0) and checkpoint_due(7, 1, 0)  # step 0 is never a save; every step


def _factorises(P) -> bool:
    try:
        np.linalg.cholesky(P)
        return True
    except np.linalg.LinAlgError:
        return False


def _a_covariance_that_only_its_padding_condemns(ctrl, rng):
    """A nearly singular torque-network P (10 x 10) that factorises alone but not inside the controller's
    padded 12 x 12 row (LAPACK's sums run over other lengths there), loaded into ``ctrl``; None if this
    LAPACK build shows no such case."""
    state = ctrl.state_dict(0)
    L = state["torque_P"].shape[0]
    for _ in range(200):
        A = rng.normal(size=(L, L - 1)) * 10.0 ** rng.uniform(-3, 3, size=L - 1)
        B = A @ A.T
        B = (B + B.T) / 2  # exactly symmetric, rank L-1: the factorisation's verdict hangs on rounding
        lo, hi = -1e-6 * np.abs(B).max(), 1e-6 * np.abs(B).max()
        for _ in range(60):  # the shift at which the 10 x 10 block stops factorising
            mid = (lo + hi) / 2
            lo, hi = (lo, mid) if _factorises(B + mid * np.eye(L)) else (mid, hi)
        for shift in np.linspace(lo, hi, 41):
            P = B + shift * np.eye(L)
            ctrl.load_state_dict(0, {**state, "torque_P": P}, resume_steps=False)
            if _factorises(P) and not _factorises(ctrl.ekf.P[ctrl.torque_ekf.rows][0]):
                return P
    return None


def test_the_full_check_judges_each_networks_own_covariance_not_its_padded_row(cfg):
    """A padded bank must condemn exactly what a bank of that network alone would."""
    ctrl = build_controllers(cfg, "dnbs", [3])
    P = _a_covariance_that_only_its_padding_condemns(ctrl, np.random.default_rng(0))
    if P is None:
        pytest.skip("this LAPACK factorises the padded and the unpadded matrices alike")
    every = ctrl.params.ekf_full_check_every
    ctrl.steps = every - 1  # the next step ends with a full check
    ref = build_reference(cfg).sample(every - 1, [3])
    ctrl.step(np.array([0.1]), np.zeros(1), ref, active=np.zeros(1))  # not trained: P stays as loaded
    assert ctrl.torque_ekf.P[0].tobytes() == P.tobytes()
    assert {k: int(v[0]) for k, v in ctrl.ekf_resets.items()} == {"alpha": 0, "torque": 0}
    assert not ctrl.torque_ekf.unhealthy(full=True).any()
    assert ctrl.ekf.unhealthy(full=True)[ctrl.n_joints]  # the padded row as a whole does not factorise


def test_a_warm_start_from_another_arms_checkpoints_says_whose_they_are(cfg, tmp_path):
    """It said only "s1.npz: missing": the folder held another arm's joints (a run of the iiwa, a1..a7)."""
    from pa10_dnbs.core.checkpoint import load_joint_checkpoints

    a = build_controllers(cfg, "dnbs", [0])
    for name in ("a1", "a2"):
        save_checkpoint(tmp_path / f"{name}.npz", a.state_dict(0), 1)
    with pytest.raises(ValueError) as e:
        load_joint_checkpoints(tmp_path, ["s1", "s2"])
    assert str(e.value) == (f"{tmp_path / 's1.npz'}: missing (a warm start needs one checkpoint per joint: s1, s2); "
                            "the folder holds joints a1, a2: another arm's run?")
    save_checkpoint(tmp_path / "s1.npz", a.state_dict(0), 1)   # one of its own joints there: only the missing one
    with pytest.raises(ValueError) as e:
        load_joint_checkpoints(tmp_path, ["s1", "s2"])
    assert str(e.value).endswith("missing (a warm start needs one checkpoint per joint: s1, s2)")
