"""ament_python / setuptools build of pa10_dnbs (dependencies are pinned in requirements.txt)."""
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "pa10_dnbs"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
        (f"share/{PACKAGE}/urdf", glob("urdf/*.urdf") + glob("urdf/*.md")),
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
        ],
    },
)
