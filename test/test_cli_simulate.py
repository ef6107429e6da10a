"""``pa10-dnbs simulate`` end to end: outputs, bad input (exit 2, nothing written), --force."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from cli_runner import run_cli

from pa10_dnbs.config import default_config_path

REPO = Path(__file__).resolve().parent.parent


def _cli_process(*args, cwd=None):
    """The console entry point in its own process (end to end); the other tests call it in-process."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", *map(str, args)], capture_output=True,
                          text=True, env=env, cwd=cwd, timeout=300)


def test_simulate_both_writes_metrics_figures_report_timeseries(tmp_path):
    out = tmp_path / "run"
    r = _cli_process("simulate", "--controller", "both", "--duration", "1.0", "--out", out, "--no-progress")
    assert r.returncode == 0, r.stderr
    for sub in ("dnbs", "pid"):
        m = json.loads((out / sub / "metrics.json").read_text())
        assert m["controller"] == sub and m["duration_s"] == pytest.approx(1.0) and m["dt_s"] == 0.001
        assert m["window_s"] == [0.5, 1.0]  # shorter than the configured [10, 20]: second half
        assert len(m["joints"]) == 7 and m["joints"][0]["name"] == "s1"
        assert {"rms_error_rad", "max_abs_error_rad", "max_abs_torque_nm", "torque_limit_nm",
                "saturated_fraction"} <= set(m["joints"][0])
        assert m["wall_time_s"] > 0 and m["real_time_factor"] > 0
        for f in ("tracking.png", "errors.png", "startup.png", "torques.png", "timeseries.npz"):
            assert (out / sub / f).stat().st_size > 1000
        assert {"settling_time_s", "max_abs_error_run_rad", "torque_variation",
                "saturated_fraction_after_s"} <= set(m["joints"][0])
    assert sorted(p.name for p in (out / "dnbs" / "checkpoints").iterdir()) == sorted(f"{j}.npz" for j in
                                                                                     ("s1", "s2", "s3", "e1", "e2",
                                                                                      "w1", "w2"))
    report = (out / "report.md").read_text()
    assert "DNBS RMS" in report and "PID RMS" in report and "errors_compare.png" in report
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary left


def test_no_figures_writes_data_and_report_without_png(tmp_path):
    out = tmp_path / "run"
    r = run_cli("simulate", "--controller", "pid", "--duration", "0.1", "--out", out, "--no-progress", "--no-figures")
    assert r.returncode == 0, r.stderr
    assert (out / "metrics.json").is_file() and (out / "timeseries.npz").is_file()
    assert not list(out.rglob("*.png"))
    report = (out / "report.md").read_text()
    assert "--no-figures" in report and ".png" not in report
    # 0.1 s of PID from 0.1 rad off: not settled, said as the console says it (not "after never s")
    assert json.loads((out / "metrics.json").read_text())["worst_settling_time_s"] is None
    assert "settled (|e| < 0.01 rad) never;" in report and "after never" not in report


def _bad_config(tmp_path, edit):
    d = yaml.safe_load(default_config_path().read_text())
    edit(d)
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(d))
    return p


@pytest.mark.parametrize("edit,named", [
    (lambda d: d["dnbs"].__setitem__("extra", 1), "dnbs.extra"),
    (lambda d: d["pid"].__setitem__("kd", "high"), "pid.kd"),
    (lambda d: d["simulation"].__setitem__("dt_s", -0.001), "simulation.dt_s"),
    (lambda d: d["dnbs"]["alpha_net"].__setitem__("q", float("inf")), "dnbs.alpha_net.q"),
    (lambda d: d.__setitem__("arm", "/no/such/arm.yaml"), "/no/such/arm.yaml"),
])
def test_bad_config_exits_2_names_key_writes_nothing(tmp_path, edit, named):
    out = tmp_path / "out"
    r = run_cli("simulate", "--config", _bad_config(tmp_path, edit), "--duration", "0.5", "--out", out)
    assert r.returncode == 2
    assert named in r.stderr and "Traceback" not in r.stderr
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml"]


def test_bad_duration_exits_2(tmp_path):
    r = run_cli("simulate", "--duration", "-3", "--out", tmp_path / "o")
    assert r.returncode == 2 and "--duration" in r.stderr and not (tmp_path / "o").exists()


def test_existing_output_needs_force(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "report.md").write_text("a previous run's report")   # --force replaces only a previous output
    (out / ".pa10-dnbs-output").write_text("Written by pa10-dnbs\n")   # the mark of one (report/outputs.py)
    (out / "keep.txt").write_text("mine")                        # (test_output_safety.py: not other folders)
    r = run_cli("simulate", "--controller", "pid", "--duration", "0.2", "--out", out)
    assert r.returncode == 2 and "--force" in r.stderr
    assert (out / "keep.txt").read_text() == "mine"
    r = run_cli("simulate", "--controller", "pid", "--duration", "0.2", "--out", out, "--force", "--no-progress")
    assert r.returncode == 0, r.stderr
    assert not (out / "keep.txt").exists() and (out / "metrics.json").exists()


def test_a_configs_faults_are_said_not_injected_in_process(tmp_path):
    """The faults section acts on the node graph's messages (launch); an in-process run has none and says so on
    stderr and in its report (it was silent: a clean report for a config that asked for faults)."""
    cfg = tmp_path / "faults.yaml"
    cfg.write_text(f"extends: {default_config_path()}\nfaults:\n  state:\n    drop_fraction: 0.5\n")
    out = tmp_path / "run"
    r = run_cli("simulate", "--config", cfg, "--controller", "pid", "--duration", "0.05", "--no-figures",
                "--no-progress", "--out", out)
    assert r.returncode == 0, r.stderr
    assert "faults section is injected by `launch` alone" in r.stderr
    assert "this in-process run has no faults" in (out / "report.md").read_text()
    r = run_cli("simulate", "--controller", "pid", "--duration", "0.05", "--no-figures", "--no-progress",
                "--out", tmp_path / "plain")
    assert "faults" not in r.stderr and "faults" not in (tmp_path / "plain" / "report.md").read_text()


@pytest.mark.parametrize("closed", [">&-", "2>&-", ">&- 2>&-"])
def test_a_closed_stdout_or_stderr_is_no_error(tmp_path, closed):
    """``simulate ... >&-``: sys.stdout is None, and the PyBullet print guard's flush ended in an AttributeError
    traceback at import, exit 1. The run is written, exit 0; a closed descriptor gets /dev/null (no file opened
    later takes its number for C-level prints)."""
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    r = subprocess.run(["sh", "-c", f'exec "$@" {closed}', "sh", sys.executable, "-m", "pa10_dnbs.cli", "simulate",
                        "--controller", "pid", "--duration", "0.05", "--no-figures", "--out", str(out)],
                       capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert (out / "report.md").is_file() and (out / "metrics.json").is_file()


@pytest.mark.parametrize("command", ["simulate", "arm"])
def test_an_ascii_only_stdout_writes_other_characters_as_escapes(tmp_path, command):
    """Under LC_ALL=POSIX PYTHONIOENCODING=ascii, an output path (or an arm's joint names) outside ASCII ended the
    run with a UnicodeEncodeError traceback on its "wrote ..." line, exit 1, after the output was written."""
    from test_arm_intake_edges import _arm_file, _chain, _write

    out = tmp_path / "ünï" / "out"
    _write(tmp_path / "named.urdf", _chain(names=("jä1", "jö2", "jü3")))
    arm = _arm_file(tmp_path, urdf="named.urdf") if command == "arm" else None
    args = ["arm", "--arm", arm] if arm else ["simulate", "--controller", "pid", "--duration",
                                                                "0.05", "--no-figures", "--out", out]
    env = {**os.environ, "PYTHONPATH": str(REPO), "LC_ALL": "POSIX", "PYTHONIOENCODING": "ascii"}
    r = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", *map(str, args)], capture_output=True, text=True,
                       encoding="ascii", env=env, timeout=300)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    if arm:
        assert "j\\xe41" in r.stdout + r.stderr
    else:
        assert f"wrote {tmp_path}/\\xfcn\\xef/out/report.md" in r.stdout and (out / "report.md").is_file()
