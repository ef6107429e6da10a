"""Arm intake at its edges: each a user's arm file or URDF that once ended in a traceback, exit 1 after the run,
or a line naming the wrong cause (review rev_a, findings 2-5, 7, 8, 14, 15). Each is now ONE line naming the
arm file or URDF and the key, joint or path, exit 2, before anything runs; the forms that mean an arm are read."""
import os
from pathlib import Path

import pytest
import yaml

from chain_urdf import chain_urdf
from cli_runner import run_cli
from pa10_dnbs.arm import ArmError, load_arm


def _chain(names=("j1", "j2", "j3"), kind="revolute", axis="0 0 1", root="robot") -> str:
    """A serial chain base -> l1..ln of 1 kg links, joints ``names`` of type ``kind`` (first axis ``axis``)."""
    inertial = ('<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>'
                '</inertial>')
    parts = [f'<link name="base">{inertial}</link>']
    parts += [f'<link name="l{i}">{inertial}</link>' for i in range(1, len(names) + 1)]
    for i, name in enumerate(names, 1):
        parent = "base" if i == 1 else f"l{i - 1}"
        parts.append(f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="l{i}"/>'
                     f'<origin xyz="0 0 0.3"/><axis xyz="{axis if i == 1 else "0 1 0"}"/>'
                     f'<limit lower="-2" upper="2" effort="50" velocity="2"/></joint>')
    return f'<?xml version="1.0"?>\n<{root} name="t">\n' + "\n".join(parts) + f"\n</{root}>\n"


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def _arm_file(tmp_path: Path, name: str = "arm.yaml", urdf: str = "chain.urdf", **fields) -> Path:
    """An arm file in ``tmp_path`` for the URDF ``urdf`` beside it (chain.urdf: a 3-joint chain, written), with
    ``fields``."""
    if urdf == "chain.urdf":
        _write(tmp_path / urdf, _chain())
    doc = {"name": "t", "urdf": urdf, "sources": {"urdf": "test"}, **fields}
    return _write(tmp_path / name, yaml.safe_dump(doc))


def _refused(arm, command=("arm",)) -> str:
    """The one line ``pa10-dnbs arm --arm ARM`` (or ``command``) refuses ``arm`` with (exit 2, nothing else on
    stderr); a line about the value itself opens with the flag, ``--arm:``."""
    r = run_cli(*command, "--arm", arm)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and lines[0].startswith("pa10-dnbs: error: "), (r.returncode,
                                                                                                  r.stderr[-2000:])
    return lines[0][len("pa10-dnbs: error: "):]


@pytest.mark.parametrize("key", ["tip_link", "flange_link"])
@pytest.mark.parametrize("value, said", [(["l3"], "got a list: ['l3']"), ({"l3": 1}, "got a mapping: {'l3': 1}")])
def test_a_link_key_that_is_not_a_string_is_named(tmp_path, key, value, said):
    """Was a TypeError traceback (a list or mapping is unhashable)."""
    path = _arm_file(tmp_path, **{key: value})
    assert _refused(path) == f"{path}: {key}: expected a link name (a string), {said}"


@pytest.mark.parametrize("key", ["tip_link", "flange_link"])
def test_an_unquoted_numeric_link_name_is_told_to_be_quoted(tmp_path, key):
    """Was "no link 2 in the URDF" for a URDF with a link named "2" (YAML reads an unquoted 2 as a number)."""
    _write(tmp_path / "numbered.urdf", _chain().replace('"l2"', '"2"'))
    path = _arm_file(tmp_path, urdf="numbered.urdf", **{key: 2})
    assert _refused(path) == (f'{path}: {key}: expected a link name (a string), got the number 2: quote it '
                              f'({key}: "2") if the URDF has a link named so')
    arm = load_arm(_arm_file(tmp_path, name="quoted.yaml", urdf="numbered.urdf", **{key: "2"}))
    assert arm.joint_names == (("j1", "j2") if key == "tip_link" else ("j1", "j2", "j3"))
    assert arm.flange_link == "2"   # given, or the tip (the last actuated joint's child)


def test_a_joint_given_twice_in_joints_is_said_so(tmp_path):
    """Was "joints: list them in chain order (j1)", the list shown holding the joint once."""
    path = _arm_file(tmp_path, joints=["j1", "j1"])
    assert _refused(path) == f"{path}: joints: 'j1' is given twice (each actuated joint once, in chain order)"


@pytest.mark.parametrize("bad, why", [("arm/j1", "it holds '/'"), ("..", "'..' names a folder"),
                                      (".", "'.' names a folder"),
                                      ("j" * 201, "201 bytes long in UTF-8, more than 200"),
                                      ("é" * 101, "202 bytes long in UTF-8, more than 200")],
                         ids=["slash", "dotdot", "dot", "201_ascii", "101_two_byte"])
def test_a_joint_name_that_cannot_be_a_file_name_is_refused_at_intake(tmp_path, bad, why):
    """Was accepted: the run completed, then its checkpoint `<joint>.npz` failed (exit 1, a temporary file named)."""
    urdf = _write(tmp_path / "named.urdf", _chain(names=(bad, "j2", "j3")))
    line = _refused(urdf)
    assert line == (f"{urdf}: joint {bad!r}: {why}: an actuated joint's name becomes a file name "
                    f"(<joint>.npz checkpoints); rename it in the URDF"), line


@pytest.mark.parametrize("written, name", [("a&#10;b", "a\nb"), ("a&#9;b", "a\tb")], ids=["newline", "tab"])
def test_a_joint_name_holding_a_control_character_is_refused_at_intake(tmp_path, written, name):
    """Was accepted (a newline as ``&#10;`` in the URDF): a checkpoint's file name and every line naming the
    joint were split in two."""
    urdf = _write(tmp_path / "named.urdf", _chain(names=(written, "j2", "j3")))
    line = _refused(urdf)
    assert line.startswith(f"{urdf}: joint {name!r}: it holds a control character ({name[1]!r})"), line


@pytest.mark.parametrize("command", ["simulate", "launch"])
def test_simulate_and_launch_refuse_it_before_the_run(tmp_path, command):
    """The review's command: ``simulate`` ran the whole run, then failed writing ``checkpoints/arm/j1.npz``."""
    urdf = _write(tmp_path / "slash.urdf", _chain(names=("arm/j1", "arm/j2", "arm/j3")))
    out = tmp_path / "out"
    line = _refused(urdf, (command, "--duration", "0.1", "--out", out))
    assert line.startswith(f"{urdf}: joint 'arm/j1': it holds '/': "), line
    assert not out.exists() and [p.name for p in tmp_path.iterdir()] == ["slash.urdf"]


def test_a_joint_name_of_200_bytes_is_accepted_of_201_refused(tmp_path):
    arm = load_arm(_write(tmp_path / "name_200.urdf", _chain(names=("j" * 200, "j2", "j3"))))
    assert arm.joint_names[0] == "j" * 200
    assert "201 bytes long" in _refused(_write(tmp_path / "name_201.urdf", _chain(names=("j" * 201, "j2", "j3"))))


def test_an_axis_whose_length_would_overflow_is_refused(tmp_path):
    """Was an overflow warning, then numpy's LinAlgError traceback from the inertia sweep (exit 1). Up to 1e6 an
    axis is divided by its length, as ever."""
    urdf = _write(tmp_path / "axis.urdf", _chain(axis="1e160 0 0"))
    line = _refused(urdf)
    assert line.startswith(f'{urdf}: joint \'j1\': <axis xyz="1e160 0 0">: each component must be within '
                           f'+/-1e+06'), line
    arm = load_arm(_write(tmp_path / "axis_ok.urdf", _chain(axis="1e6 0 0")))
    assert arm.chain.joint("j1").axis.tolist() == [1.0, 0.0, 0.0]


def test_a_chain_locked_whole_as_its_gripper_says_so_and_how_to_keep_it(tmp_path):
    """Was "no revolute joint on the chain from base" for three revolute joints named finger_*."""
    names = ("finger_1", "finger_2", "finger_3")
    urdf = _write(tmp_path / "fingers.urdf", _chain(names=names))
    line = _refused(urdf)
    assert line.startswith(f"{urdf}: every revolute joint on the chain from base is locked: finger_1, finger_2, "
                           f"finger_3 as the chain's gripper") and line.endswith("keep_gripper: true in an arm file "
                                                                                 "keeps them actuated"), line
    arm = load_arm(_arm_file(tmp_path, urdf="fingers.urdf", keep_gripper=True))
    assert arm.joint_names == names


def test_a_chain_of_prismatic_joints_names_them(tmp_path):
    """Was "no revolute joint on the chain from base", the joints and their kind unsaid."""
    urdf = _write(tmp_path / "slides.urdf", _chain(names=("p1", "p2", "p3"), kind="prismatic"))
    assert _refused(urdf) == (f"{urdf}: no revolute joint on the chain from base: its movable joints are "
                              f"p1 (prismatic), p2 (prismatic), p3 (prismatic) (only revolute or continuous "
                              f"joints can be actuated)")


@pytest.mark.parametrize("file_name", ["robot.xml", "ROBOT.URDF", "robot"])
def test_a_urdf_is_read_whatever_its_name_ends_in(tmp_path, file_name):
    """Was read as YAML: "expected a mapping of arm facts"."""
    arm = load_arm(_write(tmp_path / file_name, _chain()))
    assert arm.joint_names == ("j1", "j2", "j3")


def test_an_xml_document_that_is_not_a_urdf_is_named_so(tmp_path):
    path = _write(tmp_path / "model.sdf", _chain(root="sdf"))
    assert _refused(path) == (f"{path}: not an arm file: an XML document whose root is <sdf> (a URDF's root is "
                              f"<robot>)")


def test_an_arm_folder_is_read_through_its_arm_yaml(tmp_path):
    """docs/arms.md: an arm is a folder; given by its path it was "arm: file not found"."""
    folder = tmp_path / "myarm"
    folder.mkdir()
    path = _arm_file(folder, joints=["j1", "j2"])
    arm = load_arm(str(folder))
    assert arm.file == path.resolve() and arm.joint_names == ("j1", "j2")


def test_a_folder_without_an_arm_yaml_is_said_so(tmp_path):
    assert _refused(tmp_path) == (f"--arm: {tmp_path.resolve()} is a folder without an arm.yaml (give an arm folder, "
                                  f"an arm file or a URDF)")


def test_a_path_too_long_for_the_os_is_one_line(tmp_path):
    """Was exit 1: "[Errno 36] File name too long" without the flag or key (Path.is_file raised)."""
    long_name = "x" * 300 + ".urdf"
    line = _refused(tmp_path / long_name)
    assert line.startswith(f"--arm: {tmp_path.resolve()}/xxx") and line.endswith(": File name too long"), line
    path = _arm_file(tmp_path, urdf=long_name)
    line = _refused(path)
    assert line.startswith(f"{path}: urdf: {tmp_path.resolve()}/xxx") and line.endswith(": File name too long"), line


def test_a_loop_of_symbolic_links_is_one_line(tmp_path):
    """Was a RuntimeError traceback ("Symlink loop from ...") from Path.resolve()."""
    os.symlink(tmp_path / "loop_b", tmp_path / "loop_a")
    os.symlink(tmp_path / "loop_a", tmp_path / "loop_b")
    assert _refused(tmp_path / "loop_a") == f"--arm: {tmp_path / 'loop_a'}: a loop of symbolic links"
    path = _arm_file(tmp_path, urdf="loop_a")
    assert _refused(path) == f"{path}: urdf: {tmp_path / 'loop_a'}: a loop of symbolic links"


def test_a_pipe_is_not_taken_for_a_missing_file(tmp_path):
    """Was "file not found" for a named pipe that exists (as for bash's <(...) process substitution)."""
    os.mkfifo(tmp_path / "fifo")
    assert _refused(tmp_path / "fifo") == (f"--arm: {tmp_path / 'fifo'}: not a regular file (a pipe or a device): "
                                           f"give the path of a file")


@pytest.mark.parametrize("extra, said", [
    ("1: x\nfoo: y\n", "foo: unknown key"),
    ("1: x\n", "1 (a number, not a name): unknown key"),
    ("settings: {1: a, b: c}\n", "settings.b: unknown key"),
    ("settings: {~: a}\n", "settings.null (not a name): unknown key"),
])
def test_a_key_that_is_not_a_name_is_one_line(tmp_path, extra, said):
    """Keys of mixed types (``1:`` is a number to YAML) were a TypeError traceback from sorting the unknown ones."""
    _write(tmp_path / "chain.urdf", _chain())
    path = _write(tmp_path / "arm.yaml", "name: t\nurdf: chain.urdf\nsources: {urdf: test}\n" + extra)
    assert _refused(path).startswith(f"{path}: {said} (allowed: ")


@pytest.mark.parametrize("extra, where", [
    ("torque_limit_nm: HUGE\nsources: {urdf: t, torque_limit_nm: t}\n", "torque_limit_nm[0]"),
    ("coulomb_nm: [1, -HUGE, 1]\nsources: {urdf: t, coulomb_nm: t}\n", "coulomb_nm[1]"),
    ("settings: {pid: {kp: HUGE}}\nsources: {urdf: t}\n", "settings.pid.kp"),
])
def test_a_whole_number_too_large_for_a_float_is_one_line(tmp_path, extra, where):
    """An arm file's ``torque_limit_nm: <401 digits>`` was an OverflowError traceback."""
    _write(tmp_path / "chain.urdf", _chain())
    path = _write(tmp_path / "arm.yaml", "name: t\nurdf: chain.urdf\n" + extra.replace("HUGE", "9" * 401))
    assert _refused(path) == f"{path}: {where}: a whole number of 401 digits is too large (at most ~1.8e308)"


def test_a_yaml_alias_bomb_is_refused_before_it_is_built(tmp_path):
    """``description:`` a "billion laughs" document (anchors, each ten aliases of the one below) was built and
    str()-ed whole, taking all memory; now one line naming the arm file."""
    from yaml_bomb import alias_bomb
    _write(tmp_path / "chain.urdf", _chain())
    path = _write(tmp_path / "arm.yaml", "name: t\nurdf: chain.urdf\nsources: {urdf: test}\ndescription:\n"
                  + alias_bomb())
    assert _refused(path).startswith(f"{path}: refused: its aliases (*name) expand it to 1.23e+07 nodes")


def test_a_long_value_in_a_message_is_cut_to_one_readable_line(tmp_path):
    """``coulomb_nm: [[0, 0, ... 10000 zeros]]`` was shown whole; now its first 80 characters."""
    path = _arm_file(tmp_path, coulomb_nm=[[0] * 10000, 0, 0], sources={"urdf": "t", "coulomb_nm": "t"})
    said = _refused(path)
    assert said.startswith(f"{path}: coulomb_nm[0]: expected a finite number, got [0, 0,") and said.endswith("...")
    assert len(said) < len(str(path)) + 130, said


@pytest.mark.parametrize("source, said", [(5, "5"), (["a", "b"], "['a', 'b']"), ({"x": 1}, "{'x': 1}")])
def test_a_source_that_is_not_a_text_is_said_so(tmp_path, source, said):
    """``sources: {torque_limit_nm: 5}`` was reported "missing"; a source given is told to be a text."""
    path = _arm_file(tmp_path, torque_limit_nm=5, sources={"urdf": "t", "torque_limit_nm": source})
    assert _refused(path) == f"{path}: sources.torque_limit_nm: must be a text (where the fact came from), got {said}"


def test_a_blank_or_absent_source_is_still_missing(tmp_path):
    path = _arm_file(tmp_path, torque_limit_nm=5, sources={"urdf": "t", "torque_limit_nm": " "})
    assert _refused(path) == f"{path}: sources.torque_limit_nm: missing (every fact needs its source)"


@pytest.mark.parametrize("flange", ["base", "camera"])
def test_a_flange_link_no_actuated_joint_moves_is_refused(tmp_path, flange):
    """flange_link: the root link (or one fixed to it) was accepted, then a payload (plant.payload_kg, the study's
    payload scenarios) failed with "the URDF has no link named 'base'", which was untrue: it is the root."""
    camera = ('<link name="camera"/><joint name="camera_joint" type="fixed"><parent link="base"/>'
              '<child link="camera"/></joint>\n</robot>')
    _write(tmp_path / "camera.urdf", _chain().replace("</robot>", camera))
    path = _arm_file(tmp_path, urdf="camera.urdf", flange_link=flange)
    where = ("the URDF's root link" if flange == "base" else
             "fixed to the root link 'base' (no actuated joint moves it)")
    assert _refused(path) == (f"{path}: flange_link: {flange!r} is {where}: the flange must be a link the "
                              "actuated joints carry (the tip is 'l3')")
    assert load_arm(_arm_file(tmp_path, name="l1.yaml", urdf="camera.urdf", flange_link="l1")).flange_link == "l1"


def test_a_joint_to_an_undefined_world_link_says_how_to_define_it(tmp_path):
    """Drake's and Gazebo's URDFs fix the base to 'world' without a <link name="world"/> (Drake's pr2_simplified)."""
    text = chain_urdf(2).replace('<joint name="j1"', '<joint name="fix" type="fixed"><parent link="world"/>'
                                                      '<child link="l0"/></joint><joint name="j1"', 1)
    (tmp_path / "w.urdf").write_text(text)
    with pytest.raises(ArmError, match=r"joint 'fix': its parent link 'world' is not defined \(no <link name='world'>\); "
                                       r"Gazebo and Drake read 'world' as the world frame.*add <link name=\"world\"/>$"):
        load_arm(tmp_path / "w.urdf")
    (tmp_path / "w.urdf").write_text(text.replace('<link name="l0">', '<link name="world"/><link name="l0">', 1))
    assert load_arm(tmp_path / "w.urdf").joint_names == ("j1", "j2")


@pytest.mark.parametrize("encoding,said", [
    ("utf-16", "the file is UTF-16 text (save it as UTF-8)"),
    ("latin-1", "byte 27 (0xe9) is not UTF-8 (a binary file, or text in another encoding: save it as UTF-8)"),
])
def test_a_urdf_that_is_not_utf8_says_what_it_is(tmp_path, encoding, said):
    """A URDF saved as UTF-16 was 'not a text file (not UTF-8)': it is text, in the encoding no URDF reader takes."""
    text = _chain().replace('<?xml version="1.0"?>\n', '<?xml version="1.0"?>\n<!-- é -->\n')
    (tmp_path / "t.urdf").write_text(text, encoding=encoding)
    with pytest.raises(ArmError) as err:
        load_arm(tmp_path / "t.urdf")
    assert str(err.value) == f"{tmp_path / 't.urdf'}: not a URDF as URDF readers take it: {said}"
    (tmp_path / "u.urdf").write_text(text, encoding="utf-8-sig")   # a UTF-8 byte-order mark is UTF-8: read
    assert load_arm(tmp_path / "u.urdf").joint_names == ("j1", "j2", "j3")


@pytest.mark.parametrize("change, said", [
    ({"name": "x\nnew\ttab"}, "name: holds a control character ('\\n'), which would split the lines it is printed in"),
    ({"description": "two\nlines"}, "description: holds a control character ('\\n')"),
    ({"description": ["a", "b"]}, "description: expected a text, got ['a', 'b']"),
    ({"settings": []}, "settings: expected a mapping"),
    ({"sources": []}, "sources: expected a mapping"),
])
def test_a_name_description_settings_or_sources_of_the_wrong_kind_is_named(tmp_path, change, said):
    """A name holding a newline was printed across lines of every table and report; a description list was
    printed as Python's repr; settings: [] and sources: [] read as empty (review rev_f, finding 11)."""
    _write(tmp_path / "chain.urdf", _chain())
    path = _write(tmp_path / "arm.yaml", yaml.safe_dump({"name": "t", "urdf": "chain.urdf",
                                                         "sources": {"urdf": "test"}, **change}))
    assert _refused(path).startswith(f"{path}: {said}")


def test_a_folded_description_and_empty_settings_still_read(tmp_path):
    """YAML's folded ``>`` ends a description in a newline: kept, stripped; ``settings:`` with no value is none."""
    arm = load_arm(_arm_file(tmp_path, description="A long\ndescription folded\n".replace("\n", " ") + "\n",
                             settings=None))
    assert arm.description == "A long description folded" and arm.settings == {}


def test_huge_but_finite_facts_print_in_a_few_digits_without_overflow_warnings(tmp_path):
    """Limits of +/-1.7e308 and a torque limit of 1e300 were printed as 300-digit fixed-point numbers in the
    rule's table, and numpy's 'overflow encountered in scalar subtract' leaked from the reference rule (rev_f, 14)."""
    _write(tmp_path / "huge.urdf", _chain().replace('lower="-2" upper="2"', 'lower="-1.7e308" upper="1.7e308"', 1))
    path = _arm_file(tmp_path, urdf="huge.urdf", torque_limit_nm=1.0e300,
                     sources={"urdf": "test", "torque_limit_nm": "test"})
    r = run_cli("arm", "--arm", path)
    assert r.returncode == 0, r.stderr
    text = r.stdout + r.stderr
    assert "[-1.7e+308, +1.7e+308]" in text and "1e+300" in text
    assert "Warning" not in text and max(map(len, text.splitlines())) < 400, text


def test_a_chain_of_more_joints_than_the_rules_can_sweep_is_one_line_at_once(tmp_path):
    """A 300-joint chain ran the rules' n^3-per-pose sweep for minutes (`arm` still working after 90 s, the
    review's rev_g finding 6): more than MAX_ACTUATED joints are refused in one line, before any sweep; with
    `joints` naming a few of them the same URDF is an arm."""
    from pa10_dnbs.arm.chain_select import MAX_ACTUATED

    urdf = _write(tmp_path / "snake.urdf", chain_urdf(300))
    r = run_cli("arm", "--arm", urdf)
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert f"300 joints to actuate on the chain from l0, more than {MAX_ACTUATED}" in r.stderr, r.stderr
    doc = {"name": "few", "urdf": "snake.urdf", "sources": {"urdf": "test"}, "joints": ["j1", "j2", "j3"]}
    assert load_arm(_write(tmp_path / "few.yaml", yaml.safe_dump(doc))).joint_names == ("j1", "j2", "j3")


def test_a_mimic_of_a_joint_the_urdf_lacks_says_so(tmp_path):
    urdf = _write(tmp_path / "m.urdf", _chain().replace(
        '<joint name="j3" type="revolute">', '<joint name="j3" type="revolute"><mimic joint="nope"/>'))
    with pytest.raises(ArmError, match=r"joint 'j3' mimics joint 'nope', which is not in the URDF"):
        load_arm(urdf)
