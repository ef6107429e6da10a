"""Decentralized neural backstepping controllers (eq. 23-26), one per joint, computed as rows of arrays.

Joint i's controller (the i-th of the bank's n joints) reads only its own
angle x1 [rad], velocity x2 [rad/s] and reference; its two networks are rows
i (alpha) and n + i (torque) of one EKF bank. A joint-controller node holds
one joint; the in-process simulation holds all the arm's joints. The arithmetic of a
row does not depend on the other rows, so both agree bit for bit
(test/test_dnbs_controller.py checks it).

Per joint, at step k:
    alpha = A w1^T S1(z1) + x_d_dot + k_a e1    z1 = [x1, x_d(k+2)]     virtual control [rad/s]
    u     = U w2^T S2(z2) + k_u e2              z2 = [x1, x2, alpha]    torque [N m], clipped to the limits
    e1 = x_d(k) - x1,   e2 = alpha - x2
Both HONNs (w1, w2) are trained every step by an EKF with learning rate
eta in (0, 1] (eq. 7) on the dimensionless errors e1/E1 and e2/E2. A [rad/s]
and U [N m] scale the networks' outputs, E1 [rad] and E2 [rad/s] their
training errors: U eta / E2 [N m per rad/s] is the torque network's
adaptation gain, explicit and per joint.

e2 has the opposite sign of the paper's printed eq. 26: with H = S(z) and
w <- w + eta K e, the printed x2 - alpha is positive feedback (``e2_sign =
'printed'`` reproduces it; test_dnbs_controller shows it diverge).

The remedies for the learning transient (docs/controller.md gives each one's
reason, reference and ablation; ``config/paper.yaml`` keeps only the anti-windup):
- robust term: x_d_dot + k_a e1 in alpha and k_u e2 in u, so that k_u e2 is
  Lewis's Kv r with r = e_dot + k_a e (Lewis, Yesildirek & Liu 1996); without
  it (or with k = 0 and no feed-forward) the law is the paper's;
- anti-windup: conditional integration, an update that would push a clipped
  torque further out is skipped (Astrom & Rundqwist 1989);
- dead zone: the EKF trains on e - clip(e, -d, d), no adaptation on errors
  below the modelling error (continuous dead zone, Ioannou & Sun 8.5);
- e-modification: after each update w <- w (1 - sigma |e/E|), a leakage that
  vanishes with the error (Narendra & Annaswamy 1987);
- projection: every weight is kept in [-B, B] (Ioannou & Sun 8.5; B large
  enough for the ideal weights);
- slope bound: the torque network's weights of the terms that hold x1, x2 or
  alpha are kept in a box, so that the network's slope in each input stays
  within a fraction f of the linear term's own gain in it (k_a k_u in x1, k_u
  in x2 and alpha): the loop's gains stay within (1 +- f) of the linear
  term's, whose discrete-time margin the gain rule checked. Projection onto a
  box (Gong & Yao 2001; Ioannou & Sun 8.5); f comes from the gain rule;
- learning ramp: eta grows linearly from 0 over ramp_s seconds, so the
  networks do not learn from the first, least informative, transient;
- covariance bound: Q stops growing a diagonal entry of P beyond p_max
  (no covariance windup in unexcited directions; Haykin 2001, ch. 2).

EKF guard: after every step both trainers are checked (w and H^T P H finite, H^T P H >= 0, and every
``ekf_full_check_every`` steps P finite, symmetric, positive definite); a row that
fails is reset to its initial weights and P0, and counted in ``ekf_resets``.
``state_dict(row)`` / ``load_state_dict(row, state)`` carry what a restarted
(or warm-started) controller needs to resume: weights, covariances, step count.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from .ekf import EKFBank, EKFRows
from .honn import HONN, monomial_exponents
from .padded_layout import shared_width
from .reference import ReferenceSample


@dataclass(frozen=True)
class NetworkParams:
    """One HONN per joint and its EKF; per-joint values are arrays of shape (n,).

    max_degree: the terms are all tanh monomials of total degree <= max_degree;
    input_scale: per input, in that input's units (shared by the joints);
    output_scale: A [rad/s] or U [N m]; error_scale: E1 [rad] or E2 [rad/s];
    init_weight_std: std of the seeded normal initial weights (dimensionless);
    p0, q, r: EKF P(0) = p0 I, Q = q I, R = r (dimensionless); eta in (0, 1].
    """

    max_degree: int
    input_scale: tuple[float, ...]
    output_scale: np.ndarray
    error_scale: np.ndarray
    init_weight_std: np.ndarray
    p0: np.ndarray
    q: np.ndarray
    r: np.ndarray
    eta: np.ndarray


@dataclass(frozen=True)
class Remedies:
    """Switches and settings of the remedies (module docstring); per-joint values are arrays (n,).

    A remedy that is off has no effect at all: its gain, band or bound is
    replaced by the neutral value (0, 0, inf), so the paper's law is exact.
    """

    robust_term: bool = False
    velocity_feedforward: bool = False                    # k_v = 1: alpha also gets x_d_dot (Lewis's r)
    alpha_gain_per_s: np.ndarray | float = 0.0          # k_a [1/s]
    torque_gain_nms_per_rad: np.ndarray | float = 0.0   # k_u [N m s/rad]
    anti_windup: bool = False
    dead_zone: bool = False
    dead_zone_rad: np.ndarray | float = 0.0              # d1 on e1 [rad]
    dead_zone_rad_s: np.ndarray | float = 0.0            # d2 on e2 [rad/s]
    e_modification: bool = False
    e_modification_sigma: float = 0.0                    # sigma [-] per step, per unit of |e/E|
    projection: bool = False
    weight_bound: float = float("inf")                   # B [-]
    slope_bound: bool = False
    slope_fraction: np.ndarray | float = 0.0             # f [-] per joint: the network's slope / the linear term's
    learning_ramp: bool = False
    learning_ramp_s: float = 0.0                         # [s]
    covariance_bound: bool = False
    p_max: float = float("inf")                          # [-] largest diagonal entry of P that Q still grows


@dataclass(frozen=True)
class DNBSParams:
    """Settings of n joints' DNBS controllers (all per-joint arrays have shape (n,))."""

    alpha_net: NetworkParams
    torque_net: NetworkParams
    torque_limit_nm: np.ndarray
    dt_s: float
    remedies: Remedies = field(default_factory=Remedies)
    e2_sign: str = "stable"          # 'printed' reproduces the paper's printed e2 = x2 - alpha (diverges)
    ekf_full_check_every: int = 100  # steps between Cholesky checks of P (0: never; finiteness every step)

    @property
    def n_joints(self) -> int:
        return int(np.size(self.torque_limit_nm))

    def select(self, rows) -> "DNBSParams":
        """The parameters of a subset of the joints (e.g. one node's joint), in the order of ``rows``."""
        rows = np.asarray(rows)

        def pick(obj):
            kw = {}
            for f in fields(obj):
                v = getattr(obj, f.name)
                kw[f.name] = v[rows] if isinstance(v, np.ndarray) and v.ndim == 1 else v
            return type(obj)(**kw)

        return DNBSParams(alpha_net=pick(self.alpha_net), torque_net=pick(self.torque_net),
                          torque_limit_nm=self.torque_limit_nm[rows], dt_s=self.dt_s,
                          remedies=pick(self.remedies), e2_sign=self.e2_sign,
                          ekf_full_check_every=self.ekf_full_check_every)


def clip(x: np.ndarray, low, high, out: np.ndarray | None = None) -> np.ndarray:
    """``np.clip(x, low, high, out=out)`` in two ufunc calls, without np.clip's Python wrapping (~1.5 us a call).

    The same bits as np.clip, signed zeros and NaN included (test_dnbs_controller pins it against np.clip).
    """
    return np.minimum(np.maximum(x, low, out=out), high, out=out)


def _per_joint(value, n: int) -> np.ndarray:
    """A number or n values as a float array of shape (n,)."""
    return np.broadcast_to(np.asarray(value, dtype=float), (n,))


def initial_weights(seed: int, joint: int, n_alpha: int, n_torque: int, std_alpha: float, std_torque: float):
    """Joint ``joint``'s random initial weights (the paper: "initialized in a random way"), seeded by
    (seed, joint): the same in a bank of one as in a bank of all the arm's joints. Returns the alpha network's
    (n_alpha,) and the torque network's (n_torque,) weights, each normal with mean 0 and its standard deviation
    (dimensionless: the networks' outputs are scaled by their output scales)."""
    rng = np.random.default_rng((seed, joint))
    return rng.normal(0.0, std_alpha, n_alpha), rng.normal(0.0, std_torque, n_torque)


def max_slope(exponents: np.ndarray, input_scale, p: int) -> float:
    """The largest summed slope in input p [1/unit of p] of the HONN terms holding it: each term
    tanh(z_p / s_p)^k times factors of magnitude <= 1 has slope at most k max(tanh^(k-1) sech^2) / s_p."""
    y = np.linspace(0.0, 6.0, 6001)
    total = 0.0
    for k in np.asarray(exponents)[:, p]:
        if k > 0:
            total += float(np.max(k * np.tanh(y) ** (k - 1) / np.cosh(y) ** 2))
    return total / float(np.asarray(input_scale, float)[p])


class DNBSControllers:
    """The DNBS controllers of joints ``joints`` (indices 0..n-1 of the arm), one per row; see the module
    docstring. A :class:`~pa10_dnbs.core.controller_bank.ControllerBank` that learns."""

    learns = True

    def __init__(self, params: DNBSParams, seed: int, joints):
        joints = [int(j) for j in joints]
        if len(joints) != params.n_joints:
            raise ValueError(f"{len(joints)} joints for parameters of {params.n_joints}")
        if params.e2_sign not in ("stable", "printed"):
            raise ValueError(f"e2_sign must be 'stable' or 'printed', got {params.e2_sign!r}")
        self.params = params
        self.joints = tuple(joints)
        a, t = params.alpha_net, params.torque_net
        self.alpha_honn = HONN(monomial_exponents(2, a.max_degree), a.input_scale)
        self.torque_honn = HONN(monomial_exponents(3, t.max_degree), t.input_scale)
        la, lt = self.alpha_honn.n_terms, self.torque_honn.n_terms
        n = len(joints)
        # Both networks of every joint train in one EKF bank: rows 0..n-1 the alpha networks, n..2n-1 the
        # torque networks, each in its block of a padded row laid out so that every sum keeps its bits.
        layout = shared_width((la, lt))
        if layout is None:
            raise ValueError(f"no shared row layout for networks of {la} and {lt} weights")
        width, (oa, ot) = layout
        w0 = np.zeros((2 * n, width))
        std_a, std_t = _per_joint(a.init_weight_std, n), _per_joint(t.init_weight_std, n)
        for i, j in enumerate(joints):
            w0[i, oa:oa + la], w0[n + i, ot:ot + lt] = initial_weights(seed, j, la, lt, std_a[i], std_t[i])
        rem = params.remedies
        p_max = rem.p_max if rem.covariance_bound else np.inf
        self.ekf = EKFBank(w0, *(np.concatenate([_per_joint(getattr(a, k), n), _per_joint(getattr(t, k), n)])
                                 for k in ("p0", "q", "r", "eta")), p_max)
        self.alpha_ekf = EKFRows(self.ekf, slice(0, n), slice(oa, oa + la))
        self.torque_ekf = EKFRows(self.ekf, slice(n, 2 * n), slice(ot, ot + lt))
        self._blocks = ((self.alpha_ekf.rows, self.alpha_ekf.cols), (self.torque_ekf.rows, self.torque_ekf.cols))
        self._H = np.zeros((2 * n, width))  # both regressors, padding exact zeros
        self._S1, self._S2 = self._H[:n, oa:oa + la], self._H[n:, ot:ot + lt]
        self._w1, self._w2 = self.ekf.w[:n], self.ekf.w[n:]   # views of ekf.w (updated in place), padded rows
        self._H1, self._H2 = self._H[:n], self._H[n:]
        self._prod = np.empty((n, width))
        self._eps = np.empty(2 * n)  # the training errors of the alpha rows, then the torque rows
        self._eps1, self._eps2 = self._eps[:n], self._eps[n:]

        def on(flag, value, neutral):
            return _per_joint(value, n).copy() if flag else np.full(n, neutral)

        self._k_a = on(rem.robust_term, rem.alpha_gain_per_s, 0.0)
        self._k_v = 1.0 if rem.robust_term and rem.velocity_feedforward else 0.0
        self._k_u = on(rem.robust_term, rem.torque_gain_nms_per_rad, 0.0)
        # the dead zone's bands (d1 of the alpha rows, then d2 of the torque rows) and their negatives
        self._d = np.concatenate((on(rem.dead_zone, rem.dead_zone_rad, 0.0),
                                  on(rem.dead_zone, rem.dead_zone_rad_s, 0.0)))
        self._neg_d = -self._d
        self._sigma = rem.e_modification_sigma if rem.e_modification else 0.0
        self._bounds = self._weight_bounds(rem, n, width, ot)  # (2n, width) or None: no projection at all
        self._ramp_steps = rem.learning_ramp_s / params.dt_s if rem.learning_ramp and rem.learning_ramp_s > 0 else 0.0
        self._anti_windup = rem.anti_windup
        self._dead_zone = rem.dead_zone
        self._printed = params.e2_sign == "printed"
        self._A, self._U = a.output_scale, t.output_scale
        self._E = np.concatenate((_per_joint(a.error_scale, n), _per_joint(t.error_scale, n)))  # E1 rows, E2 rows
        self._lim = params.torque_limit_nm
        self._neg_lim = -self._lim
        self._z1 = np.empty((n, 2))
        self._z2 = np.empty((n, 3))
        self._ones = np.ones(n)
        self.alpha = np.zeros(n)                 # last virtual control [rad/s]
        self.torque_unsaturated = np.zeros(n)    # last torque before the torque-limit clip [N m]
        self.steps = 0                           # steps trained
        self._pending = None                     # (e1, e2, u, active) of an answer not yet trained on
        self.ekf_resets = {"alpha": np.zeros(n, dtype=np.int64), "torque": np.zeros(n, dtype=np.int64)}

    def _weight_bounds(self, rem: Remedies, n: int, width: int, ot: int) -> np.ndarray | None:
        """Per-weight bounds (2n, width) of the padded bank (projection's B everywhere; the slope bound's on the
        torque rows' terms of x1, x2, alpha), or None when neither remedy is on: then no weight is touched."""
        if not (rem.projection or rem.slope_bound):
            return None
        bounds = np.full((2 * n, width), float(rem.weight_bound) if rem.projection else np.inf)
        if rem.slope_bound:
            f = _per_joint(rem.slope_fraction, n)
            U = _per_joint(self.params.torque_net.output_scale, n)
            gains = (self._k_a * self._k_u, self._k_u, self._k_u)  # the linear term's gain in x1, x2, alpha
            ex = self.torque_honn.exponents
            for p in range(3):
                c = max_slope(ex, self.torque_honn.input_scale, p)
                cols = ot + np.flatnonzero(ex[:, p] > 0)
                bounds[n:, cols] = np.minimum(bounds[n:, cols], (f * gains[p] / (U * c))[:, None])
            # the alpha network: every weight within f k_a / (A c), c its summed slope in x1: its slope in x1
            # stays within f of k_a, and its output (bias and reference terms) within f k_a s1 rad/s
            A = _per_joint(self.params.alpha_net.output_scale, n)
            c = max_slope(self.alpha_honn.exponents, self.alpha_honn.input_scale, 0)
            la = self.alpha_honn.n_terms
            oa = self.alpha_ekf.cols.start
            bounds[:n, oa:oa + la] = np.minimum(bounds[:n, oa:oa + la], (f * self._k_a / (A * c))[:, None])
        self._neg_bounds = -bounds
        return bounds

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    def step(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample, active: np.ndarray | None = None) -> np.ndarray:
        """Torques (n,) [N m] for angles x1 (n,) [rad] and velocities x2 (n,) [rad/s]; trains both networks.

        ``active`` (n,) of 1.0 / 0.0: a row with 0 is not trained (its state was not trusted; its inputs must
        still be finite) and its torque is to be ignored by the caller. The same as ``answer`` then ``learn``.
        """
        u = self.answer(x1, x2, ref, active)
        self.learn()
        return u

    def answer(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample, active: np.ndarray | None = None) -> np.ndarray:
        """The torques (n,) [N m] of ``step`` without the training, which is left pending for ``learn``.

        The torque uses the weights before this step's update, so a caller can send it out first and train
        afterwards, off the critical path (Astrom & Wittenmark: "calculate output", then "update state").
        A training still pending from the previous step is done first: the results never depend on when, or
        whether, ``learn`` is called between two answers.
        """
        if self._pending is not None:
            self.learn()
        z1, z2 = self._z1, self._z2
        z1[:, 0] = x1
        z1[:, 1] = ref.position_ahead_rad
        self.alpha_honn.regressor(z1, out=self._S1)
        e1 = ref.position_rad - x1
        alpha = self._A * np.add.reduce(np.multiply(self._w1, self._H1, out=self._prod), axis=1) + self._k_a * e1
        if self._k_v:
            alpha = alpha + ref.velocity_rad_s
        z2[:, 0] = x1
        z2[:, 1] = x2
        z2[:, 2] = alpha
        self.torque_honn.regressor(z2, out=self._S2)
        e2 = alpha - x2
        u = self._U * np.add.reduce(np.multiply(self._w2, self._H2, out=self._prod), axis=1) + self._k_u * e2
        self.alpha = alpha
        self.torque_unsaturated = u
        self._pending = (e1, e2, u, active)  # the regressors stay in self._H until learn()
        return np.minimum(np.maximum(u, self._neg_lim), self._lim)

    @property
    def learning_pending(self) -> bool:
        """True between an ``answer`` and its ``learn``."""
        return self._pending is not None

    def learn(self) -> None:
        """Train both networks on the errors of the last ``answer`` (EKF update, remedies, guard); a no-op when
        nothing is pending."""
        if self._pending is None:
            return
        e1, e2, u, active = self._pending
        self._pending = None
        e2_train = -e2 if self._printed else e2
        act = None if active is None else np.concatenate((active, active))  # (2n,): alpha rows, torque rows
        if self._anti_windup:
            # Conditional integration: while the torque is clipped, skip an update that would raise |u|:
            # e2 > 0 raises u directly; e1 > 0 raises alpha, and so u wherever du/dalpha > 0.
            sat = np.abs(u) >= self._lim
            if np.logical_or.reduce(sat):
                base = self._ones if active is None else active
                act = np.concatenate((base * (1.0 - (sat & (e1 * u > 0.0))),
                                      base * (1.0 - (sat & (e2_train * u > 0.0)))))
        eps = self._eps  # both networks' errors in one array: the elementwise steps below are one call each
        self._eps1[...] = e1
        self._eps2[...] = e2_train
        if self._dead_zone:
            eps -= clip(eps, self._neg_d, self._d)
        np.divide(eps, self._E, out=eps)
        eta = self.ekf.eta
        if self._ramp_steps and self.steps < self._ramp_steps:
            eta = eta * (self.steps / self._ramp_steps)
        self.ekf.update(self._H, self._eps, eta, act)
        if self._sigma:
            leak = self._sigma * np.abs(eps)
            if act is not None:
                leak *= act
            self.ekf.w *= (1.0 - np.minimum(1.0, leak))[:, None]
        if self._bounds is not None:
            clip(self.ekf.w, self._neg_bounds, self._bounds, out=self.ekf.w)
        self.steps += 1
        self._guard()

    def _guard(self) -> None:
        every = self.params.ekf_full_check_every
        full = every > 0 and self.steps % every == 0
        ekf = self.ekf
        hph = ekf.last_hph  # (ufunc reductions: the ndarray methods wrap them in Python, ~0.2 us each)
        if not full and math.isfinite(np.add.reduce(ekf.w, None) + np.add.reduce(hph)) \
                and np.minimum.reduce(hph) >= 0.0:
            return  # the cheap check of both networks at once: every w and H^T P H finite, H^T P H >= 0
        self._reset_unhealthy(full)

    def _reset_unhealthy(self, full: bool) -> None:
        """The EKF guard past its cheap check: reset (and count) the rows ``EKFBank.unhealthy`` names."""
        ekf = self.ekf
        bad = ekf.unhealthy(full, self._blocks)  # the full check looks at each network's own block
        if bad.any():
            ekf.reset(bad)
            n = self.n_joints
            self.ekf_resets["alpha"] += bad[:n]
            self.ekf_resets["torque"] += bad[n:]

    def counters(self, row: int = 0) -> dict[str, int]:
        """Row ``row``'s EKF resets (``ekf_resets_alpha``, ``ekf_resets_torque``), for the run's report."""
        return {f"ekf_resets_{k}": int(v[row]) for k, v in self.ekf_resets.items()}

    def state_dict(self, row: int = 0) -> dict[str, np.ndarray]:
        """Row ``row``'s weights (L,), covariances (L, L), initial weights and counters (for np.savez), after
        any pending training."""
        self.learn()
        return {"joint": np.array(self.joints[row]),
                "alpha_w": self.alpha_ekf.w[row].copy(), "alpha_P": self.alpha_ekf.P[row].copy(),
                "alpha_w0": self.alpha_ekf.w0[row].copy(), "torque_w": self.torque_ekf.w[row].copy(),
                "torque_P": self.torque_ekf.P[row].copy(), "torque_w0": self.torque_ekf.w0[row].copy(),
                "steps": np.array(self.steps), "alpha": np.array(self.alpha[row]),
                "ekf_resets": np.array([self.ekf_resets["alpha"][row], self.ekf_resets["torque"][row]])}

    def load_state_dict(self, row: int, state: dict, resume_steps: bool = True) -> None:
        """Set row ``row`` from a ``state_dict()``; shapes must match. ``resume_steps`` also takes over the step
        count (a restarted controller); a warm start of a new run keeps its own (it starts at step 0)."""
        if "joint" in state and int(state["joint"]) != self.joints[row]:
            raise ValueError(f"checkpoint of joint index {int(state['joint'])}, expected {self.joints[row]}")
        self.learn()  # a pending training belongs to the state being replaced
        for name, ekf in (("alpha", self.alpha_ekf), ("torque", self.torque_ekf)):
            w, P = np.asarray(state[f"{name}_w"], float), np.asarray(state[f"{name}_P"], float)
            if w.shape != ekf.w[row].shape or P.shape != ekf.P[row].shape:
                raise ValueError(f"checkpoint {name} network has shape {w.shape}/{P.shape}, expected "
                                 f"{ekf.w[row].shape}/{ekf.P[row].shape}")
            ekf.w[row] = w
            ekf.P[row] = P
            ekf.w0[row] = np.asarray(state[f"{name}_w0"], float)
        if resume_steps:
            self.steps = int(state["steps"])
            self.alpha[row] = float(state["alpha"])
            self.ekf_resets["alpha"][row], self.ekf_resets["torque"][row] = (int(v) for v in state["ekf_resets"])
