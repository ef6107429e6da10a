"""A run whose observer never completes fails with a message that names the likely cause under SCHED_FIFO.

Real child processes (plain Python, no ROS): a "plant" that says RUNNING and ends, a "wire_monitor" that
never says COMPLETE.
"""
import sys

import pytest

from pa10_dnbs.supervisor import supervision
from pa10_dnbs.supervisor.graph_options import GraphOptions
from pa10_dnbs.supervisor.processes import ManagedProcess
from pa10_dnbs.paths import share_path


def _children(tmp_path):
    monitor = ManagedProcess("wire_monitor", [sys.executable, "-c", "import time; print('PROGRESS 5', flush=True); "
                                              "time.sleep(30)"], {}, tmp_path / "monitor.log")
    plant = ManagedProcess("plant", [sys.executable, "-c", "print('RUNNING', flush=True)"], {},
                           tmp_path / "plant.log")
    return [monitor, plant]


@pytest.mark.parametrize("rt_priority", [0, 50])
def test_an_observer_that_misses_the_run_fails_it_and_the_fifo_case_says_why(tmp_path, monkeypatch, rt_priority):
    monkeypatch.setattr(supervision, "OBSERVER_CATCH_UP_S", 0.3)
    procs = _children(tmp_path)
    try:
        opt = GraphOptions(config_path=share_path("config", "default.yaml"), mode="realtime", joint_names=("s1", "s2", "s3", "e1", "e2", "w1", "w2"), duration_s=0.01,
                           rt_priority=rt_priority)
        failure = supervision.watch(procs, opt, lambda line: None, supervision.StopRequest())
    finally:
        for p in procs:
            p.proc.kill()
            p.proc.wait()
    assert failure is not None and failure.startswith("the wire_monitor did not receive the whole run")
    assert ("SCHED_FIFO" in failure) == bool(rt_priority), failure
