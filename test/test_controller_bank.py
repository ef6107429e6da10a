"""One interface for a bank of joint controllers (pa10_dnbs/core/controller_bank.py): every bank a run can
step meets it, and the callers use it as it is, without probing for what a bank has."""
import ast
from pathlib import Path

import numpy as np
import pytest

from pa10_dnbs.controller_factory import build_controllers
from pa10_dnbs.core.controller_bank import ControllerBank
from pa10_dnbs.core.reference import ReferenceSample
from pa10_dnbs.plant.engines import open_plant
from pa10_dnbs.settings import replace_in
from pa10_dnbs.sim.computed_torque import ComputedTorqueController

PACKAGE = Path(__file__).resolve().parents[1] / "pa10_dnbs"


@pytest.mark.parametrize("kind, kernel", [("dnbs", "numpy"), ("dnbs", "c"), ("pid", "numpy")])
def test_every_bank_of_the_factory_is_a_controller_bank(cfg, kind, kernel):
    bank = build_controllers(replace_in(cfg, "dnbs.kernel", kernel), kind, [2])
    assert isinstance(bank, ControllerBank) and bank.n_joints == 1
    ref = ReferenceSample(np.array([0.1]), np.array([0.0]), np.array([0.1]))
    u = bank.answer(np.array([0.0]), np.array([0.0]), ref)
    assert bank.learning_pending == bank.learns  # a learning bank waits for learn(); a fixed one never does
    bank.learn()
    assert not bank.learning_pending and np.isfinite(u).all()
    assert bool(bank.state_dict(0)) == bank.learns
    assert set(bank.counters(0)) == ({"ekf_resets_alpha", "ekf_resets_torque"} if bank.learns else set())


def test_computed_torque_is_a_bank_that_does_not_learn(cfg):
    plant, close = open_plant(cfg)
    try:
        ctc = ComputedTorqueController(plant, cfg.ctc.kp_per_s2, cfg.ctc.kd_per_s, cfg.plant.torque_limit_nm)
        assert isinstance(ctc, ControllerBank) and not ctc.learns and ctc.state_dict(0) == {}
    finally:
        close()


def test_pid_answer_then_learn_is_step_bit_for_bit(cfg):
    a, b = build_controllers(cfg, "pid"), build_controllers(cfg, "pid")
    rng = np.random.default_rng(5)
    for _ in range(50):
        x1, x2 = rng.normal(0, 0.3, 7), rng.normal(0, 1, 7)
        ref = ReferenceSample(rng.normal(0, 0.3, 7), rng.normal(0, 1, 7), rng.normal(0, 0.3, 7))
        u = a.answer(x1, x2, ref)
        a.learn()
        assert np.array_equal(u, b.step(x1, x2, ref)) and np.array_equal(a.integral, b.integral)


def test_callers_do_not_probe_a_bank_for_what_it_has():
    """loop/, ros/, sim/, study/ and tune/ call the interface; no getattr or hasattr on a controller."""
    probes = []
    for folder in ("loop", "ros", "sim", "study", "tune"):
        for path in (PACKAGE / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                        and node.func.id in ("getattr", "hasattr") and node.args
                        and "controller" in ast.unparse(node.args[0])):
                    probes.append(f"{path.relative_to(PACKAGE)}:{node.lineno}")
    assert not probes, probes
