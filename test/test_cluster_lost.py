"""``--scheduler`` when the cluster goes away mid-run (a real Dask scheduler and workers on 127.0.0.1, started
here): the scheduler killed, or every worker killed, or workers that cannot import pa10_dnbs. Never a traceback
nor a wait for ever: one line naming --scheduler, exit 2, and the completed work kept as for a Ctrl-C (the
study's rows in study.partial.*, the tune's trials in its storage); no process of the cluster left behind."""
import json
import os
import re
import signal
import sqlite3
import subprocess
import sys
import time

import pytest

from cli_runner import run_cli
from dask_cluster import local_cluster

import pa10_dnbs.study.cluster as cluster_module

pytestmark = pytest.mark.slow

STUDY = ("study", "--scenarios", "nominal,payload_2kg", "--controllers", "pid", "--seeds", 4, "--duration", 30,
         "--no-progress")
TUNE = ("tune", "--controller", "pid", "--trials", 8, "--scenarios", "nominal", "--seeds", 1, "--duration", 30,
        "--held-out-seeds", 0, "--no-progress")
WAIT_S = 90.0   # a bound on any wait here (the runs take seconds)


def _wait(predicate, what, proc=None):
    t0 = time.monotonic()
    while not predicate():
        assert proc is None or proc.poll() is None, f"the command ended before {what}: {proc.communicate()}"
        assert time.monotonic() - t0 < WAIT_S, f"no {what} within {WAIT_S} s"
        time.sleep(0.1)


def _finished_runs(client, prefix):
    """How many of the command's runs (keys ``prefix-...``, study/executor.py) the cluster holds finished."""
    return client.run_on_scheduler(lambda dask_scheduler: sum(
        str(k).startswith(prefix) and ts.state == "memory" for k, ts in dask_scheduler.tasks.items()))


def _complete_trials(db):
    if not db.exists():
        return 0
    with sqlite3.connect(f"{db.resolve().as_uri()}?mode=ro", uri=True) as con:
        try:
            return con.execute("SELECT count(*) FROM trials WHERE state = 'COMPLETE'").fetchone()[0]
        except sqlite3.OperationalError:   # the tables not made yet
            return 0


def _command(*args):
    return subprocess.Popen([sys.executable, "-m", "pa10_dnbs.cli", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _end(proc):
    try:
        out, err = proc.communicate(timeout=WAIT_S)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return proc.returncode, out, err


def _kill_scheduler_once(cluster, proc, done):
    """SIGKILL the scheduler once ``done(client)`` (the command mid-run, work completed)."""
    from distributed import Client

    try:
        with Client(cluster.address, timeout=30) as client:
            _wait(lambda: done(client), "completed work", proc)
        time.sleep(0.5)   # the command has fetched the result (the executor polls every 0.05 s)
        os.killpg(cluster.scheduler.pid, signal.SIGKILL)
        return _end(proc)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def _one_worker_study(tmp_path, monkeypatch, worker_env: dict, controller: str, duration_s: float):
    """(exit code, stdout, stderr) of a one-run study on a cluster of one worker started with ``worker_env`` (this
    process's own environment left as it was for the command); no process of the cluster left behind."""
    for key, value in worker_env.items():
        monkeypatch.setenv(key, value)
    with local_cluster(tmp_path / "cluster", n_workers=1) as cluster:
        for key in worker_env:
            monkeypatch.delenv(key)
        result = _end(_command("study", "--scenarios", "nominal", "--controllers", controller, "--seeds", 1,
                               "--duration", duration_s, "--no-progress", "--scheduler", cluster.address,
                               "--out", tmp_path / "s"))
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    return result


def test_study_whose_scheduler_dies_keeps_its_completed_rows(tmp_path):
    with local_cluster(tmp_path / "cluster") as cluster:
        proc = _command(*STUDY, "--scheduler", cluster.address, "--out", tmp_path / "s")
        rc, out, err = _kill_scheduler_once(cluster, proc, lambda c: _finished_runs(c, "run_one-") >= 1)
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    m = re.fullmatch(r"pa10-dnbs: error: --scheduler: lost the connection to the scheduler tcp://127\.0\.0\.1:\d+ "
                     r"\(.*\); stopped after (\d) of 8 runs; kept their rows in \S+/s/study\.partial\.md .*\n", err)
    assert rc == 2 and m, (rc, err)
    rows = json.loads((tmp_path / "s" / "study.partial.json").read_text())["rows"]
    assert 1 <= len(rows) == int(m.group(1)) < 8


def test_tune_whose_scheduler_dies_says_how_many_trials_it_keeps(tmp_path):
    db = tmp_path / "t" / "tune.db"
    with local_cluster(tmp_path / "cluster") as cluster:
        proc = _command(*TUNE, "--scheduler", cluster.address, "--out", tmp_path / "t")
        rc, out, err = _kill_scheduler_once(cluster, proc, lambda c: _complete_trials(db) >= 1)
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    m = re.fullmatch(r"pa10-dnbs: error: --scheduler: lost the connection to the scheduler tcp://127\.0\.0\.1:\d+ "
                     r"\(.*\); kept (\d) completed trials? \(of --trials 8\) in \S+/t/tune\.db; run the same "
                     r"command to resume\n", err)
    assert rc == 2 and m, (rc, err)
    assert 1 <= int(m.group(1)) == _complete_trials(db) < 8


def _kill_workers_once(cluster, done):
    """A thread's job: SIGKILL every worker (nanny and all) once ``done(client)``."""
    from distributed import Client

    with Client(cluster.address, timeout=30) as client:
        _wait(lambda: done(client), "completed work")
    for w in cluster.workers:
        os.killpg(w.pid, signal.SIGKILL)
        w.wait()


@pytest.mark.parametrize("what", ["study", "tune"])
def test_a_run_whose_workers_all_die_ends_with_one_line(tmp_path, monkeypatch, what):
    """No worker for WORKERLESS_S (10 s; 2 s here) while runs wait: one line, exit 2, the completed work kept."""
    import _thread
    import threading

    monkeypatch.setattr(cluster_module, "WORKERLESS_S", 2.0, raising=False)
    db = tmp_path / "t" / "tune.db"
    with local_cluster(tmp_path / "cluster") as cluster:
        done = (lambda c: _finished_runs(c, "run_one-") >= 1) if what == "study" else \
            (lambda c: _complete_trials(db) >= 1)
        killer = threading.Thread(target=_kill_workers_once, args=(cluster, done), daemon=True)
        killer.start()
        # a run that would wait for ever: Ctrl-C (a loaded machine took 40 s to its first finished run)
        watchdog = threading.Timer(WAIT_S + 30.0, _thread.interrupt_main)
        watchdog.start()
        t0 = time.monotonic()
        try:
            r = run_cli(*(STUDY if what == "study" else TUNE), "--scheduler", cluster.address, "--out",
                        tmp_path / ("s" if what == "study" else "t"))
        finally:
            watchdog.cancel()
        seconds = time.monotonic() - t0
        killer.join(5)
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    assert r.returncode == 2 and seconds < WAIT_S + 30.0, (r.returncode, seconds, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and re.match(r"pa10-dnbs: error: --scheduler: tcp://127\.0\.0\.1:\d+ has had no worker "
                                        r"for 2 s while runs were waiting", lines[0]), r.stderr
    if what == "study":   # a run the workers finished but the command had not fetched before they died is lost
        partial = tmp_path / "s" / "study.partial.json"
        if partial.exists():
            rows = json.loads(partial.read_text())["rows"]
            assert f"stopped after {len(rows)} of 8 runs; kept their rows" in lines[0] and rows
        else:
            assert "stopped after 0 of 8 runs; nothing written" in lines[0] and not (tmp_path / "s").exists()
    else:
        n = _complete_trials(db)
        assert f"kept {n} completed trial" in lines[0] and "run the same command to resume" in lines[0] and n >= 1


BLOCK_PA10 = """
import sys


class NoPa10:
    def find_spec(self, name, path=None, target=None):
        if name == "pa10_dnbs" or name.startswith("pa10_dnbs."):
            raise ModuleNotFoundError(f"No module named {name!r}")


sys.meta_path.insert(0, NoPa10())
"""


def test_workers_that_cannot_import_the_project_are_refused_at_connect(tmp_path):
    preload = tmp_path / "block_pa10.py"
    preload.write_text(BLOCK_PA10)
    with local_cluster(tmp_path / "cluster", worker_args=("--preload", str(preload))) as cluster:
        t0 = time.monotonic()
        rc, out, err = _end(_command("study", "--scenarios", "nominal", "--controllers", "pid", "--seeds", 2,
                                     "--duration", 0.3, "--no-progress", "--scheduler", cluster.address,
                                     "--out", tmp_path / "s"))
        seconds = time.monotonic() - t0
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    assert rc == 2 and seconds < 30 and re.fullmatch(
        r"pa10-dnbs: error: --scheduler: worker tcp://127\.0\.0\.1:\d+ of tcp://127\.0\.0\.1:\d+ cannot import "
        r"pa10_dnbs \(ModuleNotFoundError: .*\): every worker needs the same pa10_dnbs .*\n", err), (rc, err)
    assert not (tmp_path / "s").exists()


def test_a_worker_running_an_edited_copy_of_the_project_is_refused_at_connect(tmp_path, monkeypatch):
    """The check compared __version__ alone (0.1.0 whatever the code): a worker running an edited copy was taken,
    and its rows differed from a local run's (payload 5 kg read as 4 kg: other RMS, exit 0)."""
    import shutil
    from pathlib import Path

    import pa10_dnbs

    copy = tmp_path / "edited"
    shutil.copytree(Path(pa10_dnbs.__file__).parent, copy / "pa10_dnbs", ignore=shutil.ignore_patterns("__pycache__"))
    scenarios = copy / "pa10_dnbs" / "study" / "scenarios.py"
    scenarios.write_text(scenarios.read_text() + "\n# an edit\n")
    # the cluster's worker imports the copy first
    rc, out, err = _one_worker_study(tmp_path, monkeypatch, {"PYTHONPATH": str(copy)}, "pid", 0.3)
    assert rc == 2 and re.fullmatch(
        r"pa10-dnbs: error: --scheduler: worker tcp://127\.0\.0\.1:\d+ of tcp://127\.0\.0\.1:\d+ runs other "
        r"pa10_dnbs code \(its source differs from this one's\): every worker needs the same pa10_dnbs .*\n", err), \
        (rc, err)
    assert not (tmp_path / "s").exists()


def test_a_run_whose_workers_keep_dying_is_named_in_one_line(tmp_path, monkeypatch):
    """Dask gives a run up (KilledWorker) once `allowed-failures` workers died running it (0 here: the first
    death; 3 by default): one line naming the run and --scheduler, exit 2, the completed rows kept."""
    from distributed import Client

    monkeypatch.setenv("DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES", "0")   # the scheduler's, at its start
    with local_cluster(tmp_path / "cluster", n_workers=1) as cluster:
        proc = _command(*STUDY, "--scheduler", cluster.address, "--out", tmp_path / "s")
        try:
            with Client(cluster.address, timeout=30) as client:
                _wait(lambda: client.run_on_scheduler(lambda dask_scheduler: any(
                    str(k).startswith("run_one-") and ts.state == "processing"
                    for k, ts in dask_scheduler.tasks.items())), "a run on the worker", proc)
                time.sleep(0.3)
                os.kill(next(iter(client.run(os.getpid).values())), signal.SIGKILL)   # its nanny starts another
            rc, out, err = _end(proc)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    assert rc == 2 and re.fullmatch(
        r"pa10-dnbs: error: --scheduler: tcp://127\.0\.0\.1:\d+ gave up the run \((nominal|payload_2kg), pid, \d\): "
        r"each worker that ran it died .*; stopped after \d of 8 runs; .*\n", err), (rc, err)


def test_a_ctrl_c_while_a_tune_waits_for_a_worker_stops_it_at_once(tmp_path):
    """A scheduler without a worker: the tune waits up to 10 s for one; a Ctrl-C meanwhile ends it within about a
    second, exit 130, the line of an interruption before any trial (it was held until the wait's end, exit 2)."""
    from test_misuse_interrupt import Command, one_line

    with local_cluster(tmp_path / "cluster", n_workers=0) as cluster:
        c = Command("tune", "--controller", "pid", "--trials", 2, "--scenarios", "nominal", "--duration", 0.2,
                    "--held-out-seeds", 0, "--no-progress", "--scheduler", cluster.address, "--out", tmp_path / "t")
        try:
            time.sleep(3.0)   # started (imports: ~2 s), waiting for a worker
            c.ctrl_c()
            rc, seconds, err = c.end()
        finally:
            c.kill()
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    assert rc == 130 and seconds < 3.0, (rc, seconds, err)
    assert re.fullmatch(r"pa10-dnbs: interrupted (before the first trial; no trial kept: run the same command to "
                        r"start|while checking its input, before any trial: .*)", one_line(err)), err
    assert not (tmp_path / "t").exists()


def test_a_worker_without_a_compiler_runs_a_dnbs_study_with_kernel_auto(tmp_path, monkeypatch):
    """`dnbs.kernel: auto` on a cluster: each worker resolves it (c where it builds, else numpy: the same bits);
    it was resolved here (c) and imposed on a worker that cannot build it: the study refused, exit 2."""
    # the worker's environment: no compiler, an empty kernel cache
    rc, out, err = _one_worker_study(tmp_path, monkeypatch, {"CC": "no-such-cc",
                                                             "PA10_DNBS_CACHE": str(tmp_path / "worker_cache")},
                                     "dnbs", 0.2)
    assert rc == 0 and err == "", (rc, err)
    assert not list((tmp_path / "worker_cache").glob("*.so"))   # the worker ran numpy's step
    assert json.loads((tmp_path / "s" / "study.json").read_text())["rows"][0]["controller"] == "dnbs"


def test_a_tls_cluster_configured_in_dasks_config_is_reached(tmp_path):
    """A scheduler and worker speaking TLS, the client's certificates in Dask's config (environment variables):
    the address probe uses that security as the Client does (it was refused, 'TLS expects a ssl_context')."""
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", key, "-out", cert,
                    "-days", "2", "-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1"],
                   check=True, capture_output=True, timeout=60)
    tls = ("--tls-ca-file", str(cert), "--tls-cert", str(cert), "--tls-key", str(key))
    env = dict(os.environ, DASK_DISTRIBUTED__COMM__TLS__CA_FILE=str(cert),
               DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT=str(cert), DASK_DISTRIBUTED__COMM__TLS__CLIENT__KEY=str(key),
               DASK_DISTRIBUTED__COMM__REQUIRE_ENCRYPTION="True")
    with local_cluster(tmp_path / "cluster", n_workers=1, scheduler_args=("--protocol", "tls", *tls),
                       worker_args=tls, wait_for_workers=False) as cluster:
        assert cluster.address.startswith("tls://")
        args = ["study", "--scenarios", "nominal", "--controllers", "pid", "--seeds", 1, "--duration", 0.2,
                "--no-progress", "--scheduler", cluster.address, "--out", tmp_path / "s"]
        proc = subprocess.Popen([sys.executable, "-m", "pa10_dnbs.cli", *map(str, args)], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, env=env)
        rc, out, err = _end(proc)
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    assert rc == 0 and err == "" and "1 runs, 0 diverged" in out, (rc, out, err)


def test_study_whose_scheduler_stops_answering_ends_in_one_line(tmp_path):
    """A scheduler that stops answering (SIGSTOP: a hung host or a dropped network leaves the connection open)
    was asked for its workers without a bound: the study waited for ever, and the first Ctrl-C went unheard."""
    with local_cluster(tmp_path / "cluster") as cluster:
        proc = _command(*STUDY, "--scheduler", cluster.address, "--out", tmp_path / "s")
        try:
            from distributed import Client

            with Client(cluster.address, timeout=30) as client:
                _wait(lambda: _finished_runs(client, "run_one-") >= 1, "completed work", proc)
            time.sleep(0.5)
            os.killpg(cluster.scheduler.pid, signal.SIGSTOP)
            t0 = time.monotonic()
            rc, out, err = _end(proc)
            took = time.monotonic() - t0
        finally:
            os.killpg(cluster.scheduler.pid, signal.SIGCONT)
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    m = re.fullmatch(r"pa10-dnbs: error: --scheduler: the scheduler tcp://127\.0\.0\.1:\d+ has not answered for "
                     r"10 s \(.*\); stopped after (\d) of 8 runs; kept their rows in \S+/s/study\.partial\.md .*\n", err)
    assert rc == 2 and m, (rc, err)
    assert took < 10.0 + 15.0, took   # the silence bound, and the client's bounded close
