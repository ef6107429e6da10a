"""The misuse harness (issue 38): every command and script the docs name, given the mistakes people make.

Out-of-range, non-finite and huge values, missing or unwritable paths, a flag without effect in the chosen mode,
and a second copy of a run into the same output at once. Each must answer with ONE line naming the flag and exit
2, before any work: no traceback, nothing written, nothing of another run touched, no process left. (Ctrl-C of
each command: test/test_misuse_interrupt.py.) Fast tier but the two graph-marked copies of ``launch``.
"""
from __future__ import annotations

import contextlib
import io
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cli_runner import run_cli
from script_module import load_script

from pa10_dnbs.output_lock import _lock_file

REPO = Path(__file__).resolve().parent.parent
PY = sys.executable


def _assert_one_line(rc: int, stdout: str, stderr: str, flag: str) -> None:
    """Exit 2, one line on stderr naming ``flag``, no traceback, nothing on stdout."""
    lines = stderr.strip().splitlines()
    assert rc == 2, (rc, stderr)
    assert len(lines) == 1, stderr
    assert flag in lines[0], (flag, lines[0])
    assert "Traceback" not in stderr + stdout and stdout == "", stdout


def _untouched(tmp_path: Path, before: set) -> None:
    assert {p.name for p in tmp_path.iterdir()} == before, "a refused command wrote something"


# (command words, the flag the one line must name); --out DIR is added as <tmp>/run
VALUE_CASES = [
    (["simulate", "--duration", "nan"], "--duration"),
    (["simulate", "--duration", "inf"], "--duration"),
    (["simulate", "--duration", "-1"], "--duration"),
    (["simulate", "--duration", "0"], "--duration"),
    (["simulate", "--duration", "0.0001"], "--duration"),          # shorter than two steps
    (["simulate", "--duration", "1e9"], "--duration"),             # was a 50.9 TiB MemoryError traceback
    (["simulate", "--controller", "all", "--duration", "1e300"], "--duration"),
    (["simulate", "--duration", "ten"], "--duration"),
    (["simulate", "--config", ""], "--config: empty: a path is needed"),    # was "config file .: a folder"
    (["simulate", "--trajectory", "a\nb"], "--trajectory: 'a\\nb' holds a control character"),
    (["simulate", "--controller", "pid", "--init-from", "/nonexistent"], "--init-from"),
    (["simulate", "--init-from", "/nonexistent"], "--init-from"),
    (["simulate", "--config", "/nonexistent.yaml"], "/nonexistent.yaml"),
    (["simulate", "--arm", "nope"], "arm"),
    (["launch", "--namespace", "bad//ns"], "--namespace"),
    (["launch", "--netns", "foo"], "--netns"),
    (["launch", "--duration", "1e9"], "--duration"),
    (["launch", "--duration", "nan"], "--duration"),
    (["launch", "--rtf", "0.5"], "--rtf"),                         # without --mode realtime: no effect
    (["launch", "--deadline-fraction", "0.5"], "--deadline-fraction"),
    (["launch", "--mode", "realtime", "--rtf", "0"], "--rtf"),
    (["launch", "--mode", "realtime", "--rtf", "nan"], "--rtf"),
    (["launch", "--mode", "realtime", "--rtf", "1e6"], "--rtf"),
    (["launch", "--mode", "realtime", "--deadline-fraction", "1.5"], "--deadline-fraction"),
    (["launch", "--effort-timeout", "inf"], "--effort-timeout"),
    (["launch", "--effort-timeout", "-2"], "--effort-timeout"),
    (["launch", "--clock-hz", "-5"], "--clock-hz"),
    (["launch", "--clock-hz", "3000"], "--clock-hz: must be in (0, 1000] Hz"),   # 0 is refused too: not "[0,"
    (["launch", "--domain-id", "500"], "--domain-id"),
    (["launch", "--rt-priority", "100"], "--rt-priority"),
    (["launch", "--bag-compression", "none"], "--bag-compression"),  # without --record: no effect
    (["launch", "--live-hz", "10"], "--live-hz"),                  # without --live: no effect
    (["launch", "--live-host", "0.0.0.0"], "--live-host"),
    (["launch", "--live", "0", "--live-hz", "inf"], "--live-hz"),
    (["launch", "--drop-states", "2"], "--drop-states"),
    (["launch", "--drop-efforts", "1"], "--drop-efforts: expected a fraction in [0, 1)"),   # a step waits forever
    (["launch", "--delay-efforts", "inf"], "--delay-efforts"),
    (["launch", "--kill", "s1@nan"], "--kill"),
    (["study", "--duration", "1e7"], "--duration"),
    (["study", "--duration", "nan"], "--duration"),
    (["study", "--seeds", "0"], "--seeds"),
    (["study", "--seeds", "1e3"], "--seeds"),
    (["study", "--jobs", "0"], "--jobs"),
    (["study", "--jobs", "4096", "--seeds", "1000"], "--jobs"),     # 2000 runs at once: more than memory holds
    (["study", "--scenarios", "nominal,nope"], "--scenarios"),
    (["tune", "--controller", "pid", "--trials", "0"], "--trials"),
    (["tune", "--controller", "pid", "--held-out-seeds", "-1"], "--held-out-seeds"),
    (["tune", "--controller", "pid", "--duration", "1e8"], "--duration"),
    (["tune", "--controller", "pid", "--duration", "-inf"], "--duration"),
    (["tune", "--controller", "pid", "--seed", "-3"], "--seed"),
    (["tune", "--controller", "pid", "--jobs", "-1"], "--jobs"),
    (["tune", "--controller", "pid", "--storage", "bogus://x"], "--storage"),
    (["tune", "--controller", "nope"], "nope"),
]


@pytest.mark.parametrize("words,flag", VALUE_CASES, ids=[" ".join(w) for w, _ in VALUE_CASES])
def test_a_bad_value_is_one_line_naming_the_flag_and_exit_2_before_any_work(tmp_path, words, flag):
    before = {p.name for p in tmp_path.iterdir()}
    r = run_cli(*words, "--out", tmp_path / "run", "--no-progress")
    _assert_one_line(r.returncode, r.stdout, r.stderr, flag)
    _untouched(tmp_path, before)


@pytest.mark.parametrize("command", [["simulate"], ["study"], ["tune", "--controller", "pid"], ["launch"]])
def test_a_config_duration_no_memory_holds_names_the_configs_key(tmp_path, command):
    """simulation.duration_s: 1e9 in a config was blamed on --duration, a flag the user never typed (review
    rev_f, finding 7)."""
    cfg = tmp_path / "long.yaml"
    cfg.write_text(f"extends: {REPO / 'config' / 'default.yaml'}\nsimulation: {{duration_s: 1.0e9, window_s: [0, 1.0e9]}}\n")
    r = run_cli(*command, "--config", cfg, "--out", tmp_path / "run", "--no-progress")
    _assert_one_line(r.returncode, r.stdout, r.stderr, "simulation.duration_s: 1e9 s is 1e12 steps")
    assert "--duration" not in r.stderr and not (tmp_path / "run").exists()


def test_study_runs_the_configs_duration_as_simulate_does(tmp_path):
    """study and tune ran 20 s whatever the config's simulation.duration_s (and measured its window_s on them):
    now their --duration defaults to the config's, as simulate's and launch's do (review rev_f, finding 8)."""
    cfg = tmp_path / "short.yaml"
    cfg.write_text(f"extends: {REPO / 'config' / 'default.yaml'}\nsimulation: {{duration_s: 0.3, window_s: [0.15, 0.3]}}\n")
    r = run_cli("study", "--config", cfg, "--scenarios", "nominal", "--controllers", "pid", "--jobs", "1",
                "--out", tmp_path / "st")
    assert r.returncode == 0, r.stderr
    assert "1 runs of 0.3 s" in (tmp_path / "st" / "study.md").read_text()


def _bag(tmp_path: Path) -> Path:
    """A directory that is not a bag: enough for replay's and analyse's argument checks, which come first."""
    bag = tmp_path / "bag"
    bag.mkdir()
    return bag


REPLAY_CASES = [(["--rate", "0"], "--rate"), (["--rate", "nan"], "--rate"), (["--start-offset", "-1"], "--start-offset"),
                (["--queue-depth", "0"], "--queue-depth"), (["--wait-for-subscribers", "inf"], "--wait-for-subscribers"),
                (["--live-hz", "5"], "--live-hz"), (["--clock", "-100"], "--clock"),
                (["--clock", "0"], "--clock: must be in (0, 1000]"),   # was accepted: silently no /clock
                (["--config", "garbage.bin"], "--config")]   # without --live: was silently ignored


@pytest.mark.parametrize("words,flag", REPLAY_CASES, ids=[" ".join(w) for w, _ in REPLAY_CASES])
def test_replay_refuses_bad_values_in_one_line(tmp_path, words, flag):
    r = run_cli("replay", _bag(tmp_path), *words)
    _assert_one_line(r.returncode, r.stdout, r.stderr, flag)


def test_arm_and_analyse_name_what_is_wrong(tmp_path):
    r = run_cli("arm", "--arm", "nope")
    _assert_one_line(r.returncode, r.stdout, r.stderr, "nope")
    assert r.stderr.startswith("pa10-dnbs: error: --arm: no arm called 'nope'"), r.stderr   # the flag typed
    r = run_cli("analyse", tmp_path / "missing_bag", "--out", tmp_path / "again")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert not (tmp_path / "again").exists()
    # a folder as --config, holding --out: it said "--out ... lies inside this run's --config" (rev_f, 10)
    bag = _bag(tmp_path)
    r = run_cli("analyse", bag, "--config", tmp_path, "--out", tmp_path / "again")
    _assert_one_line(r.returncode, r.stdout, r.stderr, f"config file {tmp_path}: a folder, not a file")


# ------------------------------------------------------------------ output paths, checked before any work
PATH_CASES = [
    (["simulate", "--duration", "0.1"], "/proc/nope/x", "--out"),   # was a raw [Errno 2], rc 1, after the run
    (["study", "--duration", "0.1"], "/proc/nope/x", "--out"),
    (["tune", "--controller", "pid", "--duration", "0.1"], "/proc/nope/x", "--out"),
    (["launch", "--duration", "0.1"], "/proc/nope/x", "--out"),
    (["simulate", "--duration", "0.1"], "", "--out: empty: a path is needed"),   # was ". is the current directory"
    (["simulate", "--duration", "0.1"], "FILE\nb", "holds a control character ('\\n')"),   # printed on 2 lines
    (["analyse", "BAG"], "/proc/nope/x", "--out"),
    (["simulate", "--duration", "0.1"], "FILE/x", "--out"),          # under a file
    (["simulate", "--duration", "0.1"], "FILE", "--out"),            # a file
]


@pytest.mark.parametrize("words,out,flag", PATH_CASES, ids=[f"{w[0]} --out {o}" for w, o, _ in PATH_CASES])
def test_an_output_that_cannot_be_made_is_refused_before_any_work(tmp_path, words, out, flag):
    (tmp_path / "FILE").write_text("not a folder")
    words = [str(_bag(tmp_path)) if w == "BAG" else w for w in words]
    out = out.replace("FILE", str(tmp_path / "FILE"))
    before = {p.name for p in tmp_path.iterdir()}
    t0 = time.monotonic()
    r = run_cli(*words, "--out", out, "--no-progress")
    _assert_one_line(r.returncode, r.stdout, r.stderr, flag)
    assert time.monotonic() - t0 < 30  # refused up front, not after the run
    _untouched(tmp_path, before)


def test_record_into_a_missing_folder_is_exit_2(tmp_path):
    """``--record nofolder/x`` gave a clear line but rc 1."""
    r = run_cli("launch", "--duration", "0.1", "--out", tmp_path / "run", "--record", tmp_path / "nofolder" / "x")
    _assert_one_line(r.returncode, r.stdout, r.stderr, "--record")
    assert sorted(p.name for p in tmp_path.iterdir()) == []


# ------------------------------------------------------------------ scripts the docs tell users to run
def _script(name: str, *argv) -> tuple[int, str, str]:
    """scripts/<name>.py's main(argv) in this process: (exit code, stdout, stderr); argparse exits too."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = load_script(name).main([str(a) for a in argv])
        except SystemExit as exc:
            rc = exc.code if isinstance(exc.code, int) else 2
    return rc, out.getvalue(), err.getvalue()


EQUAL_BUDGET_CASES = [
    (["--held-out-seeds"], "--held-out-seeds"),          # the last word: was an IndexError
    (["--held-out-seeds=0"], "--held-out-seeds"),        # was a TypeError after the tunes ran
    (["--held-out-seeds", "0"], "--held-out-seeds"),
    (["--trials", "0"], "--trials"),
    (["--duration", "nan"], "--duration"),
    (["--duration", "1e9"], "--duration"),
    (["--controllers", "pid,nope"], "--controllers"),
    (["--seeds", "-1"], "--seeds"),
    (["--jobs", "0"], "--jobs"),
    (["--bogus"], "--bogus"),
]


@pytest.mark.parametrize("words,flag", EQUAL_BUDGET_CASES, ids=[" ".join(w) for w, _ in EQUAL_BUDGET_CASES])
def test_equal_budget_refuses_bad_options_before_any_tune(tmp_path, words, flag):
    rc, out, err = _script("equal_budget", "--out", tmp_path / "eq", "--trials", "1", "--scenarios", "nominal",
                           *words)
    _assert_one_line(rc, out, err, flag)
    assert not (tmp_path / "eq").exists()


def test_equal_budget_refuses_an_unwritable_out(tmp_path):
    rc, out, err = _script("equal_budget", "--out", "/proc/nope/eq")
    _assert_one_line(rc, out, err, "--out")


def test_equal_budget_refuses_a_config_that_is_a_pipe_instead_of_waiting_on_it(tmp_path):
    """The output check read the config (for its ``extends``) before loading it: a FIFO held it forever."""
    os.mkfifo(tmp_path / "fifo")
    r = subprocess.run([PY, str(REPO / "scripts" / "equal_budget.py"), "--controllers", "pid", "--out",
                        str(tmp_path / "eq"), "--config", str(tmp_path / "fifo")], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2 and r.stderr == (f"equal_budget: error: config file {tmp_path}/fifo: not a regular file "
                                              "(a pipe or a device): give the path of a file\n"), r.stderr
    assert not (tmp_path / "eq").exists()


def _help(script: str) -> str:
    r = subprocess.run([PY, str(REPO / "scripts" / script), "--help"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stderr == ""
    return r.stdout


def test_equal_budget_help_has_a_whole_first_line_and_every_option_the_docs_pass():
    text = _help("equal_budget.py")
    first = text.split("\n\n")[1].replace("\n", " ")
    assert first.endswith(".") and "Tune several controllers" in first
    for flag in ("--arm", "--controllers", "--trials", "--config", "--out", "--scenarios", "--seeds",
                 "--held-out-seeds", "--duration", "--seed", "--jobs", "--scheduler", "--no-progress"):
        assert re.search(rf"^\s+{flag}\b", text, re.M), flag


@pytest.mark.parametrize("script", ["ablation.py", "equal_budget_table.py", "make_foxglove_layout.py"])
def test_scripts_help_starts_with_a_whole_sentence(script):
    """The description was cut mid-sentence (the docstring's first line only)."""
    text = _help(script)
    first = " ".join(text.split("\n\n")[1].split())
    assert first.endswith(".") and not first.endswith(("the.", "(the.")), first


ABLATION_CASES = [(["--long-s", "5"], "--long-s"), (["--long-s", "nan"], "--long-s"), (["--only", "99"], "--only"),
                  (["--only", "x"], "--only"), (["--workers", "0"], "--workers")]


@pytest.mark.parametrize("words,flag", ABLATION_CASES, ids=[" ".join(w) for w, _ in ABLATION_CASES])
def test_ablation_refuses_bad_options(words, flag):
    rc, out, err = _script("ablation", *words)
    _assert_one_line(rc, out, err, flag)


def test_ablation_help_lists_every_option_and_variant():
    text = _help("ablation.py")
    for flag in ("--workers", "--long-s", "--only"):
        assert re.search(rf"^\s+{flag}\b", text, re.M), flag
    assert "0 default" in text and "10 + projection" in " ".join(text.split())


def test_equal_budget_table_without_a_comparison_is_one_line(tmp_path):
    rc, out, err = _script("equal_budget_table", tmp_path / "nowhere")
    _assert_one_line(rc, out, err, "nowhere")


def test_run_main_sh_passes_a_bad_value_back_as_one_line():
    r = subprocess.run(["bash", str(REPO / "scripts" / "run_main.sh"), "--duration", "nan"], capture_output=True,
                       text=True, timeout=600, cwd=REPO)
    # the bootstrap's own notes (it reinstalls when requirements.txt or setup.* changed) are not the answer
    stderr = "".join(line for line in r.stderr.splitlines(keepends=True) if not line.startswith("bootstrap: "))
    _assert_one_line(r.returncode, r.stdout, stderr, "--duration")


# ------------------------------------------------------------------ a second copy at once
def _cli_process(*args, cwd=None) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    return subprocess.Popen([PY, "-m", "pa10_dnbs.cli", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, cwd=cwd)


def _wait_for_lock(out: Path | str, proc: subprocess.Popen, timeout_s: float = 120.0) -> None:
    """Until ``proc`` holds the lock of ``out`` (a path, or a lock's key: its lock file names it)."""
    lock = _lock_file(out if isinstance(out, str) else str(out.resolve()))
    t0 = time.monotonic()
    while not (lock.exists() and lock.read_text().split()[:1] == [str(proc.pid)]):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() - t0 < timeout_s, "the first run never took its lock"
        time.sleep(0.05)


@contextlib.contextmanager
def _paused(proc: subprocess.Popen):
    """``proc`` stopped (SIGSTOP) while the block runs, then continued (SIGCONT): it keeps what it holds (its
    lock) until the block is done, however fast the machine (a first run of 1-3 s of wall time against a second
    copy's 0.5-0.7 s was 2-4x of room)."""
    proc.send_signal(signal.SIGSTOP)
    try:
        yield
    finally:
        proc.send_signal(signal.SIGCONT)


def _leftovers(marker: str) -> list[str]:
    """Processes whose command line names ``marker`` (a test's own folder): none may outlive a test."""
    found = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit() and int(d.name) != os.getpid():
            try:
                cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            except OSError:
                continue
            if marker in cmd:
                found.append(f"{d.name}: {cmd}")
    return found


@pytest.mark.parametrize("force", [False, True], ids=["plain", "with --force"])
def test_a_second_simulate_into_a_running_ones_out_is_refused_and_the_first_is_intact(tmp_path, force):
    """--force replaces a finished run's output, never a running one's."""
    out = tmp_path / "run"
    first = _cli_process("simulate", "--controller", "pid", "--duration", "20", "--no-figures", "--out", out)
    try:
        _wait_for_lock(out, first)
        with _paused(first):
            r = run_cli("simulate", "--controller", "pid", "--duration", "0.2", "--no-figures", "--out", out,
                        *(["--force"] if force else []))
        _assert_one_line(r.returncode, r.stdout, r.stderr, "in use by another run")
        stdout, stderr = first.communicate(timeout=300)
    finally:
        first.kill() if first.poll() is None else None
    assert first.returncode == 0, stderr
    assert "over [10, 20] s" in stdout and (out / "report.md").is_file()
    assert '"duration_s": 20.0' in (out / "metrics.json").read_text()
    assert not _leftovers(str(tmp_path))
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary, no lock left beside it


def _ctrl_c(proc: subprocess.Popen) -> None:
    """Stop ``proc`` as a Ctrl-C does, and wait for it (SIGKILL after 60 s)."""
    proc.send_signal(2)
    try:
        proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate(timeout=60)


def test_a_second_tune_into_one_out_at_once_is_refused(tmp_path):
    out = tmp_path / "t"
    first = _cli_process("tune", "--controller", "pid", "--trials", "1", "--scenarios", "nominal", "--seeds", "1",
                         "--held-out-seeds", "0", "--duration", "20", "--jobs", "1", "--out", out)
    try:
        _wait_for_lock(out, first)
        with _paused(first):
            r = run_cli("tune", "--controller", "pid", "--trials", "1", "--scenarios", "nominal", "--seeds", "1",
                        "--held-out-seeds", "0", "--duration", "0.2", "--jobs", "1", "--out", out)
        _assert_one_line(r.returncode, r.stdout, r.stderr, "in use by another run")
    finally:
        _ctrl_c(first)  # the tune stops, keeps its storage and drops its lock (and its lock file)
    assert not _leftovers(str(tmp_path))
    assert not _lock_file(str(out.resolve())).exists()


def test_a_second_tune_of_one_study_in_a_shared_storage_at_once_is_refused(tmp_path):
    """Two tunes of one study in one --storage (each into its own --out) marked each other's running trials
    failed, and one ended in Optuna's UpdateFinishedTrialError traceback."""
    from pa10_dnbs.tune.tuner import study_lock_key

    url = f"sqlite:///{tmp_path / 'shared.db'}"
    args = ("tune", "--controller", "pid", "--trials", "1", "--scenarios", "nominal", "--seeds", "1",
            "--held-out-seeds", "0", "--jobs", "1", "--storage", url)
    first = _cli_process(*args, "--duration", "20", "--out", tmp_path / "a")
    try:
        _wait_for_lock(study_lock_key(url, "pa10-pid"), first)
        with _paused(first):
            r = run_cli(*args, "--duration", "20", "--out", tmp_path / "b")
        _assert_one_line(r.returncode, r.stdout, r.stderr, f"--storage: study pa10-pid in {url} is being tuned by "
                                                            f"another run (pid {first.pid})")
        assert not (tmp_path / "b").exists()
    finally:
        _ctrl_c(first)
    assert not _leftovers(str(tmp_path))


def test_an_existing_output_is_refused_without_force_and_replaced_with_it(tmp_path):
    out = tmp_path / "run"
    assert run_cli("simulate", "--controller", "pid", "--duration", "0.2", "--no-figures", "--out", out).returncode == 0
    before = (out / "metrics.json").read_text()
    r = run_cli("simulate", "--controller", "pid", "--duration", "0.3", "--no-figures", "--out", out)
    _assert_one_line(r.returncode, r.stdout, r.stderr, "--force")
    assert (out / "metrics.json").read_text() == before
    r = run_cli("simulate", "--controller", "pid", "--duration", "0.3", "--no-figures", "--out", out, "--force")
    assert r.returncode == 0 and '"duration_s": 0.3' in (out / "metrics.json").read_text()


@pytest.mark.graph
@pytest.mark.parametrize("how", ["launch", "run_main.sh"])
def test_a_second_launch_into_one_out_at_once_is_refused_and_the_first_is_intact(tmp_path, how):
    """Two copies into one --out at once: both exited 0 and the second replaced the first's results."""
    out, bag = tmp_path / "main", tmp_path / "main_bag"
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    if how == "launch":
        cmd = [str(REPO / ".venv" / "bin" / "pa10-dnbs"), "launch", "--duration", "1", "--no-figures", "--out", str(out)]
    else:  # the main job, as the README runs it, into this test's folder (later flags win)
        cmd = ["bash", str(REPO / "scripts" / "run_main.sh"), "--duration", "1", "--no-figures", "--out", str(out),
               "--record", str(bag)]
    first = subprocess.Popen(["timeout", "-s", "INT", "300", *cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True, env=env, cwd=tmp_path)
    try:
        _wait_for_any_lock(out, first)  # held by the launcher under `timeout` (and bash, for run_main.sh)
        second = subprocess.run(["timeout", "-s", "INT", "300", *cmd], capture_output=True, text=True, env=env,
                                cwd=tmp_path)
        _assert_one_line(second.returncode, second.stdout, second.stderr, "in use by another run")
        stdout, stderr = first.communicate(timeout=300)
    finally:
        if first.poll() is None:
            first.send_signal(2)
            first.communicate(timeout=60)
    assert first.returncode == 0, stderr
    assert f"wrote {out}/report.md" in stdout and (out / "report.md").is_file() and (out / "metrics.json").is_file()
    assert not _leftovers(str(tmp_path))


def _wait_for_any_lock(out: Path, proc: subprocess.Popen, timeout_s: float = 120.0) -> None:
    """Until some process under ``proc`` (the launcher, started by ``timeout`` or run_main.sh) holds the lock of
    ``out``: its lock file exists only while held."""
    lock = _lock_file(str(out.resolve()))
    t0 = time.monotonic()
    while not lock.exists():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() - t0 < timeout_s, "the first run never took its lock"
        time.sleep(0.05)


# ------------------------------------------------------------------ what the docs say, followed in order
OUTPUT_FLAG = re.compile(r"--(?:out|record)\s+((?:runs|bags)/[\w./-]+)")
RESUMES = re.compile(r"pa10-dnbs\s+tune|scripts/equal_budget\.py")  # the same command resumes: shared by design


def test_docs_blocks_never_write_one_output_with_two_different_commands():
    """A user following README.md then docs/*.md: live_view.md's first block failed because the README had
    made runs/live. An output path may recur only in the same command (a tune or comparison resumes)."""
    seen: dict[str, tuple[str, str]] = {}
    for md in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md")), REPO / "urdf" / "README.md"]:
        blocks = re.findall(r"^```bash\n(.*?)^```", md.read_text(), re.M | re.S)  # the blocks a user runs
        for line in "\n".join(blocks).replace("\\\n", " ").splitlines():
            if "pa10-dnbs" not in line and "scripts/" not in line:
                continue
            command = line.split("#")[0].strip().strip("`")
            for path in OUTPUT_FLAG.findall(command):
                path = path.rstrip(".")
                if path in seen and seen[path][1] != command and not RESUMES.search(command):
                    pytest.fail(f"{path}: {seen[path][0]} and {md.name} write it with different commands")
                seen.setdefault(path, (md.name, command))


def test_urdf_readme_lists_every_arm_that_ships():
    table = (REPO / "urdf" / "README.md").read_text()
    arms = sorted(d.name for d in (REPO / "urdf").iterdir() if (d / "arm.yaml").is_file())
    assert arms and all(f"| `{a}`" in table and f"({a}/README.md)" in table for a in arms), arms


def test_report_of_a_run_without_wall_time_says_so_instead_of_nan():
    from pa10_dnbs.report.markdown import _wall_time

    assert _wall_time(math.nan, math.nan) == "wall time not known (the run was rebuilt from a record that does not " \
                                             "hold it)"
    assert _wall_time(2.0, 10.0) == "wall time 2.00 s (10.0x real time)"


def test_numbers_are_printed_as_people_write_them(tmp_path):
    """The window of a 1.658 s run was printed [0.8290000000000001, 1.6580000000000001]."""
    from pa10_dnbs.number_text import interval, num

    assert interval((0.8290000000000001, 1.6580000000000001)) == "[0.829, 1.658]"
    assert num(1e9) == "1e9" and num(2.5e-05) == "2.5e-5" and num(20.0) == "20" and num(1160.4, 3) == "1160"
    r = run_cli("simulate", "--controller", "pid", "--duration", "1.658", "--no-figures", "--out", tmp_path / "r")
    assert r.returncode == 0 and "over [0.829, 1.658] s" in r.stdout
    assert not re.search(r"\d\.\d{12,}", r.stdout + r.stderr + (tmp_path / "r" / "report.md").read_text())


def test_a_killed_runs_lock_never_blocks_and_its_file_is_swept(tmp_path):
    """SIGKILL leaves no chance to release: the kernel drops the flock, the next run takes the path and removes
    the stale lock file; a held lock refuses with the holder's pid."""
    from pa10_dnbs.output_lock import OutputInUseError, lock_output, release_output

    out = tmp_path / "run"
    code = ("import sys, time; from pathlib import Path; from pa10_dnbs.output_lock import lock_output; "
            f"lock_output(Path({str(out)!r})); print('held', flush=True); time.sleep(60)")
    holder = subprocess.Popen([PY, "-c", code], stdout=subprocess.PIPE, text=True,
                              env={**os.environ, "PYTHONPATH": str(REPO)})
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(OutputInUseError, match=f"pid {holder.pid}"):
            lock_output(out)
    finally:
        holder.kill()
        holder.wait(timeout=60)
    stale = _lock_file(str(out.resolve()))
    assert stale.exists()
    lock_output(tmp_path / "other")     # any run sweeps what no process holds
    assert not stale.exists()
    lock_output(out)
    release_output(out)
    release_output(tmp_path / "other")
    assert not _lock_file(str(out.resolve())).exists()


def test_analyse_of_a_bag_another_run_is_recording_is_refused(tmp_path):
    """The recorder's bag is locked by its launcher until the run ends: analyse says so instead of misreading it."""
    bag = _bag(tmp_path)
    code = ("import time; from pathlib import Path; from pa10_dnbs.output_lock import lock_output; "
            f"lock_output(Path({str(bag)!r}), 'bag'); print('held', flush=True); time.sleep(60)")
    holder = subprocess.Popen([PY, "-c", code], stdout=subprocess.PIPE, text=True,
                              env={**os.environ, "PYTHONPATH": str(REPO)})
    try:
        assert holder.stdout.readline().strip() == "held"
        r = run_cli("analyse", bag, "--out", tmp_path / "again")
        _assert_one_line(r.returncode, r.stdout, r.stderr, "in use by another run")
    finally:
        holder.send_signal(2)
        holder.wait(timeout=60)
    assert not (tmp_path / "again").exists()


@pytest.mark.parametrize("flag", ["--config", "--trajectory", "--init-from", "--out", "--arm"])
def test_a_file_name_that_is_not_utf8_is_refused_before_the_run(tmp_path, flag):
    """A name in another encoding (Latin-1 'e acute', byte 0xE9: Python's surrogate escape) ran the whole
    simulation, then ended in a UnicodeEncodeError traceback where the report names it, the work lost."""
    latin1 = str(tmp_path / "caf\udce9")
    args = {"--config": ("--config", latin1 + ".yaml"), "--trajectory": ("--trajectory", latin1 + ".yaml"),
            "--init-from": ("--init-from", latin1), "--out": (), "--arm": ("--arm", latin1 + ".urdf")}[flag]
    out = latin1 if flag == "--out" else tmp_path / "out"
    before = {p.name for p in tmp_path.iterdir()}
    r = run_cli("simulate", *args, "--duration", 0.05, "--no-figures", "--no-progress", "--out", out)
    _assert_one_line(r.returncode, r.stdout, r.stderr, f"argument {flag}: ")
    assert "not valid UTF-8" in r.stderr and "caf\\xe9" in r.stderr, r.stderr
    _untouched(tmp_path, before)


OPEN_STORAGES = """
import sys, time
from pa10_dnbs.tune.tuner import open_storage
folder, start = sys.argv[1], float(sys.argv[2])
for i in range(8):   # eight new storages, both processes opening each at the same instant
    while time.time() < start + 0.5 * i:
        pass
    try:
        open_storage(f"sqlite:///{folder}/s{i}.db")
        print("ok")
    except Exception as exc:
        print("refused:", str(exc).splitlines()[0])
"""


def test_two_tunes_opening_one_new_storage_at_once_both_open_it(tmp_path):
    """Two tunes (two studies) given one new --storage created its tables twice at once: one was refused with
    "storage: cannot open ...: (sqlite3.OperationalError) table studies already exists" or a UNIQUE constraint of
    alembic_version (4 of 10 tries). One opens it at a time now; each of 8 storages opens in both processes."""
    start = time.time() + 5.0   # both past their imports
    procs = [subprocess.Popen([sys.executable, "-c", OPEN_STORAGES, str(tmp_path), repr(start)], text=True,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE) for _ in range(2)]
    outs = [p.communicate(timeout=120) for p in procs]
    for out, err in outs:
        assert out.split("\n")[:-1] == ["ok"] * 8, out + err
    assert not [f for f in _lock_file("x").parent.glob("*.lock") if str(tmp_path) in f.read_text()]  # none left


ODD_NUMBER_CASES = [
    (["simulate", "--duration", "1_0"], "--duration: expected a number, got '1_0'"),          # ran 10 s
    (["simulate", "--duration", "\u0661"], "--duration: expected a number, got '\u0661'"),    # Arabic-Indic 1: ran 1 s
    (["simulate", "--duration", " 1"], "--duration: expected a number, got ' 1'"),
    (["study", "--seeds", "1_0"], "--seeds: expected a whole number, got '1_0'"),
    (["study", "--seeds", "\u0662"], "--seeds: expected a whole number, got '\u0662'"),
    (["tune", "--controller", "pid", "--duration", "2_0.5"], "--duration: expected a number, got '2_0.5'"),
]


@pytest.mark.parametrize("words,said", ODD_NUMBER_CASES, ids=[" ".join(w) for w, _ in ODD_NUMBER_CASES])
def test_a_number_in_an_odd_spelling_is_refused(tmp_path, words, said):
    """float() and int() read ``1_0`` as 10 and an Arabic-Indic digit as its value: a flag takes plain ASCII
    digits only (``10``, ``0.5``, ``1e-3``); inf and nan are still refused as not finite."""
    before = {p.name for p in tmp_path.iterdir()}
    r = run_cli(*words, "--out", tmp_path / "run", "--no-progress")
    _assert_one_line(r.returncode, r.stdout, r.stderr, said)
    _untouched(tmp_path, before)


@pytest.mark.parametrize("words,said", [
    (["launch", "--drop-states", "0_1"], "--drop-states: expected a number, got '0_1'"),     # read as 1.0
    (["launch", "--delay-efforts", "\u0665"], "--delay-efforts: expected a number, got '\u0665'"),
    (["launch", "--fault-seed", "1_2"], "--fault-seed: expected a whole number, got '1_2'"),
    (["launch", "--live", "8_765"], "--live: expected a whole number, got '8_765'")], ids=lambda v: str(v)[:30])
def test_launchs_fault_and_live_flags_take_plain_numbers_too(words, said):
    """They were type=float/int: ``--drop-states 0_1`` dropped every state message (float('0_1') is 1.0)."""
    r = run_cli(*words)
    _assert_one_line(r.returncode, r.stdout, r.stderr, said)


@pytest.mark.parametrize("text", ["10", "+10", "0.5", ".5", "5.", "1e-3", "2.5E+3"])
def test_a_plainly_written_number_is_read(text):
    from pa10_dnbs.cli_values import seconds, whole_in
    assert seconds(text) == float(text)
    if text.lstrip("+").isdigit():
        assert whole_in(1)(text) == int(text)


@pytest.mark.parametrize("command", [("study",), ("tune", "--controller", "pid")])
def test_jobs_with_a_scheduler_is_one_line_not_silently_ignored(tmp_path, command):
    """--jobs counts local processes; with --scheduler the cluster's workers run the runs and --jobs was silently
    ignored (rev_g finding 9). Refused before anything is reached or written."""
    out = tmp_path / "o"
    r = run_cli(*command, "--jobs", "2", "--scheduler", "tcp://127.0.0.1:1", "--out", out, "--duration", "0.2")
    assert r.returncode == 2 and r.stderr == ("pa10-dnbs: error: --jobs: local worker processes only; with "
                                              "--scheduler the cluster's workers run the runs\n"), r.stderr
    assert not out.exists()


@pytest.mark.parametrize("text,why", [("{}", "no arm"), ("nope", "Expecting value"),
                                      ("5", "not a JSON object with an object of options"),
                                      ('{"arm": "pa10", "options": {}, "trials": 1, "held_out_seeds": [], '
                                       '"held_out": {}, "start_objective": 1, "best_objective": 1, '
                                       '"best_params": {}, "best_trial": 0}', "no options.scenarios"),
                                      ('{"arm": "pa10", "options": {"scenarios": [], "seeds": [], "duration_s": 1, '
                                       '"seed": 0}, "trials": 1, "held_out_seeds": 3, "held_out": {}, '
                                       '"start_objective": 1, "best_objective": 1, "best_params": {}, '
                                       '"best_trial": 0}', None)],
                         ids=["empty-object", "not-json", "a-number", "no-options", "a-number-of-seeds"])
def test_equal_budget_table_names_a_tune_report_it_cannot_read(tmp_path, text, why):
    """A damaged DIR/<controller>/tune.json was a KeyError traceback, or a JSON error naming no file."""
    (tmp_path / "eq" / "pid").mkdir(parents=True)
    (tmp_path / "eq" / "pid" / "tune.json").write_text(text)
    (tmp_path / "eq" / "comparison.md").write_text("")
    rc, out, err = _script("equal_budget_table", tmp_path / "eq")
    line = (f"equal_budget_table: error: {tmp_path}/eq/pid/tune.json: not a tune report: {why}" if why else
            f"equal_budget_table: error: a tune.json under {tmp_path}/eq is not a tune report (TypeError: ")
    assert rc == 2 and out == "" and err.count("\n") == 1 and err.startswith(line), err
