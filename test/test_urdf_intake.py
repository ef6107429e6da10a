"""URDF intake: each case a shipped URDF meets (test/fixtures/urdf_intake/), and the plant's dynamics against
MuJoCo's reading of the same file (an independent rigid-body library) on the fixtures and, where
example-robot-data is installed, on every serial arm of that collection."""
import json
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet
import pytest
import yaml

from chain_urdf import chain_urdf
from cli_runner import run_cli
from script_module import load_script
from pa10_dnbs.arm import ArmError, load_arm
from pa10_dnbs.arm.arm_file import _load
from pa10_dnbs.arm.plant_urdf import plant_urdf, principal_moments
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


def test_a_mimic_joint_is_refused_as_an_actuated_joint_and_locked_when_excluded(tmp_path):
    """A URDF ``<mimic>`` joint follows another and has no actuator of its own: driving it by a controller of its
    own is another robot. Refused in one line naming it (it was actuated as an independent joint); excluded, it is
    locked. The collection's mimic joints (the Panda's and the TALOS arm's fingers) are in the gripper, locked."""
    with pytest.raises(ArmError, match=r"mimic_joint.urdf: .*joint 'j3' mimics joint 'j2' \(<mimic>\).*exclude_joints"):
        load_arm(_fixture("mimic_joint"))
    r = run_cli("arm", "--arm", _fixture("mimic_joint"))
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "joint 'j3' mimics joint 'j2'" in r.stderr, r.stderr
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump({"name": "coupled", "urdf": str(_fixture("mimic_joint")),
                                                       "exclude_joints": ["j3"], "sources": {"urdf": "a fixture"}}))
    arm = load_arm(tmp_path / "arm.yaml")
    assert arm.joint_names == ("j1", "j2") and arm.locked_joints == ("j3",)


def _printed_while_loading(arm, capfd):
    """What the plant printed (capfd's out and err) while it loaded ``arm`` into a PyBullet client of its own."""
    capfd.readouterr()
    client = open_client()
    try:
        PyBulletArmPlant(client, arm, arm_plant_params(arm))
    finally:
        client.disconnect()
    return capfd.readouterr()


def test_package_meshes_that_do_not_resolve_neither_fail_nor_warn(capfd):
    client = open_client()
    try:
        with pytest.raises(pybullet.error):   # the file as written: PyBullet cannot load it
            client.loadURDF(str(_fixture("package_mesh")), useFixedBase=True)
    finally:
        client.disconnect()
    capfd.readouterr()
    arm = load_arm(_fixture("package_mesh"))
    out = _printed_while_loading(arm, capfd)
    assert "mesh" not in (out.out + out.err) and "b3Warning" not in (out.out + out.err)


def _cleaned(monkeypatch, cache: Path) -> Path:
    """The cleaned copy of the no_inertial_link fixture with the cache ``cache``."""
    monkeypatch.setenv("PA10_DNBS_URDF_CACHE", str(cache))
    return plant_urdf(_fixture("no_inertial_link"))[0]


def test_a_damaged_cached_copy_is_written_anew(tmp_path, monkeypatch):
    """A truncated copy was trusted by its name for ever (PyBullet then could not load it)."""
    copy = _cleaned(monkeypatch, tmp_path / "cache")
    whole = copy.read_bytes()
    copy.write_bytes(whole[:300])
    assert _cleaned(monkeypatch, tmp_path / "cache") == copy and copy.read_bytes() == whole
    assert sorted(p.name for p in copy.parent.iterdir()) == [copy.name]   # no temporary left beside it
    assert copy.stat().st_mode & 0o777 == 0o644   # other users sharing the cache can read it


@pytest.mark.parametrize("blocked", ["a file", "read-only", "unreadable copy"])
def test_a_cache_that_cannot_be_used_gives_way_to_a_private_folder(tmp_path, monkeypatch, blocked):
    """The cache path a file ([Errno 17] File exists), a read-only cache ([Errno 13] on its temporary file),
    another user's unreadable copy (PyBullet cannot load this URDF): the copy goes to a private folder instead.
    (Permissions are imitated: the tests may run as root.)"""
    whole = _cleaned(monkeypatch, tmp_path / "normal").read_bytes()
    cache = tmp_path / "cache"
    if blocked == "a file":
        cache.write_text("")
    else:
        cache.mkdir()
        mkstemp, read_bytes = tempfile.mkstemp, Path.read_bytes

        def no_write(*args, dir=None, **kw):
            if Path(dir) == cache:
                raise PermissionError(13, "Permission denied", str(dir))
            return mkstemp(*args, dir=dir, **kw)

        def no_read(self):
            if self.parent == cache:
                raise PermissionError(13, "Permission denied", str(self))
            return read_bytes(self)

        monkeypatch.setattr(tempfile, "mkstemp", no_write)
        if blocked == "unreadable copy":
            (cache / _cleaned(monkeypatch, tmp_path / "normal").name).write_bytes(b"")
            monkeypatch.setattr(Path, "read_bytes", no_read)
    copy = _cleaned(monkeypatch, cache)
    assert copy.parent != cache and copy.parent.name.startswith("pa10_dnbs_urdf-")
    assert _bytes(copy) == whole and _cleaned(monkeypatch, cache) == copy


def _bytes(path: Path) -> bytes:
    """The file's bytes, past a patched Path.read_bytes."""
    with open(path, "rb") as f:
        return f.read()


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


# A URDF that is not one tree, or a malformed joint: refused by the intake (pa10_dnbs/kinematics/urdf_tree.py)
# before PyBullet sees it. CRASHERS kill the process in PyBullet's importer (SIGSEGV, no message) when they get
# through, so they run in a child process: on a crash the test fails with returncode -11, not the test session.
NOT_A_TREE = {  # fixture -> what the one line must name
    "duplicate_joint": "joint 'j2' is defined twice",
    "two_parents": "link 'l3' is the child of two joints, 'j3' and 'j4'",
    "stray_link": "two root links, 'base_link' and 'world'",
    "duplicate_link": "link 'l2' is defined twice",
    "missing_child": "joint 'j3': its child link 'l9' is not defined",
    "missing_parent": "joint 'j3': its parent link 'l9' is not defined",
    "bad_axis": "joint 'j2': <axis xyz=\"0 1\">: expected 3 finite numbers",
    "nan_axis": "joint 'j2': <axis xyz=\"0 nan 1\">: expected 3 finite numbers",
    "zero_axis": "joint 'j2': <axis xyz=\"0 0 0\">: zero axis",
    "loop": "a kinematic loop through link 'l1' (l1 -> l2 -> l3 -> base_link -> l1; no root link)",
    "detached_loop": "a kinematic loop through link 'l3' (l3 -> l2 -> l3; not reachable from the root link "
                     "'base_link')",
}
CRASHERS = ("duplicate_joint", "two_parents", "stray_link")


def _cli_child(*args) -> subprocess.CompletedProcess:
    """``pa10-dnbs ARGS`` in a child process (a crash in PyBullet's C++ is its returncode, -11)."""
    return subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


def _refused_in_one_line(r, urdf: Path, what: str, out: Path) -> None:
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "Traceback" not in r.stderr, (r.returncode, r.stderr[-2000:])
    assert f"{urdf}: {what}" in lines[0], lines[0]
    assert not out.exists()


@pytest.mark.parametrize("name", sorted(NOT_A_TREE))
def test_a_urdf_that_is_not_one_tree_is_refused_in_one_line_naming_the_file_and_the_joint_or_link(name, tmp_path):
    urdf, out = _fixture(name).resolve(), tmp_path / "out"
    args = ("simulate", "--arm", urdf, "--duration", "0.2", "--no-figures", "--out", out)
    r = _cli_child(*args) if name in CRASHERS else run_cli(*args)
    _refused_in_one_line(r, urdf, NOT_A_TREE[name], out)
    with pytest.raises(ArmError, match=re.escape(NOT_A_TREE[name])):
        load_arm(urdf)


# A name with surrounding whitespace, or a number finite but absurd (bounds in pa10_dnbs/kinematics/urdf_tree.py):
# the names were accepted, the origins of 1e300 m ended in a traceback, the 1e300 kg link ran.
BAD_NAME_OR_SIZE = {
    "blank_joint_name": "joint ' ': a name that is blank or has leading/trailing whitespace",
    "padded_joint_name": "joint ' j2': a name that is blank or has leading/trailing whitespace",
    "padded_link_name": "link 'l2 ': a name that is blank or has leading/trailing whitespace",
    "huge_joint_origin": "joint 'j3': <origin xyz=\"0 0 1e300\">: each must be within +/-1000 m",
    "huge_inertial_origin": "link 'l2': <origin xyz=\"0.01 0 1e300\">: each must be within +/-1000 m",
    "huge_mass": "link 'l2': <mass value=\"1e300\">: expected a finite mass in [0, 100000] kg",
    "huge_inertia": "link 'l2': <inertia ixx=\"1e300\">: expected a finite value within +/-1e+07 kg m^2",
}


@pytest.mark.parametrize("name", sorted(BAD_NAME_OR_SIZE))
def test_a_blank_name_or_an_absurd_size_is_refused_in_one_line_naming_the_file_and_the_joint_or_link(name, tmp_path):
    urdf, out = _fixture(name).resolve(), tmp_path / "out"
    r = run_cli("simulate", "--arm", urdf, "--controller", "pid", "--duration", "0.05", "--no-figures", "--out", out)
    _refused_in_one_line(r, urdf, BAD_NAME_OR_SIZE[name], out)


def test_the_size_bounds_refuse_no_urdf_of_the_installed_collections():
    """pybullet_data's and example-robot-data's URDFs (where installed) read as before the bounds."""
    from pa10_dnbs.kinematics.urdf_chain import UrdfChain
    from pa10_dnbs.kinematics.urdf_tree import UrdfError
    import pybullet_data
    roots = [Path(pybullet_data.getDataPath()), *([COLLECTION] if COLLECTION else [])]
    files = [f for root in roots if root.is_dir() for f in root.rglob("*.urdf")]
    assert len(files) > 100
    for f in files:
        try:
            UrdfChain(f.read_text())
        except UrdfError as exc:
            assert not any(w in str(exc) for w in ("whitespace", "within", "finite mass")), (f, exc)
        except (ValueError, ET.ParseError):
            pass   # not a URDF this reader takes (refused before the bounds existed too)


def test_every_way_in_refuses_a_urdf_pybullet_would_crash_on(tmp_path):
    """An arm file naming it, a config's ``arm``, the arm and robot commands, the MuJoCo engine."""
    urdf = _fixture("two_parents").resolve()
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump({"name": "twop", "urdf": str(urdf),
                                                       "sources": {"urdf": "a fixture"}}))
    (tmp_path / "config.yaml").write_text(yaml.safe_dump({"arm": str(urdf)}))
    what, out = NOT_A_TREE["two_parents"], tmp_path / "out"
    for args in (("simulate", "--arm", tmp_path / "arm.yaml", "--duration", "0.2", "--out", out),
                 ("simulate", "--config", tmp_path / "config.yaml", "--duration", "0.2", "--out", out),
                 ("simulate", "--arm", urdf, "--engine", "mujoco", "--duration", "0.2", "--out", out),
                 ("arm", "--arm", urdf), ("robot", "--arm", urdf)):
        _refused_in_one_line(_cli_child(*args), urdf, what, out)


def test_a_urdf_pybullet_still_cannot_load_is_one_line_naming_the_file(tmp_path):
    urdf, out = _fixture("unloadable_geometry").resolve(), tmp_path / "out"
    load_arm(urdf)                                 # a sound tree: the intake passes it
    client = open_client()
    try:
        with pytest.raises(pybullet.error):        # PyBullet's own answer: "Cannot load URDF file."
            client.loadURDF(str(urdf), useFixedBase=True)
    finally:
        client.disconnect()
    r = run_cli("simulate", "--arm", urdf, "--duration", "0.2", "--no-figures", "--out", out)
    _refused_in_one_line(r, urdf, "PyBullet cannot load this URDF: Cylinder shape must have both length and radius "
                         "attributes", out)


def test_a_urdf_on_one_long_line_loads_as_with_line_breaks(tmp_path):
    """A 30-joint chain written on one line (9 KB) was refused, "PyBullet cannot load this URDF" with PyBullet's
    b3Error run into that line: PyBullet reads a URDF in lines of at most 8191 bytes and joins the pieces of a
    longer one with a newline, inside a tag. Such a URDF is loaded from a copy written one tag a line."""
    from test_arm_intake_edges import _chain

    text = _chain(names=tuple(f"j{i}" for i in range(1, 31)))
    (tmp_path / "lines.urdf").write_text(text)
    (tmp_path / "one.urdf").write_text(text.replace("\n", ""))
    assert len((tmp_path / "one.urdf").read_bytes()) > 8191
    arm = load_arm(tmp_path / "one.urdf")
    assert arm.plant_urdf is not None and load_arm(tmp_path / "lines.urdf").plant_urdf is None
    assert max(len(line) for line in arm.plant_urdf.read_bytes().split(b"\n")) <= 8191
    metrics = []
    for name in ("one", "lines"):
        out = tmp_path / f"out_{name}"
        r = run_cli("simulate", "--arm", tmp_path / f"{name}.urdf", "--controller", "pid", "--duration", "0.02",
                    "--no-figures", "--out", out)
        assert r.returncode == 0, r.stderr
        metrics.append(json.loads((out / "metrics.json").read_text())["worst_rms_error_rad"])
    assert metrics[0] == metrics[1]


def test_a_binary_arm_file_or_urdf_is_refused_in_one_line(tmp_path):
    for name in ("binary.yaml", "binary.urdf"):
        path = tmp_path / name
        path.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe\x00\x80" * 8)
        r = run_cli("arm", "--arm", path)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
        assert f"{path}: not " in r.stderr and "not UTF-8" in r.stderr, r.stderr


def test_a_robot_without_a_name_loads_named_after_its_file(tmp_path):
    """xacro output without ``<robot name>`` (ROBOTIS' open_manipulator.urdf): PyBullet refuses it ("Expected a name
    for robot"); the cleaned copy is named after the file, and the plant is the URDF's."""
    named = chain_urdf(3)
    (tmp_path / "named.urdf").write_text(named)
    (tmp_path / "nameless.urdf").write_text(named.replace('<robot name="chain">', "<robot>"))
    arm = load_arm(tmp_path / "nameless.urdf")
    assert ET.parse(arm.plant_urdf).getroot().get("name") == "nameless"
    d = compare_with_mujoco(arm, states=5, urdf=tmp_path / "named.urdf")
    assert d.worst < MUJOCO_RTOL, d


def test_a_fixed_base_without_inertial_loads_without_pybullets_warning(tmp_path, capfd):
    """A root link without ``<inertial>`` (a bare ``world`` or ``base``: common) is loaded as written (a fixed
    base's mass never moves); PyBullet's "No inertial data for link, using mass=1" for it, and the link's name it
    prints without a newline, used to land on stdout glued to the next line (`arm`: "baseARM ok ...")."""
    urdf = tmp_path / "bare_base.urdf"
    inertial = ('<inertial><origin xyz="0 0 0.1"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" '
                'iyz="0" izz="0.01"/></inertial>')
    urdf.write_text(f'<robot name="t"><link name="base"/><link name="l1">{inertial}</link>'
                    '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>'
                    '<limit lower="-2" upper="2" effort="50" velocity="2"/></joint></robot>')
    arm = load_arm(urdf)
    assert arm.plant_urdf is None   # loaded as written
    capfd.readouterr()
    out = _printed_while_loading(arm, capfd)
    assert out.out == "" and out.err == "", out


def test_a_warning_the_copy_did_not_foresee_is_kept():
    from pa10_dnbs.plant.pybullet_plant import _unforeseen_warnings

    tag = "b3Warning[examples/Importers/ImportURDFDemo/BulletUrdfImporter.cpp,126]:\n"
    root = f"{tag}No inertial data for link, using mass=1, localinertiadiagonal = 1,1,1, identity local inertial frame{tag}world"
    other = f"{tag}No inertial data for link, using mass=1, localinertiadiagonal = 1,1,1, identity local inertial frame{tag}l3"
    assert _unforeseen_warnings(root, "world") == ""
    assert _unforeseen_warnings(root + other, "world") == ("No inertial data for link, using mass=1, localinertiadiagonal "
                                                           "= 1,1,1, identity local inertial frame l3")
