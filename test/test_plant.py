"""Plant layer: the URDF against the facts sheet, and the PyBullet plant's dynamics."""

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet
import pytest
from pybullet_utils.bullet_client import BulletClient

from pa10_dnbs.arm import ArmError, load_arm
from pa10_dnbs.plant import PlantParams, PyBulletArmPlant
from pa10_dnbs.plant.from_config import arm_plant_params

PA10 = load_arm("pa10")

URDF = Path(__file__).resolve().parents[1] / "urdf" / "pa10" / "pa10_7ce.urdf"

# Numbers typed in from the facts sheet (sources A-D, paper Table 2), not read from the code.
JOINT_NAMES = ("s1", "s2", "s3", "e1", "e2", "w1", "w2")
LINK_NAMES = ("link1", "link2", "link3", "link4", "link5", "link6", "link7")
LINK_MASS_KG = {"base_link": 3.04, "link1": 9.78, "link2": 8.41, "link3": 3.51,
                "link4": 4.31, "link5": 3.45, "link6": 1.46, "link7": 0.24}
LINK_COM_Z_M = {"base_link": 0.075, "link1": 0.148, "link2": 0.377, "link3": 0.672,
                "link4": 0.810, "link5": 1.099, "link6": 1.234, "link7": 1.315}
LIMIT_DEG = (177, 94, 174, 137, 255, 165, 255)
VELOCITY_RAD_S = (1.0, 1.0, 2.0, 2.0, 2 * math.pi, 2 * math.pi, 2 * math.pi)
TABLE2_NM = np.array([232.0, 232.0, 100.0, 100.0, 14.5, 14.5, 14.5])
ROTOR_KGM2 = np.array([0.75, 0.75, 0.2125, 0.2125, 0.00575, 0.00575, 0.00575])
S2_AXIS_Z, E1_AXIS_Z, W1_AXIS_Z, FLANGE_Z = 0.315, 0.765, 1.265, 1.345
G = 9.81

FRICTIONLESS = dict(viscous_nms_per_rad=(0.0,) * 7, coulomb_nm=(0.0,) * 7)
# A moving state that stays inside the joint limits for the first ~0.75 s under gravity.
Q_MOVING = np.array([0.3, -0.3, -0.5, -0.4, 0.2, 0.3, 0.1])
QD_MOVING = np.array([0.5, 0.6, 0.8, 0.5, -1.5, -0.5, 2.0])
# A faster state that stays inside the joint limits for 2 s without gravity.
Q_SPIN = np.array([0.3, 0.4, -0.5, 0.9, 0.2, -0.6, 0.1])
QD_SPIN = np.array([0.5, -0.4, 0.8, 0.6, -1.5, 1.2, 2.0])


@pytest.fixture
def client():
    c = BulletClient(connection_mode=pybullet.DIRECT)
    yield c
    c.disconnect()


@pytest.fixture
def make_plant(client):
    def _make(**kwargs):
        return PyBulletArmPlant(client, PA10, arm_plant_params(PA10, **kwargs))
    return _make


@pytest.fixture(scope="module")
def urdf_xml():
    return ET.parse(URDF).getroot()


def _random_states(plant, n, seed):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = rng.uniform(0.9 * plant.lower_limit_rad, 0.9 * plant.upper_limit_rad)
        qd = rng.uniform(-1.5, 1.5, 7)
        tau = rng.uniform(-TABLE2_NM, TABLE2_NM)
        yield q, qd, tau


def _energy_trace(plant, seconds, every=1):
    n = int(round(seconds / plant.dt_s))
    kinetic, potential = [], []
    for k in range(n + 1):
        if k % every == 0:
            e = plant.energy(*plant.state)
            kinetic.append(e[0])
            potential.append(e[1])
        if k < n:
            plant.step(np.zeros(7))
    return np.array(kinetic), np.array(potential)


# ----------------------------------------------------------------- URDF
def test_urdf_has_seven_named_revolute_joints_with_table_limits(client, make_plant):
    plant = make_plant()
    body = plant.body_id
    assert client.getNumJoints(body) == 8
    infos = [client.getJointInfo(body, j) for j in range(8)]
    assert [i[2] for i in infos] == [pybullet.JOINT_REVOLUTE] * 7 + [pybullet.JOINT_FIXED]
    assert tuple(i[1].decode() for i in infos[:7]) == JOINT_NAMES
    assert plant.joint_names == JOINT_NAMES
    assert [i[12].decode() for i in infos] == list(LINK_NAMES) + ["flange"]
    limit_rad = np.radians(LIMIT_DEG)
    np.testing.assert_allclose([i[8] for i in infos[:7]], -limit_rad, atol=1e-8)
    np.testing.assert_allclose([i[9] for i in infos[:7]], limit_rad, atol=1e-8)
    np.testing.assert_allclose(plant.lower_limit_rad, -limit_rad, atol=1e-8)
    np.testing.assert_allclose(plant.upper_limit_rad, limit_rad, atol=1e-8)
    np.testing.assert_allclose([i[10] for i in infos[:7]], TABLE2_NM)
    np.testing.assert_allclose([i[11] for i in infos[:7]], VELOCITY_RAD_S, atol=1e-8)


def test_urdf_masses_com_heights_and_lengths(client, make_plant, urdf_xml):
    masses = {l.get("name"): float(l.find("inertial/mass").get("value")) for l in urdf_xml.iter("link")}
    assert masses == {**LINK_MASS_KG, "flange": 0.0}
    base_com = float(urdf_xml.find("link[@name='base_link']/inertial/origin").get("xyz").split()[2])
    assert base_com == pytest.approx(LINK_COM_Z_M["base_link"])

    plant = make_plant()
    body = plant.body_id
    plant.sync_visual()  # zero pose
    for j, name in enumerate(LINK_NAMES):
        assert client.getDynamicsInfo(body, j)[0] == pytest.approx(LINK_MASS_KG[name])
        com = client.getLinkState(body, j, computeForwardKinematics=1)[0]
        np.testing.assert_allclose(com, [0.0, 0.0, LINK_COM_Z_M[name]], atol=1e-6)

    def frame_z(j):
        return client.getLinkState(body, j, computeForwardKinematics=1)[4][2]

    assert frame_z(1) == pytest.approx(S2_AXIS_Z, abs=1e-6)  # link2 frame sits on the s2 axis
    assert frame_z(3) == pytest.approx(E1_AXIS_Z, abs=1e-6)
    assert frame_z(5) == pytest.approx(W1_AXIS_Z, abs=1e-6)
    assert frame_z(7) == pytest.approx(FLANGE_Z, abs=1e-6)


def test_urdf_axes_inertias_and_no_damping(urdf_xml):
    joints = {j.get("name"): j for j in urdf_xml.iter("joint")}
    for name in JOINT_NAMES:
        axis = joints[name].find("axis").get("xyz").split()
        assert [float(a) for a in axis] == ([0, 1, 0] if name in ("s2", "e1", "w1") else [0, 0, 1])
        assert joints[name].find("dynamics") is None
    assert urdf_xml.find(".//dynamics") is None
    for link in urdf_xml.iter("link"):
        if link.get("name") == "flange":
            continue
        m = float(link.find("inertial/mass").get("value"))
        inertia = {k: float(v) for k, v in link.find("inertial/inertia").attrib.items()}
        cyl = link.find("collision/geometry/cylinder")
        r, length = float(cyl.get("radius")), float(cyl.get("length"))
        assert 0.04 <= r <= 0.10
        assert inertia["ixx"] == pytest.approx(m * (3 * r**2 + length**2) / 12, rel=1e-5)
        assert inertia["iyy"] == pytest.approx(inertia["ixx"])
        assert inertia["izz"] == pytest.approx(m * r**2 / 2, rel=1e-5)
        assert inertia["ixy"] == inertia["ixz"] == inertia["iyz"] == 0.0


def test_positive_pitch_tilts_arm_towards_plus_x(client, make_plant):
    plant = make_plant()
    plant.reset([0.0, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0], np.zeros(7))
    plant.sync_visual()
    flange = client.getLinkState(plant.body_id, 7, computeForwardKinematics=1)[4]
    reach = FLANGE_Z - S2_AXIS_Z
    np.testing.assert_allclose(flange, [reach * math.sin(0.3), 0.0, S2_AXIS_Z + reach * math.cos(0.3)], atol=1e-6)


# -------------------------------------------------------------- dynamics
def test_defaults_are_table2_and_source_d(make_plant):
    """The PA10's facts live in its arm file (urdf/pa10/arm.yaml); a plant takes them where its params leave
    them out."""
    np.testing.assert_array_equal(PA10.torque_limit_nm, TABLE2_NM)
    np.testing.assert_array_equal(PA10.rotor_inertia_kgm2, ROTOR_KGM2)
    params = make_plant().params
    np.testing.assert_array_equal(params.torque_limit_nm, TABLE2_NM)
    np.testing.assert_array_equal(params.rotor_inertia_kgm2, ROTOR_KGM2)
    assert PlantParams().dt_s == 1e-3


def test_mass_matrix_spd_and_includes_rotor_inertia(client, make_plant):
    plant = make_plant()
    for q, _, _ in _random_states(plant, 20, seed=1):
        m = plant.mass_matrix(q)
        m_pb = np.array(client.calculateMassMatrix(plant.body_id, q.tolist()))
        np.testing.assert_allclose(m, m.T, atol=1e-12)
        assert np.linalg.eigvalsh(m).min() > 0.0
        assert np.linalg.eigvalsh(m_pb).min() > 0.0
        np.testing.assert_allclose(np.diag(m - m_pb), ROTOR_KGM2, rtol=1e-12)
        off = ~np.eye(7, dtype=bool)
        np.testing.assert_array_equal((m - m_pb)[off], 0.0)


def test_mass_matrix_at_zero_pose_matches_hand_calculation(make_plant, urdf_xml):
    inertia = {l.get("name"): {k: float(v) for k, v in l.find("inertial/inertia").attrib.items()}
               for l in urdf_xml.iter("link")}
    m = make_plant().mass_matrix(np.zeros(7))
    # s1 about the vertical: every moving link spins about its own z axis.
    assert m[0, 0] == pytest.approx(ROTOR_KGM2[0] + sum(inertia[n]["izz"] for n in LINK_NAMES), rel=1e-6)
    # s2 about y through z = 0.315: links 2..7 with the parallel-axis term.
    s2 = sum(inertia[n]["iyy"] + LINK_MASS_KG[n] * (LINK_COM_Z_M[n] - S2_AXIS_Z) ** 2 for n in LINK_NAMES[1:])
    assert m[1, 1] == pytest.approx(ROTOR_KGM2[1] + s2, rel=1e-6)


def test_gravity_torque_matches_hand_calculation(make_plant):
    plant = make_plant()
    theta = 0.5
    q = np.array([0.0, theta, 0.0, 0.0, 0.0, 0.0, 0.0])
    moment = sum(LINK_MASS_KG[n] * (LINK_COM_Z_M[n] - S2_AXIS_Z) for n in LINK_NAMES[1:])
    bias = plant.bias_torque(q, np.zeros(7))
    # Holding torque about +y is negative when the arm leans towards +x.
    assert bias[1] == pytest.approx(-G * math.sin(theta) * moment, rel=1e-6)
    np.testing.assert_allclose(bias[[0, 2, 4, 6]], 0.0, atol=1e-9)
    # Gravity is a client setting: a second plant on the same client must not change the first.
    no_gravity = make_plant(gravity_mps2=0.0)
    np.testing.assert_allclose(no_gravity.bias_torque(q, np.zeros(7)), 0.0, atol=1e-12)
    np.testing.assert_array_equal(plant.bias_torque(q, np.zeros(7)), bias)
    moon = make_plant(gravity_mps2=1.62)
    np.testing.assert_allclose(moon.bias_torque(q, np.zeros(7)), bias * 1.62 / G, rtol=1e-9, atol=1e-12)


def test_forward_acceleration_matches_independent_solve(client, make_plant):
    fv = np.array([10.0, 10.0, 5.0, 5.0, 2.0, 2.0, 2.0])
    fc = np.array([3.0, 3.0, 2.0, 2.0, 0.5, 0.5, 0.5])
    eps = 0.05
    plant = make_plant(viscous_nms_per_rad=fv, coulomb_nm=fc, coulomb_smoothing_rad_s=eps)
    body, zeros = plant.body_id, [0.0] * 7
    for q, qd, tau in _random_states(plant, 20, seed=2):
        m_pb = np.array(client.calculateMassMatrix(body, q.tolist()))
        bias = np.array(client.calculateInverseDynamics(body, q.tolist(), qd.tolist(), zeros))
        friction = fv * qd + fc * np.tanh(qd / eps)
        expected = np.linalg.solve(m_pb + np.diag(ROTOR_KGM2), tau - bias - friction)
        qdd = plant.forward_acceleration(q, qd, tau)
        np.testing.assert_allclose(qdd, expected, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(plant.bias_torque(q, qd), bias, rtol=0, atol=0)
        # PyBullet's own inverse dynamics is M_pb qdd + bias (no rotor term) ...
        tau_id = np.array(client.calculateInverseDynamics(body, q.tolist(), qd.tolist(), qdd.tolist()))
        np.testing.assert_allclose(tau_id, m_pb @ qdd + bias, rtol=1e-9, atol=1e-8)
        # ... so closing the loop needs the rotor and friction torques added back.
        np.testing.assert_allclose(tau_id + ROTOR_KGM2 * qdd + friction, tau, rtol=1e-9, atol=1e-8)


def _bisect(g, lo, hi):
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(mid) < 0 else (lo, mid)
    return 0.5 * (lo + hi)


def test_one_step_is_semi_implicit_euler(client, make_plant):
    plant = make_plant(coulomb_nm=(1.0,) * 7)
    fv, fc, eps = (np.array(plant.params.viscous_nms_per_rad), np.array(plant.params.coulomb_nm),
                   plant.params.coulomb_smoothing_rad_s)
    dt = plant.dt_s
    for q, qd, tau in _random_states(plant, 5, seed=3):
        plant.reset(q, qd)
        plant.step(tau)
        m = np.array(client.calculateMassMatrix(plant.body_id, q.tolist())) + np.diag(ROTOR_KGM2)
        bias = np.array(client.calculateInverseDynamics(plant.body_id, q.tolist(), qd.tolist(), [0.0] * 7))
        rhs = tau - bias - fv * qd
        m_inv = np.linalg.inv(m)
        v_free, k = qd + dt * m_inv @ rhs, dt * fc * np.diag(m_inv)
        v = np.array([_bisect(lambda x: x - vf + kj * np.tanh(x / eps), vf - kj, vf + kj)  # Coulomb: implicit
                      for vf, kj in zip(v_free, k)])
        qdd = m_inv @ (rhs - fc * np.tanh(v / eps))
        qd1 = qd + dt * qdd
        q1 = q + dt * qd1
        q_got, qd_got = plant.state
        np.testing.assert_allclose(qd_got, qd1, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(q_got, q1, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(plant.applied_torque_nm, tau)
        assert plant.step_count == 1


def test_the_implicit_coulomb_root_converges_where_plain_newton_cycles():
    """A sticking wrist of the PA10's coulomb scenario (v_free, k = dt Fc / J, 1 / eps): Newton alone cycles
    across the steep part of tanh (the solver before rtsafe's safeguard left |g| = 0.12 there); a sweep of
    sticking and sliding joints converges to the tolerance, inside the bracket, equal to bisection."""
    from pa10_dnbs.plant.pybullet_plant import _implicit_coulomb_speed

    inv_eps = 100.0
    rng = np.random.default_rng(5)
    vf = np.concatenate([[-0.0473812413467337], rng.uniform(-0.2, 0.2, 300), rng.uniform(-5.0, 5.0, 100)])
    k = np.concatenate([[0.06283910477885069], rng.uniform(0.0, 0.5, 300), rng.uniform(0.0, 2.0, 100)])
    v = _implicit_coulomb_speed(vf, k, inv_eps)
    g = v - vf + k * np.tanh(v * inv_eps)
    assert np.all(np.abs(g) <= 1e-13 * (1.0 + np.abs(vf)))
    assert np.all((v >= vf - k) & (v <= vf + k))
    ref = np.array([_bisect(lambda x: x - a + b * np.tanh(x * inv_eps), a - b, a + b) for a, b in zip(vf, k)])
    np.testing.assert_allclose(v, ref, rtol=0, atol=1e-12)


def test_torque_saturation_clips_to_table2(make_plant):
    plant = make_plant()
    twin = make_plant()
    signs = np.array([1, -1, 1, -1, 1, -1, 1])
    plant.step(3.0 * TABLE2_NM * signs)
    np.testing.assert_array_equal(plant.applied_torque_nm, TABLE2_NM * signs)
    twin.step(TABLE2_NM * signs)  # the same step with the torque already at the limit
    for a, b in zip(plant.state, twin.state):
        np.testing.assert_array_equal(a, b)

    inside = 0.5 * TABLE2_NM
    plant.step(inside)
    np.testing.assert_array_equal(plant.applied_torque_nm, inside)
    plant.step(np.full(7, -np.inf))
    np.testing.assert_array_equal(plant.applied_torque_nm, -TABLE2_NM)

    before = plant.state
    with pytest.raises(ValueError, match="torque_nm"):
        plant.step(np.full(7, np.nan))
    with pytest.raises(ValueError, match="torque_nm"):
        plant.step(np.zeros(6))
    np.testing.assert_array_equal(plant.state[0], before[0])
    np.testing.assert_array_equal(plant.applied_torque_nm, -TABLE2_NM)
    assert plant.step_count == 3


def test_energy_conserved_without_gravity_or_friction(make_plant):
    plant = make_plant(gravity_mps2=0.0, **FRICTIONLESS)
    plant.reset(Q_SPIN, QD_SPIN)
    kinetic, potential = _energy_trace(plant, 2.0, every=10)
    total = kinetic + potential
    assert plant.limit_hits.sum() == 0
    np.testing.assert_array_equal(potential, 0.0)
    # Measured: max relative deviation 2.1e-4 at dt = 1 ms (first order in dt), no secular drift.
    assert np.max(np.abs(total - total[0])) / total[0] < 1e-3


def test_energy_conserved_with_gravity(make_plant):
    plant = make_plant(**FRICTIONLESS)
    plant.reset(Q_MOVING, QD_MOVING)
    kinetic, potential = _energy_trace(plant, 0.6, every=5)
    total = kinetic + potential
    assert plant.limit_hits.sum() == 0
    assert potential[0] - potential.min() > 30.0  # gravity really did work
    # Measured: |dE| 0.17 J (4e-3 of the peak kinetic energy, 43 J) at dt = 1 ms; the error
    # is the integrator's O(dt) wobble (see the next test), so allow 1e-2.
    assert np.max(np.abs(total - total[0])) < 1e-2 * kinetic.max()


def test_energy_error_is_first_order_in_dt(make_plant):
    drift = []
    for dt in (1e-3, 5e-4):
        plant = make_plant(dt_s=dt, **FRICTIONLESS)
        plant.reset(Q_MOVING, QD_MOVING)
        kinetic, potential = _energy_trace(plant, 0.5, every=int(round(0.01 / dt)))
        total = kinetic + potential
        drift.append(np.max(np.abs(total - total[0])))
    # An inconsistency between PyBullet's gravity torque and the CoM heights would not shrink with dt.
    assert 1.8 < drift[0] / drift[1] < 2.2


def test_friction_dissipates_energy(make_plant):
    plant = make_plant(coulomb_nm=(2.0, 2.0, 1.0, 1.0, 0.2, 0.2, 0.2))
    plant.reset(Q_MOVING, QD_MOVING)
    kinetic, potential = _energy_trace(plant, 0.6)
    total = kinetic + potential
    assert plant.limit_hits.sum() == 0
    # Measured: every step loses at least 1e-3 J; allow 1e-6 J for the integrator's O(dt) wobble.
    assert np.all(np.diff(total) < 1e-6)
    assert total[-1] < total[0] - 5.0


def test_joint_limit_clamps_zeroes_outward_velocity_and_counts(make_plant):
    plant = make_plant(gravity_mps2=0.0)
    upper = plant.upper_limit_rad
    q0 = np.zeros(7)
    q0[5] = upper[5] - 1e-3
    qd0 = np.zeros(7)
    qd0[5] = 2.0
    plant.reset(q0, qd0)
    push = np.zeros(7)
    push[5] = 14.5
    for _ in range(50):
        plant.step(push)
    q, qd = plant.state
    assert q[5] == upper[5]
    assert qd[5] == 0.0
    np.testing.assert_array_equal(plant.limit_hits, [0, 0, 0, 0, 0, 50, 0])

    # Pulling back: velocity inward is kept, the counter stops.
    for _ in range(10):
        plant.step(-push)
    q, qd = plant.state
    assert q[5] < upper[5] and qd[5] < 0.0
    assert plant.limit_hits[5] == 50

    # Lower side, one joint only.
    lower = plant.lower_limit_rad
    q0 = np.zeros(7)
    q0[1] = lower[1] + 1e-4
    qd0 = np.zeros(7)
    qd0[1] = -0.5
    plant.reset(q0, qd0)
    plant.step(np.zeros(7))
    q, qd = plant.state
    assert q[1] == lower[1] and qd[1] == 0.0
    np.testing.assert_array_equal(plant.limit_hits, [0, 1, 0, 0, 0, 0, 0])


def test_reset_validates_state(make_plant):
    plant = make_plant()
    with pytest.raises(ValueError, match="q0"):
        plant.reset(plant.upper_limit_rad + 0.01, np.zeros(7))
    with pytest.raises(ValueError, match="qd0"):
        plant.reset(np.zeros(7), np.full(7, np.nan))
    with pytest.raises(ValueError, match="q0"):
        plant.reset(np.zeros(3), np.zeros(7))


def test_deterministic_across_clients_and_resets(client):
    torques = np.random.default_rng(4).uniform(-1.2 * TABLE2_NM, 1.2 * TABLE2_NM, size=(400, 7))
    params = arm_plant_params(PA10, coulomb_nm=(1.0,) * 7)
    other = BulletClient(connection_mode=pybullet.DIRECT)
    try:
        plants = [PyBulletArmPlant(client, PA10, params), PyBulletArmPlant(other, PA10, params)]
        for p in plants:
            p.reset(Q_MOVING, QD_MOVING)
        for tau in torques:
            for p in plants:
                p.step(tau)
        (qa, qda), (qb, qdb) = plants[0].state, plants[1].state
        assert np.all(np.isfinite(qa)) and np.all(np.isfinite(qda))
        np.testing.assert_array_equal(qa, qb)
        np.testing.assert_array_equal(qda, qdb)
        np.testing.assert_array_equal(plants[0].applied_torque_nm, plants[1].applied_torque_nm)
        np.testing.assert_array_equal(plants[0].limit_hits, plants[1].limit_hits)
        # Same plant again after a reset.
        plants[0].reset(Q_MOVING, QD_MOVING)
        for tau in torques:
            plants[0].step(tau)
        np.testing.assert_array_equal(plants[0].state[0], qa)
        np.testing.assert_array_equal(plants[0].state[1], qda)
        assert plants[0].step_count == len(torques)
    finally:
        other.disconnect()


@pytest.mark.parametrize(
    "field, value",
    [
        ("dt_s", 0.0),
        ("dt_s", math.nan),
        ("gravity_mps2", -9.81),
        ("gravity_mps2", math.inf),
        ("rotor_inertia_kgm2", (-0.1,) + (0.1,) * 6),
        ("viscous_nms_per_rad", (1.0,) * 6 + (math.nan,)),
        ("viscous_nms_per_rad", "fast"),
        ("coulomb_nm", (-1.0,) * 7),
        ("coulomb_smoothing_rad_s", 0.0),
        ("torque_limit_nm", (232.0,) * 6 + (0.0,)),
    ],
)
def test_bad_params_raise_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        PlantParams(**{field: value})


@pytest.mark.parametrize("field, value", [("rotor_inertia_kgm2", (0.75,) * 6), ("torque_limit_nm", (232.0,) * 8)])
def test_params_of_the_wrong_length_for_the_arm_raise(make_plant, field, value):
    with pytest.raises(ValueError, match=rf"{field}: expected 7 values \(one per joint of pa10\)"):
        make_plant(**{field: value})


def test_missing_urdf_raises(tmp_path):
    (tmp_path / "arm.yaml").write_text("name: x\nurdf: no_such_arm.urdf\n")
    with pytest.raises(ArmError, match="urdf: file not found: .*no_such_arm.urdf"):
        load_arm(tmp_path / "arm.yaml")


def test_steep_coulomb_friction_on_a_light_wrist_does_not_ring(make_plant):
    """Fc / eps = 72.5 N m s/rad on a ~0.01 kg m^2 wrist: an explicit step would ring (dt Fc/(eps J) ~ 7);
    the linearly implicit step brings the joint to rest without sign flips growing."""
    fc = (11.6, 11.6, 5.0, 5.0, 0.725, 0.725, 0.725)
    plant = make_plant(coulomb_nm=fc, gravity_mps2=0.0)
    plant.reset(np.zeros(7), np.array([0, 0, 0, 0, 0.5, -0.5, 0.5]))
    speeds = []
    for _ in range(300):
        plant.step(np.zeros(7))
        speeds.append(np.abs(plant.state[1][4:]).max())
    assert speeds[-1] < 1e-3
    assert all(b <= a + 1e-12 for a, b in zip(speeds, speeds[1:])), "the wrist speeds only decay"


def test_payload_and_link_mass_scale_change_the_dynamics(make_plant):
    """5 kg at the flange: the gravity torque on S2 with the arm horizontal grows by m g (flange - S2 axis)."""
    q = np.array([0.0, np.pi / 2, 0, 0, 0, 0, 0])
    base = make_plant()
    loaded = make_plant(payload_kg=5.0)
    heavier = make_plant(link_mass_scale=1.3)
    d = loaded.bias_torque(q, np.zeros(7)) - base.bias_torque(q, np.zeros(7))
    assert abs(d[1]) == pytest.approx(5.0 * 9.81 * (1.345 - 0.315), rel=1e-6)
    g0, g1 = base.bias_torque(q, np.zeros(7)), heavier.bias_torque(q, np.zeros(7))
    np.testing.assert_allclose(g1, 1.3 * g0, rtol=1e-9, atol=1e-9)  # gravity is linear in the link masses
    rotor = np.array(ROTOR_KGM2)
    np.testing.assert_allclose(np.diag(heavier.mass_matrix(q)) - rotor, 1.3 * (np.diag(base.mass_matrix(q)) - rotor),
                               rtol=1e-9)
