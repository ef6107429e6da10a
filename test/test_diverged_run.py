"""A run that diverges (|e| > 1 rad, or non-finite) is a result: metrics say where and why, the report and its
figures are written, exit 1; the study and the tuner count the same runs."""
import json
from pathlib import Path

import numpy as np

from cli_runner import run_cli
from pa10_dnbs.config import default_config_path
from pa10_dnbs.core.metrics import DIVERGED_RAD, divergence, first_non_finite

CONTINUOUS = Path(__file__).parent / "fixtures" / "urdf_intake" / "continuous_joint.urdf"


def test_first_non_finite_names_the_step_and_the_joint_running_away():
    q = np.zeros((6, 3))
    qd = np.zeros((6, 3))
    tau = np.zeros((6, 3))
    assert first_non_finite(q, qd, tau) is None
    qd[3] = [1.0, -50.0, 2.0]
    q[4, 0] = np.inf
    assert first_non_finite(q, qd, tau) == {"step": 4, "joint": 1}
    tau[2, 2] = np.nan
    assert first_non_finite(q, qd, tau) == {"step": 2, "joint": 0}
    q[0, 2] = np.nan
    assert first_non_finite(q, None, tau) == {"step": 0, "joint": 2}


def test_divergence_is_an_error_beyond_1_rad_or_a_non_finite_sample_whichever_comes_first():
    e, q, qd, tau = (np.zeros((8, 3)) for _ in range(4))
    e[:, 1] = np.linspace(0.0, 0.9, 8)
    assert divergence(e, q, qd, tau) is None            # 0.9 rad: not diverged
    e[5, 2] = -DIVERGED_RAD * 1.01
    assert divergence(e, q, qd, tau) == {"step": 5, "joint": 2, "non_finite": False}
    qd[5, 0], qd[6, 0] = 3.0, np.inf
    assert divergence(e, q, qd, tau)["step"] == 5       # the error came first
    tau[4, 1] = np.nan
    assert divergence(e, q, qd, tau) == {"step": 4, "joint": 0, "non_finite": True}


def test_absurd_gains_diverge_into_a_report_not_a_traceback(tmp_path):
    """A PID with gains 1e8 times what the loop stands (T k_d / J ~ 1e6) and torque limits of 1e12 N m: the
    continuous joint's state overflows within a few steps."""
    cfg = tmp_path / "absurd.yaml"
    cfg.write_text(f"extends: {default_config_path()}\nplant:\n  torque_limit_nm: 1.0e+12\n"
                   f"pid:\n  kp: 1.0e+9\n  kd: 1.0e+8\n")
    out = tmp_path / "out"
    r = run_cli("simulate", "--config", cfg, "--arm", CONTINUOUS, "--controller", "both", "--duration", "0.5",
                "--out", out)
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr + r.stdout
    m = _strict_json(out / "pid" / "metrics.json")
    d = m["diverged"]
    assert d is not None and 0 < d["step"] < 100 and d["joint"] in ("j1", "j2", "j3")
    assert d["time_s"] == d["step"] * m["dt_s"] and not m["all_finite"]
    assert m["non_finite_from_step"] >= d["step"]   # past 1 rad a step before it overflows, or at that step
    assert m["worst_rms_error_rad"] is None   # undefined, written null: the file is strict JSON
    assert _strict_json(out / "summary.json")["pid"]["worst_rms_error_rad"] is None
    assert "DIVERGED" in r.stdout and f"step {d['step']}" in r.stdout
    assert json.loads((out / "dnbs" / "metrics.json").read_text())["diverged"] is None
    report = (out / "report.md").read_text()
    assert "**diverged**" in report and f"step {d['step']}" in report
    for name in ("arm.png", "tracking.png", "errors.png", "startup.png", "torques.png"):
        assert (out / "pid" / name).stat().st_size > 0, name
    assert (out / "errors_compare.png").is_file()


def test_a_run_that_swings_past_1_rad_is_diverged_where_the_study_says_so(tmp_path):
    """A run 1.3 rad off (a PID with zero gains: the PA10 falls under gravity), every value finite: metrics.json
    said "diverged": null and simulate exited 0, while the study counted the same run diverged (|e| > 1 rad).
    Now one definition: metrics.json says where and why, the summary line and the report say DIVERGED, exit 1,
    the figures are whole (nothing non-finite to cut); the study counts it."""
    cfg = tmp_path / "zero_gains.yaml"
    cfg.write_text(f"extends: {default_config_path()}\npid:\n  kp: 0.0\n  ki: 0.0\n  kd: 0.0\n")
    out = tmp_path / "out"
    r = run_cli("simulate", "--config", cfg, "--controller", "pid", "--duration", "1", "--out", out)
    assert r.returncode == 1, r.stderr
    m = _strict_json(out / "metrics.json")
    d = m["diverged"]
    assert d["why"] == "|e| > 1 rad" and d["joint"] == "s2" and 0 < d["step"] < 1000, d
    assert m["all_finite"] and m["non_finite_from_step"] is None and m["worst_max_abs_error_run_rad"] > DIVERGED_RAD
    assert f"DIVERGED: |e| > 1 rad from step {d['step']}" in r.stdout
    assert f"**diverged**: |e| > 1 rad from step {d['step']}" in (out / "report.md").read_text()
    r = run_cli("study", "--config", cfg, "--scenarios", "nominal", "--controllers", "pid", "--seeds", "1",
                "--duration", "1", "--jobs", "1", "--no-progress", "--out", tmp_path / "study")
    assert "1 runs, 1 diverged" in r.stdout, r.stdout + r.stderr


def _strict_json(path):
    """The file's JSON, read as RFC 8259 readers (jq, JavaScript's JSON.parse) read it: NaN and Infinity refused."""
    def refuse(name):
        raise AssertionError(f"{path}: {name} is not JSON")
    return json.loads(path.read_text(), parse_constant=refuse)


def test_what_the_guards_did_in_process_is_in_the_metrics_the_report_and_the_summary(tmp_path):
    """The state guard refusing states (answered by the held torque, not trained on) left no trace in an
    in-process run's metrics.json or report.md (the graph's nodes count it). A speed limit of 0.05 rad/s: the
    reference's own speed passes it within the first 0.3 s on some joints."""
    cfg = tmp_path / "slow_guard.yaml"
    cfg.write_text(f"extends: {default_config_path()}\nguards:\n  max_speed_rad_s: 0.05\n")
    out = tmp_path / "out"
    r = run_cli("simulate", "--config", cfg, "--controller", "dnbs", "--duration", "0.3", "--no-figures", "--out", out)
    counts = _strict_json(out / "metrics.json")["guard_counters"]
    assert counts and all(c.get("bad_states_speed", 0) > 0 for c in counts.values()), counts
    first = next(iter(counts))
    assert f"guards acted: {first}: bad_states_speed {counts[first]['bad_states_speed']}" in r.stdout
    assert "**guards acted**" in (out / "report.md").read_text()
    clean = tmp_path / "clean"
    assert run_cli("simulate", "--controller", "dnbs", "--duration", "0.3", "--no-figures", "--out",
                   clean).returncode == 0
    assert _strict_json(clean / "metrics.json")["guard_counters"] == {}
    assert "guards acted" not in (clean / "report.md").read_text()


def test_torques_within_the_limits_is_what_the_controllers_asked_not_what_the_plant_clipped(monkeypatch):
    """The figure checked the applied torque, which the plant clips: it could not be false in-process. A PID
    that asks twice its limits (the paper's claim broken) is now reported outside them, and a sound one within."""
    from pa10_dnbs.core.pid_controller import PIDControllers
    from pa10_dnbs.report.metrics_file import metrics_dict, metrics_settings
    from pa10_dnbs.run_settings import build_settings
    from pa10_dnbs.sim.closed_loop import simulate

    settings = build_settings(default_config_path(), report=False)

    def within(run):
        return metrics_dict(run, metrics_settings(settings, 0.05))["torques_within_limits"]

    assert within(simulate(settings, "pid", 0.05))
    limit = np.asarray(settings.plant.torque_limit_nm)
    monkeypatch.setattr(PIDControllers, "answer", lambda self, x1, x2, ref, active=None: 2.0 * limit)
    run = simulate(settings, "pid", 0.05)
    assert np.all(np.abs(run.torque_nm) <= limit)   # the plant clipped them
    assert run.extra["torques_asked_beyond_limits"] == [50] * 7 and not within(run)


def test_huge_but_finite_values_are_left_out_of_the_figures(tmp_path):
    """A bag whose joint states swing between +-1e308 (finite): matplotlib's ticks overflowed (ValueError
    'arange: cannot compute length', analyse ended in a traceback). Samples beyond PLOT_BOUND are not drawn."""
    from pa10_dnbs.report.figures import error_figure, startup_figure, torque_figure, tracking_figure
    from pa10_dnbs.run_data import RunData

    n = 300
    q = np.zeros((n, 2))
    q[150:] = np.where(np.arange(n - 150) % 2, 1e308, -1e308)[:, None]
    run = RunData("dnbs", 0.001, ("s1", "s2"), np.array([10.0, 10.0]), q, q.copy(), np.zeros((n, 2)), q.copy())
    error_figure([run], tmp_path / "errors.png", (0.15, 0.3), [[None, None]])
    tracking_figure(run, tmp_path / "tracking.png")
    startup_figure(run, tmp_path / "startup.png", 0.01, [None, None])
    torque_figure(run, tmp_path / "torques.png")
    for name in ("errors.png", "tracking.png", "startup.png", "torques.png"):
        assert (tmp_path / name).stat().st_size > 0, name
