"""Answer first, train after: DNBS's ``answer`` + ``learn`` is ``step`` bit for bit, whenever ``learn`` is called.

A node publishes the torque of ``answer`` and then calls ``learn``, so the EKF update is off the
state-to-effort path; the in-process simulation calls ``step``. These tests hold the two to the same bits,
with the guard's untrusted rows, saturation and an EKF reset on the way, and check that a training is never
lost or done twice (a second answer, a checkpoint, a resent state).
"""
import numpy as np
import pytest

from pa10_dnbs.controller_factory import build_controllers, build_guarded_controllers, build_reference
from pa10_dnbs.loop.joint_loop import JointLoop


def _states(n_steps: int, ref, rng):
    k = np.arange(n_steps)
    x1 = ref.position(k) + 0.05 * np.sin(0.01 * k)[:, None] + 1e-3 * rng.normal(size=(n_steps, 7))
    x2 = ref.velocity(k) + 0.1 * rng.normal(size=(n_steps, 7))
    x2[300:310, 2] = 1e3   # implausible speeds: untrusted rows, not trained
    x1[500, 4] = np.nan
    return x1, x2


def _same(a, b):
    return all(np.array_equal(getattr(a.ekf, f), getattr(b.ekf, f)) for f in ("w", "P")) and a.steps == b.steps


@pytest.mark.parametrize("when", ["after_each_answer", "only_by_the_next_answer"])
def test_answer_then_learn_equals_step_bit_for_bit(cfg, when):
    ref = build_reference(cfg)
    x1, x2 = _states(800, ref, np.random.default_rng(3))
    stepped, split = build_guarded_controllers(cfg, "dnbs"), build_guarded_controllers(cfg, "dnbs")
    for k in range(800):
        if k == 600:  # a broken network (after step 599's training): the guard resets it, in both
            split.learn()
            for g in (stepped, split):
                g.controllers.ekf.w[3, 0] = np.inf
        with np.errstate(invalid="ignore"):  # inf * 0 in the broken row, until the guard resets it
            u = stepped.step(x1[k], x2[k], ref.sample(k))
            v = split.answer(x1[k], x2[k], ref.sample(k))
        assert split.controllers.learning_pending
        assert np.array_equal(u, v), k
        if when == "after_each_answer":
            with np.errstate(invalid="ignore"):
                split.learn()
            assert _same(stepped.controllers, split.controllers), k
    split.learn()
    assert _same(stepped.controllers, split.controllers)
    assert stepped.controllers.ekf_resets["alpha"][3] == split.controllers.ekf_resets["alpha"][3] == 1
    assert np.array_equal(stepped.bad_states["speed"], split.bad_states["speed"])
    split.learn()  # nothing pending: a no-op
    assert _same(stepped.controllers, split.controllers)


def test_a_checkpoint_taken_between_answer_and_learn_holds_the_training(cfg):
    ref = build_reference(cfg)
    stepped, split = build_controllers(cfg, "dnbs", [1]), build_controllers(cfg, "dnbs", [1])
    x1, x2 = np.array([0.05]), np.array([0.1])
    for k in range(5):
        stepped.step(x1, x2, ref.sample(k, [1]))
        split.answer(x1, x2, ref.sample(k, [1]))
    state = split.state_dict(0)  # trains first
    assert not split.learning_pending and int(state["steps"]) == 5
    assert np.array_equal(state["torque_P"], stepped.state_dict(0)["torque_P"])
    split.learn()
    assert split.steps == 5  # not trained twice


def test_joint_loop_answers_before_training_and_a_resent_state_trains_nothing(cfg):
    loop = JointLoop(build_guarded_controllers(cfg, "dnbs", [0]), cfg.reference.preview_steps)
    ref = build_reference(cfg)
    n = 40 + cfg.reference.preview_steps
    loop.add_reference(0, ref.position(np.arange(n))[:, 0].tolist(), ref.velocity(np.arange(n))[:, 0].tolist())
    ctrl = loop.controller
    [(step, u)] = loop.on_state(0, 0.01, 0.0)
    assert step == 0 and loop.learning_pending and ctrl.steps == 0
    loop.learn()
    assert not loop.learning_pending and ctrl.steps == 1
    assert loop.on_state(0, 0.01, 0.0) == [(0, u)]  # a resend: the same answer, nothing to train
    assert not ctrl.learning_pending and ctrl.steps == 1


def test_pid_has_nothing_to_learn(cfg):
    loop = JointLoop(build_guarded_controllers(cfg, "pid", [0]), cfg.reference.preview_steps)
    loop.add_reference(0, [0.0] * 200, [0.0] * 200)
    [(_, u)] = loop.on_state(0, 0.001, 0.0)  # an error small enough not to saturate (no integration stop)
    assert not loop.learning_pending  # the node does not yield for it
    loop.learn()
    assert np.isfinite(u) and abs(u) < cfg.plant.torque_limit_nm[0] and loop.controller.integral[0] != 0.0
