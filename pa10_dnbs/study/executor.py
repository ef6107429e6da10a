"""Where the runs of a study or a tune execute: this process, a local process pool, or a Dask cluster.

One interface, :class:`Executor`: ``run(fn, tasks, on_done)`` calls ``fn(*args)`` for every ``key -> args`` of
``tasks`` and returns ``{key: result}``. The runs are deterministic, so where a run executes does not change
its result. On a Dask cluster a run whose worker dies is rescheduled on another worker (at least once); the
results are keyed, so a run that comes back twice is counted once and ``on_done`` sees each key once.

- ``scheduler`` given (``tcp://host:port``): a ``distributed.Client`` to that scheduler; its workers must
  import the same pa10_dnbs (docs/tuning.md, "A cluster").
- otherwise ``jobs`` local processes (default: one per core); ``jobs == 1`` runs in this process.

The cluster lost while runs are out (its scheduler gone, or no worker for ``WORKERLESS_S``, or a run's workers
killed again and again): :class:`ClusterLost`, one line naming ``scheduler`` (exit 2); a local worker process
killed (the OOM killer): :class:`PoolBroken`, naming ``jobs``. The runs completed so far went to ``on_done``, so
the command keeps them as for a Ctrl-C.

A Ctrl-C (or SIGTERM) while runs are out is noted and raised at the wait loop's next check (every ``POLL_S``),
never inside concurrent.futures' or Dask's own code: raised there, it can leave a future's lock held by this
thread, and the pool's manager thread, blocked on that lock, then holds the interpreter's exit forever.
Interrupted (Ctrl-C, an error) while runs are out: the local workers (which ignore SIGINT, pa10_dnbs/interrupt.py)
are terminated and reaped within ``STOP_GRACE_S`` (then killed); a cluster's futures are cancelled, so the
scheduler drops every run not started (a run already on a worker thread ends with that run, its result dropped).
"""
from __future__ import annotations

import os
import time
import uuid
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Callable, Hashable

from ..config_error import ConfigError
from ..interrupt import POLL_S, check, deferred, immediate, pool_worker_start, sigint_blocked
from .cluster import CLOSE_TIMEOUT_S, ClusterWatch, connect
from .lost_runs import ClusterLost, PoolBroken
from .pool_race import quiet_cancelled_future_race

STOP_GRACE_S = 2.0         # interrupted: SIGTERM to the workers, SIGKILL after this


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
            quiet_cancelled_future_race()   # CPython 3.11's manager thread, a stop cancelling as a worker dies
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
            with deferred():   # a Ctrl-C raised by check() below, at a point where no lock is held
                self._run_on_cluster(fn, tasks, finished)
        elif self._pool is not None:
            with deferred():
                self._run_in_pool(fn, tasks, finished)
        else:
            for key, args in tasks.items():
                with immediate():   # pure computation: a Ctrl-C stops it at once
                    value = fn(*args)
                finished(key, value)
        return results

    def _run_on_cluster(self, fn: Callable, tasks: dict[Hashable, tuple], finished: Callable) -> None:
        """Every task as a Dask future; ``finished(key, result)`` as each comes back (polled every ``POLL_S / 2``)."""
        from distributed import as_completed as dask_completed

        token = uuid.uuid4().hex[:12]
        futures = {}
        try:
            for i, (key, args) in enumerate(tasks.items()):
                futures[self._client.submit(fn, *args, pure=False, key=f"{fn.__name__}-{token}-{i}")] = key
            done = dask_completed(list(futures), loop=self._client.loop)
            watch = ClusterWatch(self._client, self.scheduler)
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

    def _run_in_pool(self, fn: Callable, tasks: dict[Hashable, tuple], finished: Callable) -> None:
        """Every task to the local pool; ``finished(key, result)`` in submission order within each poll (``POLL_S``)."""
        futures, order, procs = {}, {}, dict(self._pool._processes or {})
        try:
            with sigint_blocked():   # the workers forked by the first submit must not see a Ctrl-C
                for key, args in tasks.items():
                    try:
                        fut = self._pool.submit(fn, *args)
                    except BrokenProcessPool:   # a worker died between two calls of run (one idle)
                        check()   # ... by the group's signal of a stop noted meanwhile: the stop, not a lost worker
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
                    check()   # the workers ended by a stop's signal to the whole group (`timeout`): the stop
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
    oom = " (out of memory? fewer `jobs` need less)" if -signal.SIGKILL in codes else ""
    return PoolBroken(f"a local worker process died ({how}){oom}, so its run cannot finish")
