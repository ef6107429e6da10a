"""Misused trajectory inputs end in one line and exit 2, nothing written, never a traceback: a whole number too
large for a float, ``time_from_start: {}``, a header that is not a mapping (a file for --trajectory or the
sender); the sender's flags out of range (--stamp, --wait, the gaps, --namespace) and files whose times would wrap
on the wire (refused as --trajectory refuses them), all before ROS starts; Ctrl-C while the sender waits: one
line, exit 130. Tab-indented JSON reads as the same trajectory as the same content in YAML."""
import json
import os
import re
import subprocess
import sys
import threading
import time

import pytest
import yaml
from cli_runner import run_cli
from graph_harness import REPO, Proc, ros_env

from pa10_dnbs.core.joint_trajectory import TrajectoryError
from pa10_dnbs.trajectory_file import read_sendable, read_trajectory

EXAMPLE = REPO / "config" / "trajectory_example.yaml"
HUGE = "1" * 400   # a whole number past the largest float (~1.8e308)


def _example():
    return yaml.safe_load(EXAMPLE.read_text())


def _text(kind: str, field: str) -> str:
    """The example with one field of points[1] replaced by HUGE, as JSON or YAML text."""
    doc = _example()
    point = doc["points"][1]
    if field == "positions":
        point["positions"][3] = "HUGE"
    elif field == "time_from_start":
        point["time_from_start"] = "HUGE"
    else:
        point["time_from_start"] = {"sec": "HUGE", "nanosec": 0}
    text = json.dumps(doc) if kind == "json" else yaml.safe_dump(doc)
    return text.replace('"HUGE"', HUGE).replace("HUGE", HUGE)   # JSON quotes the placeholder, YAML does not


def _one_line(r_rc, err, *words):
    assert r_rc == 2, (r_rc, err)
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for w in words:
        assert str(w) in err, err


def _sender(*args, timeout=120):
    """The sender run with nothing to talk to (its refusals come before ROS starts)."""
    r = subprocess.run([sys.executable, "-m", "pa10_dnbs.ros.trajectory_sender", *map(str, args)], text=True,
                       capture_output=True, cwd=REPO, env=ros_env(0), timeout=timeout)
    return r.returncode, r.stdout + r.stderr


@pytest.mark.parametrize("kind", ["json", "yaml"])
@pytest.mark.parametrize("field", ["positions", "time_from_start", "sec"])
def test_a_whole_number_too_large_for_a_float_is_one_line(tmp_path, kind, field):
    f = tmp_path / f"huge.{kind}"
    f.write_text(_text(kind, field))
    where = {"positions": "points[1].positions[3]", "time_from_start": "points[1].time_from_start",
             "sec": "points[1].time_from_start.sec"}[field]
    with pytest.raises(TrajectoryError, match=r"too large for a float") as exc:
        read_trajectory(f)
    assert str(exc.value).startswith(where) and "\n" not in str(exc.value) and HUGE not in str(exc.value)
    out = tmp_path / "o"
    r = run_cli("simulate", "--trajectory", f, "--controller", "pid", "--duration", "0.02", "--no-figures",
                "--out", out)
    _one_line(r.returncode, r.stderr, "trajectory", f, where, "too large")
    assert not out.exists()


@pytest.mark.parametrize("field", ["velocities", "accelerations"])
def test_a_finite_value_whose_quintic_overflows_is_one_line(tmp_path, field):
    """velocities or accelerations of 1e308 (finite, read) made the quintic's coefficients inf: numpy's
    LinAlgError traceback from the limit check, exit 1 (review rev_f, finding 1); 1e300 was refused already."""
    zeros = [0.0] * 7
    first = {"time_from_start": 0.1, "positions": [0.2, 0.1, 0.0, 0.2, 0.0, 0.0, 0.0], "velocities": zeros,
             "accelerations": zeros}
    first[field] = [1.0e308] + zeros[1:]
    doc = {"joint_names": ["s1", "s2", "s3", "e1", "e2", "w1", "w2"],
           "points": [first, {**first, "time_from_start": 0.2, field: zeros}]}
    f = tmp_path / "t.yaml"
    f.write_text(yaml.safe_dump(doc))
    out = tmp_path / "o"
    r = run_cli("simulate", "--trajectory", f, "--controller", "pid", "--duration", "0.3", "--no-figures",
                "--out", out)
    _one_line(r.returncode, r.stderr, "trajectory", f, "points[0]: the quintic from t = 0 s to this point at 0.1 s "
              "overflows a float")
    assert "Warning" not in r.stderr and not out.exists()


@pytest.mark.parametrize("change, words", [
    (lambda d: d["points"][2].update(time_from_start={}), "points[2].time_from_start: {} gives no time"),
    (lambda d: d.update(header="garbage"), "header: expected a mapping"),
    (lambda d: d.update(header=[1, 2]), "header: expected a mapping"),
    # JSON writers print NaN, which YAML reads as text: said as text that is no finite number, not just "got 'NaN'"
    (lambda d: d["points"][1].update(positions=["NaN", 0.0]),
     "positions: expected a list of numbers, got ['NaN', 0.0] ('NaN' is text, not a number: the values must be finite)"),
])
def test_an_empty_time_a_header_that_is_not_a_mapping_or_text_for_a_number_is_refused(tmp_path, change, words):
    doc = _example()
    change(doc)
    f = tmp_path / "t.yaml"
    f.write_text(yaml.safe_dump(doc))
    with pytest.raises(TrajectoryError, match=re.escape(words)):
        read_trajectory(f)


def test_a_header_mapping_and_a_partial_duration_still_read(tmp_path):
    doc = _example()
    doc["header"] = {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""}
    doc["points"][0]["time_from_start"] = {"nanosec": 800000000}
    doc["points"][1]["time_from_start"] = {"sec": 1, "nanosec": 600000000}
    f = tmp_path / "t.yaml"
    f.write_text(yaml.safe_dump(doc))
    assert read_trajectory(f).time_from_start_s.tolist() == read_trajectory(EXAMPLE).time_from_start_s.tolist()


def test_tab_indented_json_reads_as_the_same_yaml(tmp_path):
    doc = _example()
    doc["points"][2]["velocities"] = []   # an empty list, nested: tabs at two depths
    tabs, spaces = tmp_path / "tabs.json", tmp_path / "same.yaml"
    tabs.write_text(json.dumps(doc, indent="\t"))
    spaces.write_text(yaml.safe_dump(doc))
    assert "\t" in tabs.read_text()
    a, b = read_trajectory(tabs), read_trajectory(spaces)
    assert a.joint_names == b.joint_names
    assert a.time_from_start_s.tobytes() == b.time_from_start_s.tobytes()
    assert a.positions_rad.tobytes() == b.positions_rad.tobytes() and a.velocities_rad_s is b.velocities_rad_s
    # the strict checks of the fast path hold with tabs too: a key given twice is still refused in one line
    twice = tmp_path / "twice.json"
    twice.write_text(json.dumps(doc, indent="\t").replace('"points"', '"joint_names": [],\n\t"points"', 1))
    with pytest.raises(TrajectoryError, match="not YAML or JSON"):
        read_trajectory(twice)


@pytest.mark.parametrize("time, words", [
    ("1e999", "inf s is out of range"), ("1e308", "1e+308 s is out of range"),
    ("4294967296.5", "4.29497e+09 s is out of range"), ("-1", "-1 s is out of range"),
    ("NaN", "nan s is out of range"),
])
def test_the_sender_refuses_times_that_trajectory_refuses(tmp_path, time, words):
    doc = _example()
    doc["points"][-1]["time_from_start"] = "T"
    if time == "NaN":   # not JSON: YAML's .nan
        f = tmp_path / "far.yaml"
        f.write_text(yaml.safe_dump(doc).replace("time_from_start: T", "time_from_start: .nan"))
    else:
        f = tmp_path / "far.json"
        f.write_text(json.dumps(doc).replace('"T"', time))
    with pytest.raises(TrajectoryError, match=re.escape(words)):
        read_sendable(f)
    rc, err = _sender(f)
    _one_line(rc, err, "trajectory_sender: error:", f, "points[4].time_from_start", words)
    r = run_cli("simulate", "--trajectory", f, "--controller", "pid", "--duration", "0.02", "--no-figures",
                "--out", tmp_path / "o")
    assert r.returncode == 2 and "points[4].time_from_start" in r.stderr, r.stderr


def test_the_sender_reads_what_trajectory_reads():
    a, b = read_sendable(EXAMPLE), read_trajectory(EXAMPLE)
    assert a.time_from_start_s.tobytes() == b.time_from_start_s.tobytes()
    assert a.positions_rad.tobytes() == b.positions_rad.tobytes()


@pytest.mark.parametrize("flags, words", [
    (("--stamp", "nan"), "--stamp"), (("--stamp", "1e300"), "--stamp"), (("--stamp", "-1"), "--stamp"),
    (("--stamp", "4294967296.5"), "past what header.stamp carries"),
    (("--stamp", "2147483647.9999999999"), "past what header.stamp carries"),
    (("--namespace", "bad ns"), "--namespace"), (("--namespace", "/é"), "--namespace"),
    (("--namespace", "/"), "--namespace"),
    (("--wait", "nan"), "--wait"), (("--wait", "0"), "--wait"), (("--wait", "3601"), "--wait"),
    (("--gap", "inf"), "--gap"), (("--clock-gap", "-1"), "--clock-gap"), (("--after-clock", "nan"), "--after-clock"),
])
def test_sender_flags_out_of_range_are_one_line_before_ros_starts(flags, words):
    rc, err = _sender(EXAMPLE, *flags)
    _one_line(rc, err, "trajectory_sender: error:", words)


def test_a_stamp_within_range_is_carried_exactly():
    from pa10_dnbs.ros.trajectory_sender import message
    msg = message(read_sendable(EXAMPLE), 2147483647.5)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (2147483647, 500000000)
    assert [(p.time_from_start.sec, p.time_from_start.nanosec) for p in msg.points][-1] == (4, 0)


@pytest.mark.graph
def test_ctrl_c_while_the_sender_waits_is_one_line_and_130(domain):
    sender = Proc([sys.executable, "-m", "pa10_dnbs.ros.trajectory_sender", EXAMPLE, "--wait", "60"], domain)
    try:
        sender.wait_for(r"waiting for a graph that takes trajectories", timeout=60)
        started = time.monotonic()
        sender.interrupt()
        rc = sender.wait(timeout=30)
    finally:
        sender.kill()
    assert rc == 130, (rc, sender.output)
    assert time.monotonic() - started < 10, sender.output
    assert "Traceback" not in sender.output and sender.lines[-1] == (
        "trajectory_sender: interrupted (the files above marked sent were sent)"), sender.output
    assert not any(line.startswith("sent ") for line in sender.lines), sender.output


@pytest.mark.parametrize("field", ["positions", "sec"])
def test_the_sender_refuses_a_whole_number_too_large_for_a_float(tmp_path, field):
    f = tmp_path / "huge.json"
    f.write_text(_text("json", field))
    rc, err = _sender(f)
    _one_line(rc, err, "trajectory_sender: error:", f, "too large for a float")


def test_a_yaml_alias_bomb_is_refused_before_it_is_built(tmp_path):
    """A "billion laughs" ``effort:`` (anchors, each ten aliases of the one below) was expanded by the message's
    repr, taking all memory; now one line naming the file."""
    from yaml_bomb import alias_bomb
    f = tmp_path / "bomb.yaml"
    f.write_text("joint_names: [a]\npoints:\n  - time_from_start: 1\n    positions: [0]\n    effort:\n"
                 + alias_bomb(indent="      "))
    with pytest.raises(TrajectoryError, match=re.escape("refused: its aliases (*name) expand it to 1.23e+07 nodes")):
        read_trajectory(f)
    r = run_cli("simulate", "--trajectory", f, "--controller", "pid", "--duration", "0.02", "--no-figures",
                "--out", tmp_path / "o")
    _one_line(r.returncode, r.stderr[-300:], "--trajectory", f, "refused: its aliases")
    assert len(r.stderr.splitlines()[-1]) < 300 and not (tmp_path / "o").exists()


def test_a_pipe_or_a_device_is_refused_unread(tmp_path):
    """A FIFO with no writer blocked the read forever, /dev/zero read until MemoryError: refused as --config and
    --arm refuse them, unread (bash's ``<(...)`` is a pipe too). A FIFO still read (old code) is unblocked here."""
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    said = []

    def read():
        try:
            read_trajectory(fifo)
        except TrajectoryError as exc:
            said.append(str(exc))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(timeout=10)
    if reader.is_alive():   # blocked opening the FIFO: a writer that closes at once ends the read
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        reader.join(timeout=30)
    assert said == ["not a regular file (a pipe or a device): give the path of a file"], said
    for device in ("/dev/null", "/dev/zero"):
        r = run_cli("simulate", "--trajectory", device, "--controller", "pid", "--duration", "0.02", "--no-figures",
                    "--out", tmp_path / "o")
        assert r.returncode == 2 and r.stderr.splitlines()[-1] == (f"pa10-dnbs: error: --trajectory {device}: not a "
                                                                   f"regular file (a pipe or a device): give the path "
                                                                   f"of a file"), r.stderr[-500:]
        assert not (tmp_path / "o").exists()


def _listener(domain, *namespaces):
    listener = Proc([sys.executable, REPO / "test" / "trajectory_listener.py", domain, *namespaces], domain)
    listener.wait_for("LISTENING", timeout=60)
    return listener


@pytest.mark.graph
def test_without_namespace_the_sender_finds_the_graph_of_another_arm(domain):
    """A graph of the Panda (/panda) takes the file with no --namespace given; the sender used to send to /pa10
    whatever the arm, and waited there until --wait ran out (exit 1)."""
    listener = _listener(domain, "/panda")
    sender = Proc([sys.executable, "-m", "pa10_dnbs.ros.trajectory_sender", EXAMPLE, "--wait", "60"], domain)
    try:
        rc = sender.wait(timeout=90)
        listener.wait_for("GOT /panda/trajectory", timeout=30)
    finally:
        sender.kill()
        listener.interrupt()
        listener.wait(timeout=30)
    assert rc == 0, sender.output
    assert f"sent {EXAMPLE} at /clock 0.000 s" in sender.lines, sender.output


@pytest.mark.graph
def test_without_namespace_two_graphs_are_one_line_naming_both(domain):
    listener = _listener(domain, "/panda", "/iiwa")
    sender = Proc([sys.executable, "-m", "pa10_dnbs.ros.trajectory_sender", EXAMPLE, "--wait", "60"], domain)
    try:
        rc = sender.wait(timeout=90)
    finally:
        sender.kill()
        listener.interrupt()
        listener.wait(timeout=30)
    assert rc == 2, sender.output
    err = [x for x in sender.lines if "error" in x]
    assert err == ["trajectory_sender: error: several graphs take trajectories (/iiwa/trajectory, "
                   "/panda/trajectory): give --namespace"], sender.output
    assert not any(x.startswith("sent ") for x in sender.lines) and "GOT" not in listener.output, listener.output
