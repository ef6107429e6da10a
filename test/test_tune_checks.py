"""``pa10-dnbs tune``'s checks before anything is written: the memory of the runs that really step at once (the
tuner asks ``--jobs // runs per trial`` trials at once), a pool no larger than what runs at once, a resumed study
whose arm, URDF or settings changed (refused, naming the flag), an in-memory ``--storage`` (refused)."""
import json

import pytest

from cli_runner import run_cli

import pa10_dnbs.run_size as run_size

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
