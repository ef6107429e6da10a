"""The start handshake without ROS: status texts, the plant's board, a node's announcer."""
from pa10_dnbs.loop.start_handshake import ReadyAnnouncer, ReadyBoard, parse_status, status_text


def test_status_texts_round_trip():
    assert status_text("reference", None) == "reference ready"
    assert parse_status("reference ready") == ("reference", None)
    text = status_text("joint_controller_s1", "its /pa10/s1/state reader has not matched the plant")
    assert parse_status(text) == ("joint_controller_s1", "its /pa10/s1/state reader has not matched the plant")
    for junk in ("", "reference", "reference done", " ready"):
        assert parse_status(junk) is None, junk


def test_the_board_is_complete_once_every_expected_node_said_ready():
    board = ReadyBoard(["wire_monitor", "reference", ""])  # '' (the parameter's empty default) is no node
    assert board.expected == ["wire_monitor", "reference"]
    assert not board.complete
    assert board.lacking == ["wire_monitor (no status on the ready topic)", "reference (no status on the ready topic)"]
    board.offer("reference waiting: no /clock received yet")
    board.offer("live_view ready")  # not waited for
    board.offer("garbage")
    assert board.lacking == ["wire_monitor (no status on the ready topic)", "reference (waiting: no /clock received yet)"]
    board.offer("wire_monitor ready", now=1.0)
    board.offer("reference ready", now=2.0)
    assert board.complete and board.lacking == []
    board.offer("reference waiting: late news")  # a node once ready stays ready
    assert board.complete and board.first_ready == {"wire_monitor": 1.0, "reference": 2.0}


def test_the_announcer_publishes_changes_at_a_bounded_rate_and_ready_at_once():
    now = [0.0]
    waiting = ["a"]
    sent = []
    ann = ReadyAnnouncer("n", lambda: waiting[0], sent.append, min_period_s=0.5, now=lambda: now[0])
    assert not ann.poll() and sent == ["n waiting: a"]
    assert not ann.poll() and sent == ["n waiting: a"]  # unchanged: not sent again
    waiting[0] = "b"
    now[0] = 0.2
    assert not ann.poll() and sent == ["n waiting: a"]  # changed, but too soon
    now[0] = 0.6
    assert not ann.poll() and sent == ["n waiting: a", "n waiting: b"]
    waiting[0] = None
    now[0] = 0.7
    assert ann.poll() and sent[-1] == "n ready" and ann.ready_after_s == 0.7
    assert ann.poll() and len(sent) == 3  # done: nothing more
