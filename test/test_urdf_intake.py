"""URDF intake: each case a shipped URDF meets (test/fixtures/urdf_intake/), and the plant's dynamics against
MuJoCo's reading of the same file (an independent rigid-body library) on the fixtures and, where
example-robot-data is installed, on every serial arm of that collection."""
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet
import pytest
import yaml

from cli_runner import run_cli
from script_module import load_script
from pa10_dnbs.arm import ArmError, load_arm
from pa10_dnbs.arm.arm_file import _load
from pa10_dnbs.arm.plant_urdf import principal_moments
from pa10_dnbs.arm.summary import arm_line
from pa10_dnbs.plant.dynamics_check import compare_with_mujoco
from pa10_dnbs.plant.from_config import arm_plant_params, open_client
from pa10_dnbs.plant.pybullet_plant import PyBulletArmPlant

FIXTURES = Path(__file__).parent / "fixtures" / "urdf_intake"
MUJOCO_RTOL = 1e-8  # PyBullet diagonalises an off-diagonal inertia (threshold 1e-6): M to 1e-10, qdd to 3e-9
assert MUJOCO_RTOL == load_script("dynamics_check").TOLERANCE


def _fixture(name: str) -> Path:
    return FIXTURES / f"{name}.urdf"


def _pybullet_loads(urdf: Path) -> tuple[int, list]:
    """(body id, [(mass, local inertia diagonal) per link]) of ``urdf`` in a fresh client, as the plant loads it."""
    client = open_client()
    try:
        body = client.loadURDF(str(urdf), useFixedBase=True, flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        return body, [client.getDynamicsInfo(body, j)[:3:2] for j in range(client.getNumJoints(body))]
    finally:
        client.disconnect()


@pytest.mark.parametrize("name", ["fixed_frame_branch", "no_inertial_link", "end_gripper", "continuous_joint",
                                  "package_mesh"])
def test_the_plant_equals_mujoco_on_every_intake_fixture(name):
    d = compare_with_mujoco(load_arm(_fixture(name)))
    assert d.worst < MUJOCO_RTOL, (name, d)


def test_fixed_frames_at_the_root_and_the_tip_are_skipped():
    """UR-like: world -> base_link, which carries a fixed `base` frame beside the arm; tool0 and ee_link at the tip."""
    arm = load_arm(_fixture("fixed_frame_branch"))
    assert arm.joint_names == ("j1", "j2", "j3") and arm.locked_joints == () and arm.flange_link == "l3"


def test_a_link_without_inertial_is_massless_not_one_kilogram():
    arm = load_arm(_fixture("no_inertial_link"))
    assert arm.plant_urdf is not None and arm.plant_urdf != arm.urdf
    _, as_written = _pybullet_loads(arm.urdf)
    assert as_written[-1] == (1.0, (1.0, 1.0, 1.0))        # what PyBullet does with the file itself
    _, loaded = _pybullet_loads(arm.physics_urdf)
    assert loaded[-1] == (0.0, (0.0, 0.0, 0.0))             # the plant's copy: massless, as the spec says
    assert [m for m, _ in loaded[:-1]] == [m for m, _ in as_written[:-1]]
    assert f"the plant loads the cleaned copy {arm.plant_urdf}" in arm_line(arm)


def test_a_tensor_pybullet_would_zero_is_repaired_with_one_line_naming_the_link(capsys):
    _load.cache_clear()   # the line is said when the arm is read, once per file and process
    arm = load_arm(_fixture("bad_inertia"))
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "link 'l3'" in err[0] and "triangle inequality" in err[0] and "repaired" in err[0]
    _, as_written = _pybullet_loads(arm.urdf)
    assert as_written[2][1] == (0.0, 0.0, 0.0)              # PyBullet zeroes it
    _, loaded = _pybullet_loads(arm.physics_urdf)
    link = next(el for el in ET.parse(arm.physics_urdf).getroot().findall("link") if el.get("name") == "l3")
    moments, _ = principal_moments(link.find("inertial"))
    original = next(el for el in ET.parse(arm.urdf).getroot().findall("link") if el.get("name") == "l3")
    before, _ = principal_moments(original.find("inertial"))
    assert moments[0] + moments[1] > moments[2] and moments[2] == pytest.approx(before[2], rel=1e-12)
    assert np.all(moments >= before - 1e-15)               # only added, never taken away
    np.testing.assert_allclose(sorted(loaded[2][1]), moments, rtol=1e-9)   # PyBullet keeps the repaired tensor
    d = compare_with_mujoco(arm, urdf=arm.physics_urdf)     # MuJoCo refuses the original tensor too
    assert d.worst < MUJOCO_RTOL, d


def test_a_negative_principal_moment_is_refused_with_one_line_naming_the_link(tmp_path):
    with pytest.raises(ArmError, match=r"link 'l2'"):
        load_arm(_fixture("negative_inertia"))
    r = run_cli("simulate", "--arm", _fixture("negative_inertia"), "--duration", "0.1", "--out", tmp_path / "o")
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert "l2" in r.stderr and not (tmp_path / "o").exists()


def test_a_gripper_at_the_chain_end_is_locked_unless_kept(tmp_path):
    arm = load_arm(_fixture("end_gripper"))
    assert arm.joint_names == ("j1", "j2", "j3") and arm.locked_joints == ("jointGripper",)
    assert arm.locked_position_rad == (0.0,)
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump({"name": "kept", "urdf": str(_fixture("end_gripper")),
                                                       "keep_gripper": True, "sources": {"urdf": "a fixture"}}))
    kept = load_arm(tmp_path / "arm.yaml")
    assert kept.joint_names == ("j1", "j2", "j3", "jointGripper") and kept.locked_joints == ()
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump({"name": "bad", "urdf": str(_fixture("end_gripper")),
                                                      "keep_gripper": "yes", "sources": {"urdf": "a fixture"}}))
    with pytest.raises(ArmError, match="keep_gripper: expected true or false"):
        load_arm(tmp_path / "bad.yaml")


def test_package_meshes_that_do_not_resolve_neither_fail_nor_warn(capfd):
    client = open_client()
    try:
        with pytest.raises(pybullet.error):   # the file as written: PyBullet cannot load it
            client.loadURDF(str(_fixture("package_mesh")), useFixedBase=True)
    finally:
        client.disconnect()
    capfd.readouterr()
    arm = load_arm(_fixture("package_mesh"))
    client = open_client()
    try:
        PyBulletArmPlant(client, arm, arm_plant_params(arm))
    finally:
        client.disconnect()
    out = capfd.readouterr()
    assert "mesh" not in (out.out + out.err) and "b3Warning" not in (out.out + out.err)


def test_presets_load_their_urdf_as_written():
    for name in ("pa10", "iiwa", "panda"):
        arm = load_arm(name)
        assert arm.plant_urdf is None and arm.physics_urdf == arm.urdf, name
        assert "cleaned copy" not in arm_line(arm)


def test_a_continuous_joint_arm_runs_every_controller(tmp_path):
    arm = load_arm(_fixture("continuous_joint"))
    assert arm.lower_rad[0] == -np.inf and arm.upper_rad[0] == np.inf
    out = tmp_path / "out"
    r = run_cli("simulate", "--arm", _fixture("continuous_joint"), "--controller", "all", "--duration", "1",
                "--out", out, "--no-figures")
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    for kind in ("dnbs", "pid", "ctc"):
        m = json.loads((out / kind / "metrics.json").read_text())
        assert m["all_finite"] and m["diverged"] is None, kind


DYNAMICS_CHECK = load_script("dynamics_check")
COLLECTION = DYNAMICS_CHECK.collection_root()


@pytest.mark.skipif(COLLECTION is None, reason="example-robot-data is not installed (131 MB; "
                    "pip install example-robot-data==6.0.0 to run this check)")
@pytest.mark.parametrize("path", DYNAMICS_CHECK.COLLECTION_ARMS)
def test_the_plant_equals_mujoco_on_every_serial_arm_of_the_collection(path):
    arm = load_arm(COLLECTION / path)
    d = compare_with_mujoco(arm, states=10)
    assert d.worst < MUJOCO_RTOL, (path, d)


def test_a_urdf_without_joints_is_refused_in_one_line(tmp_path):
    (tmp_path / "empty.urdf").write_text('<?xml version="1.0"?>\n<robot name="empty"/>\n')   # example-robot-data's ur3.urdf
    with pytest.raises(ArmError, match=r"empty.urdf: the URDF has no joints"):
        load_arm(tmp_path / "empty.urdf")
