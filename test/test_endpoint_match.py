"""Waiting for matched endpoints (loop/endpoint_match.py) with fake counts and a fake clock."""
from pa10_dnbs.loop.endpoint_match import MatchWait, Need


def test_met_waiting_and_timeout():
    counts = {"a": 0, "b": 1}
    t = [0.0]
    w = MatchWait([Need("/pa10/s1/state", "subscribers", 2, lambda: counts["a"]),
                   Need("/pa10/s1/effort", "publishers", 1, lambda: counts["b"])], 5.0, now=lambda: t[0])
    assert w.poll() == "waiting" and w.lacking == ["/pa10/s1/state (0 of 2 subscribers)"]
    counts["a"] = 2
    assert w.poll() == "met" and w.lacking == []
    counts["b"] = 0
    t[0] = 5.0
    assert w.poll() == "timeout" and w.lacking == ["/pa10/s1/effort (0 of 1 publishers)"] and w.waited_s == 5.0


def test_nothing_needed_is_met_at_once():
    assert MatchWait([], 0.0).poll() == "met"
