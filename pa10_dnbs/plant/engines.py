"""Which physics engine runs the plant: PyBullet (the project's own plant, the default) or MuJoCo (an independent
second engine, ``mujoco_plant.py``). Both take the same config and give the same Python interface."""
from __future__ import annotations

from typing import Callable

from ..arm import Arm, arm_of
from .from_config import initial_state, open_client, plant_from_config, plant_params

ENGINES = ("pybullet", "mujoco")
DEFAULT_ENGINE = "pybullet"


def open_plant(cfg: dict, engine: str = DEFAULT_ENGINE, arm: Arm | None = None) -> tuple[object, Callable[[], None]]:
    """(the arm's plant on ``engine``, reset to the configured initial state; the call that releases it).

    ``cfg``: a validated config (its ``plant`` section and ``simulation.dt_s``); ``arm``: the config's own
    when None. ValueError naming the engine when it is not one of ``ENGINES``."""
    if engine == "pybullet":
        client = open_client()
        try:
            return plant_from_config(cfg, client, arm), client.disconnect
        except BaseException:
            client.disconnect()
            raise
    if engine == "mujoco":
        from .mujoco_plant import MuJoCoArmPlant

        plant = MuJoCoArmPlant(arm_of(cfg) if arm is None else arm, plant_params(cfg))
        plant.reset(*initial_state(cfg))
        return plant, plant.close
    raise ValueError(f"engine: must be one of {', '.join(ENGINES)}, got {engine!r}")
