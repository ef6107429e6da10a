"""``python -m pa10_dnbs.ros.<node> --help`` prints how the node is started and its parameters, exit 0; it started
a real node before (which waited out its start timeout on domain 0 and left its files in /dev/shm)."""
from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NODES = ["plant.node", "joint_controller_node", "reference_node", "wire_monitor", "recorder_node",
         "live_observer_node", "joint_bus_node", "mujoco_robot_node"]


@pytest.mark.parametrize("module", NODES)
def test_a_node_s_help_lists_its_parameters_and_starts_nothing(module, domain):
    from pa10_dnbs.ros.shm_cleanup import shm_files, unused

    params = importlib.import_module(f"pa10_dnbs.ros.{module}").PARAMS   # rclpy: LTTng-UST's files, ours
    before = shm_files()
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    done = subprocess.run([sys.executable, "-m", f"pa10_dnbs.ros.{module}", "--help"], capture_output=True,
                          text=True, timeout=60, cwd=ROOT, env=env)
    assert done.returncode == 0 and done.stderr == "", (done.returncode, done.stderr)
    lines = done.stdout.splitlines()
    assert lines[0].startswith(f"usage: python -m pa10_dnbs.ros.{module} [--ros-args"), lines[0]
    listed = [line.split()[0] for line in lines if line.startswith("  ")]
    assert listed == list(params), listed
    assert not any(line.startswith(("READY", "RUNNING", "FAILED")) for line in lines), lines
    assert unused(shm_files() - before, frozenset({os.getpid()})) == set()   # other runs' live files do not count


def test_a_node_s_help_into_a_closed_pipe_is_no_traceback(domain):
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    done = subprocess.run(f"{sys.executable} -m pa10_dnbs.ros.plant.node --help | true; exit ${{PIPESTATUS[0]}}",
                          shell=True, executable="/bin/bash", capture_output=True, text=True, timeout=60, cwd=ROOT,
                          env=env)
    assert done.returncode in (0, 1) and done.stderr == "", (done.returncode, done.stderr)
