"""Which physics engine runs the plant: PyBullet (the project's own plant, the default) or MuJoCo (an independent
second engine, ``mujoco_plant.py``). Both take the same config and give the same Python interface."""
from __future__ import annotations

from typing import Callable

from ..settings import Settings
from .from_config import initial_state, open_client, plant_from_settings, plant_params

ENGINES = ("pybullet", "mujoco")
DEFAULT_ENGINE = "pybullet"


def open_plant(settings: Settings, engine: str = DEFAULT_ENGINE) -> tuple[object, Callable[[], None]]:
    """(the settings' arm on ``engine`` with ``settings.plant``, reset to the configured initial state; the call
    that releases it).

    ValueError naming the engine when it is not one of ``ENGINES``."""
    if engine not in ENGINES:
        raise ValueError(f"engine: must be one of {', '.join(ENGINES)}, got {engine!r}")
    if engine == "mujoco":
        from .mujoco_plant import MuJoCoArmPlant

        plant = MuJoCoArmPlant(settings.arm, plant_params(settings.plant, settings.simulation.dt_s))
        plant.reset(*initial_state(settings.simulation, settings.reference))
        return plant, plant.close
    client = open_client()
    try:
        return plant_from_settings(settings, client), client.disconnect
    except BaseException:
        client.disconnect()
        raise
