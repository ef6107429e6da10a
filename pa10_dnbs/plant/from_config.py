"""Build the PyBullet plant and its initial state from a run's typed settings."""
from __future__ import annotations

import numpy as np

from ..interrupt import deferred
from ..settings import Settings
from .pybullet_plant import PlantParams, PyBulletArmPlant
from .quiet_stdout import quiet_c_stdout


def open_client(gui: bool = False):
    """A private PyBullet client (pybullet_utils BulletClient): DIRECT unless the GUI is asked for.

    A Ctrl-C meanwhile is raised once the client is whole (``interrupt.deferred``): one interrupted inside its
    ``__init__`` leaves an object whose ``__del__`` prints a traceback when it is collected."""
    with deferred(), quiet_c_stdout():
        import pybullet
        from pybullet_utils.bullet_client import BulletClient

        return BulletClient(connection_mode=pybullet.GUI if gui else pybullet.DIRECT)


def plant_from_settings(settings: Settings, client) -> PyBulletArmPlant:
    """The settings' arm on PyBullet with ``settings.plant``, reset to the configured initial state."""
    plant = PyBulletArmPlant(client, settings.arm, plant_params(settings))
    q0, qd0 = initial_state(settings)
    plant.reset(q0, qd0)
    return plant


def plant_params(settings: Settings) -> PlantParams:
    """The plant's parameters (``plant`` section, ``simulation.dt_s``): either engine's."""
    p = settings.plant
    return PlantParams(
        dt_s=settings.simulation.dt_s,
        gravity_mps2=p.gravity_mps2,
        rotor_inertia_kgm2=p.rotor_inertia_kgm2,
        viscous_nms_per_rad=p.viscous_nms_per_rad,
        coulomb_nm=p.coulomb_nm,
        coulomb_smoothing_rad_s=p.coulomb_smoothing_rad_s,
        torque_limit_nm=p.torque_limit_nm,
        payload_kg=p.payload_kg,
        link_mass_scale=p.link_mass_scale,
    )


def initial_state(settings: Settings) -> tuple[np.ndarray, np.ndarray]:
    """x1(0) = x_d(0) + offset (x_d(0) = the reference's centre for eq. 27: 0 on the PA10), x2(0) = the
    configured velocity; (n,) each."""
    sim = settings.simulation
    q0 = np.array(sim.initial_position_offset_rad, float)
    centre = np.array(settings.reference.centre_rad, float)
    if np.any(centre != 0.0):
        q0 = centre + q0
    return q0, np.array(sim.initial_velocity_rad_s, float)
