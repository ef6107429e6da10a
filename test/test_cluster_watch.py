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


class _SilentClient:
    """A client whose every ask of the scheduler times out (``answers``: how many are answered first)."""

    status = "running"
    scheduler = type("rpc", (), {"identity": None})()

    def __init__(self, answers: int = 0):
        self.answers, self.asks = answers, 0

    def sync(self, func, callback_timeout=None, **kwargs):
        self.asks += 1
        if self.asks <= self.answers:
            return {"n_workers": 2}
        raise TimeoutError


def test_one_slow_answer_after_a_pause_in_the_asks_is_no_silence(monkeypatch):
    """Asks pause while results keep coming: timed from the last answer, the first slow ask after a pause of
    over SILENT_S said "has not answered for 10 s" of a scheduler that had answered all along."""
    clock = [1000.0]
    monkeypatch.setattr(cluster.time, "monotonic", lambda: clock[0])
    watch = ClusterWatch(_SilentClient(), "tcp://127.0.0.1:8786")
    clock[0] += 60.0                    # a minute of results without a check
    watch.check()                       # the first ask that gets no answer: not lost yet
    for _ in range(9):
        clock[0] += cluster.WATCH_S
        watch.check()                   # 9 s without an answer
    clock[0] += cluster.WATCH_S
    with pytest.raises(ClusterLost, match=r"^scheduler: the scheduler tcp://127\.0\.0\.1:8786 has not answered for "
                                          r"10 s \(its process stopped"):
        watch.check()


def test_an_answer_ends_the_silence():
    watch = ClusterWatch(_SilentClient(answers=1), "tcp://127.0.0.1:8786")
    watch.last_asked = -10.0
    watch.check()
    assert watch.unanswered_since is None and watch.client.asks == 1
