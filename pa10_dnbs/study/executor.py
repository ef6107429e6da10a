"""Where the runs of a study or a tune execute: this process, a local process pool, or a Dask cluster.

One interface, :class:`Executor`: ``run(fn, tasks, on_done)`` calls ``fn(*args)`` for every ``key -> args`` of
``tasks`` and returns ``{key: result}``. The runs are deterministic, so where a run executes does not change
its result. On a Dask cluster a run whose worker dies is rescheduled on another worker (at least once); the
results are keyed, so a run that comes back twice is counted once and ``on_done`` sees each key once.

- ``scheduler`` given (``tcp://host:port``): a ``distributed.Client`` to that scheduler; its workers must
  import the same pa10_dnbs (docs/tuning.md, "A cluster").
- otherwise ``jobs`` local processes (default: one per core); ``jobs == 1`` runs in this process.

The cluster lost while runs are out (its scheduler gone, or no worker for ``WORKERLESS_S``, or a run's workers
killed again and again): :class:`ClusterLost`, one line naming ``--scheduler`` (exit 2); a local worker process
killed (the OOM killer): :class:`PoolBroken`, naming ``--jobs``. The runs completed so far went to ``on_done``, so
the command keeps them as for a Ctrl-C.

Interrupted (Ctrl-C, an error) while runs are out: the local workers (which ignore SIGINT, pa10_dnbs/interrupt.py)
are terminated and reaped within ``STOP_GRACE_S`` (then killed); a cluster's futures are cancelled, so the
scheduler drops every run not started (a run already on a worker thread ends with that run, its result dropped).
"""
from __future__ import annotations

import os
import re
import time
import uuid
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Callable, Hashable

from ..config_error import ConfigError
from ..interrupt import POLL_S, check, immediate, pool_worker_start, sigint_blocked

CONNECT_TIMEOUT_S = 10.0   # to reach the scheduler and to see its first worker
STOP_GRACE_S = 2.0         # interrupted: SIGTERM to the workers, SIGKILL after this
CLOSE_TIMEOUT_S = 5.0      # interrupted: the cluster connection closes within this
WORKERLESS_S = CONNECT_TIMEOUT_S   # runs out and the scheduler without a worker this long: the cluster is lost
WATCH_S = 1.0              # how often a waiting executor asks the scheduler for its number of workers


class RunsLost(ConfigError):
    """The runs cannot be finished where they run: one line naming the option that chose the place (``flag``)
    and exit 2; what completed before was given to ``on_done``, and the command keeps it as for a Ctrl-C."""

    setting_name, flag = "jobs", "--jobs"

    def __init__(self, message: str, scheduler_alive: bool = False):
        super().__init__(f"{self.setting_name}: {message}", setting=self.setting_name)
        self.scheduler_alive = scheduler_alive

    def line(self) -> str:
        """The message, opening with the flag."""
        return self.named(self.flag)


class ClusterLost(RunsLost):
    """The Dask cluster cannot finish the runs (its scheduler gone, no worker left, a run whose workers died
    again and again): named ``--scheduler``, as an unreachable scheduler."""

    setting_name, flag = "scheduler", "--scheduler"


class PoolBroken(RunsLost):
    """A local worker process died (SIGKILL: the OOM killer, a ``kill -9``): the pool cannot go on."""


class Executor:
    """Use as a context manager: the pool or the cluster connection lives until ``__exit__``."""

    def __init__(self, jobs: int | None = None, scheduler: str | None = None):
        if jobs is not None and jobs < 1:
            raise ConfigError(f"jobs: must be >= 1, got {jobs}", setting="jobs")
        self.scheduler = scheduler
        self.jobs = jobs or os.cpu_count() or 1
        self._pool = None
        self._client = None

    def __enter__(self) -> "Executor":
        if self.scheduler is not None:
            with immediate():   # seconds of waits (probe, handshake, a worker): a Ctrl-C stops them at once,
                self._client = connect(self.scheduler)   # also inside a tune's deferred() (interrupt.py)
            self.jobs = max(1, len(self._client.scheduler_info(n_workers=-1)["workers"]))
        elif self.jobs > 1:
            self._pool = ProcessPoolExecutor(max_workers=self.jobs, initializer=pool_worker_start,
                                             initargs=(os.getpid(),))
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if self._pool is not None:
            if exc_type is None:
                self._pool.shutdown(wait=True, cancel_futures=True)
            else:
                self._stop_pool()
            self._pool = None
        if self._client is not None:
            if exc_type is None:
                self._client.close()
            else:
                self._client.close(timeout=CLOSE_TIMEOUT_S)
            self._client = None

    def _stop_pool(self) -> None:
        """Interrupted: cancel what is queued, terminate the workers (their runs are pure computation), reap
        them; bounded by ``STOP_GRACE_S`` plus a second, whatever a worker was doing."""
        pool = self._pool
        procs = list((pool._processes or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for p in procs:
            p.terminate()
        deadline = time.monotonic() + STOP_GRACE_S
        for p in procs:
            p.join(max(0.0, deadline - time.monotonic()))
        for p in procs:
            if p.is_alive():
                p.kill()
                p.join(1.0)
        manager = getattr(pool, "_executor_manager_thread", None)
        if manager is not None:   # it sees the workers gone and ends; joined here so exit does not wait on it
            manager.join(1.0)

    @property
    def where(self) -> str:
        """In words, for reports: 'this process', '2 local processes', 'Dask cluster tcp://... (2 workers)'."""
        if self.scheduler is not None:
            return f"Dask cluster {self.scheduler} ({self.jobs} workers)"
        return "this process" if self.jobs == 1 else f"{self.jobs} local processes"

    def run(self, fn: Callable, tasks: dict[Hashable, tuple], on_done: Callable | None = None) -> dict:
        """``{key: fn(*args)}`` for every ``key -> args``; ``on_done(key, result)`` once per key as each finishes."""
        results: dict = {}

        def finished(key, value):
            if key in results:          # a rescheduled run that came back twice: counted once
                return
            results[key] = value
            if on_done is not None:
                on_done(key, value)

        if self._client is not None:
            from distributed import as_completed as dask_completed

            token = uuid.uuid4().hex[:12]
            futures = {}
            try:
                for i, (key, args) in enumerate(tasks.items()):
                    futures[self._client.submit(fn, *args, pure=False, key=f"{fn.__name__}-{token}-{i}")] = key
                done = dask_completed(list(futures), loop=self._client.loop)
                watch = _Watch(self._client, self.scheduler)
                while not done.is_empty():   # polled: a Ctrl-C noted meanwhile (interrupt.deferred) is raised here
                    batch = done.next_batch(block=False)
                    for fut in batch:
                        finished(futures[fut], watch.result(fut, futures[fut]))
                    check()
                    if not batch:
                        watch.check()   # the scheduler gone, or no worker for WORKERLESS_S: ClusterLost
                        time.sleep(POLL_S / 2)
            except BaseException as exc:
                if self._client.status == "running" and not isinstance(exc, ClusterLost) or \
                        isinstance(exc, ClusterLost) and exc.scheduler_alive:
                    self._client.cancel(list(futures), force=True)   # the scheduler drops them: nothing left queued
                raise
        elif self._pool is not None:
            futures, order, procs = {}, {}, dict(self._pool._processes or {})
            try:
                with sigint_blocked():   # the workers forked by the first submit must not see a Ctrl-C
                    for key, args in tasks.items():
                        try:
                            fut = self._pool.submit(fn, *args)
                        except BrokenProcessPool:   # a worker died between two calls of run (one idle)
                            raise _pool_broken(self._pool, list(procs.values())) from None
                        futures[fut], order[fut] = key, len(order)
                pending = set(futures)
                while pending:   # polled: a Ctrl-C noted meanwhile (interrupt.deferred) is raised here
                    procs.update(self._pool._processes or {})   # forked as needed: their exit codes, if one dies
                    done, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
                    broken = False
                    for fut in sorted(done, key=lambda f: order[f]):
                        if isinstance(fut.exception(), BrokenProcessPool):
                            broken = True   # the runs that did complete first (on_done)
                        else:
                            finished(futures[fut], fut.result())
                    if broken:
                        raise _pool_broken(self._pool, list(procs.values()))
                    check()
            except BaseException as exc:
                procs.update(self._pool._processes or {})
                if isinstance(exc, PoolBroken) or any(p.exitcode is not None for p in procs.values()):
                    # broken (a worker gone: the group's SIGTERM of `timeout`): its manager thread fails every
                    # future; none is cancelled under it (an InvalidStateError traceback in that thread)
                    manager = getattr(self._pool, "_executor_manager_thread", None)
                    if manager is not None:
                        manager.join(STOP_GRACE_S)
                else:
                    for fut in futures:
                        fut.cancel()
                raise
        else:
            for key, args in tasks.items():
                with immediate():   # pure computation: a Ctrl-C stops it at once
                    value = fn(*args)
                finished(key, value)
        return results


def _pool_broken(pool, procs) -> PoolBroken:
    """The line of ``pool`` whose worker died: how (its signal), and the likely why. Its manager thread (which
    fails every future and ends the other workers) is let finish first, and every worker reaped, so that the
    exit codes are known (and no future is cancelled under it: an InvalidStateError in that thread)."""
    import signal

    manager = getattr(pool, "_executor_manager_thread", None)
    if manager is not None:
        manager.join(STOP_GRACE_S)
    for p in procs:
        p.join(STOP_GRACE_S)
    codes = sorted({p.exitcode for p in procs if p.exitcode not in (None, 0)})
    if len(codes) > 1 and -signal.SIGTERM in codes:   # the others, ended by the pool itself (terminate_broken)
        codes.remove(-signal.SIGTERM)
    how = ", ".join(f"killed by {signal.Signals(-c).name}" if c < 0 and -c in signal.valid_signals()
                    else f"exit code {c}" for c in codes) or "ended"
    oom = " (out of memory? fewer --jobs need less)" if -signal.SIGKILL in codes else ""
    return PoolBroken(f"a local worker process died ({how}){oom}, so its run cannot finish")


class _Watch:
    """What a waiting executor checks on its cluster: the client still connected to the scheduler (a future it
    did not cancel itself comes back cancelled when the connection is lost), and a worker there at least once
    every ``WORKERLESS_S`` (asked every ``WATCH_S``)."""

    def __init__(self, client, address: str):
        self.client, self.address = client, address
        self.last_worker = self.last_asked = time.monotonic()

    def lost(self, why: str, scheduler_alive: bool = False) -> ClusterLost:
        return ClusterLost(why, scheduler_alive)

    def result(self, fut, key=None):
        """``fut.result()``; ClusterLost for a run the cluster could not finish (not an error of the run)."""
        from distributed import CancelledError
        from distributed.scheduler import KilledWorker

        try:
            return fut.result()
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
        try:
            n = self.client.scheduler_info(n_workers=0).get("n_workers", 1)
        except Exception:   # noqa: BLE001 - asked again at the next poll; a lost connection shows in the status
            return
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
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except Exception as exc:   # the scheduler went away since the probe
        raise ConfigError(f"scheduler: cannot connect to {address}: "
                          f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}", setting="scheduler") from None
    try:
        try:
            client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError):
            raise ConfigError(f"scheduler: {address} has no worker (waited {CONNECT_TIMEOUT_S:g} s)",
                              setting="scheduler") from None
        _check_workers(client, address)
    except BaseException:   # a Ctrl-C too: the client closed, not left to close itself (noisily) at exit
        client.close(timeout=CLOSE_TIMEOUT_S)
        raise
    return client


def _check_workers(client, address: str) -> None:
    """ConfigError unless every worker of ``client`` imports this pa10_dnbs, at this version (its tasks are the
    project's functions: a worker that cannot unpickle them dies on each, and the runs would wait for ever).
    ``eval`` of a string: a builtin, so the check itself unpickles on any worker."""
    from .. import __version__

    try:
        found = client.run(eval, "__import__('pa10_dnbs').__version__", on_error="return")
    except Exception as exc:   # noqa: BLE001 - the scheduler went away meanwhile: said in one line
        raise ConfigError(f"scheduler: cannot check the workers of {address}: "
                          f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}", setting="scheduler") \
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
