"""Arm presets urdf/iiwa and urdf/panda: the data files alone (PyBullet + numpy + yaml, no project code).

Checks that each preset's URDF loads the way the plant loads it (fixed base, inertia from the file),
that its chain and the YAML agree, that every link inertia is physically possible, that the total
mass is the manufacturer's, that M(q) + diag(rotor) is positive definite across the joint ranges,
and that gravity alone never needs more than the torque limits. Run with ``-s`` to see the numbers
(gravity-to-limit ratios, effective-inertia ranges) that the controllers' gains depend on.
"""

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet
import pytest
import yaml
from pybullet_utils.bullet_client import BulletClient

URDF_DIR = Path(__file__).resolve().parents[1] / "urdf"
G = 9.81

# Typed in from the manufacturers' data (see each preset's README.md), not read from the files.
EXPECTED = {
    "iiwa": dict(
        joints=("a1", "a2", "a3", "a4", "a5", "a6", "a7"),
        torque_nm=(320.0, 320.0, 176.0, 176.0, 110.0, 40.0, 40.0),
        limit_deg=((-170, 170), (-120, 120), (-170, 170), (-120, 120), (-170, 170), (-120, 120), (-175, 175)),
        total_mass_kg=29.5,   # KUKA data sheet: arm incl. base, no tool
        payload_kg=14.0,      # rated payload
    ),
    "panda": dict(
        joints=tuple(f"panda_joint{i}" for i in range(1, 8)),
        torque_nm=(87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0),
        limit_deg=tuple((math.degrees(lo), math.degrees(hi)) for lo, hi in (
            (-2.8973, 2.8973), (-1.7628, 1.7628), (-2.8973, 2.8973), (-3.0718, -0.0698),
            (-2.8973, 2.8973), (-0.0175, 3.7525), (-2.8973, 2.8973))),
        total_mass_kg=18.0,   # Franka data sheet: arm ~17.3-18 kg plus hand ~0.7 kg; "about 18 kg"
        payload_kg=3.0,       # rated payload
    ),
}
MASS_TOLERANCE = 0.05
N_RANDOM = 500


def _load_preset(name):
    yaml_path = URDF_DIR / name / "arm.yaml"
    cfg = yaml.safe_load(yaml_path.read_text())
    return cfg, yaml_path.parent / cfg["urdf"]


@pytest.fixture(params=sorted(EXPECTED))
def preset(request):
    name = request.param
    cfg, urdf = _load_preset(name)
    client = BulletClient(connection_mode=pybullet.DIRECT)
    client.setGravity(0, 0, -G)
    body = client.loadURDF(str(urdf), useFixedBase=True, flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
    yield dict(name=name, cfg=cfg, urdf=urdf, client=client, body=body)
    client.disconnect()


def _revolute(preset):
    c, b = preset["client"], preset["body"]
    return [j for j in range(c.getNumJoints(b)) if c.getJointInfo(b, j)[2] == pybullet.JOINT_REVOLUTE]


def _limits(preset):
    c, b = preset["client"], preset["body"]
    info = [c.getJointInfo(b, j) for j in _revolute(preset)]
    return np.array([i[8] for i in info]), np.array([i[9] for i in info])


def _random_poses(preset, n, seed):
    lo, hi = _limits(preset)
    return np.random.default_rng(seed).uniform(lo, hi, size=(n, len(lo)))


def _mass_matrix(preset, q):
    return np.array(preset["client"].calculateMassMatrix(preset["body"], list(map(float, q))))


def _gravity(preset, q):
    n = len(q)
    return np.array(preset["client"].calculateInverseDynamics(
        preset["body"], list(map(float, q)), [0.0] * n, [0.0] * n))


def test_yaml_format_and_chain(preset):
    """7 revolute joints in chain order, named as expected; YAML lists match them and the URDF's efforts."""
    cfg, c, b = preset["cfg"], preset["client"], preset["body"]
    exp = EXPECTED[preset["name"]]
    assert cfg["name"] == preset["name"]
    assert cfg["exclude_joints"] == []
    assert set(cfg["sources"]) == {"urdf", "torque_limit_nm", "rotor_inertia_kgm2", "viscous_nms_per_rad",
                                   "coulomb_nm"}
    rev = _revolute(preset)
    names = tuple(c.getJointInfo(b, j)[1].decode() for j in rev)
    assert names == exp["joints"]
    # chain order: each revolute joint's parent link is the previous revolute joint's child link
    for prev, nxt in zip(rev, rev[1:]):
        assert c.getJointInfo(b, nxt)[16] == prev
    for key in ("torque_limit_nm", "rotor_inertia_kgm2", "viscous_nms_per_rad", "coulomb_nm"):
        assert len(cfg[key]) == len(rev), key
        assert all(isinstance(v, float) and v >= 0.0 for v in cfg[key]), key
    assert all(v > 0.0 for v in cfg["rotor_inertia_kgm2"])
    np.testing.assert_array_equal(cfg["torque_limit_nm"], exp["torque_nm"])
    efforts = [c.getJointInfo(b, j)[10] for j in rev]
    np.testing.assert_allclose(efforts, exp["torque_nm"])
    lo, hi = _limits(preset)
    np.testing.assert_allclose(np.degrees(lo), [d[0] for d in exp["limit_deg"]], atol=1e-6)
    np.testing.assert_allclose(np.degrees(hi), [d[1] for d in exp["limit_deg"]], atol=1e-6)
    assert all(c.getJointInfo(b, j)[11] > 0.0 for j in rev)   # velocity limits present


def test_flange_link_is_massless_and_after_the_last_joint(preset):
    cfg, c, b = preset["cfg"], preset["client"], preset["body"]
    links = {c.getJointInfo(b, j)[12].decode(): j for j in range(c.getNumJoints(b))}
    flange = links[cfg["flange_link"]]
    assert c.getJointInfo(b, flange)[2] == pybullet.JOINT_FIXED
    assert c.getJointInfo(b, flange)[16] == _revolute(preset)[-1]
    assert c.getDynamicsInfo(b, flange)[0] == 0.0


def _file_inertias(urdf):
    out = {}
    for link in ET.parse(urdf).getroot().iter("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        m = float(inertial.find("mass").get("value"))
        a = {k: float(inertial.find("inertia").get(k)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        tensor = np.array([[a["ixx"], a["ixy"], a["ixz"]], [a["ixy"], a["iyy"], a["iyz"]],
                           [a["ixz"], a["iyz"], a["izz"]]])
        out[link.get("name")] = (m, tensor)
    return out


def test_link_inertias_physical_and_read_by_pybullet(preset):
    """Positive definite, triangle inequality, and PyBullet's principal moments equal the file's."""
    c, b = preset["client"], preset["body"]
    index = {c.getJointInfo(b, j)[12].decode(): j for j in range(c.getNumJoints(b))}
    index[c.getBodyInfo(b)[0].decode()] = -1
    for name, (m, tensor) in _file_inertias(preset["urdf"]).items():
        if m == 0.0:
            assert not tensor.any(), name
            continue
        ev = np.linalg.eigvalsh(tensor)
        assert ev.min() > 0.0, name
        assert ev[0] + ev[1] >= ev[2] * (1 - 1e-9), name      # triangle inequality (sorted principal moments)
        if index[name] == -1:
            continue                                           # a fixed base reads back as mass 0
        dyn = c.getDynamicsInfo(b, index[name])
        assert dyn[0] == pytest.approx(m, rel=1e-12), name
        np.testing.assert_allclose(np.sort(dyn[2]), ev, rtol=1e-6, atol=1e-12, err_msg=name)


def test_total_mass_is_the_manufacturers(preset):
    """Base included (from the file: PyBullet reports a fixed base's mass as 0)."""
    c, b = preset["client"], preset["body"]
    masses = {name: m for name, (m, _) in _file_inertias(preset["urdf"]).items()}
    moving = sum(c.getDynamicsInfo(b, j)[0] for j in range(c.getNumJoints(b)))
    base = masses[c.getBodyInfo(b)[0].decode()]
    assert moving + base == pytest.approx(sum(masses.values()), rel=1e-12)
    total = moving + base
    expected = EXPECTED[preset["name"]]["total_mass_kg"]
    print(f"\n{preset['name']}: total mass {total:.3f} kg, data sheet {expected} kg ({total / expected - 1:+.1%})")
    assert abs(total / expected - 1.0) < MASS_TOLERANCE


def test_mass_matrix_with_rotor_positive_definite(preset):
    rotor = np.array(preset["cfg"]["rotor_inertia_kgm2"])
    worst = np.inf
    for q in _random_poses(preset, 100, seed=1):
        m = _mass_matrix(preset, q)
        np.testing.assert_allclose(m, m.T, atol=1e-12)
        assert np.linalg.eigvalsh(m).min() > 0.0
        worst = min(worst, np.linalg.eigvalsh(m + np.diag(rotor)).min())
    assert worst > 0.0


def _worst_gravity(preset, seed):
    """Largest |g_j(q)| per joint over random poses, each refined by a coordinate search within the limits."""
    lo, hi = _limits(preset)
    poses = _random_poses(preset, N_RANDOM, seed)
    grav = np.array([np.abs(_gravity(preset, q)) for q in poses])
    worst = np.zeros(len(lo))
    for j in range(len(lo)):
        q = poses[np.argmax(grav[:, j])].copy()
        best = abs(_gravity(preset, q)[j])
        for _ in range(3):
            for k in range(len(lo)):
                for v in np.linspace(lo[k], hi[k], 25):
                    trial = q.copy()
                    trial[k] = v
                    val = abs(_gravity(preset, trial)[j])
                    if val > best:
                        best, q = val, trial
        worst[j] = best
    return worst


def test_gravity_below_torque_limits(preset):
    limit = np.array(preset["cfg"]["torque_limit_nm"])
    worst = _worst_gravity(preset, seed=2)
    ratio = worst / limit
    print(f"\n{preset['name']}: worst |gravity torque| [N m] {np.round(worst, 2).tolist()}")
    print(f"{preset['name']}: ratio to the torque limit   {np.round(ratio, 3).tolist()}")
    assert np.all(ratio < 1.0)


def test_effective_inertia_range(preset):
    """J_eff,j(q) = 1 / [(M(q) + diag(rotor))^-1]_jj, the inertia joint j feels with the others free."""
    rotor = np.array(preset["cfg"]["rotor_inertia_kgm2"])
    with_r, without_r = [], []
    for q in _random_poses(preset, N_RANDOM, seed=3):
        m = _mass_matrix(preset, q)
        with_r.append(1.0 / np.diag(np.linalg.inv(m + np.diag(rotor))))
        without_r.append(1.0 / np.diag(np.linalg.inv(m)))
    with_r, without_r = np.array(with_r), np.array(without_r)
    for label, arr in (("with rotor", with_r), ("links only", without_r)):
        lo_, hi_ = arr.min(axis=0), arr.max(axis=0)
        print(f"\n{preset['name']} J_eff {label} [kg m^2], {N_RANDOM} poses:")
        for j in range(arr.shape[1]):
            print(f"  joint {j + 1}: min {lo_[j]:.5g}  max {hi_[j]:.5g}  max/min {hi_[j] / lo_[j]:.3g}")
    assert np.all(with_r.min(axis=0) >= rotor * (1 - 1e-9))     # the rotor is always felt in full
    assert np.all(with_r > without_r)


def test_gravity_with_rated_payload_below_torque_limits(preset):
    """The rated payload as a point mass on the flange link still leaves every joint within its limit."""
    c, b, cfg = preset["client"], preset["body"], preset["cfg"]
    flange = {c.getJointInfo(b, j)[12].decode(): j for j in range(c.getNumJoints(b))}[cfg["flange_link"]]
    kg = EXPECTED[preset["name"]]["payload_kg"]
    c.changeDynamics(b, flange, mass=kg, localInertiaDiagonal=[1e-6] * 3)
    worst = _worst_gravity(preset, seed=2)
    ratio = worst / np.array(cfg["torque_limit_nm"])
    print(f"\n{preset['name']} + {kg} kg at the flange: worst |gravity torque| [N m] {np.round(worst, 2).tolist()}")
    print(f"{preset['name']} + {kg} kg: ratio to the torque limit   {np.round(ratio, 3).tolist()}")
    assert np.all(ratio < 1.0)
