"""Runs that only read a bag share it (a shared lock, output_lock.lock_input); a run that writes it holds it alone.

Two `analyse` of one bag at once: the second was refused "in use by another run" (analyse took the recorder's
exclusive lock). Now any number of readers hold a path at once; a reader is refused only while a writer holds it, a
writer while anyone does; the lock file stays while a reader holds it and is removed by the last one out.
"""
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from cli_runner import run_cli
from test_bag_files import _write_run_bag

from pa10_dnbs.output_lock import (OutputInUseError, _lock_file, lock_input, lock_output, release_output)

REPO = Path(__file__).resolve().parent.parent


def _holder(path: Path, how: str) -> subprocess.Popen:
    """A process holding ``path``'s lock (``how``: lock_input or lock_output) until SIGINT."""
    code = (f"import time; from pathlib import Path; from pa10_dnbs.output_lock import {how}; "
            f"{how}(Path({str(path)!r}), 'bag'); print('held', flush=True); time.sleep(60)")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                         env={**os.environ, "PYTHONPATH": str(REPO)})
    assert p.stdout.readline().strip() == "held"
    return p


def _stop(p: subprocess.Popen) -> None:
    p.send_signal(signal.SIGINT)   # KeyboardInterrupt: the holder leaves through atexit, releasing its lock
    p.wait(timeout=60)


def test_readers_share_a_path_and_a_writer_is_refused_while_one_holds_it(tmp_path):
    path = tmp_path / "bag"
    file = _lock_file(str(path.resolve()))
    reader = _holder(path, "lock_input")
    try:
        lock_input(path)                         # a second reader at the same time
        with pytest.raises(OutputInUseError, match=f"in use by another run \\(pid ({reader.pid}|{os.getpid()})\\)"):
            _refused_writer(path)                # the pid of a reader: the last to take it
        release_output(path)
        assert file.exists()                     # the other reader still holds it: its file stays
        with pytest.raises(OutputInUseError, match="in use by another run"):
            lock_output(path)
    finally:
        _stop(reader)
    assert not file.exists()                     # the last reader out removed it
    lock_output(path)                            # now a writer takes it
    release_output(path)


def _try_in_another_process(call: str, path: Path) -> None:
    """``call`` (lock_output or lock_input) of ``path`` in another process: raises the OutputInUseError it got."""
    code = (f"import sys; from pathlib import Path; from pa10_dnbs.output_lock import OutputInUseError, {call}\n"
            f"try:\n    {call}(Path({str(path)!r}), 'bag')\nexcept OutputInUseError as e:\n"
            "    print(e); sys.exit(3)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                       env={**os.environ, "PYTHONPATH": str(REPO)})
    if r.returncode == 3:
        raise OutputInUseError(r.stdout.strip())
    assert r.returncode == 0, r.stderr


def _refused_writer(path: Path) -> None:
    """A writer in another process tries ``path``."""
    _try_in_another_process("lock_output", path)


def test_a_reader_is_refused_while_a_writer_holds_the_path(tmp_path):
    path = tmp_path / "bag"
    writer = _holder(path, "lock_output")
    try:
        with pytest.raises(OutputInUseError, match=f"pid {writer.pid}\\), which writes it"):
            lock_input(path)
    finally:
        _stop(writer)
    lock_input(path)
    release_output(path)
    assert not _lock_file(str(path.resolve())).exists()


def test_a_shared_lock_is_made_exclusive_only_when_no_other_reader_holds_it(tmp_path):
    """The same process asking alone for what it holds shared: granted when it is the only reader, refused (still
    holding it shared) while another reader holds it."""
    path = tmp_path / "bag"
    lock_input(path)
    reader = _holder(path, "lock_input")
    try:
        with pytest.raises(OutputInUseError):
            lock_output(path)
        lock_input(path)                         # held shared still: a no-op
    finally:
        _stop(reader)
    lock_output(path)
    with pytest.raises(OutputInUseError, match="which writes it"):
        _refused_reader(path)
    release_output(path)
    assert not _lock_file(str(path.resolve())).exists()


def _refused_reader(path: Path) -> None:
    """A reader in another process tries ``path``."""
    _try_in_another_process("lock_input", path)


def test_analyse_of_a_bag_another_run_reads_runs(tmp_path):
    """The reviewer's case: a second analyse (or a replay) of a bag the first is reading. The reader that holds it
    is a process with the shared lock, as a running analyse holds it."""
    bag = _write_run_bag(tmp_path / "b", n=50, ns="/pa10")
    reader = _holder(bag, "lock_input")
    try:
        r = run_cli("analyse", bag, "--out", tmp_path / "out", "--no-figures", "--no-progress")
        assert r.returncode == 0, r.stderr
        assert (tmp_path / "out" / "metrics.json").is_file()
    finally:
        _stop(reader)


def test_replay_of_a_bag_another_run_writes_is_refused(tmp_path):
    """replay reads the bag: it takes the shared lock, so a bag being recorded (or replaced with --force) is
    refused in one line before ROS, and a recorder's --force waits for no replay to read it away."""
    bag = _write_run_bag(tmp_path / "b", n=50, ns="/pa10")
    writer = _holder(bag, "lock_output")
    try:
        r = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "replay", str(bag)], cwd=REPO, capture_output=True,
                           text=True, timeout=120, env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    finally:
        _stop(writer)
    assert r.returncode == 2 and r.stdout == "", r.stdout + r.stderr
    assert r.stderr.strip() == f"pa10-dnbs: error: bag {bag} is in use by another run (pid {writer.pid}), which " \
                               "writes it; wait for it to end", r.stderr
