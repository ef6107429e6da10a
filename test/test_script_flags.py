"""The developer scripts refuse a bad flag in ONE line naming it, exit 2, before any work and writing nothing.

Each case runs the script for real (a subprocess, in an empty working folder); every one must be refused by
the argument checks (or the arm/config load right after them), so no case runs a benchmark: a case that
started one would take far longer than its timeout.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

# (script, arguments, the flag the one line must name); {dir}: an existing folder, {missing}: a path in a
# folder that does not exist, {binary}: a file of non-UTF-8 bytes, {garbage}: a text file that is not the
# expected JSON/YAML, {fifo}: a named pipe, {out}: a writable file path (so a wrongly accepted case could not touch
# the checkout)
ONE_ROW = ["--arms", "twodof", "--modes", "bare", "--duration", "0.2", "--jobs", "1"]   # arm_collection: 1 s if run
CASES = [
    ("bench_sim", ["--save-record", "{dir}"], "--save-record"),
    ("bench_sim", ["--save-record", "{missing}"], "--save-record"),
    ("bench_sim", ["--duration", "nan"], "--duration"),
    ("bench_sim", ["--duration", "-1"], "--duration"),
    ("bench_sim", ["--repeat", "0"], "--repeat"),
    ("bench_sim", ["--kernels", ""], "--kernels"),
    ("bench_sim", ["--kernels", "foo"], "--kernels"),
    ("bench_dnbs_step", ["--duration", "0"], "--duration"),
    ("bench_dnbs_step", ["--duration", "nan"], "--duration"),
    ("bench_dnbs_step", ["--repeat", "0"], "--repeat"),
    ("bench_bag_writer", ["--seconds", "nan"], "--seconds"),
    ("bench_bag_writer", ["--seconds", "-1"], "--seconds"),
    ("bench_bag_writer", ["--repeat", "0"], "--repeat"),
    ("bench_bag_writer", ["--save-record", "{dir}"], "--save-record"),
    ("bench_graph", ["--duration", "-1"], "--duration"),
    ("bench_graph", ["--duration", "nan"], "--duration"),
    ("bench_graph", ["--factors", "nan"], "--factors"),
    ("bench_graph", ["--repeat", "0"], "--repeat"),
    ("bench_graph", ["--save-record", "{missing}"], "--save-record"),
    ("bench_graph", ["--config", "{garbage}"], "--config"),
    ("bench_observers", ["--duration", "nan"], "--duration"),
    ("bench_observers", ["--repeat", "0"], "--repeat"),
    ("bench_observers", ["--modes", "foo"], "--modes"),
    ("bench_joint_bus", ["--rounds", "0"], "--rounds"),
    ("bench_joint_bus", ["--duration", "nan"], "--duration"),
    ("bench_joint_bus", ["--json", "{dir}"], "--json"),
    ("bench_joint_bus", ["--workdir", "{binary}"], "--workdir"),
    ("soak_lifecycle", ["--runs", "0"], "--runs"),
    ("soak_lifecycle", ["--duration", "nan"], "--duration"),
    ("soak_lifecycle", ["--run-timeout", "nan"], "--run-timeout"),
    ("soak_lifecycle", ["--json", "{dir}"], "--json"),
    ("soak_lifecycle", ["--keep", "{binary}"], "--keep"),
    ("soak_realtime", ["--minutes", "nan"], "--minutes"),
    ("soak_realtime", ["--rtf", "0"], "--rtf"),
    ("interrupt_tune", ["--tries", "0"], "--tries"),
    ("interrupt_tune", ["--duration", "nan"], "--duration"),
    ("interrupt_tune", ["--out", "{dir}"], "--out"),
    ("dynamics_check", ["--states", "0"], "--states"),
    ("dynamics_check", ["--tolerance", "nan"], "--tolerance"),
    ("engine_comparison", ["--duration", "inf"], "--duration"),
    ("arm_collection", ["--jobs", "abc", "--out", "{out}"], "--jobs"),
    ("arm_collection", [*ONE_ROW, "--out", "{dir}"], "--out"),
    ("arm_collection", [*ONE_ROW, "--out", "{binary}/table.json"], "--out"),
    ("arm_collection", [*ONE_ROW, "--out", "{fifo}"], "--out"),
    ("arm_collection", [*ONE_ROW, "--out", "{dir}/table.md"], "--out"),
    ("arm_collection", [*ONE_ROW, "--arms", "", "--out", "{out}"], "--arms"),
    ("preset_results", ["--arms", "foo"], "--arms"),
    ("preset_results", ["--duration", "nan"], "--duration"),
    ("preset_results", ["--duration", "0.1"], "--duration"),
    ("preset_results", ["--save-record", "{dir}"], "--save-record"),
    ("arm_collection", [*ONE_ROW, "--modes", ",", "--out", "{out}"], "--modes"),
    ("arm_collection", [*ONE_ROW, "--duration", "0.0001", "--out", "{out}"], "--duration"),
    ("arm_collection", [*ONE_ROW, "--duration", "1e4", "--out", "{out}"], "--duration"),
    ("readme_figures", ["--records", "{missing}", "--check"], "--records"),
    ("compare_bags", ["{dir}", "{dir}", "--topics"], "--topics"),
    ("intake_timing", ["--joints", "abc"], "--joints"),
    ("intake_timing", ["--points", "-5"], "--points"),
    ("intake_timing", ["--points", "0"], "--points"),
    ("intake_timing", ["--repeat", "0"], "--repeat"),
    ("encoder_noise_filters", ["--duration", "nan"], "--duration"),
    ("encoder_noise_filters", ["--cutoffs", "abc"], "--cutoffs"),
    ("encoder_noise_filters", ["--arm", "zz"], "--arm"),
    ("cascade_modes", ["--arm", "zz"], "--arm"),
    ("cascade_modes", ["--ekf-gain", "-1"], "--ekf-gain"),
    ("cascade_modes", ["--ekf-gain", "1e308"], "--ekf-gain"),   # a Kalman gain is at most 1: was a LinAlgError
    ("intake_timing", ["--points", "1e30"], "--points"),         # was a ValueError traceback
    ("intake_timing", ["--joints", "99999999999999999999"], "--joints"),   # was a hang
    ("engine_comparison", ["--arms", ","], "--arms"),             # was an empty table, exit 0
    ("engine_comparison", ["--controllers", "pid,nope"], "--controllers"),
    ("result_fingerprint", ["--compare", "{missing}"], "--compare"),
    ("result_fingerprint", ["--compare", "{dir}"], "--compare"),
    ("result_fingerprint", ["--compare", "{binary}"], "--compare"),
    ("result_fingerprint", ["--compare", "{garbage}"], "--compare"),
    ("result_fingerprint", ["--compare", "{fifo}"], "--compare"),
    ("result_fingerprint", ["--save", "{dir}"], "--save"),
    ("result_fingerprint", ["--save", "{fifo}"], "--save"),
    ("result_fingerprint", ["--save", "/dev/full"], "--save"),
    ("make_foxglove_layout", ["--arm", "zz", "--out", "{out}"], "--arm"),
    ("make_foxglove_layout", ["--namespace", "bad ns", "--out", "{out}"], "--namespace"),
    ("make_foxglove_layout", ["--out", "{dir}"], "--out"),
    ("make_foxglove_layout", ["--config", "{garbage}", "--out", "{out}"], "--config"),
    ("make_foxglove_layout", ["--config", "{binary}", "--out", "{out}"], "--config"),
    ("make_foxglove_layout", ["--arm", "", "--out", "{out}"], "--arm"),   # named --config
    ("make_foxglove_layout", ["--arm", "iiwa"], "--out"),   # overwrote the PA10's config/foxglove_layout.json
    ("live_probe", ["notaurl"], "url"),
    ("live_probe", ["--wait", "nan"], "--wait"),
    ("live_probe", ["--wait", "0"], "--wait"),
]


@pytest.mark.parametrize("script,args,flag", CASES, ids=[f"{s}{' '.join(a)}" for s, a, _ in CASES])
def test_bad_flag_is_one_line_exit_2(tmp_path, script, args, flag):
    work = tmp_path / "work"
    (work / "a_folder").mkdir(parents=True)
    (work / "binary.json").write_bytes(bytes(range(256)))
    (work / "garbage.json").write_text("this is neither JSON nor a config: [\n")
    os.mkfifo(work / "a_pipe")
    before = sorted(p.relative_to(work) for p in work.rglob("*"))
    paths = {"dir": work / "a_folder", "missing": work / "no_such_folder" / "x.json",
             "binary": work / "binary.json", "garbage": work / "garbage.json", "fifo": work / "a_pipe",
             "out": work / "layout.json"}
    argv = [a.format(**paths) for a in args]
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / f"{script}.py"), *argv], cwd=work,
                          capture_output=True, text=True, timeout=60)
    lines = done.stderr.splitlines()
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    assert len(lines) == 1, done.stderr
    assert "Traceback" not in done.stderr + done.stdout
    assert f"argument {flag}" in lines[0], lines[0]
    assert sorted(p.relative_to(work) for p in work.rglob("*")) == before  # nothing written, no DIR.tmp
    assert (work / "a_pipe").is_fifo()   # not replaced by a file


def test_a_good_record_path_passes(tmp_path):
    """The --save-record check lets a new file in an existing folder through, and an existing record."""
    sys.path.insert(0, str(ROOT / "scripts"))
    from bench_record import record_path
    assert record_path(str(tmp_path / "new.json")) == tmp_path / "new.json"
    (tmp_path / "old.json").write_text("{}")
    assert record_path(str(tmp_path / "old.json")) == tmp_path / "old.json"


def test_bench_graph_writes_no_record_when_every_run_failed(tmp_path, monkeypatch, capsys):
    """Every attempt of every run failing (GraphFailure, as a starved or crashed graph raises it) is exit 1
    with one line saying so, and no record: it used to exit 0 with a record of NaNs. The graph's launcher is
    replaced by one that fails at once, so the test is about the benchmark's accounting, not the graph."""
    from script_module import load_script
    bench_graph = load_script("bench_graph")

    def failing_graph(opt, workdir, say, on_hard_stop=None):
        raise bench_graph.GraphFailure("nodes exited with non-zero codes: plant=1")

    monkeypatch.setattr(bench_graph, "run_graph", failing_graph)
    record = tmp_path / "bench_graph.json"
    monkeypatch.setattr(sys, "argv", ["bench_graph.py", "--duration", "0.1", "--repeat", "1", "--factors", "1",
                                      "--rt-priority", "0", "--save-record", str(record)])
    assert bench_graph.main() == 1
    err = capsys.readouterr().err
    assert "every run failed every attempt" in err and "no record written" in err, err
    assert not record.exists() and list(tmp_path.iterdir()) == []
