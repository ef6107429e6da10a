"""PID baseline: the law and the gains of the reference baseline (docs/design.md)."""
import numpy as np
import pytest

from pa10_dnbs.controller_factory import build_controllers
from pa10_dnbs.core.reference import ReferenceSample
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.settings import replace_in


def _ref(x, v):
    return ReferenceSample(np.array([x]), np.array([v]), np.array([x]))


def test_gains_are_the_shipped_ones(cfg):
    """The PA10's PID as tuned with the equal budget (urdf/pa10/arm.yaml, docs/tuning.md)."""
    p = build_controllers(cfg, "pid").params
    assert p.kp.tolist() == [25500, 25500, 10200, 10200, 766, 766, 766]
    assert p.kd.tolist() == [327, 327, 98.1, 98.1, 4.91, 4.91, 4.91]
    assert p.ki.tolist() == [283000, 283000, 113000, 113000, 8490, 8490, 8490]


def test_the_rule_of_thumb_gains_stay_available(cfg):
    from pa10_dnbs.paths import share_path

    p = build_controllers(build_settings(share_path("config", "pa10_pid_rule_of_thumb.yaml")), "pid").params
    assert p.kp.tolist() == [2000, 2000, 800, 800, 60, 60, 60]
    assert p.kd.tolist() == [200, 200, 60, 60, 3, 3, 3]
    assert p.ki.tolist() == (5 * p.kp).tolist()


def test_law_and_saturation(cfg):
    pid = build_controllers(cfg, "pid", [4])  # kp 766, ki 8490, kd 4.91, limit 14.5
    u = pid.step(np.array([0.0]), np.array([0.2]), _ref(0.01, 0.5))
    assert u[0] == pytest.approx(766 * 0.01 + 8490 * 0.01 * 1e-3 + 4.91 * (0.5 - 0.2))
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
    cfg = replace_in(cfg, "pid.anti_windup", False)
    plain = build_controllers(cfg, "pid", [4, 5])
    for _ in range(500):
        assert np.array_equal(guarded.step(np.zeros(2), np.zeros(2), ref), plain.step(np.zeros(2), np.zeros(2), ref))
    assert guarded.integral[0] == 0.0 and plain.integral[0] == pytest.approx(10.0 * 0.5)
    assert guarded.integral[1] == plain.integral[1] == pytest.approx(0.001 * 0.5)
    back = ReferenceSample(np.array([-0.05, 0.0]), np.zeros(2), np.array([-0.05, 0.0]))
    assert guarded.step(np.zeros(2), np.zeros(2), back)[0] < 0.0   # answers the reversed error at once
    assert plain.step(np.zeros(2), np.zeros(2), back)[0] == 14.5     # still wound up at the limit
