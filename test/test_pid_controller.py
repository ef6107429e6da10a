"""PID baseline: the law and the gains of the reference baseline (docs/design.md)."""
import numpy as np
import pytest

from pa10_dnbs.controller_factory import build_controllers
from pa10_dnbs.core.reference import ReferenceSample


def _ref(x, v):
    return ReferenceSample(np.array([x]), np.array([v]), np.array([x]))


def test_gains_are_the_shipped_ones(cfg):
    """The PA10's PID as tuned with the equal budget (urdf/pa10/arm.yaml, docs/tuning.md)."""
    p = build_controllers(cfg, "pid").params
    assert p.kp.tolist() == [18600, 18600, 7430, 7430, 557, 557, 557]
    assert p.kd.tolist() == [331, 331, 99.4, 99.4, 4.97, 4.97, 4.97]
    assert p.ki.tolist() == [116000, 116000, 46200, 46200, 3470, 3470, 3470]


def test_the_rule_of_thumb_gains_stay_available(cfg):
    from pa10_dnbs.config import load_config
    from pa10_dnbs.paths import share_path

    p = build_controllers(load_config(share_path("config", "pa10_pid_rule_of_thumb.yaml")), "pid").params
    assert p.kp.tolist() == [2000, 2000, 800, 800, 60, 60, 60]
    assert p.kd.tolist() == [200, 200, 60, 60, 3, 3, 3]
    assert p.ki.tolist() == (5 * p.kp).tolist()


def test_law_and_saturation(cfg):
    pid = build_controllers(cfg, "pid", [4])  # kp 557, ki 3470, kd 4.97, limit 14.5
    u = pid.step(np.array([0.0]), np.array([0.2]), _ref(0.01, 0.5))
    assert u[0] == pytest.approx(557 * 0.01 + 3470 * 0.01 * 1e-3 + 4.97 * (0.5 - 0.2))
    assert pid.step(np.zeros(1), np.zeros(1), _ref(10.0, 0.0))[0] == 14.5


def test_an_inactive_row_does_not_integrate(cfg):
    pid = build_controllers(cfg, "pid", [4, 5])
    pid.step(np.zeros(2), np.zeros(2), ReferenceSample(np.full(2, 0.01), np.zeros(2), np.full(2, 0.01)),
             active=np.array([1.0, 0.0]))
    assert pid.integral[0] == pytest.approx(0.01e-3) and pid.integral[1] == 0.0


def test_anti_windup_holds_the_integral_of_a_saturated_row_only(cfg):
    """Conditional integration: a row pushed into its limit keeps its integral; the other row integrates as the
    plain PID does, and after the error reverses the wound-up PID stays saturated far longer."""
    ref = ReferenceSample(np.array([10.0, 0.001]), np.zeros(2), np.array([10.0, 0.001]))
    guarded = build_controllers(cfg, "pid", [4, 5])
    cfg["pid"]["anti_windup"] = False
    plain = build_controllers(cfg, "pid", [4, 5])
    for _ in range(500):
        assert np.array_equal(guarded.step(np.zeros(2), np.zeros(2), ref), plain.step(np.zeros(2), np.zeros(2), ref))
    assert guarded.integral[0] == 0.0 and plain.integral[0] == pytest.approx(10.0 * 0.5)
    assert guarded.integral[1] == plain.integral[1] == pytest.approx(0.001 * 0.5)
    back = ReferenceSample(np.array([-0.05, 0.0]), np.zeros(2), np.array([-0.05, 0.0]))
    assert guarded.step(np.zeros(2), np.zeros(2), back)[0] < 0.0   # answers the reversed error at once
    assert plain.step(np.zeros(2), np.zeros(2), back)[0] == 14.5     # still wound up at the limit
