"""Where the runs of a study or a tune execute: this process, a local process pool, or a Dask cluster.

One interface, :class:`Executor`: ``run(fn, tasks, on_done)`` calls ``fn(*args)`` for every ``key -> args`` of
``tasks`` and returns ``{key: result}``. The runs are deterministic, so where a run executes does not change
its result. On a Dask cluster a run whose worker dies is rescheduled on another worker (at least once); the
results are keyed, so a run that comes back twice is counted once and ``on_done`` sees each key once.

- ``scheduler`` given (``tcp://host:port``): a ``distributed.Client`` to that scheduler; its workers must
  import the same pa10_dnbs (docs/tuning.md, "A cluster").
- otherwise ``jobs`` local processes (default: one per core); ``jobs == 1`` runs in this process.
"""
from __future__ import annotations

import os
import uuid
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Callable, Hashable

from ..config_error import ConfigError

CONNECT_TIMEOUT_S = 10.0   # to reach the scheduler and to see its first worker


class Executor:
    """Use as a context manager: the pool or the cluster connection lives until ``__exit__``."""

    def __init__(self, jobs: int | None = None, scheduler: str | None = None):
        if jobs is not None and jobs < 1:
            raise ConfigError(f"--jobs: must be >= 1, got {jobs}")
        self.scheduler = scheduler
        self.jobs = jobs or os.cpu_count() or 1
        self._pool = None
        self._client = None

    def __enter__(self) -> "Executor":
        if self.scheduler is not None:
            self._client = connect(self.scheduler)
            self.jobs = max(1, len(self._client.scheduler_info(n_workers=-1)["workers"]))
        elif self.jobs > 1:
            self._pool = ProcessPoolExecutor(max_workers=self.jobs)
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._client is not None:
            self._client.close()
            self._client = None

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
            futures = {self._client.submit(fn, *args, pure=False, key=f"{fn.__name__}-{token}-{i}"): key
                       for i, (key, args) in enumerate(tasks.items())}
            for fut in dask_completed(list(futures), loop=self._client.loop):
                finished(futures[fut], fut.result())
        elif self._pool is not None:
            futures = {self._pool.submit(fn, *args): key for key, args in tasks.items()}
            try:
                for fut in as_completed(futures):
                    finished(futures[fut], fut.result())
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
        else:
            for key, args in tasks.items():
                finished(key, fn(*args))
        return results


def connect(address: str):
    """A ``distributed.Client`` to ``address`` with at least one worker; ConfigError (exit 2) if unreachable."""
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - pinned in requirements.txt
        raise ConfigError("--scheduler: the 'distributed' package is not installed") from None
    import logging

    for name in ("distributed.client", "distributed.comm", "distributed.core", "distributed.batched"):
        logging.getLogger(name).setLevel(logging.CRITICAL)  # its own connection errors: we say it in one line
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ConfigError(f"--scheduler: cannot connect to {address}: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    try:
        client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError) as exc:
        client.close()
        raise ConfigError(f"--scheduler: {address} has no worker (waited {CONNECT_TIMEOUT_S:g} s)") from None
    return client
