"""ROS_DOMAIN_ID leases: a domain per run that no other run on this host uses at the same time.

A lease is an exclusive ``flock`` on ``<tmp>/pa10_dnbs_domains/<id>.lock``,
held for as long as the lease (or the process) lives: the kernel drops it
when the holder exits, however it exits, so a crashed run never blocks an id.
Launchers and test suites on one host take their domains here and so never
share one. Ids come from 1..101, valid on every platform (0, the ROS
default, is left to other users of the host).

A lease ends when its holder lets go, but the processes of its run may not
all be gone by then (a launcher killed hard leaves its nodes running, still
publishing on the domain's topics). So every process started for a domain
holds a shared ``flock`` on ``<id>.busy`` (:func:`occupy`, inherited through
``pass_fds``), and no lease is granted on a domain while any of them lives.
"""
from __future__ import annotations

import fcntl
import os
import tempfile
from pathlib import Path

from ..config_error import ConfigError

DOMAIN_IDS = range(1, 102)
MAX_DOMAIN_ID = 232  # the largest ROS_DOMAIN_ID ROS 2 accepts (its DDS ports must stay below 65536)
LOCK_DIR = Path(tempfile.gettempdir()) / "pa10_dnbs_domains"


class NoFreeDomain(RuntimeError):
    """Every domain id is leased by another run on this host."""


class DomainLease:
    """One leased domain id; ``release()`` (or the process's exit) frees it."""

    def __init__(self, domain_id: int, fd: int):
        self.domain_id = domain_id
        self._fd: int | None = fd

    def release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)  # closing the descriptor drops the flock
            self._fd = None

    def __enter__(self) -> "DomainLease":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def _locked(path: Path, how: int) -> int | None:
    """A descriptor of ``path`` holding ``flock(how)``, or None when another holder's lock is in the way (``how``
    with LOCK_NB)."""
    LOCK_DIR.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        fcntl.flock(fd, how)
    except BlockingIOError:
        os.close(fd)
        return None
    return fd


def occupy(domain_id: int) -> int:
    """A descriptor holding a shared lock on ``domain_id``'s occupancy file: pass it to a process started for the
    domain (``pass_fds``) and close it here; the domain cannot be leased until that process (and whatever
    inherited it) has exited."""
    return _locked(LOCK_DIR / f"{domain_id}.busy", fcntl.LOCK_SH)


def is_occupied(domain_id: int) -> bool:
    """True while some process started for ``domain_id`` (:func:`occupy`) still lives."""
    fd = _locked(LOCK_DIR / f"{domain_id}.busy", fcntl.LOCK_EX | fcntl.LOCK_NB)
    if fd is None:
        return True
    os.close(fd)
    return False


def try_lease(domain_id: int) -> DomainLease | None:
    """Lease ``domain_id`` if no other holder has it and no process of an earlier run on it lives, else None."""
    fd = _locked(LOCK_DIR / f"{domain_id}.lock", fcntl.LOCK_EX | fcntl.LOCK_NB)
    if fd is None:
        return None
    if is_occupied(domain_id):
        os.close(fd)
        return None
    return DomainLease(domain_id, fd)


def _last_leased(domain_id: int) -> float:
    """When ``domain_id`` was last leased on this host (its lock file's mtime), 0 for never."""
    try:
        return (LOCK_DIR / f"{domain_id}.lock").stat().st_mtime
    except OSError:
        return 0.0


def lease_domain() -> DomainLease:
    """The free id leased longest ago (ties: from an offset derived from the PID, so concurrent callers rarely
    race). Not the one just let go: a graph's nodes exit without destroying their DDS participants, whose
    endpoints stay in discovery for their lease duration (~20 s); a new graph there saw their publishers (a second
    commander, a second effort publisher)."""
    n = len(DOMAIN_IDS)
    start = os.getpid() % n
    ids = sorted((DOMAIN_IDS[(start + i) % n] for i in range(n)), key=_last_leased)   # stable: offset order on ties
    for domain_id in ids:
        lease = try_lease(domain_id)
        if lease is not None:
            os.utime(LOCK_DIR / f"{domain_id}.lock")
            return lease
    raise NoFreeDomain(f"all {n} ROS domain ids are in use by other runs on this host ({LOCK_DIR})")


def shell_domain(whose: str) -> int:
    """This shell's ROS_DOMAIN_ID (0 when unset), for a process that joins it (``whose``: what the domain is for,
    e.g. "the robot's domain"); ConfigError when it is not a whole number in 0..MAX_DOMAIN_ID (rcl reads a
    negative one as 0, the DDS refuses one above: the node would start and fail, or join another domain)."""
    raw = os.environ.get("ROS_DOMAIN_ID", "").strip() or "0"
    try:
        domain = int(raw)
    except ValueError:
        raise ConfigError(f"ROS_DOMAIN_ID: expected a number for {whose}, got {raw!r}") from None
    if not 0 <= domain <= MAX_DOMAIN_ID:
        raise ConfigError(f"ROS_DOMAIN_ID: {whose} must be in 0..{MAX_DOMAIN_ID} (what ROS 2 accepts), got {raw!r}")
    return domain
