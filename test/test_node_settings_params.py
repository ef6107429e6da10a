"""The plant's and the reference node's settings are ROS parameters: valued from the launcher's params file alone
(the config file is not read), read-only, and readable through the nodes' parameter services while they run."""
import json
import subprocess
import sys

import pytest

from graph_harness import REPO, Proc, ros_env
from pa10_dnbs.supervisor.params_file import write_params_file
from pa10_dnbs.ros.settings_params import NODE_SECTIONS, section_values
from pa10_dnbs.settings import replace_in

pytestmark = pytest.mark.graph  # starts ROS processes

NO_CONFIG = "/no/such/config.yaml"  # read only for defaults the params file does not give: never here
ROS = ["--ros-args", "-r", "__ns:=/pa10", "-p", f"config_file:={NO_CONFIG}"]


def _run_settings(cfg):
    """The default settings with values no config file holds: 17 significant digits, a changed gravity."""
    s = replace_in(cfg, "plant.gravity_mps2", 9.80665)
    s = replace_in(s, "simulation.initial_position_offset_rad", tuple(0.1 + 0.2 * k / 3.0 for k in range(7)))
    return replace_in(s, "reference.centre_rad", tuple((k - 3) * (0.1 + 0.2) for k in range(7)))


def test_the_plant_and_reference_run_read_only_settings_from_the_params_file(cfg, tmp_path, domain):
    settings = _run_settings(cfg)
    params = write_params_file(tmp_path / "ros_params.yaml", settings, "pid", "/pa10")
    plant = Proc([sys.executable, "-m", "pa10_dnbs.ros.plant.node", *ROS, "-p", "start_timeout_s:=120.0",
                  "--params-file", params], domain)
    ref = Proc([sys.executable, "-m", "pa10_dnbs.ros.reference_node", *ROS, "-p", "duration_s:=1.0",
                "--params-file", params], domain)
    try:
        plant.wait_for("READY plant", 60)
        ref.wait_for("READY reference", 60)
        probe = subprocess.run(["timeout", "-k", "5", "90", sys.executable, str(REPO / "test" / "settings_probe.py"),
                                "/pa10/plant", "plant.torque_limit_nm", "/pa10/reference", "simulation.dt_s"],
                               cwd=REPO, env=ros_env(domain), text=True, capture_output=True, timeout=100)
        assert probe.returncode == 0, probe.stderr
        got = json.loads(probe.stdout.strip().splitlines()[-1])
    finally:
        plant.interrupt()
        ref.interrupt()
        rcs = plant.wait(30), ref.wait(30)
    assert rcs == (0, 0), plant.output + ref.output
    for node, name in (("/pa10/plant", "plant"), ("/pa10/reference", "reference")):
        want = section_values(settings, NODE_SECTIONS[name])
        seen = got[node]
        # every setting is there with the run's value, bit for bit (floats compared with ==), and read-only
        assert {k: seen["values"][k] for k in want} == want, node
        assert all(seen["read_only"][k] for k in want), node
        ok, reason = seen["set"]
        assert not ok and "read-only" in reason, (node, reason)
        assert seen["values"]["config_file"] == NO_CONFIG  # never read: nothing but the params file gave them
    plant_p = got["/pa10/plant"]
    assert plant_p["values"]["plant.gravity_mps2"] == 9.80665
    assert "[N m]" in plant_p["descriptions"]["plant.torque_limit_nm"]
    assert "[m/s^2]" in plant_p["descriptions"]["plant.gravity_mps2"]
    assert plant_p["values"]["arm_file"] == str(cfg.arm.file)
    assert "simulation.dt_s" in got["/pa10/reference"]["values"] and "plant.gravity_mps2" not in got["/pa10/reference"]["values"]


def test_each_node_reads_its_arm_once_from_the_path_its_params_give(cfg, tmp_path, domain):
    """The arm file and its URDF are parsed once per node (a joint controller too), from arm_file (here the iiwa's, with a config file
    for the PA10 that a node never reads once the params file gives everything)."""
    from pa10_dnbs.arm import load_arm
    from pa10_dnbs.run_settings import build_settings

    iiwa = build_settings(REPO / "config" / "default.yaml", arm="iiwa", report=False)
    params = write_params_file(tmp_path / "ros_params.yaml", iiwa, "pid", "/pa10")
    probe = subprocess.run(["timeout", "-k", "5", "90", sys.executable, str(REPO / "test" / "arm_parse_probe.py"),
                            params, NO_CONFIG], cwd=REPO, env=ros_env(domain), text=True, capture_output=True,
                           timeout=100)
    assert probe.returncode == 0, probe.stderr
    reads = json.loads(probe.stdout.strip().splitlines()[-1])
    once = [str(load_arm("iiwa").file)]
    assert reads == {"plant": once, "reference": once, "joint_controller_a1": once}, reads
