"""A Ctrl-C once a ``launch --record`` run has finished, while the launcher writes its outputs (after its
``launch: stopped:`` line): the bag is whole by then, so the outputs are finished too and the line says so (exit
130), as ``simulate`` does. Before, they were thrown away with "interrupted before it wrote anything ...: run the
same command again", which the bag then refused ("--record: ... exists; pass --force"). A second Ctrl-C ends at
once, and its line says the bag is whole."""
from __future__ import annotations

import os
import time

import pytest

from test_misuse_interrupt import BOUND_S, SECOND_PRESS_S, Command, one_line

pytestmark = pytest.mark.graph  # starts ROS processes


def _launch_recording(tmp_path, domain, monkeypatch, *extra) -> Command:
    """A 1 s lockstep ``launch --record`` in its own process group, stopped at its ``launch: stopped:`` line."""
    from graph_harness import ros_env

    monkeypatch.setattr(os, "environ", dict(os.environ))   # the ROS_* settings stay in this test
    os.environ.update({k: v for k, v in ros_env(domain).items() if k.startswith("ROS_")})
    c = Command("launch", "--domain-id", domain, "--duration", 1, "--no-progress", "--out", tmp_path / "run",
                "--record", tmp_path / "bag", *extra)
    for line in c.proc.stdout:
        if line.startswith("launch: stopped:"):   # the graph has stopped: the recorder closed the bag
            return c
    c.kill()
    pytest.fail("the graph never stopped: " + c.proc.stderr.read())


def test_a_ctrl_c_while_launch_writes_its_outputs_finishes_them_and_says_so(tmp_path, domain, monkeypatch):
    c = _launch_recording(tmp_path, domain, monkeypatch, "--no-figures")
    try:
        c.ctrl_c()
        rc, seconds, err = c.end()
    finally:
        c.kill()
    run, bag = tmp_path / "run", tmp_path / "bag"
    assert rc == 130 and seconds < BOUND_S, (rc, seconds, err)
    assert one_line(err) == (f"pa10-dnbs: interrupted as it finished: {run} is written whole ({run}/report.md); "
                             f"the bag {bag} is whole"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag", "run"]   # no hidden .run.partial-XXXX
    assert (run / "report.md").is_file() and (run / "metrics.json").is_file()


def test_a_second_ctrl_c_while_launch_writes_its_outputs_ends_at_once_and_names_the_whole_bag(
        tmp_path, domain, monkeypatch):
    c = _launch_recording(tmp_path, domain, monkeypatch)   # with figures: seconds of writing
    try:
        c.ctrl_c()
        time.sleep(SECOND_PRESS_S)
        c.ctrl_c()
        rc, seconds, err = c.end()
    finally:
        c.kill()
    run, bag = tmp_path / "run", tmp_path / "bag"
    assert rc == 130 and seconds < SECOND_PRESS_S + 2.0, (rc, seconds, err)
    assert one_line(err) == (f"pa10-dnbs launch: interrupted again: stopped at once; nothing written to {run}; the "
                             f"bag {bag} is whole (`pa10-dnbs analyse {bag} --out DIR` makes the report from it; a "
                             "new run into it needs --force)"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]   # the half-written folder removed
