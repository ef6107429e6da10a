"""exit_deadline: a process whose main thread holds the GIL in C (as a hung rclpy teardown does) still ends at
its deadline, with the exit code it was given; a cancelled deadline does nothing. Child processes, no ROS."""
import subprocess
import sys
import time

import pytest

from graph_harness import REPO

CHILD = """
import ctypes, sys
from pa10_dnbs.ros.exit_deadline import arm
deadline = arm(0.3, int(sys.argv[1]))
assert deadline is not None, "no POSIX timer threads"
if sys.argv[2] == "cancel":
    deadline.cancel()
    ctypes.PyDLL(None).sleep(1)   # past the deadline, the GIL held
    sys.exit(9)
ctypes.PyDLL(None).sleep(60)      # the GIL held in C: no Python thread or signal handler can run
"""


def _child(code: int, mode: str) -> tuple[int, float]:
    t0 = time.monotonic()
    r = subprocess.run([sys.executable, "-c", CHILD, str(code), mode], cwd=REPO, capture_output=True, text=True,
                       timeout=30)
    assert "Traceback" not in r.stderr, r.stderr
    return r.returncode, time.monotonic() - t0


@pytest.mark.parametrize("code", [0, 7])
def test_a_process_holding_the_gil_ends_at_its_deadline_with_its_code(code):
    rc, wall = _child(code, "hang")
    assert rc == code and wall < 20  # not the 60 s sleep


def test_a_cancelled_deadline_does_nothing():
    assert _child(0, "cancel")[0] == 9


def test_bad_arguments_are_refused():
    from pa10_dnbs.ros.exit_deadline import arm

    for seconds, code in ((0.0, 0), (1.0, 256), (1.0, -1)):
        with pytest.raises(ValueError):
            arm(seconds, code)
