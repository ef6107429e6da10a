"""``--scheduler``: studies and tunes on a real Dask cluster (a scheduler and two worker processes on
127.0.0.1, started here): the same rows and trials as the local runs; a worker killed mid-study has its runs
redone elsewhere, none lost, none counted twice; every process of the cluster is gone afterwards."""
import json

import pytest

from cli_runner import run_cli
from dask_cluster import local_cluster, logged_sleep

from pa10_dnbs.study.executor import Executor
from pa10_dnbs.study.runner import run_study

pytestmark = pytest.mark.slow


def _log(path):
    return [line.split() for line in path.read_text().splitlines()] if path.exists() else []


def test_a_killed_workers_task_is_redone_and_counted_once(tmp_path):
    log = tmp_path / "tasks.log"
    keys = [f"k{i}" for i in range(4)]   # two running, two queued: a victim, and a second chance to find one
    seen, killed = [], []
    with local_cluster(tmp_path / "cluster") as cluster:
        def on_done(key, result):
            seen.append(key)
            if killed:
                return
            ends = {(k, pid) for what, k, pid in _log(log) if what == "end"}
            done_pid = next(pid for k, pid in ends if k == key)
            running = [(k, pid) for what, k, pid in _log(log)
                       if what == "start" and (k, pid) not in ends and pid != done_pid]
            if running:   # the other worker is mid-task (a late callback may find none: then the next one)
                killed.append(running[0])
                cluster.kill_worker_of(int(running[0][1]))

        with Executor(scheduler=cluster.address) as ex:
            assert ex.jobs == 2
            # k0 is short: when it is done, the other worker has 1.5 s of a 2 s task left, whatever the load
            results = ex.run(logged_sleep, {k: (k, str(log), 0.5 if k == "k0" else 2.0) for k in keys}, on_done)
        pids = cluster.pids
    assert not pids(), "processes of the cluster left behind"
    assert results == {k: f"{k} done" for k in keys} and sorted(seen) == keys   # none lost, none twice
    assert killed, f"no callback found the other worker mid-task: {_log(log)}"
    victim, victim_pid = killed[0]
    starts = [pid for what, k, pid in _log(log) if what == "start" and k == victim]
    ends = [pid for what, k, pid in _log(log) if what == "end" and k == victim]
    assert victim_pid in starts and len(starts) == 2 and ends and victim_pid not in ends   # redone elsewhere


def test_a_study_on_the_cluster_writes_the_local_rows_even_when_a_worker_dies(tmp_path, cfg):
    args = ("--scenarios", "nominal,delay_1_tick", "--controllers", "dnbs,pid", "--seeds", 2, "--duration", 1.0,
            "--no-progress")
    r = run_cli("study", *args, "--jobs", 1, "--out", tmp_path / "local")
    assert r.returncode == 0, r.stderr
    local = json.loads((tmp_path / "local" / "study.json").read_text())["rows"]
    with local_cluster(tmp_path / "cluster") as cluster:
        r = run_cli("study", *args, "--scheduler", cluster.address, "--out", tmp_path / "dask")
        assert r.returncode == 0, r.stderr
        seen = []

        def kill_after_first(row):
            seen.append((row["scenario"], row["controller"], row["seed"]))
            if len(seen) == 1:
                cluster.kill_worker_of(cluster.workers[0].pid)

        rows = run_study(cfg, ["nominal", "delay_1_tick"], ["dnbs", "pid"], 2, 1.0, scheduler=cluster.address,
                         on_done=kill_after_first)
        pids = cluster.pids
    assert not pids()
    assert json.loads((tmp_path / "dask" / "study.json").read_text())["rows"] == local
    assert rows == local and len(seen) == len(set(seen)) == 8


def test_a_tune_on_the_cluster_gives_the_local_trials(tmp_path):
    import optuna

    args = ("--controller", "pid", "--trials", 3, "--scenarios", "nominal", "--seeds", 2, "--duration", 0.5,
            "--held-out-seeds", 0, "--no-progress")

    def trials(out):
        study = optuna.load_study(study_name="pa10-pid", storage=f"sqlite:///{out / 'tune.db'}")
        return [(t.params, t.value) for t in study.trials]

    r = run_cli("tune", *args, "--jobs", 2, "--out", tmp_path / "local")
    assert r.returncode == 0, r.stderr
    with local_cluster(tmp_path / "cluster") as cluster:
        r = run_cli("tune", *args, "--scheduler", cluster.address, "--out", tmp_path / "dask")
        assert r.returncode == 0, r.stderr
        pids = cluster.pids
    assert not pids()
    assert trials(tmp_path / "dask") == trials(tmp_path / "local") and len(trials(tmp_path / "local")) == 3
    assert "Dask cluster" in (tmp_path / "dask" / "tune.md").read_text()
