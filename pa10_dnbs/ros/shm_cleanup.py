"""Remove the shared-memory files that dead ROS processes left behind, and never a live one's.

Fast DDS keeps segments in /dev/shm (``fastrtps_<hex>``, ``fastrtps_port<N>``
with ``_el`` lock files and ``sem.fastrtps_port<N>_mutex`` semaphores). A
participant destroyed in order removes them; a killed process does not, and
neither does a node of this graph, which leaves without destroying its node
(``ros/runtime.py``: ``exit_process``). Left behind, they can disturb later
runs. Port segments are shared across domains (the metatraffic ports
``fastrtps_port7000``... are taken first-free by every domain on the host),
so deleting by pattern would break other live graphs.

A file goes only when its owner is dead, as Fast DDS itself tells it: the
process that created segment ``X`` holds an exclusive ``flock`` on ``X_el``
from before the segment exists until it exits (its participant segment and
every port it listens on). The file is removed while this process holds that
lock itself (so no participant can take the port meanwhile), and only if no
live process maps the segment (a sender's cached mapping of a port must stay
the file a new listener reopens). Mappings alone are not enough: a participant
starting in a concurrent run has locked and created its port but not yet
mapped it, and removing the name then leaves it deaf (the next sender creates
a new segment under the name), so that run's discovery never completes.

So a launcher sweeps every dead file at the end of its run (``remove_stale(shm_files())``),
its own and those another run could not remove because this run still mapped
them, and so does a trajectory sender when it leaves (it maps the graph's ports,
so a sender that outlives the graph keeps them from the launcher's sweep);
``--snapshot``/``--since`` remove only what appeared meanwhile.

The ROS wheels' rcl and rmw also load LTTng-UST (tracetools), which creates
``lttng-ust-wait-<version>[-<uid>]`` (4 KB each, for waking traced apps when
an LTTng session daemon starts) and never removes it. It has no lock file:
removed when no live process maps it.
"""
from __future__ import annotations

import fcntl
import glob
import os
from contextlib import contextmanager

SHM_DIR = "/dev/shm"


def shm_files() -> set[str]:
    """Names of the Fast DDS and LTTng-UST files in /dev/shm now."""
    try:
        return {f for f in os.listdir(SHM_DIR)
                if "fastrtps" in f or "fast_datasharing" in f or f.startswith("lttng-ust-wait-")}
    except FileNotFoundError:
        return set()


def _mapped_segments(ignore_pids: frozenset[int] = frozenset()) -> set[str]:
    """Names of the /dev/shm files some live process (other than ignore_pids) maps."""
    names = set()
    for maps in glob.glob("/proc/[0-9]*/maps"):
        if int(maps.split("/")[2]) in ignore_pids:
            continue
        try:
            with open(maps) as fh:
                for line in fh:
                    i = line.find(SHM_DIR + "/")
                    if i >= 0:
                        names.add(line[i + len(SHM_DIR) + 1:].split()[0])
        except OSError:
            continue
    return names


def _owner(name: str) -> str:
    """The segment whose mapping keeps ``name`` in use."""
    if name.startswith("sem.") and name.endswith("_mutex"):
        return name[4:-6]
    if name.endswith("_el"):
        return name[:-3]
    return name


def _lock_holders() -> dict[int, set[int]]:
    """inode -> pids holding a flock on it, from /proc/locks (what a failed lock attempt cannot say: who)."""
    holders: dict[int, set[int]] = {}
    try:
        with open("/proc/locks") as fh:
            for line in fh:
                parts = line.split()
                if len(parts) > 5 and parts[1] == "FLOCK":
                    holders.setdefault(int(parts[5].split(":")[2]), set()).add(int(parts[4]))
    except (OSError, ValueError, IndexError):
        pass
    return holders


@contextmanager
def _dead_owner(owner: str, ignore_pids: frozenset[int]):
    """Yield True while this process holds ``owner``'s Fast DDS lock file (its creator is gone, and no participant
    can take it meanwhile), False if a live process other than ``ignore_pids`` holds it, None if it has none."""
    path = os.path.join(SHM_DIR, owner + "_el")
    try:
        fd = os.open(path, os.O_RDWR | os.O_CLOEXEC)
    except FileNotFoundError:
        yield None
        return
    except OSError:
        yield False  # another user's file
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            dead = True
        except BlockingIOError:
            pids = _lock_holders().get(os.fstat(fd).st_ino, set())
            dead = bool(ignore_pids) and bool(pids) and pids <= ignore_pids
        yield dead
    finally:
        os.close(fd)  # drops the lock


def _removable(names: set[str], ignore_pids: frozenset[int]):
    """(owner, its files among ``names``, whether they may go) for each owner: dead (lock file free, or held only
    by ``ignore_pids``) and unmapped; without a lock file, unmapped. The lock is held while the caller acts."""
    groups: dict[str, set[str]] = {}
    for n in names:
        groups.setdefault(_owner(n), set()).add(n)
    busy = _mapped_segments(ignore_pids)
    for owner, files in sorted(groups.items()):
        with _dead_owner(owner, ignore_pids) as dead:
            free = dead is not False and not (files | {owner}) & busy
            yield owner, files, free


def unused(names: set[str], ignore_pids: frozenset[int] = frozenset()) -> set[str]:
    """The files among ``names`` whose owner is gone and that no live process (other than ignore_pids) maps: a
    run's leftovers, not the segments of other graphs running on the host at the same time."""
    return {f for _, files, free in _removable(names, ignore_pids) if free for f in files}


def remove_stale(created_during_run: set[str], ignore_pids: frozenset[int] = frozenset()) -> list[str]:
    """Delete the given files whose owner is gone and that no live process uses; return what was removed.

    ignore_pids: processes about to exit whose mappings and locks do not count (a test
    session that loaded rclpy itself, at its end).
    """
    removed = []
    for owner, files, free in _removable(created_during_run, ignore_pids):
        if not free:
            continue
        for name in sorted(files, key=lambda f: f.endswith("_el")):  # the lock file last
            try:
                os.unlink(os.path.join(SHM_DIR, name))
                removed.append(name)
            except OSError:
                pass
    return sorted(removed)


SNAPSHOT_HEADER = "# pa10_dnbs.ros.shm_cleanup snapshot of /dev/shm"


def main(argv: list[str] | None = None) -> int:
    """``python -m pa10_dnbs.ros.shm_cleanup --snapshot FILE`` before a hand-started session writes the names
    present; ``--since FILE`` after it removes the files that appeared since, whose creator is gone and that no
    live process maps. A path that cannot be written or read, or a file that is no snapshot: one line, exit 2."""
    import argparse
    import sys

    ap = argparse.ArgumentParser(prog="python -m pa10_dnbs.ros.shm_cleanup", description=main.__doc__)
    group = ap.add_mutually_exclusive_group(required=True)
    group.add_argument("--snapshot", metavar="FILE", help="write the Fast DDS / LTTng-UST names in /dev/shm now")
    group.add_argument("--since", metavar="FILE", help="remove the unused files that are not in this snapshot")
    args = ap.parse_args(argv)
    flag, path = ("--snapshot", args.snapshot) if args.snapshot is not None else ("--since", args.since)

    def refuse(why: str) -> int:
        print(f"shm_cleanup: {flag} {path!r}: {why}", file=sys.stderr)
        return 2

    if not path:
        return refuse("give the snapshot file's path")
    if flag == "--snapshot":
        try:
            with open(path, "w") as fh:
                fh.write("".join(f"{line}\n" for line in [SNAPSHOT_HEADER, *sorted(shm_files())]))
        except OSError as exc:
            return refuse(f"cannot write it: {exc.strerror or exc}")
        return 0
    try:
        with open(path, encoding="utf-8") as fh:
            lines = fh.read().splitlines()
    except OSError as exc:
        return refuse(f"cannot read it: {exc.strerror or exc}")
    except UnicodeDecodeError:
        lines = []
    if not lines or lines[0] != SNAPSHOT_HEADER:
        return refuse("not a snapshot this module wrote (--snapshot FILE writes one)")
    removed = remove_stale(shm_files() - set(lines[1:]))
    print(f"shm_cleanup: removed {len(removed)} files from {SHM_DIR}" + (f": {' '.join(removed)}" if removed else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
