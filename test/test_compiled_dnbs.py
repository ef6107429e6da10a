"""``dnbs.kernel: c``: the compiled DNBS step gives the numpy reference's bits, in every branch of the law.

Each test runs the same inputs through a ``DNBSControllers`` bank and a ``CompiledDNBSControllers`` bank
and asserts equal bits (torques, alpha, weights, covariances, counters), not closeness: the kernel is an
implementation of the reference, not an approximation of it.
"""
import os
import subprocess
import sys

import numpy as np
import pytest

from pa10_dnbs.accel import compiled_dnbs
from pa10_dnbs.accel.build import KernelBuildError
from pa10_dnbs.accel.choice import auto_kernel, resolve_kernel
from pa10_dnbs.accel.compiled_dnbs import CompiledDNBSControllers
from pa10_dnbs.config import default_config_path
from pa10_dnbs.controller_factory import build_controllers, build_guarded_controllers, build_reference
from pa10_dnbs.core.dnbs_controller import DNBSControllers
from pa10_dnbs.run_data import RunData
from pa10_dnbs.settings import replace_in
from pa10_dnbs.sim.closed_loop import simulate


def _kernels(cfg):
    """(settings on the numpy reference, on the compiled kernel): explicit both, as the default is auto."""
    return replace_in(cfg, "dnbs.kernel", "numpy"), replace_in(cfg, "dnbs.kernel", "c")


def _every_remedy(cfg):
    """Every remedy on, eta < 1, a wider torque network (max degree 3: L = 20, another padded width)."""
    for key, value in (("remedies.dead_zone.enabled", True), ("remedies.e_modification.enabled", True),
                       ("remedies.projection.enabled", True), ("remedies.dead_zone.alpha_rad", (1e-3,) * 7),
                       ("remedies.dead_zone.torque_rad_s", (2e-3,) * 7), ("remedies.e_modification.sigma", 1e-3),
                       ("remedies.projection.weight_bound", 0.5), ("alpha_net.eta", (0.7,) * 7),
                       ("torque_net.eta", (0.9,) * 7), ("torque_net.max_degree", 3),
                       ("torque_net.input_scale", (3.0, 3.0, 3.0))):
        cfg = replace_in(cfg, f"dnbs.{key}", value)
    return cfg


def _same_bits(a, b) -> bool:
    """Equal values, NaN where NaN, and the same sign bits (array_equal takes -0.0 for +0.0; a checkpoint does not)."""
    a, b = np.asarray(a), np.asarray(b)
    return np.array_equal(a, b, equal_nan=True) and np.array_equal(np.signbit(a), np.signbit(b))


def _same_state(a, b) -> bool:
    return (all(_same_bits(getattr(a.ekf, f), getattr(b.ekf, f)) for f in ("w", "P", "last_hph"))
            and _same_bits(a.alpha, b.alpha) and _same_bits(a.torque_unsaturated, b.torque_unsaturated)
            and a.steps == b.steps
            and all(_same_bits(a.ekf_resets[k], b.ekf_resets[k]) for k in ("alpha", "torque")))


def test_a_closed_loop_on_the_kernel_is_the_numpy_loop_bit_for_bit(cfg):
    numpy_cfg, c_cfg = _kernels(cfg)
    a, b = simulate(numpy_cfg, "dnbs", 2.0), simulate(c_cfg, "dnbs", 2.0)
    assert type(a.extra["controllers"]) is DNBSControllers
    assert isinstance(b.extra["controllers"], CompiledDNBSControllers)
    for field in ("position_rad", "velocity_rad_s", "torque_nm"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field


@pytest.mark.parametrize("variant", ["default", "every_remedy", "printed_sign", "slope_bound", "zero_bound"])
def test_every_branch_of_the_step_gives_the_same_bits(cfg, variant):
    """Saturation and anti-windup, the learning ramp, the covariance bound, untrusted rows (``active``),
    an EKF reset, and per variant the dead zone, e-modification, projection, eta < 1, another width, or
    the diverging printed sign; on random states that keep the torques hitting their limits."""
    if variant == "every_remedy":
        cfg = _every_remedy(cfg)
    if variant == "printed_sign":
        cfg = replace_in(cfg, "dnbs.e2_sign", "printed")
    if variant == "slope_bound":  # per-weight bounds (2n, W), tight enough to act
        cfg = replace_in(cfg, "dnbs.remedies.slope_bound.enabled", True)
        cfg = replace_in(cfg, "dnbs.remedies.slope_bound.fraction", (0.02,) * 7)
    if variant == "zero_bound":  # a slope fraction of 0 (the rule's least): every slope bound 0, a clip at +/-0
        cfg = replace_in(cfg, "dnbs.remedies.slope_bound.enabled", True)
        cfg = replace_in(cfg, "dnbs.remedies.slope_bound.fraction", (0.0,) * 7)
    cfg = replace_in(cfg, "dnbs.remedies.learning_ramp.ramp_s", 0.3)  # the ramp ends inside the run
    numpy_cfg, c_cfg = _kernels(cfg)
    ref = build_reference(cfg)
    ref_bank, c_bank = build_guarded_controllers(numpy_cfg, "dnbs"), build_guarded_controllers(c_cfg, "dnbs")
    assert isinstance(c_bank.controllers, CompiledDNBSControllers)
    rng = np.random.default_rng(11)
    n = 900
    k = np.arange(n)
    x1 = ref.position(k) + 0.2 * np.sin(0.02 * k)[:, None] + 1e-2 * rng.normal(size=(n, 7))
    x2 = ref.velocity(k) + 0.5 * rng.normal(size=(n, 7))
    x2[200:230, 1] = 1e3      # implausible speed: an untrusted row, not trained
    x1[400, 5] = np.nan        # a non-finite state
    limit = np.asarray(cfg.plant.torque_limit_nm)
    saturated = 0
    for step in range(n):
        if step == 600:  # a broken network: the guard resets it, in both
            for g in (ref_bank, c_bank):
                g.controllers.ekf.P[9, 2, 2] = np.nan
        with np.errstate(invalid="ignore", over="ignore"):
            u, v = ref_bank.step(x1[step], x2[step], ref.sample(step)), c_bank.step(x1[step], x2[step], ref.sample(step))
        assert _same_bits(u, v), step
        assert _same_state(ref_bank.controllers, c_bank.controllers), step
        saturated += bool((np.abs(c_bank.controllers.torque_unsaturated) >= limit).any())
    assert c_bank.controllers.ekf_resets["torque"][2] >= 1
    assert ref_bank.bad_states["speed"][1] == c_bank.bad_states["speed"][1] == 30
    assert saturated > 0  # the anti-windup branch was taken
    if variant in ("slope_bound", "zero_bound"):  # the projection acted: some weight sits on its bound
        bank = c_bank.controllers
        assert np.any(np.abs(bank.ekf.w) == bank._bounds)
    if variant == "zero_bound":  # weights held at a bound of 0 are +0.0, in numpy's bank and the kernel's
        for bank in (ref_bank.controllers, c_bank.controllers):
            zero = bank._bounds == 0.0
            assert zero.any() and not np.signbit(bank.ekf.w[zero]).any()


def test_a_single_joint_bank_answer_then_learn_and_checkpoints(cfg):
    """A node's bank of one: answer, then learn; a checkpoint of the reference loads into the kernel's bank
    and both go on alike (the kernel works on the bank's own arrays)."""
    numpy_cfg, c_cfg = _kernels(cfg)
    ref = build_reference(cfg)
    a, b = build_controllers(numpy_cfg, "dnbs", [4]), build_controllers(c_cfg, "dnbs", [4])
    x1, x2 = np.array([0.05]), np.array([0.3])
    for k in range(300):
        assert np.array_equal(a.answer(x1, x2, ref.sample(k, [4])), b.answer(x1, x2, ref.sample(k, [4])))
        assert b.learning_pending
        if k % 3:
            a.learn()
            b.learn()
        x1, x2 = x1 + 1e-3 * x2, x2 * 0.99
    state = a.state_dict(0)  # trains the pending step first, in both
    assert all(np.array_equal(v, b.state_dict(0)[key]) for key, v in state.items())
    fresh = build_controllers(c_cfg, "dnbs", [4])
    fresh.load_state_dict(0, state)
    for k in range(300, 400):
        assert np.array_equal(a.step(x1, x2, ref.sample(k, [4])), fresh.step(x1, x2, ref.sample(k, [4])))
    # (a checkpoint holds each network's own block of P, not the padding's diagonal, which nothing reads)
    assert all(np.array_equal(v, fresh.state_dict(0)[key]) for key, v in a.state_dict(0).items())


def test_without_a_compiler_the_error_names_the_key_and_the_cli_exits_2(cfg, tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-pa10")
    monkeypatch.setenv("PA10_DNBS_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(compiled_dnbs, "_LIB", None)  # as in a new process: not loaded yet
    with pytest.raises(KernelBuildError, match="dnbs.kernel: c"):
        build_controllers(_kernels(cfg)[1], "dnbs")
    config = tmp_path / "c.yaml"
    config.write_text(f"extends: {default_config_path()}\ndnbs:\n  kernel: c\n")
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "simulate", "--config", str(config),
                           "--duration", "0.1", "--out", str(out), "--no-progress"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    assert "dnbs.kernel: c" in done.stderr and "no-such-compiler-pa10" in done.stderr
    assert not out.exists()


@pytest.fixture
def new_process(tmp_path, monkeypatch):
    """As in a new process with an empty kernel cache: nothing loaded, ``auto`` not resolved yet."""
    monkeypatch.setenv("PA10_DNBS_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(compiled_dnbs, "_LIB", None)
    auto_kernel.cache_clear()
    yield tmp_path / "cache"
    auto_kernel.cache_clear()


def test_auto_without_a_compiler_runs_numpy_says_so_in_one_line_and_gives_the_same_bits(cfg, new_process,
                                                                                        tmp_path, monkeypatch):
    compiled = simulate(_kernels(cfg)[1], "dnbs", 0.3)  # built and loaded before the compiler goes away
    built = sorted(new_process.iterdir())
    monkeypatch.setattr(compiled_dnbs, "_LIB", None)
    monkeypatch.setenv("CC", "no-such-compiler-pa10")
    said = []
    resolved = resolve_kernel(cfg, say=said.append)
    assert cfg.dnbs.kernel == "auto" and resolved.dnbs.kernel == "numpy"
    assert len(said) == 1 and "\n" not in said[0]
    assert said[0].startswith("dnbs.kernel: auto -> numpy") and "no-such-compiler-pa10" in said[0]
    assert type(build_controllers(cfg, "dnbs")) is DNBSControllers  # auto, unresolved: the same answer
    fallback = simulate(resolved, "dnbs", 0.3)
    assert type(fallback.extra["controllers"]) is DNBSControllers
    for field in ("position_rad", "velocity_rad_s", "torque_nm"):
        assert np.array_equal(getattr(fallback, field), getattr(compiled, field)), field
    # the CLI on the default config (auto): exit 0, the one line, the same bits
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "simulate", "--duration", "0.3", "--out", str(out),
                           "--no-progress", "--no-figures"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stdout.splitlines() if "dnbs.kernel" in line]
    assert len(lines) == 1 and lines[0].startswith("dnbs.kernel: auto -> numpy"), done.stdout
    assert sorted(new_process.iterdir()) == built  # nothing more built
    assert np.array_equal(RunData.load_npz(out / "timeseries.npz").torque_nm, compiled.torque_nm)


def test_auto_picks_the_compiled_step_where_it_builds(cfg, new_process):
    said = []
    resolved = resolve_kernel(cfg, say=said.append)
    assert resolved.dnbs.kernel == "c"
    assert len(said) == 1 and said[0].startswith("dnbs.kernel: auto -> c") and str(new_process) in said[0]
    assert len(list(new_process.glob("libdnbs_kernel-*.so"))) == 1  # built into this (empty) cache
    assert isinstance(build_controllers(cfg, "dnbs"), CompiledDNBSControllers)
    assert resolve_kernel(resolved) is resolved  # c and numpy are left as they are


def test_auto_builds_nothing_for_pid_and_numpy_builds_nothing(cfg, new_process, tmp_path):
    ref, _ = _kernels(cfg)
    assert resolve_kernel(ref, say=pytest.fail) is ref
    out = tmp_path / "pid"
    done = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "simulate", "--controller", "pid", "--duration",
                           "0.05", "--out", str(out), "--no-progress", "--no-figures"],
                          capture_output=True, text=True, timeout=120, env={**os.environ, "CC": "no-such-compiler-pa10"})
    assert done.returncode == 0, done.stderr
    assert "dnbs.kernel" not in done.stdout
    assert not new_process.exists()
