"""``pa10-dnbs tune``: the search spaces, the objective, bad input (exit 2, nothing written), a short tune's
files (a tuned.yaml that ``simulate --config`` runs), the same trials from the same command, and resuming
after Ctrl-C."""
import json
import math
import shutil
import subprocess
import sys

import optuna
import pytest

from cli_runner import run_cli
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.tune import objective as obj
from pa10_dnbs.tune.space import SPACES, Param, apply, on_bound, settings_fragment, start_values

SHORT = ("--duration", 1.0, "--held-out-seeds", 1, "--no-progress")


def _tune(*args):
    return run_cli("tune", *args)


def _trials(out):
    study = optuna.load_study(study_name=json.loads((out / "tune.json").read_text())["study"],
                              storage=f"sqlite:///{out / 'tune.db'}")
    return [(t.number, t.state.name, t.params, t.value) for t in study.trials]


@pytest.mark.parametrize("controller", list(SPACES))
def test_the_start_point_is_the_config_itself(cfg, controller):
    start = start_values(controller, cfg)
    assert apply(cfg, settings_fragment(controller, cfg, start)) == cfg


def test_pid_bandwidth_damping_and_integral_scale_the_gains(cfg):
    frag = settings_fragment("pid", cfg, {"bandwidth": 2.0, "damping": 0.5, "integral": 3.0})["pid"]
    assert frag["kp"][0] == pytest.approx(4 * cfg.pid.kp[0])
    assert frag["kd"][2] == pytest.approx(1.0 * cfg.pid.kd[2])      # d w = 0.5 x 2
    assert frag["ki"][6] == pytest.approx(3.0 * 8 * cfg.pid.ki[6])
    dn = settings_fragment("dnbs", cfg, {"torque_gain": 2.0, "ekf_q": 10.0, "ramp_s": 0.0})["dnbs"]
    assert dn["remedies"]["robust_term"]["torque_gain_nms_per_rad"][0] == 2 * 400.0
    assert dn["alpha_net"]["q"][0] == dn["torque_net"]["q"][3] == pytest.approx(0.1)
    assert dn["remedies"]["learning_ramp"] == {"enabled": False, "ramp_s": 0.0}


def test_on_bound_names_the_bound():
    p = (Param("w", 0.5, 8.0, True, ""), Param("r", 0.0, 5.0, False, ""))
    assert on_bound(p, {"w": 7.9, "r": 2.0}) == ["w (upper, 8)"]
    assert on_bound(p, {"w": 2.0, "r": 2.5}) == []
    assert on_bound(p, {"w": 0.5, "r": 4.99}) == ["w (lower, 0.5)", "r (upper, 5)"]


def test_objective_ranks_runs():
    row = {"diverged": False, "worst_rms_error_rad": 1e-4, "worst_settling_time_s": 0.5, "duration_s": 20.0,
           "worst_torque_variation": 2.0, "worst_saturated_fraction_after_s": 0.0}
    assert obj.run_cost(row) == pytest.approx(-4 + 0.1)
    worse = [dict(row, worst_rms_error_rad=1e-3), dict(row, worst_settling_time_s=None),
             dict(row, worst_torque_variation=2000.0), dict(row, worst_saturated_fraction_after_s=0.1)]
    assert all(obj.run_cost(w) > obj.run_cost(row) for w in worse)
    assert obj.run_cost(dict(row, diverged=True)) == obj.FAIL_COST > obj.run_cost(dict(row, worst_rms_error_rad=0.9))
    assert obj.objective([row] + worse) == max(obj.run_cost(w) for w in worse)


def test_held_out_verdict_warns_when_the_tuned_settings_lose_to_the_start():
    from pa10_dnbs.tune.report import held_out_verdict

    row = {"diverged": False, "worst_rms_error_rad": 1e-5, "worst_settling_time_s": 0.2, "duration_s": 20.0,
           "worst_torque_variation": 2.0, "worst_saturated_fraction_after_s": 0.0, "seed": 100}
    start = [dict(row, scenario="nominal"), dict(row, scenario="coulomb", worst_rms_error_rad=2e-5)]
    better = [dict(row, scenario="nominal"), dict(row, scenario="coulomb")]
    worse = [dict(row, scenario="nominal"), dict(row, scenario="coulomb", worst_rms_error_rad=4e-5, seed=101)]
    assert held_out_verdict({"start": start, "tuned": better}) is None
    assert held_out_verdict({"start": start, "tuned": start}) is None
    says = held_out_verdict({"start": start, "tuned": worse})
    assert "worse than the start" in says and "worst: coulomb seed 101" in says


@pytest.mark.parametrize("args, says", [
    (("--controller", "lqr"), "--controller: unknown lqr"),
    (("--controller", "pid", "--params", "bandwidth,gain"), "--params: unknown gain"),
    (("--controller", "dnbs", "--scenarios", "nominal,moon"), "--scenarios: unknown moon"),
    (("--controller", "pid", "--trials", 0), "--trials"),
    (("--controller", "pid", "--storage", "sqlite:////no/such/dir/t.db"), "--storage: cannot open"),
    (("--controller", "pid", "--storage", "nosuchdb://x"), "--storage: cannot open"),
    # SQLAlchemy only warned (two lines naming its own source) and the tune went on without the argument
    (("--controller", "pid", "--storage", "sqlite:////no/such/dir/t.db?foo=bar"), "Query string argument(s) 'foo'"),
    (("--controller", "pid", "--storage", "t.db"), "(a database URL; for a file: sqlite:///t.db)"),
    (("--controller", "pid", "--scheduler", "tcp://127.0.0.1:9"), "--scheduler: cannot connect"),
])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, monkeypatch, args, says):
    monkeypatch.setattr("pa10_dnbs.study.cluster.CONNECT_TIMEOUT_S", 1.0)
    r = _tune(*args, "--out", tmp_path / "t", *SHORT)
    assert r.returncode == 2, r.stderr
    assert says in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "t").exists()


def test_an_unreachable_scheduler_leaves_a_given_storage_untouched(tmp_path, monkeypatch):
    monkeypatch.setattr("pa10_dnbs.study.cluster.CONNECT_TIMEOUT_S", 1.0)
    r = _tune("--controller", "dnbs", "--storage", f"sqlite:///{tmp_path / 's.db'}", "--scheduler",
              "tcp://127.0.0.1:9", "--out", tmp_path / "t", *SHORT)
    assert r.returncode == 2 and "--scheduler" in r.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_a_short_tune_writes_settings_simulate_takes(tmp_path):
    out = tmp_path / "t"
    r = _tune("--controller", "pid", "--trials", 3, "--jobs", 2, "--out", out, *SHORT)
    assert r.returncode == 0, r.stderr
    assert {"tune.db", "tuned.yaml", "tune.md", "tune.json", "history.png"} <= {p.name for p in out.iterdir()}
    info = json.loads((out / "tune.json").read_text())
    trials = _trials(out)
    assert len(trials) == 3 and all(t[1] == "COMPLETE" for t in trials)
    assert trials[0][2] == {"bandwidth": 1.0, "damping": 1.0, "integral": 1.0}   # the search starts at the arm's
    best = min(trials, key=lambda t: t[3])
    assert info["best_trial"] == best[0] and info["best_objective"] == best[3]
    tuned = build_settings(out / "tuned.yaml")
    base = build_settings(info["options"]["config_file"])
    assert tuned == apply(base, settings_fragment("pid", base, best[2]))
    assert len(info["held_out"]["tuned"]) == 8 and {r["seed"] for r in info["held_out"]["start"]} == {100}
    md = (out / "tune.md").read_text()
    assert "## Held-out" in md and "| 0 (start) |" in md and "never used by the search" in md
    r = run_cli("simulate", "--config", out / "tuned.yaml", "--controller", "pid", "--duration", 0.5,
                "--no-figures", "--no-progress", "--out", tmp_path / "sim")
    assert r.returncode == 0, r.stderr


@pytest.mark.slow
def test_the_same_command_gives_the_same_trials_on_one_worker_or_two(tmp_path):
    common = ("--controller", "dnbs", "--trials", 3, "--scenarios", "nominal,delay_1_tick", "--seeds", 1,
              "--held-out-seeds", 0, "--duration", 0.5, "--no-progress")
    runs = []
    for i, jobs in enumerate((1, 1, 2)):
        r = _tune(*common, "--jobs", jobs, "--out", tmp_path / f"t{i}")
        assert r.returncode == 0, r.stderr
        runs.append(_trials(tmp_path / f"t{i}"))
    assert runs[0] == runs[1] == runs[2]
    assert len({json.dumps(t[2], sort_keys=True) for t in runs[0]}) == 3   # three different points
    r = _tune(*common, "--seed", 1, "--jobs", 1, "--out", tmp_path / "s1")
    assert r.returncode == 0 and _trials(tmp_path / "s1")[1] != runs[0][1]   # the seed sets the sampler


@pytest.mark.slow
@pytest.mark.parametrize("stop_at_run", [2, 4])   # in trial 0 (the start point), in trial 1
def test_ctrl_c_keeps_completed_trials_and_the_same_command_resumes(tmp_path, monkeypatch, stop_at_run):
    from pa10_dnbs.tune import tuner

    calls = []
    real = tuner.tune_run

    def interrupted(*args):
        calls.append(args[1:4])
        if len(calls) == stop_at_run:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(tuner, "tune_run", interrupted)
    cmd = ("--controller", "pid", "--trials", 3, "--scenarios", "nominal", "--seeds", 2, "--jobs", 1,
           "--out", tmp_path / "t", *SHORT)
    r = _tune(*cmd)
    assert r.returncode == 130 and "run the same command to resume" in r.stderr
    assert not (tmp_path / "t" / "tune.md").exists()
    study = optuna.load_study(study_name="pa10-pid", storage=f"sqlite:///{tmp_path / 't' / 'tune.db'}")
    kept = [t.state.name for t in study.trials]
    assert kept == (["FAIL"] if stop_at_run == 2 else ["COMPLETE", "FAIL"])   # the trial cut short fails
    r = _tune(*cmd)
    assert r.returncode == 0, r.stderr
    trials = _trials(tmp_path / "t")
    assert [t[1] for t in trials] == kept + ["COMPLETE"] * (4 - len(kept))
    if stop_at_run == 4:
        assert trials[0][2:] == (study.trials[0].params, study.trials[0].value)
    start = [t for t in optuna.load_study(study_name="pa10-pid", storage=f"sqlite:///{tmp_path / 't' / 'tune.db'}")
             .trials if t.user_attrs.get("start") and t.state.name == "COMPLETE"]
    assert len(start) == 1 and start[0].params == {"bandwidth": 1.0, "damping": 1.0, "integral": 1.0}
    info = json.loads((tmp_path / "t" / "tune.json").read_text())
    assert info["trials"] == 3 and math.isfinite(info["best_objective"]) and info["start_objective"] is not None


@pytest.mark.slow
def test_equal_budget_writes_one_table_of_every_controller(tmp_path):
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "scripts" / "equal_budget.py"
    spec = importlib.util.spec_from_file_location("equal_budget", path)
    eq = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(eq)
    rc = eq.main(["--controllers", "pid,ctc", "--out", str(tmp_path / "eq"), "--trials", "2", "--scenarios",
                  "nominal", "--seeds", "1", "--held-out-seeds", "1", "--duration", "0.5", "--jobs", "1",
                  "--no-progress"])
    assert rc == 0
    md = (tmp_path / "eq" / "comparison.md").read_text()
    table = [line for line in md.splitlines() if line.startswith("| ")]
    assert table[0] == "| scenario | PID shipped | PID tuned | CTC shipped | CTC tuned |"
    assert len(table) == 1 + 8 + 2 and all(line.count("|") == 6 for line in table)
    for c in ("pid", "ctc"):
        assert json.loads((tmp_path / "eq" / c / "tune.json").read_text())["trials"] == 2
    # the README's table of several comparisons: one column per arm, the tuned controllers, DNBS first
    from pa10_dnbs.tune.comparison import arms_table

    shutil.copytree(tmp_path / "eq", tmp_path / "eq2")   # a second arm's comparison, for the layout (one per arm)
    for c in ("pid", "ctc"):
        report = json.loads((tmp_path / "eq2" / c / "tune.json").read_text())
        (tmp_path / "eq2" / c / "tune.json").write_text(json.dumps({**report, "arm": "iiwa"}))
    many = arms_table([tmp_path / "eq", tmp_path / "eq2"]).splitlines()
    assert many[0] == "| scenario | pa10 PID / CTC | iiwa PID / CTC |"
    assert len(many) == 2 + 8 + 1 and all(line.count("|") == 4 for line in many)
    tuned = json.loads((tmp_path / "eq" / "pid" / "tune.json").read_text())["held_out"]["tuned"]
    assert many[2].startswith(f"| nominal | {tuned[0]['worst_rms_error_rad']:.1e} / ".replace("e-0", "e-"))
    table = subprocess.run([sys.executable, str(path.parent / "equal_budget_table.py"), str(tmp_path / "eq"),
                            str(tmp_path / "nowhere")], capture_output=True, text=True)
    assert table.returncode == 2 and table.stdout == ""
    assert table.stderr.strip().splitlines() == [f"equal_budget_table: error: no DIR/<controller>/tune.json "
                                                 f"under {tmp_path / 'nowhere'}"]


def test_progress_draws_trials_best_and_elapsed_on_a_terminal_only(tmp_path):
    import io

    from pa10_dnbs.tune.tuner import TrialProgress

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(storage=f"sqlite:///{tmp_path / 'p.db'}", study_name="p")
    study.add_trial(optuna.trial.create_trial(params={}, distributions={}, value=-3.5))
    clock = iter([0.0, 75.0, 80.0])
    quiet, shown = io.StringIO(), io.StringIO()
    TrialProgress(study, 10, "tune pid", enabled=False, stream=quiet)(1, 2, 6)
    bar = TrialProgress(study, 10, "tune pid", enabled=True, stream=shown, clock=lambda: next(clock))
    bar(1, 2, 6)
    assert quiet.getvalue() == ""
    assert shown.getvalue() == "\r\x1b[Ktune pid: 1/10 trials  runs 2/6  best -3.500 (trial 0)  elapsed 0:01:15"


def test_importances_are_drawn_from_two_different_points_on(tmp_path):
    """With one completed trial optuna still draws importance.png, each parameter at 1/k (0.33 for three): a
    figure that reads as a result and measures nothing; docs/tuning.md says "from 2 trials on"."""
    from pa10_dnbs.tune.report import tune_figures

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study()
    study.enqueue_trial({"a": 1.0, "b": 2.0})
    study.optimize(lambda t: t.suggest_float("a", 0, 3) + t.suggest_float("b", 0, 3), n_trials=1)
    assert tune_figures(study, tmp_path) == ["history.png"] and not (tmp_path / "importance.png").exists()
    study.enqueue_trial({"a": 1.0, "b": 2.0})   # the same point again: still nothing to compare
    study.optimize(lambda t: t.suggest_float("a", 0, 3) + t.suggest_float("b", 0, 3), n_trials=1)
    assert tune_figures(study, tmp_path) == ["history.png"]
    study.enqueue_trial({"a": 2.0, "b": 0.5})
    study.optimize(lambda t: t.suggest_float("a", 0, 3) + t.suggest_float("b", 0, 3), n_trials=1)
    assert tune_figures(study, tmp_path) == ["history.png", "importance.png"]


def test_the_arms_table_refuses_an_unfinished_comparison(tmp_path):
    """An interrupted comparison (one tune done, no comparison.md) was printed beside finished ones, no note."""
    from pa10_dnbs.tune.comparison import arms_table

    (tmp_path / "eq" / "pid").mkdir(parents=True)
    (tmp_path / "eq" / "pid" / "tune.json").write_text(json.dumps({"arm": "pa10", "trials": 2, "held_out": {}}))
    with pytest.raises(ValueError, match=r"eq is an unfinished comparison \(no comparison.md"):
        arms_table([tmp_path / "eq"])
