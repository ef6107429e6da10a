"""The arm's model: the PyBullet plant (the only module that imports pybullet), the MuJoCo plant, their shared
parameters and checks, the rules' tools (inertia sweep, reference torque); the plant node is ros/plant/."""

from pa10_dnbs.plant.quiet_stdout import quiet_c_stdout

with quiet_c_stdout():
    import pybullet  # noqa: F401  (prints its build time on stdout at import)

from pa10_dnbs.plant.plant_params import PlantParams  # noqa: E402
from pa10_dnbs.plant.pybullet_plant import PyBulletArmPlant  # noqa: E402

__all__ = ["PlantParams", "PyBulletArmPlant"]
