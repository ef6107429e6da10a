"""``pa10-dnbs tune``'s checks before anything is written: the memory of the runs that really step at once (the
tuner asks ``--jobs // runs per trial`` trials at once), a pool no larger than what runs at once, a resumed study
whose arm, URDF or settings changed (refused, naming the flag), an in-memory ``--storage`` (refused)."""
import json
import shutil

import pytest

from cli_runner import run_cli

import pa10_dnbs.run_size as run_size
from pa10_dnbs.setting_flags import SETTING_FLAGS

ONE_RUN = ("--controller", "pid", "--scenarios", "nominal", "--seeds", 1, "--held-out-seeds", 0, "--no-progress")


def test_the_memory_check_counts_the_runs_of_a_batch_of_trials(tmp_path, monkeypatch):
    """One run per trial and --jobs 2: two trials, two runs step at once; refused as the study of the same runs
    is (memory between one run's and two runs' need)."""
    steps = 200_000   # 200 s at dt 1 ms
    one = run_size.run_bytes(steps, 7, 1, 1) + run_size.WORKER_BYTES
    two = run_size.run_bytes(steps, 7, 1, 2) + 2 * run_size.WORKER_BYTES
    monkeypatch.setattr(run_size, "available_bytes", lambda: (one + two) // 2)
    study = run_cli("study", "--scenarios", "nominal", "--controllers", "pid", "--seeds", 2, "--duration", 200,
                    "--no-progress", "--jobs", 2, "--out", tmp_path / "s")
    tune = run_cli("tune", *ONE_RUN, "--trials", 2, "--duration", 200, "--jobs", 2, "--out", tmp_path / "t")
    assert study.returncode == tune.returncode == 2, (study.stderr, tune.stderr)
    assert study.stderr.startswith("pa10-dnbs: error: --jobs: 2 runs at once of 200000 steps need about")
    assert tune.stderr == study.stderr and tune.stderr.count("\n") == 1
    assert not (tmp_path / "s").exists() and not (tmp_path / "t").exists()


def test_the_held_out_runs_count_too(tmp_path, monkeypatch):
    """--trials 1 of 1 run, but --held-out-seeds 1: 2 x 16 held-out runs, --jobs 2 of them at once."""
    steps = 200_000
    one = run_size.run_bytes(steps, 7, 1, 1) + run_size.WORKER_BYTES
    two = run_size.run_bytes(steps, 7, 1, 2) + 2 * run_size.WORKER_BYTES
    monkeypatch.setattr(run_size, "available_bytes", lambda: (one + two) // 2)
    args = list(ONE_RUN)
    args[args.index("--held-out-seeds") + 1] = 1
    r = run_cli("tune", *args, "--trials", 1, "--duration", 200, "--jobs", 2, "--out", tmp_path / "t")
    assert r.returncode == 2 and r.stderr.startswith("pa10-dnbs: error: --jobs: 2 runs at once"), r.stderr


def test_the_pool_is_no_larger_than_what_runs_at_once(tmp_path):
    """--jobs 4 for one trial of one run: it runs in this process (tune.md says where), not in 4 processes."""
    r = run_cli("tune", *ONE_RUN, "--trials", 1, "--duration", 0.2, "--jobs", 4, "--out", tmp_path / "t")
    assert r.returncode == 0, r.stderr
    text = (tmp_path / "t" / "tune.md").read_text()
    assert "this process" in text and "local processes" not in text


def _arm_dir(tmp_path, name, effort_nm):
    """A bare URDF ``robot.urdf`` (arm name 'robot', its file's stem) of a 3-joint chain in folder ``name``."""
    from chain_urdf import chain_urdf

    (tmp_path / name).mkdir()
    (tmp_path / name / "robot.urdf").write_text(chain_urdf(3, effort_nm))
    return tmp_path / name / "robot.urdf"


SHORT = ONE_RUN + ("--duration", 0.2)


def test_a_storage_of_another_arm_of_the_same_name_is_refused(tmp_path):
    """Two arms named 'robot' (other torque limits): the second tune into one --storage does not resume the first's
    study 'robot-pid' (its trials scored another arm's objective)."""
    storage = f"sqlite:///{tmp_path / 'shared.db'}"
    a, b = _arm_dir(tmp_path, "a", 200.0), _arm_dir(tmp_path, "b", 150.0)
    first = run_cli("tune", *SHORT, "--trials", 1, "--arm", a, "--storage", storage, "--out", tmp_path / "ta")
    assert first.returncode == 0, first.stderr
    r = run_cli("tune", *SHORT, "--trials", 2, "--arm", b, "--storage", storage, "--out", tmp_path / "tb")
    error = [line for line in r.stderr.splitlines() if line.startswith("pa10-dnbs")]   # after the arm's table
    assert r.returncode == 2 and len(error) == 1 and r.stderr.endswith(error[0] + "\n"), r.stderr
    assert "study 'robot-pid'" in error[0] and "--arm: the arm file's and URDF's content, sha256" in error[0]
    assert not (tmp_path / "tb").exists()
    again = run_cli("tune", *SHORT, "--trials", 2, "--arm", a, "--storage", storage, "--out", tmp_path / "ta")
    assert again.returncode == 0, again.stderr   # the same arm resumes


def test_a_config_edited_in_place_is_refused(tmp_path):
    from pa10_dnbs.config import default_config_path

    config = tmp_path / "my.yaml"
    config.write_text(f"extends: {default_config_path()}\n")
    first = run_cli("tune", *SHORT, "--trials", 1, "--config", config, "--out", tmp_path / "t")
    assert first.returncode == 0, first.stderr
    before = {p.name: p.read_bytes() for p in (tmp_path / "t").iterdir()}
    config.write_text(f"extends: {default_config_path().with_name('pa10_pid_rule_of_thumb.yaml')}\n")  # other gains
    r = run_cli("tune", *SHORT, "--trials", 2, "--config", config, "--out", tmp_path / "t")
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "--config: the merged settings, sha256" in r.stderr and "--arm" not in r.stderr
    assert {p.name: p.read_bytes() for p in (tmp_path / "t").iterdir()} == before
    (tmp_path / "t" / "tune.json").unlink()   # an interrupted tune (only its storage): refused by the storage too
    r = run_cli("tune", *SHORT, "--trials", 2, "--config", config, "--out", tmp_path / "t")
    assert r.returncode == 2 and "--config: the merged settings, sha256" in r.stderr, r.stderr


def test_a_study_of_an_older_version_is_refused_in_one_line(tmp_path):
    """A storage whose study holds the options without the digests (stored before they were): one line."""
    import optuna

    from pa10_dnbs.tune.tuner import STUDY_ATTR

    first = run_cli("tune", *SHORT, "--trials", 1, "--out", tmp_path / "t")
    assert first.returncode == 0, first.stderr
    done = json.loads((tmp_path / "t" / "tune.json").read_text())
    old = {k: v for k, v in done["options"].items() if not k.endswith("_digest")}
    study = optuna.load_study(study_name=done["study"], storage=f"sqlite:///{tmp_path / 't' / 'tune.db'}")
    study.set_user_attr(STUDY_ATTR, old)
    (tmp_path / "t" / "tune.json").write_text(json.dumps(dict(done, options=old)))
    for _ in range(2):   # refused by tune.json, then (without it) by the storage
        r = run_cli("tune", *SHORT, "--trials", 2, "--out", tmp_path / "t")
        assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
        assert "--arm: the arm file's and URDF's content, sha256" in r.stderr
        assert "(stored: not recorded (an older pa10-dnbs's study))" in r.stderr
        (tmp_path / "t" / "tune.json").unlink(missing_ok=True)


@pytest.mark.parametrize("url", ["sqlite://", "sqlite:///:memory:", "sqlite:///file:t?mode=memory&uri=true"])
def test_an_in_memory_storage_is_refused(tmp_path, url):
    r = run_cli("tune", *SHORT, "--trials", 1, "--storage", url, "--out", tmp_path / "t")
    assert r.returncode == 2 and r.stderr == (
        f"pa10-dnbs: error: --storage: {url} is an in-memory database: its trials would end with this run, nothing "
        "kept or resumed; give a file (sqlite:///PATH.db), a database server, or leave --storage out (DIR/tune.db)\n")
    assert not (tmp_path / "t").exists()


def test_no_importance_figure_from_a_single_point(tmp_path):
    """--trials 1 (the start point only): history.png, but no importance.png (optuna draws equal shares of a
    single point) and no link to it; from 2 trials at different points on, both."""
    r = run_cli("tune", *SHORT, "--trials", 1, "--out", tmp_path / "t")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "t" / "history.png").exists() and not (tmp_path / "t" / "importance.png").exists()
    assert "importance.png" not in (tmp_path / "t" / "tune.md").read_text()
    r = run_cli("tune", *SHORT, "--trials", 2, "--out", tmp_path / "t")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "t" / "importance.png").exists() and "importance.png" in (tmp_path / "t" / "tune.md").read_text()


def test_one_study_is_tuned_once_however_its_sqlite_file_is_named(tmp_path):
    """A tune into --out A (its storage A/tune.db, no --storage) and one naming that file as its --storage,
    spelled otherwise (``//`` in the path): the second is refused while the first runs (both ran, and one ended
    in Optuna's UpdateFinishedTrialError traceback)."""
    from test_misuse_inputs import _cli_process, _ctrl_c, _leftovers, _paused, _wait_for_lock

    from pa10_dnbs.tune.tuner import study_lock_key

    args = ("tune", "--controller", "pid", "--trials", 2, "--scenarios", "nominal", "--seeds", 1,
            "--held-out-seeds", 0, "--jobs", 1, "--duration", 20)
    first = _cli_process(*args, "--out", tmp_path / "a")
    try:
        _wait_for_lock(study_lock_key(f"sqlite:///{tmp_path / 'a' / 'tune.db'}", "pa10-pid"), first)
        url = f"sqlite:///{tmp_path}//a/tune.db"
        with _paused(first):
            r = run_cli(*args, "--storage", url, "--out", tmp_path / "b")
        assert r.returncode == 2 and r.stderr == (f"pa10-dnbs: error: --storage: study pa10-pid in {url} is being "
                                                  f"tuned by another run (pid {first.pid}); wait for it to end (the "
                                                  "same command then resumes it)\n"), r.stderr
        assert not (tmp_path / "b").exists()
    finally:
        _ctrl_c(first)
    assert not _leftovers(str(tmp_path))


def test_an_out_holding_another_storages_tune_is_refused(tmp_path):
    """DIR holds a finished tune (its trials in DIR/tune.db): a tune of the same study in another --storage into
    DIR would replace its reports with that storage's study's (and disagree with DIR/tune.db); refused, nothing
    replaced. The same without tune.json (an interrupted tune), and the other way round."""
    out = tmp_path / "t"
    assert run_cli("tune", *SHORT, "--trials", 2, "--out", out).returncode == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    other = f"sqlite:///{tmp_path / 'other.db'}"
    r = run_cli("tune", *SHORT, "--trials", 1, "--storage", other, "--out", out)
    assert r.returncode == 2 and r.stderr == (
        f"pa10-dnbs: error: --out: {out} holds the reports of the tune in sqlite:///{(out / 'tune.db').resolve()}, "
        f"not in {other}: give another --out for this tune (or rerun without --storage to resume that one)\n")
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before and not (tmp_path / "other.db").exists()
    (out / "tune.json").unlink()
    r = run_cli("tune", *SHORT, "--trials", 1, "--storage", other, "--out", out)
    assert r.returncode == 2 and r.stderr.startswith(f"pa10-dnbs: error: --out: {out}/tune.db holds the trials of a "
                                                     f"tune without --storage, not of {other}"), r.stderr
    out2 = tmp_path / "t2"
    assert run_cli("tune", *SHORT, "--trials", 1, "--storage", other, "--out", out2).returncode == 0
    r = run_cli("tune", *SHORT, "--trials", 1, "--out", out2)
    assert r.returncode == 2 and f"(or rerun with --storage {other} to resume that one)" in r.stderr, r.stderr
    assert not (out2 / "tune.db").exists()


@pytest.mark.parametrize("left", ["finished", "interrupted"])
def test_equal_budget_checks_every_controllers_tune_before_the_first(tmp_path, left):
    """DIR/ctc holds a tune of other options (finished, or interrupted: only its tune.db): refused before the PID
    tune runs, in one line naming DIR/ctc and the script's flags (it came after the PID tune, naming
    --out/--storage)."""
    from test_misuse_inputs import _script

    eq = tmp_path / "eq"
    assert run_cli("tune", "--controller", "ctc", "--trials", 1, "--scenarios", "nominal", "--seeds", 1,
                   "--duration", 0.3, "--held-out-seeds", 0, "--no-progress", "--out", eq / "ctc").returncode == 0
    if left == "interrupted":
        (eq / "ctc" / "tune.json").unlink()
    rc, out, err = _script("equal_budget", "--trials", 2, "--scenarios", "nominal", "--seeds", 1, "--duration", 0.2,
                           "--held-out-seeds", 1, "--no-progress", "--controllers", "pid,ctc", "--out", eq)
    assert rc == 2 and err == (
        f"equal_budget: error: {eq}/ctc: study 'pa10-ctc' there was run with other options, so its trials do not "
        "score the same objective: --duration 0.2 (stored: 0.3); rerun with the stored options to resume it, or "
        "give another --out (a new comparison)\n"), err
    assert not (eq / "pid").exists() and out == ""


def test_equal_budget_refuses_a_controllers_list_that_would_drop_a_tune_from_the_comparison(tmp_path):
    """DIR compares PID and CTC; the same command with --controllers pid rewrote comparison.md with PID alone,
    silently: now refused in one line, comparison.md kept as it was."""
    from test_misuse_inputs import _script

    eq = tmp_path / "eq"
    common = ("--trials", 1, "--scenarios", "nominal", "--seeds", 1, "--duration", 0.2, "--held-out-seeds", 1,
              "--no-progress", "--jobs", 1, "--out", eq)
    assert _script("equal_budget", *common, "--controllers", "pid,ctc")[0] == 0
    before = (eq / "comparison.md").read_bytes()
    rc, out, err = _script("equal_budget", *common, "--controllers", "pid")
    assert rc == 2 and out == "" and err == (
        f"equal_budget: error: --controllers: {eq} holds the tune of ctc too, which comparison.md would drop: list "
        "every controller of the comparison (the same command resumes), or give another --out\n"), err
    assert (eq / "comparison.md").read_bytes() == before
    assert _script("equal_budget", *common, "--controllers", "ctc,pid")[0] == 0   # the same comparison resumes


def test_equal_budget_table_refuses_unfinished_and_unequal_comparisons(tmp_path):
    """An interrupted comparison (no comparison.md), comparisons of other budgets put side by side without a
    word, and one arm in two columns (the same DIR twice, or two of one arm): now one line each, exit 2."""
    from test_misuse_inputs import _script

    common = ("--controllers", "pid", "--scenarios", "nominal", "--seeds", 1, "--held-out-seeds", 1,
              "--no-progress", "--jobs", 1)
    assert _script("equal_budget", *common, "--trials", 1, "--duration", 0.2, "--out", tmp_path / "a")[0] == 0
    assert _script("equal_budget", *common, "--trials", 2, "--duration", 0.2, "--out", tmp_path / "b")[0] == 0
    rc, out, err = _script("equal_budget_table", tmp_path / "a", tmp_path / "a")   # two columns "pa10 PID" before
    assert rc == 2 and out == "" and err == f"equal_budget_table: error: {tmp_path}/a given twice\n", err
    shutil.copytree(tmp_path / "a", tmp_path / "a_copy")
    rc, out, err = _script("equal_budget_table", tmp_path / "a", tmp_path / "a_copy")
    assert rc == 2 and out == "" and err == (f"equal_budget_table: error: {tmp_path}/a and {tmp_path}/a_copy are both "
                                             "comparisons on an arm named pa10 (the columns are named by arm): "
                                             "give one DIR per arm\n"), err
    rc, out, err = _script("equal_budget_table", tmp_path / "a")
    assert rc == 0 and out.startswith("| scenario | pa10 PID |\n"), err
    report = tmp_path / "a_copy" / "pid" / "tune.json"   # as a tune with --held-out-seeds 0 writes it
    report.write_text(json.dumps({**json.loads(report.read_text()), "held_out": None}))
    rc, out, err = _script("equal_budget_table", tmp_path / "a_copy")   # a TypeError's text before
    assert rc == 2 and out == "" and err == (f"equal_budget_table: error: {report}: a tune without held-out runs "
                                             "(no held-out seeds): the comparison's tables are of held-out "
                                             "runs\n"), err
    rc, out, err = _script("equal_budget_table", tmp_path / "a", tmp_path / "b")
    assert rc == 2 and out == "" and err == (
        f"equal_budget_table: error: not equal budgets: {tmp_path}/a/pid: 1 trials of 1 scenarios x 1 seeds x 0.2 s, "
        f"1 held-out seeds, seed 0; {tmp_path}/b/pid: 2 trials of 1 scenarios x 1 seeds x 0.2 s, 1 held-out seeds, "
        "seed 0\n"), err
    (tmp_path / "a" / "comparison.md").unlink()
    rc, out, err = _script("equal_budget_table", tmp_path / "a")
    assert rc == 2 and err.startswith(f"equal_budget_table: error: {tmp_path}/a is an unfinished comparison"), err


def test_a_folder_named_tune_db_in_out_is_named_as_such_not_as_a_storage(tmp_path):
    """DIR/tune.db a folder, no --storage given: the line blamed "--storage: cannot open sqlite:////.../tune.db"."""
    from pa10_dnbs.config import ConfigError
    from pa10_dnbs.tune.tuner import open_storage

    out = tmp_path / "t"
    (out / "tune.db").mkdir(parents=True)
    r = run_cli("tune", *SHORT, "--trials", 1, "--out", out)
    assert r.returncode == 2 and r.stderr == (f"pa10-dnbs: error: --out: {out}/tune.db is not a file (a folder or "
                                              "another kind of file): a tune keeps its trials in DIR/tune.db; move "
                                              "it or give another --out\n"), r.stderr
    assert [p.name for p in out.iterdir()] == ["tune.db"] and not any((out / "tune.db").iterdir())
    with pytest.raises(ConfigError) as e:   # the tune's own storage that does not open: `out` and the file
        open_storage(f"sqlite:///{out / 'tune.db'}", default_file=out / "tune.db")
    assert str(e.value).startswith(f"`out`: cannot open {out}/tune.db (the tune's storage): ") and not e.value.setting
    assert e.value.named(SETTING_FLAGS).startswith(f"--out: cannot open {out}/tune.db")
