"""The gain rule for arms without rotor inertia (issue 35) and the DNBS slope bound (bounded weights).

A joint whose inertia varies 100x along the run (an arm without rotor inertia) under one DNBS controller:
without the slope bound its networks' weights run away and the error passes 1 rad (the study's "diverged");
with it every weight stays in its box and the error stays below half of that. The rule: presets-like ranges
are left as before, wider ranges get a slower cascade and a warning naming the discrete-time limit.
"""
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from pa10_dnbs.arm.gain_rule import (E1_BASE, RATIO_SAFE, SEPARATION, InertiaSweep, discrete_limit_rad_s,
                                     gain_rule, rotor_inertia_for_ratio, rule_warnings)
from pa10_dnbs.config import ConfigError, default_config_path
from pa10_dnbs.core.dnbs_controller import DNBSControllers, DNBSParams, NetworkParams, Remedies
from pa10_dnbs.core.reference import Reference
from pa10_dnbs.run_settings import build_settings

T = 1e-3


def _one_joint(slope_bound: bool, j_light=1e-3, ratio=100.0, limit=100.0, duration_s=20.0):
    """Max |e1| [rad] and the largest |w| of each network after a run of one joint, J(t) = J_light (1 + (ratio -
    1) (1 + sin(2 pi t / 2 s)) / 2), the rule's k_u and k_a, E1 = 0.5 (not slowed), U = the torque limit."""
    k_u = 0.4 * j_light / T
    k_a = min(20.0, k_u / (SEPARATION * j_light * ratio))
    one = lambda v: np.array([float(v)])  # noqa: E731
    alpha_net = NetworkParams(2, (3.0, 3.0), one(1.0), one(0.5), one(0.01), one(1.0), one(0.01), one(1.0), one(1.0))
    torque_net = NetworkParams(2, (3.0, 3.0, 3.0), one(limit), one(limit / k_u), one(1e-4), one(1.0), one(0.01),
                               one(1.0), one(1.0))
    rem = Remedies(robust_term=True, velocity_feedforward=True, alpha_gain_per_s=one(k_a),
                   torque_gain_nms_per_rad=one(k_u), anti_windup=True, learning_ramp=True, learning_ramp_s=1.0,
                   covariance_bound=True, p_max=10.0, slope_bound=slope_bound, slope_fraction=one(0.5))
    bank = DNBSControllers(DNBSParams(alpha_net, torque_net, one(limit), T, rem), seed=0, joints=[0])
    ref = Reference([1.0], [0.01], [0.6], dt_s=T)
    x1, x2, worst = one(0.1), one(0.0), 0.0
    for k in range(int(round(duration_s / T))):
        j = j_light * (1.0 + (ratio - 1.0) * 0.5 * (1.0 + np.sin(2.0 * np.pi * k * T / 2.0)))
        sample = ref.sample(k)
        u = bank.step(x1, x2, sample)
        x2 = x2 + T * u / j
        x1 = x1 + T * x2
        worst = max(worst, abs(float(sample.position_rad[0] - x1[0])))
        if not worst < 10.0:
            break
    return worst, float(np.abs(bank.torque_ekf.w).max()), float(np.abs(bank.alpha_ekf.w).max()), bank


def test_without_the_slope_bound_the_loop_diverges_and_with_it_it_does_not():
    worst_off, _, alpha_off, _ = _one_joint(slope_bound=False)
    worst_on, torque_on, alpha_on, bank = _one_joint(slope_bound=True)
    assert worst_off > 1.0 and alpha_off > 20.0       # diverged (the study's 1 rad), weights running away
    assert worst_on < 0.5 and alpha_on < 1.0           # bounded
    assert np.all(np.abs(bank.ekf.w) <= bank._bounds)  # every weight in its box


def test_an_inactive_slope_bound_changes_no_bit():
    """Bounds the weights never reach: the same bits as no bound at all (how the iiwa and Panda keep theirs)."""
    a = _one_joint(slope_bound=False, ratio=2.0, duration_s=2.0)[3]
    rem = a.params.remedies
    b_params = DNBSParams(a.params.alpha_net, a.params.torque_net, a.params.torque_limit_nm, T,
                          Remedies(**{**rem.__dict__, "slope_bound": True, "slope_fraction": np.array([0.5])}))
    b = DNBSControllers(b_params, seed=0, joints=[0])
    assert b._bounds is not None and a._bounds is None
    ref = Reference([1.0], [0.01], [0.6], dt_s=T)
    a = DNBSControllers(a.params, seed=0, joints=[0])
    x1, x2 = np.array([0.1]), np.array([0.0])
    for k in range(1500):
        s = ref.sample(k)
        ua, ub = a.step(x1, x2, s), b.step(x1, x2, s)
        assert np.array_equal(ua, ub) and np.array_equal(a.ekf.w, b.ekf.w), k
        x2, x1 = x2 + T * ua / 2e-3, x1 + T * (x2 + T * ua / 2e-3)


def _sweep(light, heavy):
    light, heavy = np.asarray(light, float), np.asarray(heavy, float)
    return InertiaSweep(light, heavy, np.zeros((1, light.size)), (np.diag(1.0 / light),))


def _arm(n):
    return SimpleNamespace(name="toy", n_joints=n, joint_names=[f"j{i}" for i in range(n)],
                           torque_limit_nm=np.full(n, 10.0), viscous_nms_per_rad=np.zeros(n))


def test_the_rule_leaves_ranges_within_10x_as_they_were():
    frag = gain_rule(_arm(2), _sweep([0.2, 1.0], [0.8, 1.5]), T)
    rt = frag["dnbs"]["remedies"]["robust_term"]
    k_u = np.array([0.4 * 0.2 / T, 0.4 * 1.0 / T])
    assert rt["torque_gain_nms_per_rad"] == pytest.approx(k_u)
    assert rt["alpha_gain_per_s"] == pytest.approx(np.clip(k_u / (8 * np.array([0.8, 1.5])), 5, 20))
    assert frag["dnbs"]["alpha_net"]["error_scale_rad"] == [E1_BASE, E1_BASE]
    assert frag["dnbs"]["remedies"]["slope_bound"]["enabled"] is False  # the presets run without it
    assert frag["dnbs"]["torque_net"]["error_scale_rad_s"] == pytest.approx(10.0 / k_u)


def test_a_wide_range_gets_a_slower_cascade_and_a_warning_with_its_discrete_time_limit():
    light, heavy = np.array([2e-4, 1e-3]), np.array([2.4e-2, 2e-3])  # 120x and 2x
    frag = gain_rule(_arm(2), _sweep(light, heavy), T)
    k_u = 0.4 * light / T
    k_a = frag["dnbs"]["remedies"]["robust_term"]["alpha_gain_per_s"]
    assert k_a[0] == pytest.approx(k_u[0] / (8 * heavy[0])) and k_a[0] < 5.0  # not raised to invert the cascade
    slow = 120.0 / RATIO_SAFE
    assert frag["dnbs"]["alpha_net"]["error_scale_rad"] == pytest.approx([E1_BASE * slow ** 3] * 2)
    assert frag["dnbs"]["torque_net"]["error_scale_rad_s"] == pytest.approx(10.0 / k_u)
    assert frag["dnbs"]["remedies"]["slope_bound"]["enabled"] is True
    lines = rule_warnings(_arm(2), _sweep(light, heavy), k_u, T)
    assert len(lines) == 1 and "joint j0" in lines[0]
    assert f"{float(discrete_limit_rad_s(light[0], heavy[0], T)):.3g} rad/s" in lines[0]
    assert float(rotor_inertia_for_ratio(light[0], heavy[0])) == pytest.approx((2.4e-2 - 10 * 2e-4) / 9)
    # that rotor inertia does bring the range to 10x
    j_r = float(rotor_inertia_for_ratio(light[0], heavy[0]))
    assert (heavy[0] + j_r) / (light[0] + j_r) == pytest.approx(10.0)


XARM7 = Path(__file__).parent / "fixtures" / "urdf_intake" / "xarm7_no_meshes.urdf"   # the rule turns the bound on


def _config(tmp_path, remedies: str) -> Path:
    path = tmp_path / "remedies.yaml"
    path.write_text(f"extends: {default_config_path()}\ndnbs:\n  remedies:\n{remedies}")
    return path


def test_the_robust_term_off_leaves_the_rules_slope_bound_off(tmp_path):
    """Its bounds are fractions of the robust term's gains, 0 with it off: the bare xArm7 with the robust term off
    (the paper's law) had every weight held at 0 (alpha_w all 0, a constant torque, 6.4 rad off, exit 0)."""
    assert build_settings(default_config_path(), XARM7, report=False).dnbs.remedies.slope_bound.enabled
    off = build_settings(_config(tmp_path, "    robust_term: {enabled: false}\n"), XARM7, report=False)
    assert not off.dnbs.remedies.robust_term.enabled and not off.dnbs.remedies.slope_bound.enabled


def test_the_slope_bound_without_the_robust_term_is_refused_in_one_line(tmp_path):
    cfg = _config(tmp_path, "    robust_term: {enabled: false}\n    slope_bound: {enabled: true}\n")
    with pytest.raises(ConfigError, match=r"^dnbs\.remedies\.slope_bound\.enabled: true needs "
                                          r"dnbs\.remedies\.robust_term\.enabled: .* held at 0"):
        build_settings(cfg, XARM7, report=False)
