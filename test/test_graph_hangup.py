"""SIGHUP (the terminal closed, an ssh session dropped: the shell hangs up its jobs, the launcher and its nodes) is a
stop like Ctrl-C and SIGTERM (interrupt.STOP_SIGNALS). Before, its default action ended the launcher at once: exit
129, no line, the hidden ``.OUT.partial-XXXX`` folder left beside --out for good, and the nodes killed by the same
signal (the recorder's bag cut short, never closed)."""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys

import pytest

from test_misuse_interrupt import REPO, Command, _running

from pa10_dnbs.interrupt import child_pids


@pytest.mark.graph
def test_a_hangup_stops_launch_as_sigterm_does(tmp_path, domain, monkeypatch):
    from graph_harness import assert_no_leftovers, ros_env
    from pa10_dnbs.bag.bag_reader import Bag
    from pa10_dnbs.ros.shm_cleanup import shm_files

    monkeypatch.setattr(os, "environ", dict(os.environ))   # the ROS_* settings stay in this test
    os.environ.update({k: v for k, v in ros_env(domain).items() if k.startswith("ROS_")})
    shm_before = shm_files()
    bag = tmp_path / "bag"
    c = Command("launch", "--domain-id", domain, "--duration", 60, "--no-figures", "--no-progress",
                "--out", tmp_path / "run", "--record", bag)   # its own process group: a terminal's job
    try:
        _running(c)
        nodes = child_pids(c.proc.pid)
        os.killpg(c.proc.pid, signal.SIGHUP)   # the shell's hang-up of its job: the launcher and every node
        out, err = c.proc.communicate(timeout=30)
    finally:
        c.kill()
    assert c.proc.returncode == 130, (c.proc.returncode, out, err)
    assert err.splitlines() == ["pa10-dnbs launch: FAILED: interrupted (SIGHUP)",
                                f"pa10-dnbs launch: the bag recorded so far is closed and readable: {bag}"], err
    codes = dict(kv.split("=") for kv in out.split("launch: stopped: ")[1].split(";")[0].split())
    assert len(codes) == len(nodes) and set(codes.values()) == {"0"}, codes   # each node stopped on its own path
    assert_no_leftovers(nodes, shm_before)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]   # no output, no hidden .run.partial-XXXX
    with Bag(bag) as b:   # closed: footer, summary and metadata.yaml agree
        assert b.topics["/pa10/joint_states"].count > 0


@pytest.mark.graph
def test_a_closed_terminal_stops_launch_with_exit_130_and_leaves_no_partial_folder(tmp_path, domain, monkeypatch):
    """The terminal itself goes (its pty closed, as sshd does when the connection drops): the kernel hangs up the
    foreground group, and every write to the terminal fails (EIO). The stop's line cannot be written; its error
    must not replace the exit code (130: it was 1), nor the clean-up (it was 129: the .partial folder left, the
    nodes killed by the hang-up, the bag unfinished)."""
    import pty
    import select
    import time

    from graph_harness import ros_env
    from pa10_dnbs.bag.bag_reader import Bag

    bag = tmp_path / "bag"
    argv = [sys.executable, "-m", "pa10_dnbs.cli", "launch", "--domain-id", str(domain), "--duration", "60",
            "--no-figures", "--out", str(tmp_path / "run"), "--record", str(bag)]
    env = ros_env(domain)
    pid, fd = pty.fork()   # the child: a session of its own, on the pty as its controlling terminal
    if pid == 0:   # pragma: no cover - the child
        try:
            os.chdir(REPO)
            os.execve(sys.executable, argv, env)
        finally:
            os._exit(127)
    seen, nodes, closed = b"", [], False
    try:
        deadline = time.monotonic() + 120
        while b"launch: plant running" not in seen:
            assert time.monotonic() < deadline, seen.decode(errors="replace")
            if select.select([fd], [], [], 1.0)[0]:
                try:
                    seen += os.read(fd, 4096)
                except OSError:   # EIO: the launcher ended
                    pytest.fail(seen.decode(errors="replace"))
        nodes = child_pids(pid)
        os.close(fd)   # the terminal goes away
        closed = True
        t0 = time.monotonic()
        while (ended := os.waitpid(pid, os.WNOHANG))[0] == 0:
            assert time.monotonic() - t0 < 30, "still running 30 s after its terminal closed"
            time.sleep(0.05)
        code = os.waitstatus_to_exitcode(ended[1])
    finally:
        if not closed:
            os.close(fd)
        with contextlib.suppress(ChildProcessError, ProcessLookupError):
            if os.waitpid(pid, os.WNOHANG)[0] == 0:
                os.killpg(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
    assert code == 130, code
    time.sleep(0.5)
    assert not [p for p in nodes if os.path.exists(f"/proc/{p}")], nodes
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]   # no output, no hidden .run.partial-XXXX
    with Bag(bag) as b:   # each node stopped on its own path: the recorder closed the bag
        assert b.topics["/pa10/joint_states"].count > 0


@pytest.mark.parametrize("ignored", [False, True], ids=["hangup", "nohup"])
def test_the_stop_signals_take_sighup_unless_nohup_ignores_it(ignored):
    """A command (and a launcher's node: it inherits the disposition) under ``nohup`` is to outlive its terminal:
    SIGHUP stays ignored there; elsewhere it stops the command with its line, exit 130."""
    code = ("import os, signal, sys, time; from pa10_dnbs import interrupt\n"
            "with interrupt.two_stage_sigint():\n"
            "    try:\n"
            "        os.kill(os.getpid(), signal.SIGHUP); time.sleep(0.5); print('outlived', flush=True)\n"
            "    except KeyboardInterrupt:\n"
            "        print('stopped', flush=True)\n")
    argv = [sys.executable, "-c", code]
    r = subprocess.run(["nohup", *argv] if ignored else argv, cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)),
                       capture_output=True, text=True, timeout=60)
    assert (r.returncode, r.stdout) == (0, "outlived\n" if ignored else "stopped\n"), r
