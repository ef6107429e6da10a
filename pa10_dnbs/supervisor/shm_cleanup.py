"""Remove the shared-memory files a run's ROS processes left behind, and only those.

Fast DDS keeps segments in /dev/shm (``fastrtps_<hex>``, ``fastrtps_port<N>``
with ``_el`` lock files and ``sem.fastrtps_port<N>_mutex`` semaphores). A
participant destroyed in order removes them; a killed process does not, and
neither does a node of this graph, which leaves without destroying its node
(``ros/runtime.py``: ``exit_process``). Port segments are numbered
across all domains, so deleting by pattern would break other live graphs: a
segment is removed only if it appeared during this run and no live process
maps it (a semaphore counts as in use while its port segment is mapped).

The ROS wheels' rcl and rmw also load LTTng-UST (tracetools), which creates
``lttng-ust-wait-<version>[-<uid>]`` (4 KB each, for waking traced apps when
an LTTng session daemon starts) and never removes it. The same rule applies:
removed if this run created it and no live process maps it.
"""
from __future__ import annotations

import glob
import os

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


def unused(names: set[str], ignore_pids: frozenset[int] = frozenset()) -> set[str]:
    """The files among ``names`` that no live process (other than ignore_pids) uses: a run's leftovers,
    not the segments of other graphs running on the host at the same time."""
    busy = _mapped_segments(ignore_pids)
    return {n for n in names if n not in busy and _owner(n) not in busy}


def remove_stale(created_during_run: set[str], ignore_pids: frozenset[int] = frozenset()) -> list[str]:
    """Delete the given files that no live process uses; return what was removed.

    ignore_pids: processes about to exit whose mappings do not count (a test
    session that loaded rclpy itself, at its end).
    """
    busy = _mapped_segments(ignore_pids)
    removed = []
    for name in sorted(created_during_run):
        if name in busy or _owner(name) in busy:
            continue
        try:
            os.unlink(os.path.join(SHM_DIR, name))
            removed.append(name)
        except OSError:
            pass
    return removed


def main(argv: list[str] | None = None) -> int:
    """``python -m pa10_dnbs.supervisor.shm_cleanup --snapshot FILE`` before a hand-started session writes the names
    present; ``--since FILE`` after it removes the files that appeared since and that no live process maps."""
    import argparse
    import sys

    ap = argparse.ArgumentParser(prog="python -m pa10_dnbs.supervisor.shm_cleanup", description=main.__doc__)
    group = ap.add_mutually_exclusive_group(required=True)
    group.add_argument("--snapshot", metavar="FILE", help="write the Fast DDS / LTTng-UST names in /dev/shm now")
    group.add_argument("--since", metavar="FILE", help="remove the unused files that are not in this snapshot")
    args = ap.parse_args(argv)
    if args.snapshot:
        with open(args.snapshot, "w") as fh:
            fh.write("".join(f"{name}\n" for name in sorted(shm_files())))
        return 0
    try:
        with open(args.since) as fh:
            before = set(fh.read().split())
    except OSError as exc:
        print(f"shm_cleanup: --since: cannot read the snapshot: {exc}", file=sys.stderr)
        return 2
    removed = remove_stale(shm_files() - before)
    print(f"shm_cleanup: removed {len(removed)} files from {SHM_DIR}" + (f": {' '.join(removed)}" if removed else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
