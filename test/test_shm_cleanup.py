"""The /dev/shm cleanup removes only files nobody maps and whose creator is gone (Fast DDS's lock on the ``_el``
file is free), and counts a mapping or that lock in another process.

The test file stays mapped by this process while a test runs: another test's clean-up (a parallel worker's
``domain`` fixture, a launcher) counts that mapping and leaves it alone, and these tests ignore it
(``ignore_pids``) where they mean "unmapped"."""
import mmap
import os
import subprocess
import sys
from contextlib import contextmanager

import pytest

from pa10_dnbs.ros.shm_cleanup import SHM_DIR, remove_stale, shm_files, unused


HERE = frozenset({os.getpid()})


@pytest.fixture
def shm_file():
    name = f"lttng-ust-wait-test-{os.getpid()}"
    path = os.path.join(SHM_DIR, name)
    with open(path, "wb") as fh:
        fh.write(b"\0" * mmap.PAGESIZE)
    with open(path, "r+b") as fh, mmap.mmap(fh.fileno(), mmap.PAGESIZE):
        yield name, path
    if os.path.exists(path):
        os.unlink(path)


def test_unmapped_file_is_removed_and_listed(shm_file):
    name, path = shm_file
    assert name in shm_files()
    assert remove_stale({name}, ignore_pids=HERE) == [name]
    assert not os.path.exists(path)


def test_file_mapped_here_is_kept_unless_this_process_is_ignored(shm_file):
    name, path = shm_file  # mapped here by the fixture
    assert remove_stale({name}) == []
    assert os.path.exists(path)
    assert remove_stale({name}, ignore_pids=HERE) == [name]
    assert not os.path.exists(path)


@contextmanager
def another_process(code: str):
    """A child running ``code`` (which prints one line when it holds what it takes, then waits on stdin) until the
    block ends."""
    child = subprocess.Popen([sys.executable, "-c", code + "; print('holding', flush=True); sys.stdin.read()"],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "holding"
        yield child
    finally:
        child.stdin.close()
        child.wait(timeout=10)


def test_file_mapped_by_another_process_is_kept(shm_file):
    name, path = shm_file
    with another_process(f"import mmap, sys; fh = open({path!r}, 'r+b'); m = mmap.mmap(fh.fileno(), {mmap.PAGESIZE})"):
        assert remove_stale({name}, ignore_pids=HERE) == []
        assert os.path.exists(path)
    assert remove_stale({name}, ignore_pids=HERE) == [name]


def test_snapshot_then_since_removes_only_the_new_unused_files(shm_file, tmp_path):
    """The hand-start clean-up of docs/graph.md: a file in the snapshot stays, one created after it goes."""
    from pa10_dnbs.ros.shm_cleanup import main

    old_name, old_path = shm_file
    snap = tmp_path / "before.txt"
    assert main(["--snapshot", str(snap)]) == 0 and old_name in snap.read_text().split()
    new_path = os.path.join(SHM_DIR, f"lttng-ust-wait-test-new-{os.getpid()}")
    with open(new_path, "wb") as fh:
        fh.write(b"\0" * mmap.PAGESIZE)
    try:
        assert main(["--since", str(snap)]) == 0
        assert not os.path.exists(new_path) and os.path.exists(old_path)
    finally:
        if os.path.exists(new_path):
            os.unlink(new_path)
    assert main(["--since", str(tmp_path / "missing.txt")]) == 2


@pytest.fixture
def port_files():
    """A Fast DDS port's three files, as a participant leaves them: segment, lock file, semaphore (unmapped)."""
    owner = f"fastrtps_port_test_{os.getpid()}"
    names = {owner, owner + "_el", f"sem.{owner}_mutex"}
    for n in names:
        with open(os.path.join(SHM_DIR, n), "wb") as fh:
            fh.write(b"\0" * 64)
    yield owner, names
    for n in names:
        if os.path.exists(os.path.join(SHM_DIR, n)):
            os.unlink(os.path.join(SHM_DIR, n))


def test_a_port_whose_creator_lives_is_kept_though_nobody_maps_it(port_files):
    """A participant starting in a concurrent run has locked its port and created it, but not mapped it yet:
    removing the name then would leave it deaf (the next sender makes a new segment under that name)."""
    owner, names = port_files
    with another_process(f"import fcntl, os, sys; fd = os.open({os.path.join(SHM_DIR, owner + '_el')!r}, "
                         "os.O_RDWR); fcntl.flock(fd, fcntl.LOCK_EX)"):
        assert unused(names, ignore_pids=HERE) == set()
        assert remove_stale(names, ignore_pids=HERE) == []
        assert all(os.path.exists(os.path.join(SHM_DIR, n)) for n in names)
    assert unused(names, ignore_pids=HERE) == names  # the creator is gone: the kernel dropped its lock
    assert remove_stale(names, ignore_pids=HERE) == sorted(names)
    assert not any(os.path.exists(os.path.join(SHM_DIR, n)) for n in names)


def test_a_port_locked_by_an_ignored_process_goes(port_files):
    """At a test session's end its own in-process participants' files count as gone (ignore_pids)."""
    import fcntl

    owner, names = port_files
    fd = os.open(os.path.join(SHM_DIR, owner + "_el"), os.O_RDWR)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        assert remove_stale(names) == []
        assert remove_stale(names, ignore_pids=HERE) == sorted(names)
    finally:
        os.close(fd)


@pytest.mark.parametrize("flag, path, why", [
    ("--snapshot", "", "give the snapshot file's path"),
    ("--since", "", "give the snapshot file's path"),
    ("--snapshot", "{tmp}", "cannot write it"),                  # a directory
    ("--snapshot", "{tmp}/missing/snap.txt", "cannot write it"),  # its folder is missing
    ("--since", "{tmp}", "cannot read it"),
    ("--since", "{tmp}/binary.bin", "not a snapshot"),
    ("--since", "{tmp}/other.txt", "not a snapshot"),             # text, but no snapshot of this module
])
def test_a_path_it_cannot_use_is_one_line_and_exit_2(flag, path, why, tmp_path, capsys):
    """The hand-start clean-up's own mistakes: no traceback (``--snapshot ''`` fell through to --since with None,
    a directory or a binary file raised), and --since removes nothing it was not given a snapshot for."""
    from pa10_dnbs.ros.shm_cleanup import main

    (tmp_path / "binary.bin").write_bytes(bytes(range(256)))
    (tmp_path / "other.txt").write_text("fastrtps_port7000\n")
    assert main([flag, path.format(tmp=tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"shm_cleanup: {flag} ") and why in err[0], err
