"""SIGUSR1 makes a node write every thread's Python stack into its log and go on; SIGINT still stops it with 0.

The launcher sends SIGUSR1 to a node that ignored SIGINT for 5 s (supervisor/processes.py, stop_all), so that a
node stuck in C code says where. One node process (the wire monitor, which needs no other node), ~3 s.
"""
import os
import signal
import subprocess
import sys
import time

from graph_harness import REPO, ros_env

TIMEOUT_S = 60


def _wait_for(proc, word: str, timeout_s: float) -> list[str]:
    lines, end = [], time.monotonic() + timeout_s
    while time.monotonic() < end:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        if word in line:
            return lines
    raise AssertionError(f"no {word!r} within {timeout_s} s: {''.join(lines)}")


def test_sigusr1_dumps_the_stacks_and_the_node_keeps_running(domain, tmp_path):
    out = tmp_path / "wire.npz"
    proc = subprocess.Popen(["timeout", "-k", "5", str(TIMEOUT_S), sys.executable, "-m", "pa10_dnbs.ros.wire_monitor",
                             "--ros-args", "-p", f"out_file:={out}"], cwd=REPO, env=ros_env(domain), text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    try:
        _wait_for(proc, "READY", TIMEOUT_S / 2)
        # `timeout` runs the node as its child: signal the node itself
        node = int(subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()[0])
        os.kill(node, signal.SIGUSR1)
        dump = "".join(_wait_for(proc, "spin_until", 10))
        assert "most recent call first" in dump and "runtime.py" in dump, dump
        assert proc.poll() is None  # still running
        os.kill(node, signal.SIGINT)
        rest, _ = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, rest
    assert out.is_file()  # it closed normally: its record is written


PROBE = """
import ctypes, os, signal, sys, threading
import rclpy
from rclpy.node import Node
from std_msgs.msg import String
from pa10_dnbs.ros import runtime

runtime.TEARDOWN_LIMIT_S = 1.5
hang = lambda *a, **k: ctypes.PyDLL(None).sleep(60)  # blocks in C with the GIL held, as the teardown did in CI
for name in ("try_shutdown", "shutdown"):
    setattr(rclpy, name, hang)
for name in ("destroy_node", "destroy_publisher", "destroy_subscription", "destroy_service", "destroy_timer"):
    setattr(Node, name, hang)


class Probe(Node):
    def __init__(self):
        super().__init__("teardown_probe")
        self.create_publisher(String, "probe", 1)
        threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()

    def close(self):
        print("CLOSED", flush=True)
        if sys.argv[1] == "hang_in_close":
            ctypes.PyDLL(None).sleep(60)


runtime.exit_process(runtime.run_node(Probe, []))
"""


def _probe(domain: int, mode: str) -> tuple[subprocess.CompletedProcess, float]:
    t0 = time.monotonic()
    r = subprocess.run(["timeout", "-k", "5", str(TIMEOUT_S), sys.executable, "-c", PROBE, mode], cwd=REPO,
                       env=ros_env(domain), capture_output=True, text=True)
    return r, time.monotonic() - t0


def test_after_close_a_node_leaves_without_any_rclpy_teardown(domain):
    """Every rclpy teardown call (destroying endpoints, the node, the context) hangs here in C with the GIL held,
    as one did under load (a graph update stuck on a shared-memory port's mutex): the node never makes one
    after close(), so it exits 0 at once and its log holds no stacks."""
    r, wall = _probe(domain, "plain")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "CLOSED" in r.stdout
    assert wall < 20 and "Timeout (" not in r.stderr, r.stderr


def test_a_hung_close_is_cut_short_with_exit_code_3_and_its_stacks(domain):
    """close() blocks in C with the GIL held: the exit deadline ends the node after TEARDOWN_LIMIT_S with 3 (a
    failure: its files may be incomplete), the stacks of where it hung in its log."""
    r, wall = _probe(domain, "hang_in_close")
    assert r.returncode == 3, r.stdout + r.stderr
    assert wall < 30  # the 60 s hang was cut short
    assert "Timeout (" in r.stderr and "in close" in r.stderr, r.stderr
