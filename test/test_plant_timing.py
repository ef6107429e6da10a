"""The plant's latency record, CPU meter and SCHED_FIFO helper (no ROS processes)."""
import subprocess
import sys

import numpy as np
import pytest

from pa10_dnbs.loop.cpu_meter import CpuMeter
from pa10_dnbs.ros.plant.timing import PlantTiming, step_ranges
from pa10_dnbs.loop.scheduling import apply_fifo, check_priority


def test_latency_from_the_first_send_to_the_first_answer():
    t = PlantTiming(n_steps=3, n_joints=2)
    t.published(0, 1_000_000)
    t.published(0, 9_000_000)                      # a resend does not move the send time
    t.answered(0, 1, 1_400_000)
    t.answered(0, 1, 5_000_000)                    # a second answer does not move the latency
    t.answered(2, 0, 5_000_000)                    # no state 2 yet: nothing to measure against
    t.answered(9, 0, 5_000_000)                    # beyond the run
    assert t.latency_s[0, 1] == pytest.approx(400e-6)
    assert np.isnan(t.latency_s[2, 0])
    s = t.joint_summary(1, steps=1)
    assert s["latency_median_us"] == pytest.approx(400.0) and s["latency_max_us"] == pytest.approx(400.0)
    assert t.joint_summary(0, steps=3)["latency_median_us"] is None


def test_step_ranges():
    assert step_ranges([1, 2, 3, 7, 9, 10]) == [[1, 3], [7, 7], [9, 10]]
    assert step_ranges([1, 2, 3, 7, 9, 10], limit=2) == [[1, 3], [7, 7]]
    assert step_ranges([]) == []


def test_cpu_meter_counts_between_first_and_last_mark():
    m = CpuMeter(every=50)
    assert m.report()["cpu_per_step_us"] is None
    m.mark(10)
    x = 0
    for i in range(300_000):
        x += i
    m.mark(99)                                     # not a multiple of 50: not read
    m.mark(100)
    r = m.report()
    assert r["steps"] == 90 and r["cpu_s"] > 0 and r["cpu_per_step_us"] == pytest.approx(1e6 * r["cpu_s"] / 90)
    assert m.line("plant").startswith("CPU plant ")


def test_rt_priority_range():
    check_priority(0)
    check_priority(99)
    for bad in (-1, 100):
        with pytest.raises(ValueError):
            check_priority(bad)


CHILD = """
import os, threading, time
from pa10_dnbs.loop.scheduling import apply_fifo
t = threading.Thread(target=time.sleep, args=(1,)); t.start()
ok, msg = apply_fifo(3)
print(ok, os.sched_getscheduler(0) == os.SCHED_FIFO, msg)
"""


def test_rt_priority_is_applied_or_explained():
    """In a child process (the policy stays with it): SCHED_FIFO on every thread where allowed, else a message."""
    out = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, check=True).stdout.split(" ", 2)
    applied, fifo, msg = out[0] == "True", out[1] == "True", out[2]
    assert applied == fifo
    if applied:
        assert "SCHED_FIFO on 2 threads" in msg
    else:
        assert "not permitted" in msg and "default scheduling" in msg
    assert apply_fifo(0) == (False, "rt_priority 0: default scheduling")
