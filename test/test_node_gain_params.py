"""A running joint controller's gains are ROS parameters: read-only, with their unit and range, valued from the
launcher's params file, and readable through the node's parameter services."""
import json
import subprocess
import sys

import pytest
import yaml

from graph_harness import REPO, Proc, ros_env
from pa10_dnbs.supervisor.params_file import params_document

pytestmark = pytest.mark.graph  # starts ROS processes


def test_a_running_controllers_gains_are_read_through_its_parameter_services(cfg, tmp_path, domain):
    doc = params_document(cfg, "pid", "/pa10")
    doc["/pa10/joint_controller_s2"]["ros__parameters"]["pid"]["kp"] = 1234.5  # not the config's: the file rules
    params = tmp_path / "ros_params.yaml"
    params.write_text(yaml.safe_dump(doc, sort_keys=False))
    node = Proc(["timeout", "-k", "5", "60", sys.executable, "-m", "pa10_dnbs.ros.joint_controller_node",
                 "--ros-args", "-r", "__node:=joint_controller_s2", "-r", "__ns:=/pa10", "-p", "joint:=s2",
                 "-p", "controller:=pid", "--params-file", params], domain)
    try:
        node.wait_for(r"CONTROLLER joint_controller s2: PIDControllers", 30)
        names = ["pid.kp", "pid.ki", "pid.kd", "plant.torque_limit_nm"]
        probe = subprocess.run(["timeout", "-k", "5", "60", sys.executable, str(REPO / "test" / "gain_probe.py"),
                                "/pa10/joint_controller_s2", *names], cwd=REPO, env=ros_env(domain), text=True,
                               capture_output=True, timeout=70)
        assert probe.returncode == 0, probe.stderr
        got = json.loads(probe.stdout.strip().splitlines()[-1])
    finally:
        node.interrupt()
        rc = node.wait(15)
    assert rc == 0, node.output
    assert got["pid.kp"]["value"] == 1234.5
    assert got["pid.ki"]["value"] == cfg.pid.ki[1] and got["pid.kd"]["value"] == cfg.pid.kd[1]
    assert got["plant.torque_limit_nm"]["value"] == cfg.plant.torque_limit_nm[1]
    assert all(p["read_only"] for p in got.values())
    assert "[N m/rad]" in got["pid.kp"]["description"] and "[N m]" in got["plant.torque_limit_nm"]["description"]
    assert got["pid.kp"]["range"][0][0] == 0.0  # the config's bound: a gain >= 0
