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


def test_a_need_names_who_it_waits_for():
    """The plant's start-timeout message names the node (and the parameter) it waits for."""
    n = Need("/pa10/s1/state", "subscribers", 2, lambda: 1,
             "joint_controller_s1 (state_subscribers:=1) and the recorder")
    assert n.missing() == ("/pa10/s1/state (1 of 2 subscribers: joint_controller_s1 (state_subscribers:=1) "
                           "and the recorder)")
    assert Need("/clock", "subscribers", 1, lambda: 1, "the reference node").missing() is None


def test_plant_needs_name_the_recorder_and_the_parameters():
    from pa10_dnbs.ros.plant.endpoints import _who

    assert _who("joint_controller_s1", 1, "state_subscribers", 1) == (
        "joint_controller_s1 (state_subscribers:=1) and the recorder (recorders:=1)")
    assert _who("the reference node", 0, "clock_subscribers", 2) == "2 recorders (recorders:=2)"
    assert _who("an observer", 3, "min_joint_states_subscribers", 0) == "3 readers (min_joint_states_subscribers:=3)"
