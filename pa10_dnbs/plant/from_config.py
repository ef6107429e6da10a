"""Build the PyBullet plant and its initial state from a run's typed settings."""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from ..arm import Arm
from ..interrupt import deferred
from ..settings import PlantSettings, ReferenceSettings, RunSettings, Settings
from .plant_params import PlantParams
from .pybullet_plant import PyBulletArmPlant
from .quiet_stdout import quiet_c_stdout


def open_client(gui: bool = False):
    """A private PyBullet client (pybullet_utils BulletClient): DIRECT unless the GUI is asked for.

    A Ctrl-C meanwhile is raised once the client is whole (``interrupt.deferred``): one interrupted inside its
    ``__init__`` leaves an object whose ``__del__`` prints a traceback when it is collected."""
    with deferred(), quiet_c_stdout():
        import pybullet
        from pybullet_utils.bullet_client import BulletClient

        return BulletClient(connection_mode=pybullet.GUI if gui else pybullet.DIRECT)


@contextmanager
def opened_plant(arm: Arm, params: PlantParams):
    """``with opened_plant(arm, params) as plant``: the arm on PyBullet with ``params`` on a private client,
    released on leaving (for what is read off the model before a run: the rules, a scenario's torque)."""
    client = open_client()
    try:
        yield PyBulletArmPlant(client, arm, params)
    finally:
        client.disconnect()


def plant_from_settings(settings: Settings, client) -> PyBulletArmPlant:
    """The settings' arm on PyBullet with ``settings.plant``, reset to the configured initial state."""
    plant = PyBulletArmPlant(client, settings.arm, plant_params(settings.plant, settings.simulation.dt_s))
    plant.reset(*initial_state(settings.simulation, settings.reference))
    return plant


def plant_params(plant: PlantSettings, dt_s: float) -> PlantParams:
    """The plant's parameters from the ``plant`` section (the arm's facts resolved into it) and the step
    ``dt_s`` [s]: either engine's."""
    return PlantParams(
        dt_s=dt_s,
        gravity_mps2=plant.gravity_mps2,
        rotor_inertia_kgm2=plant.rotor_inertia_kgm2,
        viscous_nms_per_rad=plant.viscous_nms_per_rad,
        coulomb_nm=plant.coulomb_nm,
        coulomb_smoothing_rad_s=plant.coulomb_smoothing_rad_s,
        torque_limit_nm=plant.torque_limit_nm,
        payload_kg=plant.payload_kg,
        link_mass_scale=plant.link_mass_scale,
    )


def arm_plant_params(arm: Arm, **changes) -> PlantParams:
    """The arm file's facts (rotor inertia, friction, torque limits) as plant parameters, with ``changes``
    (PlantParams fields): for a tool or a test that runs an arm without a config; a run's plant takes its
    settings' ``plant`` section (:func:`plant_params`)."""
    facts = {"rotor_inertia_kgm2": arm.rotor_inertia_kgm2, "viscous_nms_per_rad": arm.viscous_nms_per_rad,
             "coulomb_nm": arm.coulomb_nm, "torque_limit_nm": arm.torque_limit_nm}
    return PlantParams(**{**{k: tuple(float(x) for x in v) for k, v in facts.items()}, **changes})


def initial_state(run: RunSettings, reference: ReferenceSettings) -> tuple[np.ndarray, np.ndarray]:
    """x1(0) = x_d(0) + offset (x_d(0) = the reference's centre for eq. 27: 0 on the PA10), x2(0) = the
    configured velocity; (n,) each."""
    q0 = np.array(run.initial_position_offset_rad, float)
    centre = np.array(reference.centre_rad, float)
    if np.any(centre != 0.0):
        q0 = centre + q0
    return q0, np.array(run.initial_velocity_rad_s, float)
