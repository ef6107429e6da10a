"""The MuJoCo plant against the PyBullet plant: an independent engine's M(q), bias torques and steps on the same
arms, and the in-process loop on it."""
import json

import numpy as np
import pytest

from cli_runner import run_cli
from pa10_dnbs.arm import load_arm
from pa10_dnbs.config import default_config_path
from pa10_dnbs.plant.from_config import arm_plant_params, open_client
from pa10_dnbs.plant.mujoco_plant import MuJoCoArmPlant
from pa10_dnbs.plant.pybullet_plant import PyBulletArmPlant
from pa10_dnbs.run_settings import build_settings
from test_arms import three_link_urdf, write_arm

# Two engines' rigid-body algorithms (PyBullet's CRBA / RNEA, MuJoCo's) on the same URDF: the same numbers to
# round-off, relative to the largest entry. The Panda's URDF inertias have off-diagonal terms, which MuJoCo
# diagonalises on loading (an eigen-decomposition: ~1e-10 relative, measured 1.2e-10).
REL_TOL = 1e-8


@pytest.fixture
def client():
    c = open_client()
    yield c
    c.disconnect()


def _max_rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(np.abs(a).max(), 1.0))


def _random_states(arm, rng, count=25):
    lo, hi = np.maximum(arm.lower_rad, -3.0), np.minimum(arm.upper_rad, 3.0)
    for _ in range(count):
        yield rng.uniform(lo, hi), rng.uniform(-2.0, 2.0, arm.n_joints)


@pytest.mark.parametrize("name", ["pa10", "iiwa", "panda"])
def test_mass_matrix_and_bias_torques_agree_with_pybullet(client, name):
    """M(q) + armature and h(q, qd) (Coriolis, centrifugal, gravity) of MuJoCo equal PyBullet's plant's, so the
    two engines model the same arm with the same rotor inertias (the independent dynamics check)."""
    arm = load_arm(name)
    pb, mj = PyBulletArmPlant(client, arm, arm_plant_params(arm)), MuJoCoArmPlant(arm, arm_plant_params(arm))
    assert np.allclose(np.diag(mj.mass_matrix(np.zeros(arm.n_joints))) - np.diag(pb.mass_matrix(
        np.zeros(arm.n_joints))), 0.0, atol=REL_TOL)
    worst_m = worst_h = 0.0
    for q, qd in _random_states(arm, np.random.default_rng(7)):
        worst_m = max(worst_m, _max_rel(pb.mass_matrix(q), mj.mass_matrix(q)))
        worst_h = max(worst_h, _max_rel(pb.bias_torque(q, qd), mj.bias_torque(q, qd)))
    assert worst_m < REL_TOL and worst_h < REL_TOL, (worst_m, worst_h)


def test_the_arm_files_facts_are_mujocos_joint_properties():
    arm = load_arm("panda")
    mj = MuJoCoArmPlant(arm, arm_plant_params(arm))
    np.testing.assert_array_equal(mj.model.dof_armature, arm.rotor_inertia_kgm2)
    np.testing.assert_array_equal(mj.model.dof_damping, arm.viscous_nms_per_rad)
    np.testing.assert_array_equal(mj.model.dof_frictionloss, arm.coulomb_nm)
    assert mj.model.opt.timestep == 1e-3 and mj.model.opt.gravity[2] == -9.81 and mj.model.ngeom == 0


@pytest.mark.parametrize("name", ["pa10", "iiwa"])
def test_a_frictionless_step_equals_pybullets_step(client, name):
    """Without friction both plants take the same semi-implicit Euler step from the same M and h: 200 steps
    under torques from the same state stay together to round-off."""
    arm = load_arm(name)
    params = arm_plant_params(arm, viscous_nms_per_rad=(0.0,) * 7, coulomb_nm=(0.0,) * 7)
    pb, mj = PyBulletArmPlant(client, arm, params), MuJoCoArmPlant(arm, params)
    q0, qd0 = np.full(7, 0.2), np.linspace(-0.5, 0.5, 7)
    for p in (pb, mj):
        p.reset(q0, qd0)
    tau = 0.1 * arm.torque_limit_nm * np.sin(np.arange(7))
    for _ in range(200):
        pb.step(tau)
        mj.step(tau)
    np.testing.assert_allclose(mj.state[0], pb.state[0], atol=1e-10)
    np.testing.assert_allclose(mj.state[1], pb.state[1], atol=1e-9)
    assert mj.step_count == 200 and mj.time_s == pytest.approx(0.2)


def test_payload_and_heavier_links_agree_with_pybullet(client):
    arm = load_arm("iiwa")
    for params in (arm_plant_params(arm, payload_kg=5.0), arm_plant_params(arm, link_mass_scale=1.3)):
        pb, mj = PyBulletArmPlant(client, arm, params), MuJoCoArmPlant(arm, params)
        for q, qd in _random_states(arm, np.random.default_rng(3), 5):
            assert _max_rel(pb.mass_matrix(q), mj.mass_matrix(q)) < REL_TOL
            assert _max_rel(pb.bias_torque(q, qd), mj.bias_torque(q, qd)) < REL_TOL
    plain = MuJoCoArmPlant(arm, arm_plant_params(arm))
    q = np.full(7, 0.4)
    assert np.abs(MuJoCoArmPlant(arm, arm_plant_params(arm, payload_kg=5.0)).bias_torque(q, np.zeros(7))
                  - plain.bias_torque(q, np.zeros(7))).max() > 1.0  # the payload is there at all


def test_locked_joints_are_welded_where_pybullet_holds_them(client, tmp_path):
    """A locked prismatic finger (held at 0) and a locked revolute joint held at its nearer limit (0.5 rad, not
    0): MuJoCo's welded model gives PyBullet's M and h."""
    urdf = three_link_urdf(gripper=True).replace(
        '<joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.2"/>'
        '<axis xyz="0 1 0"/><limit lower="-2" upper="2"',
        '<joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.2"/>'
        '<axis xyz="0 1 0"/><limit lower="0.5" upper="1.5"')
    assert 'lower="0.5"' in urdf
    arm = load_arm(write_arm(tmp_path, urdf, exclude_joints=["j3", "finger_joint"], rotor_inertia_kgm2=[0.05, 0.05],
                             tip_link="l2"))
    assert arm.joint_names == ("j1", "j2") and arm.locked_position_rad == (0.5, 0.0)
    pb, mj = PyBulletArmPlant(client, arm, arm_plant_params(arm)), MuJoCoArmPlant(arm, arm_plant_params(arm))
    assert mj.model.nv == 2
    for q, qd in _random_states(arm, np.random.default_rng(5), 10):
        assert _max_rel(pb.mass_matrix(q), mj.mass_matrix(q)) < REL_TOL
        assert _max_rel(pb.bias_torque(q, qd), mj.bias_torque(q, qd)) < REL_TOL


def test_torques_are_saturated_nan_refused_and_limits_clamped():
    arm = load_arm("pa10")
    mj = MuJoCoArmPlant(arm, arm_plant_params(arm, gravity_mps2=0.0))
    mj.step(np.full(7, np.inf))
    np.testing.assert_array_equal(mj.applied_torque_nm, arm.torque_limit_nm)
    with pytest.raises(ValueError, match="NaN"):
        mj.step(np.full(7, np.nan))
    with pytest.raises(ValueError, match="shape"):
        mj.step(np.zeros(6))
    mj.reset(arm.upper_rad - 1e-4, np.zeros(7))
    for _ in range(50):
        mj.step(arm.torque_limit_nm)
    q, qd = mj.state
    assert np.all(q <= arm.upper_rad) and np.all(mj.limit_hits > 0) and np.all(qd <= 0.0)
    with pytest.raises(ValueError, match="outside the joint limits"):
        mj.reset(arm.upper_rad + 0.1, np.zeros(7))


def test_simulate_runs_every_controller_on_mujoco(tmp_path):
    """`simulate --engine mujoco` in-process: every controller tracks, DNBS settles within 0.5 s, the run says its
    engine; a wrong engine is one line and exit 2."""
    out = tmp_path / "run"
    r = run_cli("simulate", "--engine", "mujoco", "--arm", "iiwa", "--controller", "all", "--duration", "1",
                "--out", str(out), "--no-figures")
    assert r.returncode == 0, r.stderr
    for kind in ("dnbs", "pid", "ctc"):
        m = json.loads((out / kind / "metrics.json").read_text())
        assert m["engine"] == "mujoco" and m["all_finite"] and m["torques_within_limits"], kind
        assert m["worst_rms_error_rad"] < 1e-3, kind
    assert json.loads((out / "dnbs" / "metrics.json").read_text())["worst_settling_time_s"] < 0.5
    assert "engine: mujoco" in (out / "report.md").read_text()
    bad = run_cli("simulate", "--engine", "ode", "--out", str(tmp_path / "bad"))
    assert bad.returncode == 2 and "--engine" in bad.stderr and "Traceback" not in bad.stderr
    assert not (tmp_path / "bad").exists()


def test_a_short_closed_loop_follows_pybullets_run():
    """DNBS on the PA10 for 1 s on both engines: the same controllers and gains, trajectories within 2e-3 rad (2 %
    of the 0.1 rad start offset; measured 5.1e-4, in the transient) and 1e-4 rad after 0.5 s. The engines differ
    where friction is discretised: MuJoCo's damping is implicit in its step, the PyBullet plant's explicit."""
    from pa10_dnbs.config import default_config_path
    from pa10_dnbs.sim.closed_loop import simulate

    cfg = build_settings(default_config_path(), arm="pa10")
    pb, mj = (simulate(cfg, "dnbs", 1.0, engine=e) for e in ("pybullet", "mujoco"))
    assert np.abs(pb.position_rad - mj.position_rad).max() < 2e-3
    assert np.abs(pb.position_rad - mj.position_rad)[500:].max() < 1e-4
    assert np.abs(pb.position_rad - mj.position_rad).max() > 0.0  # two engines, not one run twice


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_a_huge_finite_torque_is_applied_not_taken_for_nan(client, engine):
    """Limits of 1e200 N m (a config may give them): the torque's square overflowed the plant's NaN test, which
    then refused a finite torque as NaN (a traceback from simulate). One NaN among finite entries is refused."""
    arm = load_arm("pa10")
    params = arm_plant_params(arm, gravity_mps2=0.0, torque_limit_nm=(1e200,) * 7)
    plant = PyBulletArmPlant(client, arm, params) if engine == "pybullet" else MuJoCoArmPlant(arm, params)
    plant.step(np.full(7, 1e200))
    np.testing.assert_array_equal(plant.applied_torque_nm, np.full(7, 1e200))
    with pytest.raises(ValueError, match="NaN"):
        plant.step(np.array([1e200] * 6 + [np.nan]))


def test_a_urdf_mujoco_cannot_parse_is_one_line_naming_it(tmp_path):
    """PyBullet and the intake let a two-number box size pass (the plant needs no geometry); MuJoCo's parser
    refuses it: one line naming the URDF and MuJoCo's reason, exit 2, nothing written (was a traceback)."""
    bad = three_link_urdf().replace('<link name="l1">',
                                    '<link name="l1"><collision><geometry><box size="1 1"/></geometry></collision>')
    assert bad != three_link_urdf()
    arm = write_arm(tmp_path, bad)
    r = run_cli("simulate", "--engine", "mujoco", "--arm", arm, "--controller", "pid", "--duration", 0.02,
                "--no-figures", "--no-progress", "--out", tmp_path / "out")
    last = r.stderr.strip().splitlines()[-1]
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert last.startswith(f"pa10-dnbs: error: {tmp_path / 'arm.urdf'}: MuJoCo cannot load this URDF") \
        and "size" in last, last
    assert not (tmp_path / "out").exists()


def test_a_step_that_blows_up_keeps_its_state_and_writes_no_log(tmp_path, monkeypatch):
    """MuJoCo resets a state whose accelerations are huge or non-finite to the zero pose and goes on, writing
    MUJOCO_LOG.TXT into the working directory: a run would then track from a state the physics never reached. The
    plant keeps the state the step reached (here every joint driven to one of its limits) and writes nothing."""
    monkeypatch.chdir(tmp_path)
    arm = load_arm("pa10")
    plant = MuJoCoArmPlant(arm, arm_plant_params(arm, torque_limit_nm=(1e300,) * 7))
    plant.reset(0.5 * arm.upper_rad, np.zeros(7))
    plant.step(np.full(7, 1e300))
    q, _ = plant.state
    assert np.all((q == arm.upper_rad) | (q == arm.lower_rad)), q
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("tiny", ["urdf", "link_mass_scale"])
def test_an_inertia_too_small_for_mujoco_is_one_line_naming_the_urdf(tmp_path, tiny):
    """A link of mass and inertia 1e-30 (PyBullet takes it), or every link scaled by plant.link_mass_scale 1e-15:
    MuJoCo's compile refused it in a traceback (ValueError 'inertia must have positive eigenvalues')."""
    from test_arms import _link

    urdf = three_link_urdf()
    config = []
    if tiny == "urdf":
        urdf = urdf.replace(_link("l3", 2.0, 0.01), _link("l3", 1e-30, 1e-30))
        assert urdf != three_link_urdf()
    else:
        (tmp_path / "tiny.yaml").write_text(f"extends: {default_config_path()}\nplant:\n  link_mass_scale: 1.0e-15\n")
        config = ["--config", tmp_path / "tiny.yaml"]
    arm = write_arm(tmp_path, urdf)
    r = run_cli("simulate", "--engine", "mujoco", "--arm", arm, *config, "--controller", "pid", "--duration", 0.02,
                "--no-figures", "--no-progress", "--out", tmp_path / "out")
    last = r.stderr.strip().splitlines()[-1]
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert last.startswith(f"pa10-dnbs: error: {tmp_path / 'arm.urdf'}: MuJoCo cannot compile this URDF") \
        and "inertia must have positive eigenvalues" in last, last
    assert ("plant.link_mass_scale 1e-15" in last) == (tiny == "link_mass_scale"), last
    assert not (tmp_path / "out").exists()
