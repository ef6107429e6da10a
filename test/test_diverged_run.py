"""A run that goes non-finite is a result: metrics say where, the report and its figures are written, exit 1."""
import json
from pathlib import Path

import numpy as np

from cli_runner import run_cli
from pa10_dnbs.config import default_config_path
from pa10_dnbs.core.metrics import divergence

CONTINUOUS = Path(__file__).parent / "fixtures" / "urdf_intake" / "continuous_joint.urdf"


def test_divergence_names_the_first_non_finite_step_and_the_joint_running_away():
    q = np.zeros((6, 3))
    qd = np.zeros((6, 3))
    tau = np.zeros((6, 3))
    assert divergence(q, qd, tau) is None
    qd[3] = [1.0, -50.0, 2.0]
    q[4, 0] = np.inf
    assert divergence(q, qd, tau) == {"step": 4, "joint": 1}
    tau[2, 2] = np.nan
    assert divergence(q, qd, tau) == {"step": 2, "joint": 0}
    q[0, 2] = np.nan
    assert divergence(q, None, tau) == {"step": 0, "joint": 2}


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
    assert m["worst_rms_error_rad"] is None   # undefined, written null: the file is strict JSON
    assert _strict_json(out / "summary.json")["pid"]["worst_rms_error_rad"] is None
    assert "DIVERGED" in r.stdout and f"step {d['step']}" in r.stdout
    assert json.loads((out / "dnbs" / "metrics.json").read_text())["diverged"] is None
    report = (out / "report.md").read_text()
    assert "**diverged**" in report and f"step {d['step']}" in report
    for name in ("arm.png", "tracking.png", "errors.png", "startup.png", "torques.png"):
        assert (out / "pid" / name).stat().st_size > 0, name
    assert (out / "errors_compare.png").is_file()


def _strict_json(path):
    """The file's JSON, read as RFC 8259 readers (jq, JavaScript's JSON.parse) read it: NaN and Infinity refused."""
    def refuse(name):
        raise AssertionError(f"{path}: {name} is not JSON")
    return json.loads(path.read_text(), parse_constant=refuse)
