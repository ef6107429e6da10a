"""The study's scenarios: each one a change of the plant or reference in the config, and/or what the
in-process loop adds between plant and controllers (sensor noise, a torque delay).

The controllers keep the configuration tuned for the nominal arm in every scenario.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Callable

from ..sim.closed_loop import Disturbances

COULOMB_FRACTION = 0.05  # Coulomb friction of every joint: 5 % of its torque limit (none is published for the PA10)


@dataclass(frozen=True)
class Scenario:
    name: str
    description: str
    edit: Callable[[dict], None] | None = None                  # changes a deep copy of the config in place
    disturbances: Callable[[int], Disturbances] | None = None   # seed -> what the loop adds


def _payload(kg: float) -> Callable[[dict], None]:
    def edit(cfg: dict) -> None:
        cfg["plant"]["payload_kg"] = kg
    return edit


def _links_heavier(cfg: dict) -> None:
    cfg["plant"]["link_mass_scale"] = 1.3


def _coulomb(cfg: dict) -> None:
    cfg["plant"]["coulomb_nm"] = tuple(COULOMB_FRACTION * x for x in cfg["plant"]["torque_limit_nm"])


def _fast_reference(cfg: dict) -> None:
    cfg["reference"]["frequency_rad_s"] = tuple(1.5 * w for w in cfg["reference"]["frequency_rad_s"])


SCENARIOS = {s.name: s for s in (
    Scenario("nominal", "the default config"),
    Scenario("payload_2kg", "2 kg point mass at the flange link", _payload(2.0)),
    Scenario("payload_5kg", "5 kg point mass at the flange link", _payload(5.0)),
    Scenario("links_heavier_30pct", "every link's mass and inertia +30 % (rotors unchanged)", _links_heavier),
    Scenario("encoder_noise", "white noise on what the controllers see: 1e-4 rad on x1, 1e-3 rad/s on x2",
             disturbances=lambda seed: Disturbances(1e-4, 1e-3, 0, seed)),
    Scenario("delay_1_tick", "every torque applied one step (1 ms) late",
             disturbances=lambda seed: Disturbances(torque_delay_steps=1)),
    Scenario("coulomb", f"Coulomb friction {COULOMB_FRACTION:.0%} of the torque limit on every joint", _coulomb),
    Scenario("fast_reference", "Table 1 frequencies x1.5", _fast_reference),
)}


def scenario_config(cfg: dict, scenario: str, seed: int) -> tuple[dict, Disturbances | None]:
    """(the config of ``scenario`` with simulation.seed = ``seed``, its disturbances)."""
    s = SCENARIOS[scenario]
    out = copy.deepcopy(cfg)
    out["simulation"]["seed"] = seed
    if s.edit is not None:
        s.edit(out)
    return out, (s.disturbances(seed) if s.disturbances is not None else None)
