"""The study's scenarios: each one a change of the plant or reference settings, and/or what the
in-process loop adds between plant and controllers (sensor noise, a torque delay).

The controllers keep the configuration tuned for the nominal arm in every scenario.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..config import ConfigError
from ..derived_settings import check_reference
from ..settings import Settings, replace_in
from ..sim.closed_loop import Disturbances

COULOMB_FRACTION = 0.05  # Coulomb friction of every joint: 5 % of its torque limit (a stated value, not an arm's)


@dataclass(frozen=True)
class Scenario:
    name: str
    description: str
    edit: Callable[[Settings], Settings] | None = None          # the changed settings (validated again)
    disturbances: Callable[[int], Disturbances] | None = None   # seed -> what the loop adds


def _payload(kg: float) -> Callable[[Settings], Settings]:
    def edit(settings: Settings) -> Settings:
        return replace_in(settings, "plant.payload_kg", kg)
    return edit


def _links_heavier(settings: Settings) -> Settings:
    return replace_in(settings, "plant.link_mass_scale", 1.3)


def _coulomb(settings: Settings) -> Settings:
    return replace_in(settings, "plant.coulomb_nm", tuple(COULOMB_FRACTION * x for x in settings.plant.torque_limit_nm))


def _fast_reference(settings: Settings) -> Settings:
    return replace_in(settings, "reference.frequency_rad_s", tuple(1.5 * w for w in settings.reference.frequency_rad_s))


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
    Scenario("fast_reference", "reference frequencies x1.5", _fast_reference),
)}


def check_scenario_references(settings: Settings, scenarios) -> None:
    """Each of ``scenarios``' references checked as a config's own is (``derived_settings.check_reference``: the
    frequency below the Nyquist rate pi / T, the envelope rate, amplitude and centre bounded), before any run: a
    scenario edits typed settings (``replace_in``), which check each value's kind and range but not these bounds
    (fast_reference's x1.5 could put a frequency past pi / T). ConfigError naming the scenario."""
    for name in scenarios:
        changed, _ = scenario_settings(settings, name, 0)
        try:
            check_reference(changed.arm, changed.to_config())
        except ConfigError as exc:
            raise ConfigError(f"scenario {name} ({SCENARIOS[name].description}): {exc}") from None


def scenario_settings(settings: Settings, scenario: str, seed: int) -> tuple[Settings, Disturbances | None]:
    """(the settings of ``scenario`` with simulation.seed = ``seed``, its disturbances)."""
    s = SCENARIOS[scenario]
    out = replace_in(settings, "simulation.seed", seed)
    if s.edit is not None:
        out = s.edit(out)
    return out, (s.disturbances(seed) if s.disturbances is not None else None)
