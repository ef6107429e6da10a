"""The UR5 URDF docs/arms.md's "Bring your own arm" walks (test/fixtures/byo_arm/) is example-robot-data's, as
shipped: its pinned hash, and the collection's own file where the collection is installed."""
import hashlib
from pathlib import Path

import pytest

from pa10_dnbs.arm.package_uri import PackageNotFound, resolve_package_uri

FIXTURE = Path(__file__).resolve().parent / "fixtures" / "byo_arm" / "ur5_joint_limited_robot.urdf"
SHA256 = "8b8daa5ee444419b44da46bbb994a4e7d41b496d2caa5c4bf996d1cd5706ba64"  # example-robot-data 6.0.0's file


def test_the_walkthroughs_ur5_is_the_collections_file_byte_for_byte():
    assert hashlib.sha256(FIXTURE.read_bytes()).hexdigest() == SHA256
    try:
        shipped = resolve_package_uri("package://example-robot-data/robots/ur_description/urdf/"
                                      "ur5_joint_limited_robot.urdf")
    except PackageNotFound:
        pytest.skip("example-robot-data is not installed (requirements-collection.txt)")
    assert shipped.read_bytes() == FIXTURE.read_bytes()
