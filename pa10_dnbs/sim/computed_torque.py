"""Computed-torque control: the centralized upper bound the decentralized controllers are compared to.

u = M(q) v + h(q, qd) + F,  v = x_d_ddot + s fb,  fb = Kd (x_d_dot - qd) + Kp (x_d - q),
with the plant's own model: M includes the rotor inertias, h the Coriolis, centrifugal and gravity
torques, F the friction (viscous and Coulomb), payload and mass changes included. F is the friction the
plant's step meets (viscous at qd, Coulomb at the speed the step is asked to reach, as the plant applies
its implicit Coulomb term): with Coulomb at qd the controller chatters at every reversal (RMS 4.3x worse).

What it does when u exceeds a torque limit (``ctc.on_saturation``):

- ``clip`` (s = 1, then each joint clipped to its limit): the textbook law. A clipped joint no longer gets
  the torque the decoupling assumed, so the other joints' error dynamics are no longer e_ddot + Kd e_dot +
  Kp e = 0; on a light, strongly coupled arm (an xArm7 or Z1 without rotor inertia) the start offset then
  drives it unstable. The PA10, iiwa and Panda presets keep it: their published numbers were made with it.
- ``scale_feedback``: the torque-limited computed torque of the time-scaling literature (Hollerbach 1984,
  "Dynamic scaling of manipulator trajectories", ASME J. Dyn. Syst. Meas. Control 106(1):102-106; Dahl and
  Nielsen 1990, "Torque-limited path following by online trajectory time scaling", IEEE Trans. Robot. Autom.
  6(5):554-561), applied to the feedback alone: the largest s in [0, 1] for which u is within every limit
  (bisection, 30 halvings: s to 1e-9), found each step. The feedforward x_d_ddot stays whole and the PD
  correction keeps its direction in joint space (a directional saturation: every joint's correction shrinks
  by the same factor), so u stays a computed torque, M(q) times one commanded acceleration, and the loop
  stays decoupled while the limits hold it back. If even s = 0 (the feedforward alone) is beyond a limit,
  s = 0 and u is clipped. When nothing saturates it is the same u as ``clip``, bit for bit.

It needs every joint's state and the exact model, so it only runs in-process (it has no node).
"""
from __future__ import annotations

import numpy as np

from ..core.controller_bank import FixedGainBank
from ..core.reference import ReferenceSample

ON_SATURATION = ("scale_feedback", "clip")
_BISECTIONS = 30  # s to 2^-30 ~ 1e-9


class ComputedTorqueController(FixedGainBank):
    """All joints at once; ``kp_per_s2`` [1/s^2] and ``kd_per_s`` [1/s] shape the error dynamics
    e_ddot + Kd e_dot + Kp e = 0 (per joint, numbers or arrays (n,)); ``on_saturation``: one of
    ON_SATURATION (module docstring). ``last_scale``: the s of the last step (1.0 when nothing saturated)."""

    def __init__(self, plant, kp_per_s2, kd_per_s, torque_limit_nm, on_saturation: str = "clip"):
        if on_saturation not in ON_SATURATION:
            raise ValueError(f"on_saturation: one of {', '.join(ON_SATURATION)}, got {on_saturation!r}")
        self.plant = plant
        self.kp = np.asarray(kp_per_s2, dtype=float)
        self.kd = np.asarray(kd_per_s, dtype=float)
        self.limit = np.asarray(torque_limit_nm, dtype=float)
        self.n_joints = self.limit.size
        self.on_saturation = on_saturation
        self.last_scale = 1.0

    def answer(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample, active: np.ndarray | None = None) -> np.ndarray:
        """Torques (n,) [N m] for angles x1 (n,) [rad] and velocities x2 (n,) [rad/s]; needs
        ``ref.acceleration_rad_s2``. (No learning: ``active`` changes nothing.)"""
        if ref.acceleration_rad_s2 is None:
            raise ValueError("computed torque needs the reference acceleration")
        p = self.plant
        v = ref.acceleration_rad_s2 + self.kd * (ref.velocity_rad_s - x2) + self.kp * (ref.position_rad - x1)
        m, h = p.mass_matrix(x1), p.bias_torque(x1, x2)
        u = m @ v + h + p.step_friction_torque(x2, v)
        self.last_scale = 1.0
        if self.on_saturation == "scale_feedback" and not self._within(u):
            u = self._scaled(x2, ref, m, h, v - ref.acceleration_rad_s2)
        return np.minimum(np.maximum(u, -self.limit), self.limit)

    def _within(self, u: np.ndarray) -> bool:
        return bool(np.all(np.abs(u) <= self.limit))

    def _scaled(self, x2, ref: ReferenceSample, m, h, fb) -> np.ndarray:
        """u at the largest feasible s in [0, 1] (bisection), or at s = 0 when even that is beyond a limit."""
        def torque(s: float) -> np.ndarray:
            v = ref.acceleration_rad_s2 + s * fb
            return m @ v + h + self.plant.step_friction_torque(x2, v)

        u = torque(0.0)
        if not self._within(u):
            self.last_scale = 0.0
            return u
        lo, hi = 0.0, 1.0
        for _ in range(_BISECTIONS):
            mid = 0.5 * (lo + hi)
            u_mid = torque(mid)
            if self._within(u_mid):
                lo, u = mid, u_mid
            else:
                hi = mid
        self.last_scale = lo
        return u
