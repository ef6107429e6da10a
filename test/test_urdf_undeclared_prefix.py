"""A URDF with tags whose prefix it never declares (old Gazebo URDFs: ``<sensor:camera>``) loads as urdfdom and
PyBullet load it (kinematics/urdf_xml.py); before, "the URDF does not parse: unbound prefix"."""
from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from chain_urdf import chain_urdf
from pa10_dnbs.arm import ArmError, load_arm
from pa10_dnbs.kinematics.urdf_xml import urdf_root
from pa10_dnbs.plant.dynamics_check import compare_with_mujoco

GAZEBO = ('<gazebo reference="l1">\n  <sensor:camera name="rgb"><sensor:imageSize>192 128</sensor:imageSize>'
          '</sensor:camera>\n  <controller:gazebo_ros_camera name="c" plugin="x.so"/>\n</gazebo>\n')
MASSIVE_FLANGE = ('<link name="flange"><inertial><mass value="0.1"/>'
                  '<inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>')


@pytest.mark.parametrize("flange", ["massless", "massive"])   # with a cleaned copy for PyBullet, and without
def test_undeclared_gazebo_prefixes_load_and_the_plant_is_the_urdfs(tmp_path, flange):
    plain = chain_urdf(3)
    if flange == "massive":
        plain = plain.replace('<link name="flange"/>', MASSIVE_FLANGE)
    (tmp_path / "plain.urdf").write_text(plain)
    (tmp_path / "gazebo.urdf").write_text(plain.replace("</robot>", GAZEBO + "</robot>"))
    with pytest.raises(ET.ParseError, match="unbound prefix"):
        ET.fromstring((tmp_path / "gazebo.urdf").read_text())
    arm = load_arm(tmp_path / "gazebo.urdf")
    assert arm.joint_names == ("j1", "j2", "j3")
    d = compare_with_mujoco(arm, states=5, urdf=tmp_path / "plain.urdf")
    assert d.worst < 1e-8, d


def test_the_prefix_is_declared_on_the_robot_line_so_later_errors_keep_their_line(tmp_path):
    text = chain_urdf(2).replace("</robot>", GAZEBO + "<link name='x'>\n</robot>")
    with pytest.raises(ET.ParseError) as exc:
        urdf_root(text)
    assert "mismatched tag" in str(exc.value) and f"line {text.count(chr(10))}" in str(exc.value)
    (tmp_path / "bad.urdf").write_text(text)
    with pytest.raises(ArmError, match=r"the URDF does not parse: mismatched tag"):
        load_arm(tmp_path / "bad.urdf")


def test_a_tag_that_only_starts_like_robot_is_not_taken_for_the_root():
    """A <robot:x> before the root (in xacro's comment) or inside: the declarations go on the root <robot>, not
    on it (review finding)."""
    root = urdf_root('<!-- made from <robot:macro> -->\n<robot name="r"><robot:x/><a:b c:d="1"/></robot>')
    assert root.tag == "robot" and [el.tag for el in root] == ["{urn:pa10-dnbs:undeclared:robot}x",
                                                               "{urn:pa10-dnbs:undeclared:a}b"]


def test_a_declared_prefix_is_left_as_written():
    root = urdf_root('<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:property name="a"/>'
                     '<sensor:camera/></robot>')
    assert [el.tag for el in root] == ["{http://www.ros.org/wiki/xacro}property",
                                       "{urn:pa10-dnbs:undeclared:sensor}camera"]


def test_a_prefix_declared_only_inside_one_element_is_declared_for_the_rest():
    """xmlns:sensor on one <gazebo> and <sensor:ray> in another: 'unbound prefix' before (the declaration was
    found in the text and taken for the file's); the inner declaration keeps its own namespace inside."""
    root = urdf_root('<robot name="r"><gazebo xmlns:sensor="http://x"><sensor:camera/></gazebo>'
                     '<gazebo><sensor:ray/></gazebo></robot>')
    assert [el[0].tag for el in root] == ["{http://x}camera", "{urn:pa10-dnbs:undeclared:sensor}ray"]
