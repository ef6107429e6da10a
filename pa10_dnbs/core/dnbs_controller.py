"""Per-joint decentralized neural backstepping controller, eq. 23-26.

For joint i at step k, using only that joint's x1 (angle, rad), x2 (velocity,
rad/s) and its own reference:
    alpha = w1^T S1(z1),  z1 = [x1, x_d(k+2)]          virtual control [rad/s]
    u     = w2^T S2(z2),  z2 = [x1, x2, alpha]         torque [N m]
    e1 = x_d(k) - x1,     e2 = alpha - x2
and both networks are trained by an EKF every step (except, with anti-windup,
an update that would push an already saturated torque further out). e2 has the opposite sign of
the paper's printed eq. 26: with H = S(z) and w <- w + eta K e the printed
x2 - alpha is positive feedback (test/test_dnbs_controller.py shows it).
The torque is saturated at the joint's Table 2 limit.

EKF guard: after every step both trainers are checked (finite w and P, and
every ``ekf_full_check_every`` steps P symmetric positive definite); a
network that fails is reset to its initial weights and P0, and counted in
``ekf_resets``. ``state_dict()`` / ``load_state_dict()`` carry everything a
restarted controller needs to resume (weights, covariances, step count).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ekf import EKFParams, EKFTrainer
from .honn import HONN, monomial_exponents
from .reference import ReferenceSample


@dataclass(frozen=True)
class NetworkParams:
    """One HONN and its EKF.

    max_degree: terms are all tanh monomials of total degree <= max_degree;
    input_scale: per input, in that input's units; init_weight_std: std of
    the seeded normal initial weights; ekf: EKF settings.
    """

    max_degree: int
    input_scale: tuple[float, ...]
    init_weight_std: float
    ekf: EKFParams


@dataclass(frozen=True)
class DNBSParams:
    """Settings of one joint's DNBS controller."""

    alpha_net: NetworkParams
    torque_net: NetworkParams
    torque_limit_nm: float
    anti_windup: bool = True       # skip updates that would push a saturated torque further out
    printed_e2_sign: bool = False  # True reproduces the paper's printed e2 = x2 - alpha (diverges)
    ekf_full_check_every: int = 100  # steps between Cholesky checks of P (0: never; finiteness every step)


class DNBSJointController:
    """Neural backstepping controller for one joint; see the module docstring."""

    def __init__(self, params: DNBSParams, seed):
        """``seed``: int or sequence of ints for numpy.random.default_rng (initial weights)."""
        self.params = params
        rng = np.random.default_rng(seed)
        self.alpha_honn = HONN(monomial_exponents(2, params.alpha_net.max_degree),
                               params.alpha_net.input_scale)
        self.torque_honn = HONN(monomial_exponents(3, params.torque_net.max_degree),
                                params.torque_net.input_scale)
        w1 = rng.normal(0.0, params.alpha_net.init_weight_std, self.alpha_honn.n_terms)
        w2 = rng.normal(0.0, params.torque_net.init_weight_std, self.torque_honn.n_terms)
        self.alpha_ekf = EKFTrainer(w1, params.alpha_net.ekf)
        self.torque_ekf = EKFTrainer(w2, params.torque_net.ekf)
        self.alpha = 0.0
        self.torque_unsaturated = 0.0
        self.steps = 0
        self.ekf_resets = {"alpha": 0, "torque": 0}

    def step(self, x1: float, x2: float, ref: ReferenceSample) -> float:
        """Compute the torque [N m] for state (x1, x2) and train both networks."""
        S1 = self.alpha_honn.regressor((x1, ref.position_ahead_rad))
        alpha = float(self.alpha_ekf.w @ S1)
        S2 = self.torque_honn.regressor((x1, x2, alpha))
        u = float(self.torque_ekf.w @ S2)

        e1 = ref.position_rad - x1
        e2 = (x2 - alpha) if self.params.printed_e2_sign else (alpha - x2)
        lim = self.params.torque_limit_nm
        # Conditional integration: while the torque is clipped, skip an update
        # that would raise |u| further: e2 > 0 raises u directly; e1 > 0 raises
        # alpha, and so u too wherever du/dalpha > 0 (the case the law relies on).
        saturated = self.params.anti_windup and abs(u) >= lim
        if not (saturated and e1 * u > 0.0):
            self.alpha_ekf.update(S1, e1)
        if not (saturated and e2 * u > 0.0):
            self.torque_ekf.update(S2, e2)

        self.alpha = alpha
        self.torque_unsaturated = u
        self.steps += 1
        self._guard()
        return min(max(u, -lim), lim)

    def _guard(self) -> None:
        every = self.params.ekf_full_check_every
        full = every > 0 and self.steps % every == 0
        for name, ekf in (("alpha", self.alpha_ekf), ("torque", self.torque_ekf)):
            if not ekf.healthy(full):
                ekf.reset()
                self.ekf_resets[name] += 1

    def state_dict(self) -> dict[str, np.ndarray]:
        """Weights (L,), covariances (L, L), initial weights and counters, as arrays (for np.savez)."""
        return {"alpha_w": self.alpha_ekf.w.copy(), "alpha_P": self.alpha_ekf.P.copy(),
                "alpha_w0": self.alpha_ekf.w0.copy(), "torque_w": self.torque_ekf.w.copy(),
                "torque_P": self.torque_ekf.P.copy(), "torque_w0": self.torque_ekf.w0.copy(),
                "steps": np.array(self.steps), "alpha": np.array(self.alpha),
                "ekf_resets": np.array([self.ekf_resets["alpha"], self.ekf_resets["torque"]])}

    def load_state_dict(self, state: dict) -> None:
        """Resume from ``state_dict()`` output; shapes must match this controller's networks."""
        for name, ekf in (("alpha", self.alpha_ekf), ("torque", self.torque_ekf)):
            w, P = np.asarray(state[f"{name}_w"], float), np.asarray(state[f"{name}_P"], float)
            if w.shape != ekf.w.shape or P.shape != ekf.P.shape:
                raise ValueError(f"checkpoint {name} network has shape {w.shape}/{P.shape}, expected "
                                 f"{ekf.w.shape}/{ekf.P.shape}")
            ekf.w[:] = w
            ekf.P[:] = P
            ekf.w0[:] = np.asarray(state[f"{name}_w0"], float)
        self.steps = int(state["steps"])
        self.alpha = float(state["alpha"])
        self.ekf_resets = dict(zip(("alpha", "torque"), (int(v) for v in state["ekf_resets"])))
