"""How the developer scripts end (scripts/script_main.py): a Ctrl-C is one line and exit 130, a setting the
library refuses is one line naming the script's flag and exit 2, a closed pipe is no traceback; each was a
traceback (or a wrong exit 0) before. And encoder_noise_filters.py runs at all (it failed on its second row)."""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = ROOT / "scripts"


def _script(name: str, *args, timeout_s: float = 120.0) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPTS / f"{name}.py"), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout_s, cwd=ROOT)


@contextlib.contextmanager
def _in_its_group(name: str, *args):
    """scripts/<name>.py ARGS running in a process group of its own (a terminal's foreground job: Ctrl-C is
    ``os.killpg(proc.pid, SIGINT)``); the group SIGKILLed on leaving if the script still runs."""
    proc = subprocess.Popen([sys.executable, str(SCRIPTS / f"{name}.py"), *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, cwd=ROOT)
    try:
        yield proc
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()


@pytest.mark.parametrize("name,args,line", [
    ("dynamics_check", ["pa10", "no_such_arm"], "dynamics_check: error: 1 of 2 arms refused, not checked: "
                                                "no_such_arm"),
    ("engine_comparison", ["--arms", "no_such_arm", "--duration", "0.1"],
     "engine_comparison: error: --arms: no arm called 'no_such_arm'"),
    ("engine_comparison", ["--arms", "pa10", "--duration", "0.0001"],
     "engine_comparison: error: --duration: 0.0001 s is shorter than two steps"),
    ("encoder_noise_filters", ["--arm", "pa10", "--duration", "0.001"],   # its default arm needs the collection
     "encoder_noise_filters: error: --duration: 0.001 s is shorter than two steps"),
], ids=["dynamics_check-refused-arm", "engine_comparison-arm", "engine_comparison-duration",
        "encoder_noise_filters-duration"])
def test_a_setting_the_library_refuses_is_one_line_naming_the_flag(name, args, line):
    done = _script(name, *args, "--states", 2) if name == "dynamics_check" else _script(name, *args)
    err = done.stderr.splitlines()
    assert done.returncode == 2 and "Traceback" not in done.stderr, (done.returncode, done.stderr)
    assert err and err[-1].startswith(line), done.stderr


def test_encoder_noise_filters_prints_every_row():
    done = _script("encoder_noise_filters", "--arm", "pa10", "--duration", 0.2, "--seeds", 1, "--cutoffs", 200)
    rows = [ln for ln in done.stdout.splitlines() if ln.startswith("| ") and "filter" not in ln]
    assert done.returncode == 0, done.stderr
    assert [r.split(" | ")[0] for r in rows] == ["| none", "| position (L = 0.0100)", "| position+lowpass 200 rad/s"]


@pytest.mark.slow
def test_ctrl_c_in_a_long_script_is_one_line_and_exit_130():
    with _in_its_group("dynamics_check", "pa10", "--states", 2000000) as proc:
        t0 = time.monotonic()
        while "| arm |" not in (proc.stdout.readline() or "| arm |"):   # its table begun: past the imports
            assert time.monotonic() - t0 < 60
        time.sleep(0.5)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130 and err == (
        "dynamics_check: interrupted; the table is not finished: run the same command again\n"), (proc.returncode, err)


def test_ctrl_c_of_interrupt_tune_is_one_line_and_leaves_no_folder(tmp_path):
    """interrupt_tune removed its tries' processes and folders on a Ctrl-C but ended in a traceback."""
    env = dict(os.environ, TMPDIR=str(tmp_path))   # its tries' folders: tempfile.mkdtemp
    proc = subprocess.Popen([sys.executable, str(SCRIPTS / "interrupt_tune.py"), "--tries", "1", "--trials", "2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            cwd=ROOT, env=env)
    try:
        t0 = time.monotonic()
        while not list(tmp_path.glob("interrupt_tune-*/full")):   # its uninterrupted tune has begun
            assert proc.poll() is None and time.monotonic() - t0 < 60, proc.communicate()
            time.sleep(0.1)
        time.sleep(1.0)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 130 and "Traceback" not in err, (proc.returncode, err)
    assert err.splitlines()[-1] == ("interrupt_tune: interrupted; the tries' processes and folders removed; "
                                    "nothing written: run the same command again"), err
    assert not list(tmp_path.glob("interrupt_tune-*"))   # left: the output locks (pa10_dnbs-locks-*)


_CHILD_SCRIPT = """
import sys
sys.path.insert(0, {scripts!r})
import script_main


def main():
    child = script_main.start_child([sys.executable, "-m", "pa10_dnbs.cli", "simulate", "--controller", "all",
                                     "--duration", "60", "--no-progress", "--out", sys.argv[1]])
    return script_main.wait_child(child)


sys.exit(script_main.run(main, "with_child"))
"""


def test_a_second_ctrl_c_lets_a_script_s_child_stop_its_own_quick_way(tmp_path):
    """A script that runs a command (a launcher, a simulate) and gets a second Ctrl-C while the command stops:
    the command gets its own second stop, which removes its half-written output, before the script kills what is
    left. Before, the script SIGKILLed it at once and its ``.out.partial-*`` folder stayed behind."""
    script, out = tmp_path / "with_child.py", tmp_path / "out"
    script.write_text(_CHILD_SCRIPT.format(scripts=str(SCRIPTS)))
    proc = subprocess.Popen([sys.executable, str(script), str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True, cwd=ROOT)
    try:
        t0 = time.monotonic()
        while not (proc.stdout.readline() or "dnbs:").startswith("dnbs:"):   # DNBS done, PID running
            assert time.monotonic() - t0 < 90
        time.sleep(0.5)
        os.killpg(proc.pid, signal.SIGINT)   # the terminal's Ctrl-C: the script's group, not its child's
        while not list(tmp_path.glob(".out.partial-*")):   # the child keeps DNBS's run: writing it (0.2-0.8 s)
            assert time.monotonic() - t0 < 120 and proc.poll() is None
            time.sleep(0.005)
        os.killpg(proc.pid, signal.SIGINT)   # while it writes (the script's second SIGINT to it: >= 0.15 s after)
        rest, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 130, rest
    assert f"pa10-dnbs: interrupted again: stopped at once; nothing written to {out}" in rest.splitlines(), rest
    assert rest.splitlines()[-1] == "with_child: interrupted again: stopped at once", rest
    assert sorted(p.name for p in tmp_path.iterdir()) == ["with_child.py"]   # no out, no .out.partial-*


@pytest.mark.parametrize("unbuffered", ["1", None], ids=["unbuffered", "buffered"])
def test_a_closed_pipe_is_no_traceback(unbuffered):
    """Buffered (the default), the failed write is the interpreter's last flush, after main returned."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    env.update({"PYTHONUNBUFFERED": unbuffered} if unbuffered else {})
    done = subprocess.run(f"{sys.executable} {SCRIPTS / 'param_tables.py'} | head -c 10; exit ${{PIPESTATUS[0]}}",
                          shell=True, executable="/bin/bash", capture_output=True, text=True, timeout=120, cwd=ROOT,
                          env=env)
    assert done.stdout == "### `plant" and done.stderr == "" and done.returncode == 1, (done.returncode, done.stderr)


def test_a_record_that_cannot_be_written_is_one_line_and_no_file(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(SCRIPTS))
    import bench_record

    target = tmp_path / "ro" / "r.json"
    target.parent.mkdir()
    target.parent.chmod(0o500)   # root ignores the mode: a file in /sys refuses everyone
    where = target if os.geteuid() != 0 else Path("/sys/kernel/pa10_record.json")
    try:
        with pytest.raises(SystemExit) as end:
            bench_record.Record.start("tests", command="x").save(where, {"n": 1})
    finally:
        target.parent.chmod(0o700)
    assert any(str(end.value).endswith(f"error: --save-record: cannot write {where}: {why}") for why in (
        "Permission denied", "Operation not permitted", "Read-only file system")), end.value
    assert not where.exists() and not where.with_suffix(".json.tmp").exists()


@pytest.mark.graph
def test_ctrl_c_stops_a_graph_benchmark_and_leaves_no_process_and_no_shared_memory():
    """bench_graph took the Ctrl-C that stopped its graph for a failed attempt and started the next run; killed
    at last, it left Fast DDS's files in /dev/shm. Now the stopped graph stops the benchmark: one line, 130."""
    import psutil
    from graph_harness import assert_no_leftovers

    from pa10_dnbs.ros.shm_cleanup import shm_files

    shm_before = shm_files()
    with _in_its_group("bench_graph", "--duration", 60, "--repeat", 1, "--factors", 1, "--rt-priority", 0) as proc:
        t0 = time.monotonic()
        while len(psutil.Process(proc.pid).children(recursive=True)) < 10:   # observer, plant, reference, 7 joints
            assert proc.poll() is None and time.monotonic() - t0 < 90, proc.communicate()
            time.sleep(0.2)
        time.sleep(2.0)
        family = [p.pid for p in psutil.Process(proc.pid).children(recursive=True)]
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.splitlines()[-1:] == [
        "bench_graph: interrupted; the graph stopped; no record written: run the same command again"], (
        proc.returncode, out, err)
    assert "attempt" not in out, out   # no second attempt, no next run
    assert_no_leftovers(family, shm_before)
