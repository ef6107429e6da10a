"""study/cluster.py's ClusterWatch.result when a connection closes under a result's fetch: Dask raised its
CommClosedError ("in <TCP (closed) ...>: ConnectionResetError") where the scheduler had just died, and the study
ended with exit 1 and that line instead of the scheduler-lost line and exit 2 (the fast tier under -n 2, once).
The future and the client here stand in for Dask's only to raise that error at will; test_cluster_lost.py kills
real schedulers."""
from __future__ import annotations

import pytest
from distributed.comm.core import CommClosedError

from pa10_dnbs.study import cluster
from pa10_dnbs.study.cluster import ClusterWatch
from pa10_dnbs.study.lost_runs import ClusterLost

RESET = "in <TCP (closed)  local=tcp://127.0.0.1:41974 remote=tcp://127.0.0.1:43091>: ConnectionResetError"


class _Client:
    status = "running"


class _Future:
    """``result`` raises CommClosedError ``closed`` times (calling ``on_close(n)`` at the n-th), then returns 7."""

    def __init__(self, closed: int, on_close=lambda n: None):
        self.closed, self.on_close, self.calls = closed, on_close, 0

    def result(self, timeout):
        self.calls += 1
        if self.calls <= self.closed:
            self.on_close(self.calls)
            raise CommClosedError(RESET)
        return 7


def test_a_closed_connection_whose_scheduler_is_gone_is_the_scheduler_lost():
    client = _Client()
    fut = _Future(closed=100, on_close=lambda n: setattr(client, "status", "closed") if n == 3 else None)
    lost = r"^scheduler: lost the connection to the scheduler tcp://127\.0\.0\.1:8786 \(its process ended"
    with pytest.raises(ClusterLost, match=lost):
        ClusterWatch(client, "tcp://127.0.0.1:8786").result(fut)
    assert fut.calls == 3


def test_a_closed_connection_with_the_scheduler_still_there_is_tried_again():
    fut = _Future(closed=2)
    assert ClusterWatch(_Client(), "tcp://127.0.0.1:8786").result(fut) == 7 and fut.calls == 3


def test_a_connection_that_stays_closed_is_one_line_after_close_timeout(monkeypatch):
    monkeypatch.setattr(cluster, "CLOSE_TIMEOUT_S", 0.2)
    lost = (r"^scheduler: lost a connection to the cluster of tcp://127\.0\.0\.1:8786 and could not fetch a run's "
            r"result for 0\.2 s \(in <TCP \(closed\)")
    with pytest.raises(ClusterLost, match=lost):
        ClusterWatch(_Client(), "tcp://127.0.0.1:8786").result(_Future(closed=10**6))
