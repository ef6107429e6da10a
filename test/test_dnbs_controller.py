"""DNBS controllers (eq. 23-26): the e2 sign, decentralization bit for bit, saturation, seeds, each remedy.

The sign test runs the paper's law (config/paper.yaml) on a single joint modelled as an inertia with
viscous friction and a gravity-like load (numpy only), tracking joint 1's reference; the paper's printed
e2 = x2 - alpha must diverge, ours converge.
"""
import copy

import numpy as np
import pytest
from pa10_dnbs.controller_factory import build_controllers, build_reference
from pa10_dnbs.core.reference import ReferenceSample
from pa10_dnbs.paths import share_path
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.settings import replace_in

J, FV, G, DT = 1.5, 10.0, 20.0, 1e-3  # kg m^2, N m s/rad, N m, s


@pytest.fixture(scope="module")
def paper_cfg():
    return build_settings(share_path("config", "paper.yaml"))


def _single_joint_run(cfg, e2_sign: str, seconds: float = 6.0):
    cfg = copy.deepcopy(cfg)
    cfg = replace_in(cfg, "dnbs.e2_sign", e2_sign)
    ctrl = build_controllers(cfg, "dnbs", [0])
    ref = build_reference(cfg)
    q, qd = 0.1, 0.0
    n = int(seconds / DT)
    err = np.empty(n)
    for k in range(n):
        u = ctrl.step(np.array([q]), np.array([qd]), ref.sample(k, [0]))[0]
        qd += DT * (u - FV * qd - G * np.sin(q)) / J
        q += DT * qd
        err[k] = ref.position(k)[0] - q
    return err


def test_printed_e2_sign_diverges_and_stable_sign_converges(paper_cfg):
    stable = _single_joint_run(paper_cfg, "stable")
    printed = _single_joint_run(paper_cfg, "printed")
    late = slice(4000, 6000)
    # Stable sign: the initial 0.1 rad error shrinks by more than 10x and stays small.
    assert np.max(np.abs(stable[late])) < 0.01
    # Printed sign: the error grows well beyond the initial offset.
    assert np.max(np.abs(printed[late])) > 0.3


def _states(n_steps: int, ref, rng):
    """Plausible joint states near the reference, (x1, x2) of shape (n_steps, 7) each."""
    k = np.arange(n_steps)
    x1 = ref.position(k) + 0.05 * np.sin(0.01 * k)[:, None] + 1e-3 * rng.normal(size=(n_steps, 7))
    x2 = ref.velocity(k) + 0.1 * rng.normal(size=(n_steps, 7))
    return x1, x2


@pytest.mark.parametrize("kind", ["dnbs", "pid"])
def test_a_bank_of_seven_equals_seven_banks_of_one_bit_for_bit(cfg, kind):
    """The in-process loop runs one bank of seven rows, each node a bank of its one joint: same bits."""
    ref = build_reference(cfg)
    x1, x2 = _states(1000, ref, np.random.default_rng(1))
    bank = build_controllers(cfg, kind)
    alone = [build_controllers(cfg, kind, [j]) for j in range(7)]
    for k in range(1000):
        u = bank.step(x1[k], x2[k], ref.sample(k))
        for j, c in enumerate(alone):
            assert c.step(x1[k, j:j + 1], x2[k, j:j + 1], ref.sample(k, [j]))[0] == u[j], (k, j)
    if kind == "dnbs":
        for j, c in enumerate(alone):
            assert np.array_equal(c.torque_ekf.P[0], bank.torque_ekf.P[j])
            assert np.array_equal(c.alpha_ekf.w[0], bank.alpha_ekf.w[j])


def test_a_row_sees_only_its_own_joint(cfg):
    """Changing joint 3's state changes joint 3's torque and nothing else."""
    ref = build_reference(cfg)
    a, b = build_controllers(cfg, "dnbs"), build_controllers(cfg, "dnbs")
    x1, x2 = _states(200, ref, np.random.default_rng(2))
    for k in range(200):
        y1 = x1[k].copy()
        y1[3] += 0.01
        a.step(x1[k], x2[k], ref.sample(k))
        b.step(y1, x2[k], ref.sample(k))
        ua, ub = a.torque_unsaturated, b.torque_unsaturated
        assert np.array_equal(np.delete(ua, 3), np.delete(ub, 3)) and ua[3] != ub[3]


def test_torque_is_saturated_at_table2(cfg):
    ctrl = build_controllers(cfg, "dnbs", [4])  # 14.5 N m joint
    ctrl.torque_ekf.w[:] = 1e3  # force a huge unsaturated output
    u = ctrl.step(np.array([0.5]), np.array([0.5]), build_reference(cfg).sample(10, [4]))
    assert abs(ctrl.torque_unsaturated[0]) > 14.5
    assert u[0] == pytest.approx(14.5 * np.sign(ctrl.torque_unsaturated[0]))


def test_same_seed_same_weights_different_joint_different_weights(cfg):
    a, b, c = (build_controllers(cfg, "dnbs", [j]) for j in (1, 1, 2))
    np.testing.assert_array_equal(a.alpha_ekf.w, b.alpha_ekf.w)
    assert not np.array_equal(a.torque_ekf.w, c.torque_ekf.w)
    assert np.array_equal(build_controllers(cfg, "dnbs").alpha_ekf.w[1], a.alpha_ekf.w[0])


def _edit(cfg, **remedies):
    for name, settings in remedies.items():
        for key, value in settings.items():
            cfg = replace_in(cfg, f"dnbs.remedies.{name}.{key}", value)
    return cfg


def _one_step(cfg, joint=1, x1=0.1, x2=0.0, k=0):
    ctrl = build_controllers(cfg, "dnbs", [joint])
    u = ctrl.step(np.array([x1]), np.array([x2]), build_reference(cfg).sample(k, [joint]))
    return ctrl, u[0]


def test_paper_law_has_no_linear_term(paper_cfg):
    ctrl = build_controllers(paper_cfg, "dnbs", [2])
    w1, w2 = ctrl.alpha_ekf.w.copy(), ctrl.torque_ekf.w.copy()
    ref = ReferenceSample(np.array([0.3]), np.array([2.0]), np.array([0.31]))
    u = ctrl.step(np.array([0.1]), np.array([0.5]), ref)
    S1 = ctrl.alpha_honn.regressor(np.array([[0.1, 0.31]]))
    assert ctrl.alpha[0] == pytest.approx(float(w1[0] @ S1[0]) * 1.0, rel=1e-12)  # A = 1 rad/s, no k_a e1
    S2 = ctrl.torque_honn.regressor(np.array([[0.1, 0.5, ctrl.alpha[0]]]))
    assert u[0] == pytest.approx(100.0 * float(w2[0] @ S2[0]), rel=1e-12)  # U = 100 N m, no k_u e2


def test_robust_term_is_lewis_kv_r(cfg):
    """With zero weights the torque is k_u (x_d_dot + k_a e1 - x2): Kv r of Lewis et al., r = e_dot + k_a e."""
    cfg = copy.deepcopy(cfg)
    cfg = replace_in(cfg, "dnbs.alpha_net.init_weight_std", (0.0,) * 7)
    cfg = replace_in(cfg, "dnbs.torque_net.init_weight_std", (0.0,) * 7)
    ctrl = build_controllers(cfg, "dnbs", [1])
    ref = ReferenceSample(np.array([0.12]), np.array([0.5]), np.array([0.121]))
    u = ctrl.step(np.array([0.1]), np.array([0.3]), ref)
    assert u[0] == pytest.approx(400.0 * (0.5 + 10.0 * 0.02 - 0.3))


def test_learning_ramp_starts_at_zero(cfg):
    ctrl = build_controllers(cfg, "dnbs", [1])
    w = ctrl.torque_ekf.w.copy()
    ctrl.step(np.array([0.01]), np.array([0.0]), build_reference(cfg).sample(0, [1]))  # not saturated
    assert np.array_equal(ctrl.torque_ekf.w, w)  # eta is 0 at step 0
    ctrl.step(np.array([0.01]), np.array([0.0]), build_reference(cfg).sample(1, [1]))
    assert not np.array_equal(ctrl.torque_ekf.w, w)


def test_dead_zone_ignores_errors_inside_the_band(cfg):
    cfg = _edit(cfg, dead_zone={"enabled": True, "alpha_rad": (0.2,) * 7, "torque_rad_s": (50.0,) * 7},
                learning_ramp={"enabled": False})
    ctrl = build_controllers(cfg, "dnbs", [1])
    w1, w2 = ctrl.alpha_ekf.w.copy(), ctrl.torque_ekf.w.copy()
    ctrl.step(np.array([0.1]), np.array([0.0]), build_reference(cfg).sample(0, [1]))  # |e1| = 0.1 < 0.2
    assert np.array_equal(ctrl.alpha_ekf.w, w1) and np.array_equal(ctrl.torque_ekf.w, w2)


def test_anti_windup_skips_the_update_that_pushes_a_clipped_torque_further(cfg):
    cfg = _edit(cfg, learning_ramp={"enabled": False})
    ctrl = build_controllers(cfg, "dnbs", [4])
    ctrl.torque_ekf.w[:] = 0.0
    ctrl.torque_ekf.w[0, 0] = 10.0  # u = 14.5 N m x 10 on the bias: clipped at +14.5
    w = ctrl.torque_ekf.w.copy()
    # x2 < alpha: e2 > 0 would raise u further: skipped
    ctrl.step(np.array([0.0]), np.array([-0.5]), ReferenceSample(np.zeros(1), np.zeros(1), np.zeros(1)))
    assert np.array_equal(ctrl.torque_ekf.w, w)
    off = build_controllers(_edit(cfg, anti_windup={"enabled": False}), "dnbs", [4])
    off.torque_ekf.w[:] = w
    off.step(np.array([0.0]), np.array([-0.5]), ReferenceSample(np.zeros(1), np.zeros(1), np.zeros(1)))
    assert not np.array_equal(off.torque_ekf.w, w)


@pytest.mark.parametrize("remedy", ["projection", "e_modification"])
def test_weight_bounding_remedies(cfg, remedy):
    settings = {"projection": {"enabled": True, "weight_bound": 0.05},
                "e_modification": {"enabled": True, "sigma": 0.5}}[remedy]
    base = dict(learning_ramp={"enabled": False}, anti_windup={"enabled": False})
    on = build_controllers(_edit(cfg, **{remedy: settings}, **base), "dnbs", [1])
    off = build_controllers(_edit(cfg, **base), "dnbs", [1])
    ref = build_reference(cfg)
    for k in range(300):  # a large constant error drives the weights up
        for c in (on, off):
            c.step(np.array([0.5]), np.array([0.0]), ref.sample(k, [1]))
    w_on, w_off = np.abs(on.torque_ekf.w).max(), np.abs(off.torque_ekf.w).max()
    assert w_on < w_off
    if remedy == "projection":
        assert w_on <= 0.05 and np.abs(on.alpha_ekf.w).max() <= 0.05


def test_network_settings_given_as_one_number_mean_that_number_for_every_joint(cfg):
    import dataclasses

    from pa10_dnbs.core.dnbs_controller import DNBSControllers

    params = build_controllers(cfg, "dnbs", [1, 2]).params
    keys = ("init_weight_std", "p0", "q", "r", "eta")

    def with_(make):
        nets = {name: dataclasses.replace(getattr(params, name), **{k: make(getattr(params, name), k) for k in keys})
                for name in ("alpha_net", "torque_net")}
        return DNBSControllers(dataclasses.replace(params, **nets), seed=3, joints=[1, 2])

    scalar = with_(lambda net, k: float(getattr(net, k)[0]))
    arrays = with_(lambda net, k: np.full(2, getattr(net, k)[0]))
    ref = build_reference(cfg)
    for k in range(20):
        x1, x2 = np.array([0.1, -0.2]), np.array([0.01, 0.0])
        assert scalar.step(x1, x2, ref.sample(k, [1, 2])).tobytes() == arrays.step(x1, x2, ref.sample(k, [1, 2])).tobytes()
    assert scalar.ekf.w.tobytes() == arrays.ekf.w.tobytes() and scalar.ekf.P.tobytes() == arrays.ekf.P.tobytes()


def test_clip_gives_the_bits_of_np_clip_signed_zeros_and_nan_included():
    # the dead zone and the projection use the two-call clip; a numpy whose maximum/minimum treat +-0 or NaN
    # differently from np.clip would change results, and this test would say so
    from pa10_dnbs.core.dnbs_controller import clip
    values = np.array([0.0, -0.0, 1e-3, -1e-3, 5e-4, -5e-4, np.nan, np.inf, -np.inf, 2.0, -2.0])
    for n in (1, 2, 7, 14, 20):
        for band in (0.0, -0.0, 5e-4, 1.0):
            x = np.resize(values, n * len(values))
            hi = np.full(x.size, band)
            lo = -hi
            want = np.clip(x, lo, hi)
            assert clip(x, lo, hi).tobytes() == want.tobytes()
            out = x.copy()
            clip(out, lo, hi, out=out)
            assert out.tobytes() == want.tobytes()
