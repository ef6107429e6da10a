"""A running joint controller's settings are ROS parameters: its gains and every other setting it runs (one
double per per-joint key: its joint's value), read-only, with their unit and range, valued from the launcher's
params file alone (the config file is not read), and readable through the node's parameter services."""
import json
import subprocess
import sys

import pytest

from graph_harness import REPO, Proc, ros_env
from pa10_dnbs.supervisor.params_file import params_document, params_yaml, write_params_file
from pa10_dnbs.ros.settings_params import joint_values
from pa10_dnbs.settings import replace_in

pytestmark = pytest.mark.graph  # starts ROS processes


def test_a_running_controllers_gains_are_read_through_its_parameter_services(cfg, tmp_path, domain):
    doc = params_document(cfg, "pid", "/pa10")
    doc["/pa10/joint_controller_s2"]["ros__parameters"]["pid"]["kp"] = 1234.5  # not the config's: the file rules
    params = tmp_path / "ros_params.yaml"
    params.write_text(params_yaml(doc))
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


NO_CONFIG = "/no/such/config.yaml"  # read only for defaults the params file does not give: never here


def test_a_running_controller_runs_read_only_settings_from_the_params_file_alone(cfg, tmp_path, domain):
    """Every setting of joint e1's DNBS controller (E1, init_weight_std, q, remedies, guards, seed ...) is a
    read-only parameter holding e1's value of the run's settings, bit for bit; its config file does not exist."""
    settings = replace_in(cfg, "dnbs.kernel", "numpy")  # no C kernel to build in the test
    settings = replace_in(settings, "dnbs.alpha_net.error_scale_rad", tuple(0.01 + 0.02 * k / 3.0 for k in range(7)))
    settings = replace_in(settings, "dnbs.torque_net.q", tuple(1e-3 * (1.0 + k / 7.0) for k in range(7)))
    params = write_params_file(tmp_path / "ros_params.yaml", settings, "dnbs", "/pa10")
    node = Proc(["timeout", "-k", "5", "60", sys.executable, "-m", "pa10_dnbs.ros.joint_controller_node",
                 "--ros-args", "-r", "__ns:=/pa10", "-p", "joint:=e1", "-p", "controller:=dnbs",
                 "-p", f"config_file:={NO_CONFIG}", "--params-file", params], domain)
    try:
        node.wait_for(r"CONTROLLER joint_controller e1: DNBSControllers", 30)
        probe = subprocess.run(["timeout", "-k", "5", "90", sys.executable, str(REPO / "test" / "settings_probe.py"),
                                "/pa10/joint_controller_e1", "dnbs.alpha_net.error_scale_rad"], cwd=REPO,
                               env=ros_env(domain), text=True, capture_output=True, timeout=100)
        assert probe.returncode == 0, probe.stderr
        got = json.loads(probe.stdout.strip().splitlines()[-1])["/pa10/joint_controller_e1"]
    finally:
        node.interrupt()
        rc = node.wait(15)
    assert rc == 0, node.output
    want = joint_values(settings, "dnbs", 3)  # e1: the fourth joint
    assert {k: got["values"][k] for k in want} == want  # every setting, bit for bit (floats compared with ==)
    assert got["values"]["dnbs.alpha_net.error_scale_rad"] == settings.dnbs.alpha_net.error_scale_rad[3]
    assert got["values"]["dnbs.alpha_net.init_weight_std"] == settings.dnbs.alpha_net.init_weight_std[3]
    assert got["values"]["dnbs.torque_net.q"] == settings.dnbs.torque_net.q[3]
    assert all(got["read_only"][k] for k in want) and got["read_only"]["config_file"]  # (not rclpy's use_sim_time)
    ok, reason = got["set"]
    assert not ok and "read-only" in reason, reason
    assert got["values"]["config_file"] == NO_CONFIG  # never read: the params file gave everything
    assert "[rad]" in got["descriptions"]["dnbs.alpha_net.error_scale_rad"]
    assert "plant.gravity_mps2" not in got["values"] and "pid.kp" not in got["values"]  # only what it runs
