"""PID baseline: the law and the gains of paper_notes.md."""
import pytest

from pa10_dnbs.controller_factory import build_controller
from pa10_dnbs.core.reference import ReferenceSample


def test_gains_are_the_reference_ones(cfg):
    kp = [2000, 2000, 800, 800, 60, 60, 60]
    kd = [200, 200, 60, 60, 3, 3, 3]
    for j in range(7):
        p = build_controller(cfg, "pid", j).params
        assert (p.kp, p.kd, p.ki) == (kp[j], kd[j], 5 * kp[j])


def test_law_and_saturation(cfg):
    pid = build_controller(cfg, "pid", 4)  # kp 60, ki 300, kd 3, limit 14.5
    u = pid.step(0.0, 0.2, ReferenceSample(0.1, 0.5, 0.1))
    assert u == pytest.approx(60 * 0.1 + 300 * 0.1 * 1e-3 + 3 * (0.5 - 0.2))
    assert pid.step(0.0, 0.0, ReferenceSample(10.0, 0.0, 10.0)) == 14.5
