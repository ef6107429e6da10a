"""ament_python / setuptools build of pa10_dnbs (dependencies are pinned in requirements.txt)."""
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "pa10_dnbs"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    package_data={"pa10_dnbs.accel": ["dnbs_kernel.c"]},  # compiled on first use (pa10_dnbs/accel/build.py)
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml") + glob("config/*.json")),
        (f"share/{PACKAGE}/urdf", glob("urdf/*.md")),
        *((f"share/{PACKAGE}/{d}", glob(f"{d}/*.urdf") + glob(f"{d}/*.yaml") + glob(f"{d}/*.md"))
          for d in sorted(p.rstrip("/") for p in glob("urdf/*/"))),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="pa10_dnbs developers",
    maintainer_email="dev@pa10-dnbs.local",
    description="Decentralized neural backstepping control of a simulated PA10-7CE arm.",
    license="Apache-2.0",
    python_requires=">=3.11,<3.12",
    entry_points={
        "console_scripts": [
            "pa10-dnbs = pa10_dnbs.cli:main",
            "plant_node = pa10_dnbs.ros.plant.node:main",
            "joint_controller_node = pa10_dnbs.ros.joint_controller_node:main",
            "reference_node = pa10_dnbs.ros.reference_node:main",
            "wire_monitor = pa10_dnbs.ros.wire_monitor:main",
            "recorder_node = pa10_dnbs.ros.recorder_node:main",
            "live_observer_node = pa10_dnbs.ros.live_observer_node:main",
            "joint_bus_node = pa10_dnbs.ros.joint_bus_node:main",
        ],
    },
)
