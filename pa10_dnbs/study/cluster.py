"""The Dask cluster of ``--scheduler`` (study/executor.py runs on it): its address checked and connected to (a
scheduler, a worker, every worker importing this pa10_dnbs), and watched while runs are out (the scheduler lost,
no worker for ``WORKERLESS_S``, a run Dask gave up): :class:`ClusterLost`, one line naming ``scheduler``."""
from __future__ import annotations

import re
import sys
import time
import warnings

from ..config_error import ConfigError
from ..interrupt import check
from .lost_runs import ClusterLost

CONNECT_TIMEOUT_S = 10.0   # to reach the scheduler and to see its first worker
CLOSE_TIMEOUT_S = 5.0      # a failed or interrupted connection closes within this
WORKERLESS_S = CONNECT_TIMEOUT_S   # runs out and the scheduler without a worker this long: the cluster is lost
WATCH_S = 1.0              # how often a waiting executor asks the scheduler for its number of workers
SILENT_S = CONNECT_TIMEOUT_S   # runs out and no answer from the scheduler this long: the cluster is lost
CLOSED_RETRY_S = 0.05      # a result's fetch whose connection closed is tried again after this


class ClusterWatch:
    """What a waiting executor checks on its cluster: the client still connected to the scheduler (a future it
    did not cancel itself comes back cancelled when the connection is lost), the scheduler answering (each ask
    waits at most ``WATCH_S``; none answered for ``SILENT_S``: lost, as a hung host or a dropped network leaves its
    connection open), and a worker there at least once every ``WORKERLESS_S`` (asked every ``WATCH_S``)."""

    def __init__(self, client, address: str):
        self.client, self.address = client, address
        self.last_worker = self.last_asked = time.monotonic()
        self.unanswered_since: float | None = None   # the first ask since the last answer that got none

    def lost(self, why: str, scheduler_alive: bool = False) -> ClusterLost:
        return ClusterLost(why, scheduler_alive)

    def result(self, fut, key=None):
        """``fut.result()``; ClusterLost for a run the cluster could not finish (not an error of the run). Waited
        for in WATCH_S slices, the cluster checked between them: a run that finished on a worker that died
        before its result was fetched is computed again, and with no worker left that wait never ended."""
        from distributed import CancelledError
        from distributed import TimeoutError as DaskTimeout
        from distributed.comm.core import CommClosedError
        from distributed.scheduler import KilledWorker

        try:
            closed_since = None
            while True:
                try:
                    return fut.result(timeout=WATCH_S)
                except DaskTimeout:
                    pass
                except CommClosedError as exc:   # a connection closed under the fetch: the scheduler's (its death
                    now = time.monotonic()       # shows in the client's status within moments) or a worker's
                    closed_since = now if closed_since is None else closed_since   # (Dask computes it again)
                    if now - closed_since > CLOSE_TIMEOUT_S:
                        raise self.lost(f"lost a connection to the cluster of {self.address} and could not fetch "
                                        f"a run's result for {CLOSE_TIMEOUT_S:g} s ({exc})") from None
                    time.sleep(CLOSED_RETRY_S)
                check()        # a Ctrl-C noted meanwhile (interrupt.deferred)
                self.check()   # the scheduler gone, or no worker for WORKERLESS_S: ClusterLost
        except CancelledError:
            raise self.lost(f"lost the connection to the scheduler {self.address} (its process ended, or its "
                            "host or the network went down)") from None
        except KilledWorker:   # Dask gives a run up once `allowed-failures` workers died running it
            run = f"the run ({', '.join(map(str, key))})" if isinstance(key, tuple) else "a run"
            raise self.lost(f"{self.address} gave up {run}: each worker that ran it died (Dask's allowed-failures "
                            "retries spent; out of memory?): see the workers' logs", scheduler_alive=True) from None

    def check(self) -> None:
        now = time.monotonic()
        if self.client.status != "running":
            raise self.lost(f"lost the connection to the scheduler {self.address} (its process ended, or its "
                            "host or the network went down)")
        if now - self.last_asked < WATCH_S:
            return
        self.last_asked = now
        try:   # bounded: scheduler_info() waits for ever on a scheduler that stopped answering, Ctrl-C unheard
            n = self.client.sync(self.client.scheduler.identity, n_workers=0, callback_timeout=WATCH_S)["n_workers"]
        except Exception:   # noqa: BLE001 - asked again at the next poll; a lost connection shows in the status
            # silent since the first ask it left unanswered (not since the last answer: asks pause while results
            # keep coming, and one slow answer after such a pause is no silence)
            self.unanswered_since = now if self.unanswered_since is None else self.unanswered_since
            if time.monotonic() - self.unanswered_since >= SILENT_S:
                raise self.lost(f"the scheduler {self.address} has not answered for {SILENT_S:g} s (its process "
                                "stopped, or its host or the network hangs)") from None
            return
        self.unanswered_since = None
        if n:
            self.last_worker = now
        elif now - self.last_worker >= WORKERLESS_S:
            raise self.lost(f"{self.address} has had no worker for {WORKERLESS_S:g} s while runs were waiting "
                            "(its workers ended, or their host went down)",
                            scheduler_alive=True)


# The address forms a Dask client reaches: [scheme://]host:port, host a name, an IPv4 or a bracketed IPv6 address
_ADDRESS = re.compile(r"^(?:(?P<scheme>[a-z]+)://)?(?P<host>[A-Za-z0-9._-]+|\[[0-9A-Fa-f:.]+\]):(?P<port>[0-9]{1,5})$")
_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")   # distributed's network comms (inproc is within one process)


def check_address(address: str) -> str:
    """``address`` as given, if it has a form a Dask client can reach (``tcp://host:port``); ConfigError else."""
    m = _ADDRESS.match(address or "")
    scheme = (m.group("scheme") or "tcp") if m else None
    if m is None or scheme not in _SCHEMES or not 0 < int(m.group("port")) < 65536:
        raise ConfigError(f"scheduler: {address!r} is not the address of a Dask scheduler (expected "
                          f"tcp://host:port; schemes: {', '.join(_SCHEMES)})", setting="scheduler")
    return address


async def _identity(address: str) -> dict:
    """The identity a Dask server at ``address`` gives (its ``type``: 'Scheduler' for a scheduler)."""
    from distributed.comm import connect as comm_connect
    from distributed.security import Security

    # Dask's configured security (TLS certificates: distributed.comm.tls.*), as the Client then uses
    comm = await comm_connect(address, timeout=CONNECT_TIMEOUT_S, **Security().get_connection_args("client"))
    try:
        await comm.write({"op": "identity", "reply": True})
        return await comm.read()
    finally:
        comm.abort()


def _probe(address: str) -> None:
    """ConfigError unless a Dask scheduler answers at ``address`` within ``CONNECT_TIMEOUT_S`` (no Client yet:
    a Client that failed to start closes itself only on garbage collection, 20 s later, with a traceback)."""
    import asyncio
    import socket

    m = _ADDRESS.match(address)
    if (m.group("scheme") or "tcp") == "ucx":
        import importlib.util

        if importlib.util.find_spec("ucp") is None:
            raise ConfigError(f"scheduler: cannot connect to {address}: ucx:// needs the ucx-py package (ucp), not "
                              "installed here", setting="scheduler")
    if (m.group("scheme") or "tcp") != "ucx":   # a TCP port first: a refusal is said at once, not after retries
        try:
            socket.create_connection((m.group("host").strip("[]"), int(m.group("port"))), CONNECT_TIMEOUT_S).close()
        except OSError as exc:
            why = f"no answer within {CONNECT_TIMEOUT_S:g} s" if isinstance(exc, TimeoutError) else \
                (exc.strerror or type(exc).__name__)
            raise ConfigError(f"scheduler: cannot connect to {address}: {why}", setting="scheduler") from None
    try:
        reply = asyncio.run(asyncio.wait_for(_identity(address), CONNECT_TIMEOUT_S + 1.0))
    except (asyncio.TimeoutError, TimeoutError):
        why = f"no Dask answer within {CONNECT_TIMEOUT_S:g} s (is it a Dask scheduler's address?)"
    except MemoryError:   # a length read from a reply that is not Dask's
        why = "what answers there is not a Dask scheduler"
    except Exception as exc:   # refused, reset, not Dask's protocol: said in one line
        text = str(exc).splitlines()[0] if str(exc) else ""
        why = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
        if "ssl_context" in text:   # tls:// or wss:// with no certificates configured
            why = ("it speaks TLS, and no client certificates are configured: set Dask's distributed.comm.tls "
                   "ca-file, client.cert and client.key (a Dask config file, or DASK_DISTRIBUTED__COMM__TLS__CA_FILE, "
                   "..._CLIENT__CERT, ..._CLIENT__KEY)")
    else:
        kind = reply.get("type") if isinstance(reply, dict) else None
        if kind == "Scheduler":
            return
        why = f"what answers there is not a Dask scheduler (a {kind})" if kind else \
            "what answers there is not a Dask scheduler"
    raise ConfigError(f"scheduler: cannot connect to {address}: {why}", setting="scheduler")


def connect(address: str):
    """A ``distributed.Client`` to ``address`` with at least one worker; ConfigError (exit 2) for an address
    that is malformed, unreachable, or answered by something other than a Dask scheduler, within
    ``CONNECT_TIMEOUT_S`` for each of: reaching the scheduler, its handshake, its first worker."""
    check_address(address)
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - pinned in requirements.txt
        raise ConfigError("scheduler: the 'distributed' package is not installed", setting="scheduler") from None
    import logging

    for name in ("distributed.client", "distributed.comm", "distributed.core", "distributed.batched"):
        logging.getLogger(name).setLevel(logging.CRITICAL)  # its own connection errors: we say it in one line
    _probe(address)
    from distributed.versions import VersionMismatchWarning

    with warnings.catch_warnings(record=True) as caught:   # Dask's version table: said in one line, or not at all
        warnings.simplefilter("always", VersionMismatchWarning)
        try:
            client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
        except Exception as exc:   # the scheduler went away since the probe
            raise ConfigError(f"scheduler: cannot connect to {address}: "
                              f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}",
                              setting="scheduler") from None
        try:
            try:
                client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
            except (OSError, TimeoutError):
                raise ConfigError(f"scheduler: {address} has no worker (waited {CONNECT_TIMEOUT_S:g} s)",
                                  setting="scheduler") from None
            _check_workers(client, address)   # a worker without pa10_dnbs: its one line, not Dask's table
        except BaseException:   # a Ctrl-C too: the client closed, not left to close itself (noisily) at exit
            client.close(timeout=CLOSE_TIMEOUT_S)
            raise
    _say_warnings(caught, address)
    return client


def _say_warnings(caught, address: str) -> None:
    """The warnings of connecting: Dask's package version mismatch as one line (the same pa10_dnbs on other
    versions of its dependencies can give other numbers), any other as Python shows it."""
    from distributed.versions import VersionMismatchWarning

    for w in caught:
        if issubclass(w.category, VersionMismatchWarning):
            rows = [[c.strip() for c in line.strip().strip("|").split("|")] for line in str(w.message).splitlines()
                    if line.strip().startswith("|")]
            named = "; ".join(f"{r[0]}: " + ", ".join(f"{h.lower()} {v}" for h, v in zip(rows[0][1:], r[1:]))
                              for r in rows[1:]) if rows else str(w.message).strip().splitlines()[0]
            print(f"pa10-dnbs: warning: the cluster at {address} runs other package versions ({named}; Dask's "
                  "check): runs on other versions may give other numbers", file=sys.stderr, flush=True)
        else:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)


def _check_workers(client, address: str) -> None:
    """ConfigError unless every worker of ``client`` imports this pa10_dnbs, at this version and of this source
    (source_digest.py): its tasks are the project's functions (a worker that cannot unpickle them dies on each,
    and the runs would wait for ever), and other code gives other numbers. ``eval`` of a string: a builtin, so
    the check itself unpickles on any worker."""
    from .. import __version__
    from ..source_digest import source_digest

    try:
        found = client.run(eval, "__import__('pa10_dnbs').__version__", on_error="return")
    except Exception as exc:   # noqa: BLE001 - the scheduler went away meanwhile: said in one line
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"scheduler: cannot check the workers of {address}: {text}", setting="scheduler") \
            from None
    for worker, got in sorted(found.items()):
        if isinstance(got, BaseException):
            raise ConfigError(f"scheduler: worker {worker} of {address} cannot import pa10_dnbs "
                              f"({type(got).__name__}: {str(got).splitlines()[0] if str(got) else ''}): every "
                              "worker needs the same pa10_dnbs (docs/tuning.md, \"A cluster\")", setting="scheduler")
        if got != __version__:
            raise ConfigError(f"scheduler: worker {worker} of {address} has pa10_dnbs {got}, this is {__version__}: "
                              "every worker needs the same pa10_dnbs (docs/tuning.md, \"A cluster\")",
                              setting="scheduler")
    # the same version can be other code (an edited copy): its source, file by file, must be this one's
    try:
        digests = client.run(eval, "__import__('importlib').import_module('pa10_dnbs.source_digest').source_digest()",
                             on_error="return")
    except Exception as exc:   # noqa: BLE001 - the scheduler went away meanwhile: said in one line
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"scheduler: cannot check the workers of {address}: {text}", setting="scheduler") \
            from None
    for worker, got in sorted(digests.items()):
        if got != source_digest():
            why = "its source differs from this one's" if not isinstance(got, BaseException) else \
                f"no digest of its source: {type(got).__name__}: {str(got).splitlines()[0] if str(got) else ''}"
            raise ConfigError(f"scheduler: worker {worker} of {address} runs other pa10_dnbs code ({why}): every "
                              "worker needs the same pa10_dnbs (docs/tuning.md, \"A cluster\")", setting="scheduler")
