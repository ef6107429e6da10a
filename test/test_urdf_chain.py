"""URDF forward kinematics (the /tf the recorder writes) against PyBullet's link frames."""

import math
from pathlib import Path

import numpy as np
import pybullet
import pytest
from pybullet_utils.bullet_client import BulletClient

from pa10_dnbs.kinematics.urdf_chain import UrdfChain, axis_angle_matrix, matrix_quaternion, rpy_matrix

URDF = Path(__file__).resolve().parents[1] / "urdf" / "pa10" / "pa10_7ce.urdf"
JOINTS = ("s1", "s2", "s3", "e1", "e2", "w1", "w2")


def test_chain_structure():
    chain = UrdfChain.from_file(URDF)
    assert [j.name for j in chain.movable] == list(JOINTS)
    assert chain.root_link == "base_link"
    assert [(t.parent, t.child) for t in chain.fixed_transforms()] == [("link7", "flange")]


def test_zero_pose_flange_height():
    """Arm straight up: the flange sits at 1.345 m (facts sheet), whatever the roll joints do."""
    chain = UrdfChain.from_file(URDF)
    pos, _ = chain.link_poses({"s1": 0.7, "s3": -1.1, "e2": 2.0, "w2": 0.4})["flange"]
    np.testing.assert_allclose(pos, [0.0, 0.0, 1.345], atol=1e-12)


def test_quaternion_round_trip():
    rng = np.random.default_rng(3)
    for _ in range(200):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle = rng.uniform(-math.pi, math.pi)
        x, y, z, w = matrix_quaternion(axis_angle_matrix(axis, angle))
        assert w >= 0 and abs(x * x + y * y + z * z + w * w - 1) < 1e-12
        half = angle / 2
        expected = np.sign(math.cos(half) or 1.0) * np.r_[axis * math.sin(half), math.cos(half)]
        np.testing.assert_allclose([x, y, z, w], expected, atol=1e-12)
    np.testing.assert_allclose(rpy_matrix(0.0, 0.0, math.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-15)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_link_frames_match_pybullet(seed):
    """Every link frame, composed from our per-joint transforms, equals PyBullet's URDF link frame."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.5, 1.5, size=7)
    chain = UrdfChain.from_file(URDF)
    poses = chain.link_poses(dict(zip(JOINTS, q)))
    client = BulletClient(connection_mode=pybullet.DIRECT)
    try:
        body = client.loadURDF(str(URDF), useFixedBase=True, flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        names = {}
        for i in range(client.getNumJoints(body)):
            info = client.getJointInfo(body, i)
            names[info[12].decode()] = i
            if info[1].decode() in JOINTS:
                client.resetJointState(body, i, float(q[JOINTS.index(info[1].decode())]))
        for link, idx in names.items():
            st = client.getLinkState(body, idx, computeForwardKinematics=True)
            pos, orn = np.array(st[4]), st[5]  # URDF link frame (not the CoM frame)
            rot = np.array(client.getMatrixFromQuaternion(orn)).reshape(3, 3)
            np.testing.assert_allclose(poses[link][0], pos, atol=1e-6, err_msg=link)  # PyBullet keeps link frames partly in float32
            np.testing.assert_allclose(poses[link][1], rot, atol=1e-6, err_msg=link)  # PyBullet keeps link frames partly in float32
    finally:
        client.disconnect()


def test_moving_transforms_equal_the_matrix_route():
    """The quaternion-product fast path of moving_transforms gives the rotations of origin_rot @ R(axis, q)."""
    chain = UrdfChain.from_file(URDF)
    rng = np.random.default_rng(5)
    for _ in range(100):
        q = dict(zip(JOINTS, rng.uniform(-math.pi, math.pi, 7)))
        for got, j in zip(chain.moving_transforms(q), chain.movable):
            want = UrdfChain._transform(j, q[j.name])
            assert (got.parent, got.child, got.translation_m) == (want.parent, want.child, want.translation_m)
            sign = 1.0 if np.dot(got.rotation_xyzw, want.rotation_xyzw) >= 0 else -1.0  # w = 0: either sign
            np.testing.assert_allclose(np.array(got.rotation_xyzw), sign * np.array(want.rotation_xyzw), atol=1e-14)
            assert got.rotation_xyzw[3] >= 0
