"""The start handshake on the wire: a plant whose nodes never all say ready gives up after start_timeout_s and
names them, with what each waits for (the launched graph's handshake: test_graph_lockstep.py)."""
import os
import sys
import time

import pytest

from graph_harness import Proc

pytestmark = pytest.mark.graph  # starts ROS processes

ROS = ["--ros-args", "-r", "__ns:=/pa10", "-p"]


def test_the_plant_names_the_nodes_that_never_became_ready(domain):
    """The reference node gets /clock (so the plant's /clock at time 0 reached it) but no controller holds its
    batches; the controller the plant waits for never starts. The plant publishes no state and exits 1."""
    ref = Proc([sys.executable, "-m", "pa10_dnbs.ros.reference_node", *ROS, "duration_s:=1.0", "-p",
                "use_sim_time:=true", "-p", "reference_subscribers:=1"], domain_id=domain)
    plant = None
    try:
        ref.wait_for("READY reference", 60)
        plant = Proc([sys.executable, "-m", "pa10_dnbs.ros.plant.node", *ROS, "duration_s:=1.0", "-p",
                      "state_subscribers:=0", "-p", "clock_subscribers:=1", "-p", "start_timeout_s:=8.0", "-p",
                      "ready_nodes:=['reference','joint_controller_s1']"], domain_id=domain)
        rc = plant.wait(120)
    finally:
        for p in (plant, ref):
            if p is not None:
                p.kill()
    out = plant.output
    assert rc == 1, out
    assert "FAILED graph not ready after start_timeout_s = 8 s" in out and "Traceback" not in out, out  # one line
    assert "reference (waiting: /pa10/s1/reference has 0 of 1 subscribers)" in out, out
    assert "joint_controller_s1 (no status on the ready topic)" in out, out
    assert "/pa10/s1/effort (0 of 1 publishers: joint_controller_s1" in out, out  # the plant's own side too
    assert "RUNNING plant" not in out and "HANDSHAKE every node ready" not in out


def _shm_mapped(pid: int) -> set[str]:
    """The /dev/shm names process ``pid`` maps now, each with its Fast DDS lock file and semaphore."""
    try:
        with open(f"/proc/{pid}/maps") as fh:
            names = {line.split("/dev/shm/", 1)[1].split()[0] for line in fh if "/dev/shm/" in line}
    except OSError:
        return set()
    return names | {f"{n}_el" for n in names} | {f"sem.{n}_mutex" for n in names}


def test_nodes_started_by_hand_leave_no_shared_memory_files(domain):
    """A node started without the launcher (by hand, or from the user's own launch file) sweeps its Fast DDS files
    from /dev/shm when it ends (it leaves without tearing DDS down: ros/runtime.py): after a failed start (the
    plant, graph not ready) and after Ctrl-C (the reference node), the last one out taking what both mapped.
    Before, both left them for a launcher that was not there."""
    from pa10_dnbs.ros.shm_cleanup import shm_files, unused

    before = shm_files()
    ref = Proc([sys.executable, "-m", "pa10_dnbs.ros.reference_node", *ROS, "duration_s:=1.0", "-p",
                "use_sim_time:=true", "-p", "reference_subscribers:=1"], domain_id=domain)
    plant = None
    mapped: set[str] = set()
    try:
        ref.wait_for("READY reference", 60)
        plant = Proc([sys.executable, "-m", "pa10_dnbs.ros.plant.node", *ROS, "duration_s:=1.0", "-p",
                      "state_subscribers:=0", "-p", "clock_subscribers:=1", "-p", "start_timeout_s:=3.0", "-p",
                      "ready_nodes:=['reference']"], domain_id=domain)
        while plant.proc.poll() is None:   # what the plant maps while it waits, until it gives up
            mapped |= _shm_mapped(plant.proc.pid) | _shm_mapped(ref.proc.pid)
            time.sleep(0.05)
        assert plant.wait(120) == 1, plant.output
        ref.interrupt()
        assert ref.wait(60) == 0, ref.output
    finally:
        for p in (plant, ref):
            if p is not None:
                p.kill()
    ours = {n for n in mapped if "fastrtps" in n}
    assert ours, mapped   # the check below has something to look at
    left = unused(shm_files() - before, frozenset({os.getpid()})) & ours   # other runs' live files do not count
    assert left == set(), sorted(left)
