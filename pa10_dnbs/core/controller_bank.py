"""What a bank of joint controllers is: the one interface the loop, the nodes, the study and the tuner use.

A bank holds n joint controllers, one row each (a node's bank holds its one joint, the in-process loop's all
of them); a row's arithmetic does not depend on the others. Per step a caller asks for the torques
(``answer``), sends them out, then lets the bank train on them (``learn``): a learning controller (DNBS) keeps
its training off the path from a state to its torque; a fixed one (PID, computed torque) has nothing to learn.
``step`` is the two at once. Arrays have shape (n,): x1 [rad], x2 [rad/s], torques [N m].
"""
from __future__ import annotations

from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

from .reference import ReferenceSample


@runtime_checkable
class ControllerBank(Protocol):
    """A bank of n joint controllers (numpy only; DNBSControllers, PIDControllers, computed torque)."""

    #: True when the bank learns (its ``state_dict`` is worth a checkpoint), False for fixed gains
    learns: ClassVar[bool]

    @property
    def n_joints(self) -> int:
        """n, the rows of the bank."""

    @property
    def learning_pending(self) -> bool:
        """True between an ``answer`` and its ``learn`` (never for a bank that does not learn)."""

    def answer(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample,
               active: np.ndarray | None = None) -> np.ndarray:
        """The torques (n,) [N m] for x1 (n,) [rad], x2 (n,) [rad/s]; a row whose ``active`` is 0.0 is not to
        be trained on (its state was not trusted; its inputs are finite stand-ins)."""

    def learn(self) -> None:
        """Train on the last ``answer`` (a no-op when nothing is pending or the bank does not learn)."""

    def step(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample,
             active: np.ndarray | None = None) -> np.ndarray:
        """``answer`` then ``learn``."""

    def state_dict(self, row: int = 0) -> dict[str, np.ndarray]:
        """Row ``row``'s learned state, what a checkpoint holds ({} for a bank that does not learn)."""

    def counters(self, row: int = 0) -> dict[str, int]:
        """Row ``row``'s event counters for the run's report (DNBS: its EKF resets; {} for a fixed bank)."""


class FixedGainBank:
    """What every bank that does not learn (PID, computed torque) shares: ``step`` is ``answer``, nothing to
    learn, no learned state, no events. A subclass defines ``answer`` and ``n_joints``."""

    learns = False
    learning_pending = False

    def step(self, x1: np.ndarray, x2: np.ndarray, ref: ReferenceSample,
             active: np.ndarray | None = None) -> np.ndarray:
        """``answer`` (the subclass's; nothing to learn)."""
        return self.answer(x1, x2, ref, active)

    def learn(self) -> None:
        """Nothing to learn."""

    def state_dict(self, row: int = 0) -> dict[str, np.ndarray]:
        """No learned state: {}."""
        return {}

    def counters(self, row: int = 0) -> dict[str, int]:
        """No events to count: {}."""
        return {}
