"""Where a URDF's tree forks into equal branches (arm/chain_select.py): a gripper's fingers end the arm; two arms,
legs or a hand's fingers with no arm before them are refused in one line that names the fork and asks for
``tip_link``, never taken as a short torso chain (Atlas, Valkyrie, TALOS full and iCub were accepted as their
2-3 torso joints before)."""
from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from cli_runner import run_cli
from pa10_dnbs.arm import ArmError, load_arm

INERTIAL = ('<inertial><origin xyz="0 0 0.05"/><mass value="0.5"/>'
            '<inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/></inertial>')


def _link(name: str) -> str:
    return f'<link name="{name}">{INERTIAL}</link>'


def _joint(name: str, parent: str, child: str, kind: str = "revolute") -> str:
    limit = '<limit lower="-2" upper="2" effort="50" velocity="2"/>' if kind != "fixed" else ""
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>{limit}</joint>')


def _branch(prefix: str, parent: str, n: int, kind: str = "revolute") -> list[str]:
    """``n`` joints ``{prefix}_j1..`` in a row from ``parent``, their links ``{prefix}_link1..``."""
    parts, link = [], parent
    for k in range(1, n + 1):
        parts += [_link(f"{prefix}_link{k}"), _joint(f"{prefix}_j{k}", link, f"{prefix}_link{k}", kind)]
        link = f"{prefix}_link{k}"
    return parts


def _urdf(tmp_path: Path, name: str, parts: list[str]) -> Path:
    path = tmp_path / f"{name}.urdf"
    path.write_text(f'<robot name="{name}">\n{_link("base")}\n' + "\n".join(parts) + "\n</robot>\n")
    return path


def _humanoid_torso(tmp_path: Path) -> Path:
    """base -> torso (1 revolute joint) -> two arms of 3 joints each."""
    return _urdf(tmp_path, "torso", _branch("torso", "base", 1) + _branch("l", "torso_link1", 3)
                 + _branch("r", "torso_link1", 3))


def test_two_equal_arms_on_one_base_are_refused_naming_the_fork_and_tip_link(tmp_path):
    urdf = _urdf(tmp_path, "dual", _branch("l", "base", 3) + _branch("r", "base", 3))
    with pytest.raises(ArmError) as exc:
        load_arm(urdf)
    assert str(exc.value) == (f"{urdf}: the chain from base forks at link 'base' into 2 branches of 3 movable joints "
                              "each (first joints: l_j1, r_j1): name the arm's last link with tip_link in an arm "
                              "file (docs/arms.md)")


def test_a_torso_before_two_arms_is_refused_not_taken_as_a_one_joint_arm(tmp_path):
    with pytest.raises(ArmError, match=r"forks at link 'torso_link1' after 1 movable joint into 2 branches of 3 "
                                       r"movable joints each \(first joints: l_j1, r_j1\)"):
        load_arm(_humanoid_torso(tmp_path))


def test_tip_link_picks_one_arm_of_the_fork(tmp_path):
    urdf = _humanoid_torso(tmp_path)
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump({"name": "left", "urdf": str(urdf), "tip_link": "l_link3",
                                                       "sources": {"urdf": "a fixture"}}))
    arm = load_arm(tmp_path / "arm.yaml")
    assert arm.joint_names == ("torso_j1", "l_j1", "l_j2", "l_j3")
    assert set(arm.locked_joints) == {"r_j1", "r_j2", "r_j3"}


def test_fingers_on_fixed_mounts_end_the_arm_before_them(tmp_path):
    """An arm of 3 joints whose hand carries two fingers, each on a fixed mount: the fork is a gripper's."""
    parts = _branch("arm", "base", 3)
    for side in ("left", "right"):
        parts += [_link(f"{side}_mount"), _joint(f"{side}_mount_joint", "arm_link3", f"{side}_mount", "fixed"),
                  _link(f"{side}_tip"), _joint(f"{side}_finger_joint", f"{side}_mount", f"{side}_tip")]
    arm = load_arm(_urdf(tmp_path, "hand", parts))
    assert arm.joint_names == ("arm_j1", "arm_j2", "arm_j3")
    assert arm.locked_joints == ("left_finger_joint", "right_finger_joint")


def test_a_robotiq_like_gripper_whose_fingers_sit_below_its_knuckles_ends_the_arm(tmp_path):
    """Robotiq's 2F-85 (and the xArm gripper): each branch starts with a knuckle, the finger below; the knuckles
    are one motor's linkage (``<mimic>``). Short branches holding a finger-like joint are a gripper's."""
    parts = _branch("arm", "base", 3)
    for side in ("left", "right"):
        parts += [_link(f"{side}_knuckle"), _joint(f"{side}_knuckle_joint", "arm_link3", f"{side}_knuckle"),
                  _link(f"{side}_tip"), _joint(f"{side}_finger_tip_joint", f"{side}_knuckle", f"{side}_tip")]
    text = "\n".join(parts).replace('<joint name="right_knuckle_joint" type="revolute">',
                                    '<joint name="right_knuckle_joint" type="revolute"><mimic joint="left_knuckle_joint"/>')
    arm = load_arm(_urdf(tmp_path, "robotiq", [text]))
    assert arm.joint_names == ("arm_j1", "arm_j2", "arm_j3")


def test_a_gripper_alone_is_refused_as_not_an_arm(tmp_path):
    urdf = _urdf(tmp_path, "gripper", _branch("finger_a", "base", 2) + _branch("finger_b", "base", 2))
    with pytest.raises(ArmError, match=r"forks at link 'base' into a gripper's fingers \(finger_a_j1, finger_b_j1\) "
                                       r"before any arm joint: not an arm"):
        load_arm(urdf)


def test_the_command_line_says_it_in_one_line_exit_2(tmp_path):
    urdf = _urdf(tmp_path, "quadruped", sum((_branch(leg, "base", 3) for leg in ("fl", "fr", "hl", "hr")), []))
    r = run_cli("arm", "--arm", urdf)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and "into 4 branches of 3 movable joints each" in r.stderr, r.stderr
