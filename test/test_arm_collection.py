"""The collection benchmark's parts (pa10_dnbs/study/collection.py, scripts/arm_collection.py) on small fixtures:
a row of an accepted arm, a refused arm's one line, the targets and the table, the script's bad flags. The
collection itself (131 MB) is not needed here."""
from pathlib import Path

import pytest

from pa10_dnbs.study.collection import ARMS, arm_file, markdown_table, run_row, targets
from script_module import load_script

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "urdf_intake"
PRESETS = Path(__file__).resolve().parent.parent / "urdf"


def test_a_row_of_an_accepted_arm_has_every_controller_and_its_targets():
    row = run_row("iiwa", "arm_file", str(PRESETS / "iiwa" / "arm.yaml"), 0.4)
    assert row["status"] == "accepted" and row["n_joints"] == 7
    for kind in ("dnbs", "pid", "ctc"):
        f = row[kind]
        assert f["rms_rad"] is not None and f["rms_rad"] < 0.2 and not f["diverged"]
        assert f["steps_at_limit_after_startup"] >= 0
    t = targets(row)
    assert set(t) == {"DNBS settles by 0.5 s", "DNBS RMS <= 2e-5 rad", "DNBS torque variation <= 10",
                      "DNBS 0 steps at a limit after 0.2 s", "DNBS never diverges"}
    assert t["DNBS never diverges"] is True
    assert "| iiwa | arm_file | accepted (7 joints) |" in markdown_table([row])


def test_a_refused_arm_is_a_row_with_its_one_line():
    bad = FIXTURES / "negative_inertia.urdf"
    row = run_row("bad", "bare", str(bad), 0.4)
    assert row["status"] == "refused" and str(bad.name) in row["reason"] and "\n" not in row["reason"]
    assert targets(row) == {}
    assert "| bad | bare | refused: " in markdown_table([row])


def test_bare_targets_flag_a_diverged_dnbs_and_a_pid_ahead():
    fig = lambda rms, settled=0.2, diverged=False: {"rms_rad": rms, "settled_s": settled,  # noqa: E731
                                                    "torque_variation": 1.0, "steps_at_limit_after_startup": 0,
                                                    "max_abs_error_rad": 0.1, "diverged": diverged}
    row = {"arm": "x", "mode": "bare", "status": "accepted", "reason": "", "n_joints": 2,
           "dnbs": fig(2.0, None, True), "pid": fig(1e-3), "ctc": fig(1e-5)}
    t = targets(row)
    assert t["CTC <= 1e-4 rad"] and not t["DNBS never diverges"] and not t["aim: DNBS ahead of PID"]
    assert "2.0e+00!" in markdown_table([row])  # a diverged run is marked


def test_every_arm_has_its_arm_file_with_sources():
    import yaml
    for key in ARMS:
        raw = yaml.safe_load(arm_file(key).read_text())
        assert raw["name"] == key and "rotor_inertia_kgm2" in raw
        assert set(raw["sources"]) >= {"urdf", "rotor_inertia_kgm2"}


def _exit_code(script, argv) -> int:
    """main's return, or argparse's exit (a flag refused as it is parsed)."""
    try:
        return script.main(argv)
    except SystemExit as exc:
        return exc.code


@pytest.mark.parametrize("argv, needle", [(["--arms", "nope"], "'nope' is not one of"),
                                          (["--duration", "-1"], "--duration"), (["--jobs", "0"], "--jobs")])
def test_the_script_refuses_bad_flags_with_one_line(argv, needle, capsys, tmp_path):
    script = load_script("arm_collection")
    assert _exit_code(script, argv + ["--out", str(tmp_path / "t.json")]) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "t.json").exists()


@pytest.mark.parametrize("sibling", ["folder", "pipe"])
def test_out_is_refused_before_any_run_when_its_markdown_sibling_cannot_be_written(sibling, capsys, tmp_path):
    """The table's .md beside --out: a folder there was an IsADirectoryError traceback after every run, a pipe (or
    a device) was replaced by a file."""
    import os

    md = tmp_path / "t.md"
    md.mkdir() if sibling == "folder" else os.mkfifo(md)
    script = load_script("arm_collection")
    argv = ["--arms", "twodof", "--modes", "bare", "--duration", "0.2", "--jobs", "1",
            "--out", str(tmp_path / "t.json")]
    assert _exit_code(script, argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and "argument --out: " in err and str(md) in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.md"] and (md.is_dir() or md.is_fifo())


def test_out_in_folders_still_to_make_passes_and_makes_nothing(tmp_path):
    script = load_script("arm_collection")
    out = tmp_path / "new" / "deeper" / "t.json"
    assert script.out_path(str(out)) == out and list(tmp_path.iterdir()) == []


def test_the_readme_table_has_one_line_per_arm_with_both_modes():
    from pa10_dnbs.study.collection import compact_table
    fig = lambda rms, settled, diverged=False: {"rms_rad": rms, "settled_s": settled,  # noqa: E731
                                                "torque_variation": 1.0, "steps_at_limit_after_startup": 0,
                                                "max_abs_error_rad": 0.1, "diverged": diverged}
    rows = [{"arm": "a", "mode": "bare", "status": "accepted", "reason": "", "n_joints": 2,
             "dnbs": fig(3e-3, None), "pid": fig(2.0, None, True), "ctc": fig(1e-5, 0.1)},
            {"arm": "a", "mode": "arm_file", "status": "accepted", "reason": "", "n_joints": 2,
             "dnbs": fig(1e-5, 0.12), "pid": fig(1e-3, 0.3), "ctc": fig(1e-5, 0.1)},
            {"arm": "b", "mode": "bare", "status": "refused", "reason": "no effort"}]
    lines = compact_table(rows).splitlines()
    assert len(lines) == 4
    assert lines[2] == "| a | 3.0e-03 / 2.0e+00! / 1.0e-05 | 1.0e-05 / 1.0e-03 / 1.0e-05 | never / 0.12 |"
    assert lines[3] == "| b | refused | - | - / - |"


def test_steps_at_a_limit_after_startup_are_the_steps_the_metrics_count(_default_cfg):
    """The collection's count of steps at a limit after startup is the metrics' own (core/metrics.at_limit from
    first_step(startup_s)): a torque at its limit at step 200 (t = 0.2 s = startup_s, 0.2 / 0.001 rounding up
    to 200.00000000000003) and one 1e-10 of the limit short of it both count, as saturated_fraction_after_s
    counts them (it used to skip step 200 and ask 1 - 1e-12 of the limit)."""
    import numpy as np

    from pa10_dnbs.report.metrics_file import metrics_dict, metrics_settings
    from pa10_dnbs.run_data import RunData
    from pa10_dnbs.study.collection import _controller_figures

    s = _default_cfg
    n, nj = 1000, s.n_joints
    lim = np.asarray(s.plant.torque_limit_nm, float)
    tau = np.zeros((n, nj))
    start = int(round(s.metrics.startup_s / s.simulation.dt_s))
    tau[start - 1, 2] = lim[2]   # before startup_s: not counted
    tau[start, 0] = lim[0]
    tau[start + 10, 1] = -lim[1] * (1 - 1e-10)
    zeros = np.zeros((n, nj))
    run = RunData("dnbs", s.simulation.dt_s, tuple(s.arm.joint_names), lim, zeros, zeros, zeros, tau)
    figures = _controller_figures(run, s, n * s.simulation.dt_s)
    m = metrics_dict(run, metrics_settings(s, n * s.simulation.dt_s))
    after = n - start
    counted = round(sum(j["saturated_fraction_after_s"] for j in m["joints"]) * after)
    assert figures["steps_at_limit_after_startup"] == counted == m["steps_at_limit_after_s"] == 2, (figures, counted)
