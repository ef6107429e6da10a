"""PA10-7C(E) plant backed by PyBullet (the only module that imports pybullet)."""

from pa10_dnbs.plant.quiet_stdout import quiet_c_stdout

with quiet_c_stdout():
    import pybullet  # noqa: F401  (prints its build time on stdout at import)

from pa10_dnbs.plant.pybullet_plant import (  # noqa: E402
    COULOMB_NM,
    N_JOINTS,
    ROTOR_INERTIA_KGM2,
    TORQUE_LIMIT_NM,
    VISCOUS_NMS_PER_RAD,
    PlantParams,
    PyBulletPA10Plant,
)

__all__ = [
    "COULOMB_NM",
    "N_JOINTS",
    "ROTOR_INERTIA_KGM2",
    "TORQUE_LIMIT_NM",
    "VISCOUS_NMS_PER_RAD",
    "PlantParams",
    "PyBulletPA10Plant",
]
