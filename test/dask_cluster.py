"""A real Dask cluster on 127.0.0.1 for tests: `dask scheduler` and `dask worker ... --nworkers 1 --nthreads 1`
processes, each in its own session (so a test can kill a worker, nanny and all), all stopped at the end; and the
tasks the tests run on it (importable by the workers: this folder is on their PYTHONPATH)."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

DASK = str(Path(sys.executable).with_name("dask"))
START_TIMEOUT_S = 60.0


def _wait(predicate, what: str, timeout_s: float = START_TIMEOUT_S) -> None:
    t0 = time.monotonic()
    while not predicate():
        if time.monotonic() - t0 > timeout_s:
            raise TimeoutError(what)
        time.sleep(0.2)


def _stop(proc: subprocess.Popen) -> None:
    """SIGTERM to the process's session, SIGKILL if it lingers; reaped."""
    for sig, wait_s in ((signal.SIGTERM, 10.0), (signal.SIGKILL, 5.0)):
        if proc.poll() is not None:
            break
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            break
        try:
            proc.wait(wait_s)
        except subprocess.TimeoutExpired:
            continue
    try:
        os.killpg(proc.pid, signal.SIGKILL)   # a worker process its nanny left behind
    except ProcessLookupError:
        pass
    proc.wait()


class Cluster:
    def __init__(self, address: str, scheduler: subprocess.Popen, workers: list[subprocess.Popen]):
        self.address, self.scheduler, self.workers = address, scheduler, workers

    def kill_worker_of(self, pid: int) -> None:
        """SIGKILL the whole `dask worker` (nanny and worker) whose worker process is ``pid``."""
        import psutil

        parents = {p.pid for p in psutil.Process(pid).parents()} | {pid}
        proc = next(w for w in self.workers if w.pid in parents)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()

    def pids(self) -> set[int]:
        """Every process of the cluster still alive (the commands and their children)."""
        import psutil

        out = set()
        for p in [self.scheduler, *self.workers]:
            try:
                proc = psutil.Process(p.pid)
                out |= {proc.pid} | {c.pid for c in proc.children(recursive=True)}
            except psutil.NoSuchProcess:
                pass
        return out


SHM = Path("/dev/shm")


def _semaphores() -> set[str]:
    """The named POSIX semaphores of Python's multiprocessing in /dev/shm (a nanny's worker makes some)."""
    return {p.name for p in SHM.glob("sem.mp-*")} if SHM.is_dir() else set()


def _mapped() -> set[str]:
    """Names of /dev/shm files some live process maps."""
    out = set()
    for maps in Path("/proc").glob("[0-9]*/maps"):
        try:
            out |= {line.rsplit("/dev/shm/", 1)[1].split()[0] for line in maps.read_text().splitlines()
                    if "/dev/shm/" in line}
        except (OSError, IndexError):
            pass
    return out


def remove_orphan_semaphores(before: set[str]) -> list[str]:
    """Remove the multiprocessing semaphores made since ``before`` that no live process maps (a SIGKILLed
    worker cannot unlink its own); the names removed."""
    gone = sorted((_semaphores() - before) - _mapped())
    for name in gone:
        (SHM / name).unlink(missing_ok=True)
    return gone


@contextmanager
def local_cluster(directory: Path, n_workers: int = 2, worker_args: tuple = (), wait_for_workers: bool = True,
                  scheduler_args: tuple = ()):
    """Yield a :class:`Cluster` of a scheduler and ``n_workers`` workers on 127.0.0.1 (random ports, no
    dashboards; ``worker_args``, ``scheduler_args``: more options of `dask worker`, `dask scheduler`;
    ``wait_for_workers`` False: not waited for, e.g. workers that die); every process is stopped and reaped at
    the end, and the semaphores its killed processes left in /dev/shm are removed."""
    directory.mkdir(parents=True, exist_ok=True)
    semaphores_before = _semaphores()
    sched_file = directory / "scheduler.json"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(__file__).parent),
                                                       os.environ.get("PYTHONPATH", "")]))
    log = open(directory / "cluster.log", "w")
    procs: list[subprocess.Popen] = []
    try:
        sched = subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                  "--scheduler-file", str(sched_file), *scheduler_args], stdout=log, stderr=log,
                                 env=env, start_new_session=True)
        procs.append(sched)
        _wait(lambda: sched_file.exists() and sched_file.stat().st_size > 0, "scheduler start")
        address = json.loads(sched_file.read_text())["address"]
        workers = [subprocess.Popen([DASK, "worker", address, "--nworkers", "1", "--nthreads", "1",
                                     "--no-dashboard", "--name", f"w{i}", "--local-directory", str(directory),
                                     *worker_args],
                                    stdout=log, stderr=log, env=env, start_new_session=True)
                   for i in range(n_workers)]
        procs += workers
        from distributed import Client

        if wait_for_workers and n_workers:
            with Client(address, timeout=START_TIMEOUT_S) as client:
                client.wait_for_workers(n_workers, timeout=START_TIMEOUT_S)
        yield Cluster(address, sched, workers)
    finally:
        for p in reversed(procs):
            _stop(p)
        log.close()
        remove_orphan_semaphores(semaphores_before)


def logged_sleep(key: str, log_path: str, seconds: float) -> str:
    """A task that writes 'start KEY PID' and 'end KEY PID' lines around a sleep (to see where it ran, and
    whether it ran twice)."""
    with open(log_path, "a") as f:
        f.write(f"start {key} {os.getpid()}\n")
    time.sleep(seconds)
    with open(log_path, "a") as f:
        f.write(f"end {key} {os.getpid()}\n")
    return f"{key} done"
