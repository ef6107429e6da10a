"""A simulated robot's side of the standard robot interface (docs/your_robot.md), without ROS: which command a
state takes, and when the plant steps.

- lockstep: state k (stamp k T) is out; the command stamped k T steps the plant once (to k + 1); a command with
  another stamp is ignored (counted as ``stale``).
- paced: every tick steps the plant with the latest command (zero effort before the first one).

A command is the arm's efforts [N m] in chain order (the node matches them by joint name); a non-finite one
is refused whole (``refused``, the robot keeps the effort it had). The plant saturates at the torque limits.
"""
from __future__ import annotations

import math

import numpy as np

from ..wire.steps import StepClock

MODES = ("lockstep", "paced")


class RobotStepper:
    """``plant``: an arm plant (``step``, ``state``, ``applied_torque_nm``, ``n_joints``); ``mode``: lockstep or
    paced; ``dt_s``: the plant's step [s]."""

    def __init__(self, plant, mode: str, dt_s: float):
        if mode not in MODES:
            raise ValueError(f"mode: must be one of {', '.join(MODES)}, got {mode!r}")
        self.plant = plant
        self.mode = mode
        self.clock = StepClock(dt_s)
        self.step = 0  # the state that is out (its stamp: clock.ns(step))
        self._latest = np.zeros(plant.n_joints)  # paced: the effort applied at every tick [N m]
        self.commands = 0  # commands taken
        self.stale = 0  # lockstep: commands stamped for another state than the current one
        self.refused = 0  # commands with a non-finite effort

    @property
    def stamp_ns(self) -> int:
        """The current state's stamp [ns] (robot time k T)."""
        return self.clock.ns(self.step)

    def offer(self, stamp_ns: int, efforts) -> bool:
        """A command (``efforts`` (n,) N m, chain order) stamped ``stamp_ns``; True when it stepped the plant
        (lockstep: the current state's answer)."""
        u = np.asarray(efforts, dtype=float)
        if not all(math.isfinite(x) for x in u.tolist()):
            self.refused += 1
            return False
        if self.mode == "paced":
            self._latest = u
            self.commands += 1
            return False
        if stamp_ns != self.stamp_ns:
            self.stale += 1
            return False
        self.commands += 1
        self._advance(u)
        return True

    def tick(self) -> None:
        """Paced: one step with the latest command."""
        if self.mode != "paced":
            raise RuntimeError("tick: only in paced mode (lockstep steps on its command)")
        self._advance(self._latest)

    def _advance(self, u: np.ndarray) -> None:
        self.plant.step(u)
        self.step += 1
