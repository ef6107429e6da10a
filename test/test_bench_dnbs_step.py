"""scripts/bench_dnbs_step.py: its timing wrappers change nothing the controller computes, and its parts add up."""
from __future__ import annotations

from pa10_dnbs.run_settings import build_settings
import numpy as np
from script_module import load_script


def test_timed_pass_trains_the_bank_as_a_plain_pass_and_its_parts_add_up():
    from pa10_dnbs.config import default_config_path
    from pa10_dnbs.controller_factory import build_guarded_controllers
    from pa10_dnbs.sim.closed_loop import simulate

    bench = load_script("bench_dnbs_step")
    cfg = build_settings(default_config_path())
    run = simulate(cfg, "dnbs", 0.3)
    rows = [0, 3, 6]
    parts, timed = bench._dnbs_pass(cfg, run, rows)
    plain = build_guarded_controllers(cfg, "dnbs", rows)
    refs = bench._references(cfg, run.n_steps, rows)
    for k in range(run.n_steps):
        plain.step(run.position_rad[k, rows], run.velocity_rad_s[k, rows], refs[k])
    assert timed.steps == plain.controllers.steps == run.n_steps
    assert np.array_equal(timed.ekf.w, plain.controllers.ekf.w)
    assert np.array_equal(timed.ekf.P, plain.controllers.ekf.P)
    assert all(v > 0.0 for v in parts.values())
    assert np.isclose(sum(v for k, v in parts.items() if k != "step"), parts["step"])
    compiled_parts, compiled = bench._dnbs_pass(cfg, run, rows, "c")  # the compiled step, timed: the same bank
    assert np.array_equal(compiled.ekf.w, plain.controllers.ekf.w)
    assert np.array_equal(compiled.ekf.P, plain.controllers.ekf.P)
    assert set(compiled_parts) == {"answer", "training", "step"}
    assert np.isclose(compiled_parts["answer"] + compiled_parts["training"], compiled_parts["step"])
