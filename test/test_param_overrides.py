"""``-p name:=value`` rules rcl cannot read, refused before rclpy.init (ros/param_overrides.py; rev_e 15): the
values rcl reads (scalars, lists of scalars) pass, a mapping or broken YAML is named in one line."""
import pytest

from pa10_dnbs.ros.param_overrides import bad_param_override


@pytest.mark.parametrize("rule", ["x:=1.0", "x:=[1.0,2.0]", "robot_command:=forward:effort_controller",
                                  'x:="forward:"', "x:=abc", "x:=[a, b]", "x:=true"])
def test_values_rcl_reads_pass(rule):
    assert bad_param_override(["node", "--ros-args", "-p", rule]) is None


@pytest.mark.parametrize("rule", ["robot_command:=forward:", "duration_s:=[1,", "mode:=foo:", "x:={a: 1}",
                                  "x:=[[1]]"])
def test_values_rcl_cannot_read_are_one_line_naming_the_parameter(rule):
    said = bad_param_override(["node", "--ros-args", "-r", "__node:=n", "--param", rule])
    assert said.startswith(f"parameter {rule.split(':=')[0]}: the override '--param {rule}'"), said


def test_only_the_ros_arguments_count():
    assert bad_param_override(["node", "-p", "x:=forward:", "--ros-args", "-p", "y:=1", "--", "-p", "z:=a:"]) is None
    assert "expected name:=value" in bad_param_override(["node", "--ros-args", "-p", "x=1"])
