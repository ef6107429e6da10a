"""The README's results and figures blocks are what benchmarks/*.json give (scripts/readme_figures.py), and the records hold
what scripts/bench_record.py promises: a hand edit of the block, or a new record committed without
regenerating the block, fails here."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from pa10_dnbs.numeric_platform import numeric_platform, platform_env
from script_module import load_script

ROOT = Path(__file__).resolve().parent.parent
figures = load_script("readme_figures")
bench_record = load_script("bench_record")
record_tests = load_script("record_tests")


def test_readme_block_matches_the_records(capsys):
    assert figures.main(["--check"]) == 0, capsys.readouterr()


def test_every_committed_record_is_complete():
    paths = sorted((ROOT / "benchmarks").glob("*.json"))
    assert paths, "no records in benchmarks/"
    for path in paths:
        rec = bench_record.read(path)
        assert rec["benchmark"] in figures.ROWS or rec["benchmark"] == figures.RESULTS, path
        assert len(rec["load_before"]) == 3 and len(rec["load_after"]) == 3, path
        assert rec["machine"]["nproc"] >= 1 and rec["date_utc"].endswith("Z"), path
        assert len(rec["git_commit"]) == 40, path


@pytest.fixture
def copy(tmp_path):
    """A copy of README.md and benchmarks/ to edit."""
    shutil.copy(ROOT / "README.md", tmp_path / "README.md")
    shutil.copytree(ROOT / "benchmarks", tmp_path / "benchmarks")
    return tmp_path


def _check(folder: Path) -> int:
    return figures.main(["--check", "--readme", str(folder / "README.md"), "--records", str(folder / "benchmarks")])


def _row(readme: Path, begin: str, end: str, opening: str) -> tuple[str, str]:
    """(the README's text, the first line between ``begin`` and ``end`` that opens with ``opening``)."""
    text = readme.read_text()
    block = text[text.index(begin):text.index(end)]
    return text, next(line for line in block.splitlines() if line.startswith(opening))


def test_a_hand_edit_of_the_block_fails_the_check_until_regenerated(copy, capsys):
    readme = copy / "README.md"
    text, row = _row(readme, figures.BEGIN, figures.END, "| main job")
    readme.write_text(text.replace(row, row.replace(" | ", " | 9.99x ", 1)))
    assert _check(copy) == 1
    assert "are not what" in capsys.readouterr().err
    assert figures.main(["--readme", str(readme), "--records", str(copy / "benchmarks")]) == 0
    assert readme.read_text() == text
    assert _check(copy) == 0


def test_a_new_record_fails_the_check_until_regenerated(copy):
    path = next(p for p in sorted((copy / "benchmarks").glob("*.json")))
    rec = json.loads(path.read_text())
    rec["date_utc"] = "2030-01-02T03:04:05Z"
    path.write_text(json.dumps(rec))
    assert _check(copy) == 1
    assert figures.main(["--readme", str(copy / "README.md"), "--records", str(copy / "benchmarks")]) == 0
    assert "2030-01-02 03:04" in (copy / "README.md").read_text()
    assert _check(copy) == 0


def test_a_readme_without_markers_or_a_foreign_record_is_bad_input(copy, capsys):
    (copy / "benchmarks" / "other.json").write_text(json.dumps(
        bench_record.Record.start("bench_elsewhere", command="x").as_dict({})))
    assert _check(copy) == 2
    assert "no README row for benchmark 'bench_elsewhere'" in capsys.readouterr().err
    (copy / "benchmarks" / "other.json").unlink()
    (copy / "README.md").write_text("# no block\n")
    assert _check(copy) == 2
    assert "no figures block" in capsys.readouterr().err


def test_the_results_block_is_the_preset_record_and_a_hand_edit_fails_the_check(copy, capsys):
    readme = copy / "README.md"
    text, rms = _row(readme, figures.RESULTS_BEGIN, figures.RESULTS_END, "| RMS error over [10, 20) s [rad] |")
    rec = json.loads((copy / "benchmarks" / "preset_results.json").read_text())
    pa10 = next(a for a in rec["figures"]["arms"] if a["arm"] == "pa10")
    assert f"**{pa10['dnbs']['rms_rad']:.1e}**".replace("e-05", "e-5") in rms   # the record's, as the README says it
    readme.write_text(text.replace(rms, rms.replace("**", "", 2)))
    assert _check(copy) == 1
    assert figures.main(["--readme", str(readme), "--records", str(copy / "benchmarks")]) == 0
    assert readme.read_text() == text


def test_the_results_block_needs_exactly_one_preset_record(copy, capsys):
    (copy / "benchmarks" / "preset_results.json").unlink()
    assert _check(copy) == 2
    assert f"{copy}/benchmarks/ holds 0 preset_results records" in capsys.readouterr().err


def test_a_pipe_a_number_or_bytes_in_place_of_a_file_is_one_line(copy, capsys):
    """A FIFO as --readme or as a record held the check forever; a record holding 5 and a README of other bytes
    were tracebacks."""
    os.mkfifo(copy / "pipe.md")
    with pytest.raises(SystemExit) as end:
        figures.main(["--check", "--readme", str(copy / "pipe.md")])
    assert end.value.code == 2 and "argument --readme: " in capsys.readouterr().err
    (copy / "README.md").write_bytes(b"\xff\xfe not text")
    assert _check(copy) == 2
    assert capsys.readouterr().err.startswith(f"readme_figures: --readme: {copy}/README.md: cannot read it as text")
    shutil.copy(ROOT / "README.md", copy / "README.md")
    (copy / "benchmarks" / "a_number.json").write_text("5")
    assert _check(copy) == 2
    assert capsys.readouterr().err == (f"readme_figures: {copy}/benchmarks/a_number.json: not a benchmark record: "
                                       "not a JSON object\n")
    (copy / "benchmarks" / "a_number.json").unlink()
    os.mkfifo(copy / "benchmarks" / "a_pipe.json")
    assert _check(copy) == 2
    assert capsys.readouterr().err == f"readme_figures: {copy}/benchmarks/a_pipe.json: not a regular file\n"


def test_the_equal_budget_block_is_the_kept_comparisons_and_refuses_unequal_budgets(copy, capsys):
    readme = copy / "README.md"
    text, row = _row(readme, figures.BUDGET_BEGIN, figures.BUDGET_END, "| nominal |")
    tune = json.loads((copy / "benchmarks" / figures.BUDGET / "pa10" / "pid" / "tune.json").read_text())
    worst = max(r["worst_rms_error_rad"] for r in tune["held_out"]["tuned"] if r["scenario"] == "nominal")
    assert f" / {worst:.1e}".replace("e-0", "e-") in row.split(" | ")[1]   # PA10's PID, tuned: its tune.json
    readme.write_text(text.replace(row, row.replace("| nominal |", "| nominal (tuned) |")))
    assert _check(copy) == 1
    tune_file = copy / "benchmarks" / figures.BUDGET / "iiwa" / "dnbs" / "tune.json"
    other = json.loads(tune_file.read_text())
    other["trials"] = 59
    tune_file.write_text(json.dumps(other))
    assert _check(copy) == 2
    assert "not equal budgets" in capsys.readouterr().err


def test_a_record_holds_date_command_commit_machine_load_and_figures(tmp_path):
    rec = bench_record.Record.start("bench_sim", command=None)
    saved = rec.save(tmp_path / "r" / "x.json", {"ratio": 1.5})
    read = bench_record.read(tmp_path / "r" / "x.json")
    assert read == saved
    assert set(bench_record.KEYS) <= set(read)
    assert read["figures"] == {"ratio": 1.5}
    assert read["command"].startswith(".venv/bin/python ")
    assert read["machine"]["model_name"] and read["machine"]["nproc"] >= 1
    (tmp_path / "bad.json").write_text(json.dumps({k: v for k, v in read.items() if k != "load_after"}))
    with pytest.raises(ValueError, match="no 'load_after'"):
        bench_record.read(tmp_path / "bad.json")


def test_the_shown_command_drops_the_interpreter_and_the_record_file():
    assert figures.short_command(".venv/bin/python scripts/bench_sim.py --duration 10 --save-record "
                                 "benchmarks/bench_sim.json --repeat 3") == "bench_sim.py --duration 10 --repeat 3"
    assert figures.short_command("bash scripts/run_tests.sh -m 'not graph'") == "bash scripts/run_tests.sh -m 'not graph'"


def test_the_suite_figures_come_from_the_junit_report(tmp_path):
    xml = tmp_path / "j.xml"
    xml.write_text('<?xml version="1.0"?><testsuites><testsuite name="pytest" errors="1" failures="2" '
                   'skipped="3" tests="40" time="61.25"></testsuite></testsuites>')
    assert record_tests.junit_figures(xml) == {"tests": 40, "passed": 34, "failed": 2, "errors": 1, "skipped": 3,
                                               "pytest_s": 61.2}


MAIN_JOB_RMS = """
import json, sys
from pa10_dnbs.config import default_config_path
from pa10_dnbs.numeric_platform import numeric_platform
from pa10_dnbs.report.metrics_file import metrics_dict, metrics_settings
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.sim.closed_loop import simulate
settings, duration_s = build_settings(default_config_path(), report=False), float(sys.argv[1])
run = simulate(settings, "dnbs", duration_s)
rms = metrics_dict(run, metrics_settings(settings, duration_s))["worst_rms_error_rad"]
print(json.dumps({"rms": rms, "platform": numeric_platform()}))
"""


def test_a_record_of_another_platform_is_rerun_on_its_own_kernels_where_the_cpu_has_them():
    here = {"blas_core": "SkylakeX", "numpy_simd": ["X86_V3", "X86_V4", "AVX512_ICL"]}
    avx512 = "flags\t: fpu sse2 avx avx2 fma avx512f avx512cd avx512bw avx512dq avx512vl\n"
    avx2 = "flags\t: fpu sse2 avx avx2 fma\n"
    assert platform_env(here, here, avx512) == {}
    assert platform_env(dict(here, blas_core="Haswell"), here, avx512) == {"OPENBLAS_CORETYPE": "Haswell"}
    assert platform_env({"blas_core": "Zen", "numpy_simd": ["X86_V3"]}, here, avx512) == {
        "OPENBLAS_CORETYPE": "Zen", "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL"}
    assert platform_env(here, dict(here, blas_core="Haswell"), avx2) is None   # no AVX-512 for SkylakeX's kernels
    assert platform_env(dict(here, numpy_simd=["X86_V3", "AVX512_SPR"]), here, avx512) is None
    assert platform_env(dict(here, blas_core="Prescott"), here, avx512) is None   # a core not in CORE_FLAGS


def test_the_recorded_main_jobs_error_is_the_in_process_runs_bit_for_bit():
    """The lockstep graph equals the in-process run bit for bit, so the main job's recorded RMS (the README's
    main-job row) must be the in-process run's on the record's numeric platform (pa10_dnbs/numeric_platform.py:
    OpenBLAS's SkylakeX kernels give ...883e-05 where its Haswell kernels give ...797e-05, on one CPU). A record
    made on a dirty tree or before a change of the numbers is caught here; where this CPU cannot run the record's
    kernels, only a change above 1e-12 is."""
    rec = json.loads((ROOT / "benchmarks" / "main_job.json").read_text())
    record, recorded = rec["figures"], rec["machine"].get("numeric_platform")
    assert recorded, "benchmarks/main_job.json does not say its numeric platform: record it again"
    env = platform_env(recorded, numeric_platform())   # None: this CPU cannot run it
    run_env = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
    if "NPY_DISABLE_CPU_FEATURES" in (env or {}):
        run_env.pop("NPY_ENABLE_CPU_FEATURES", None)   # numpy refuses both at once
    r = subprocess.run([sys.executable, "-c", MAIN_JOB_RMS, str(record["duration_s"])], cwd=ROOT, env=run_env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    ran = json.loads(r.stdout.splitlines()[-1])   # the platform it ran on: OpenBLAS may not take a forced core
    rms, same = ran["rms"], all(ran["platform"].get(k) == v for k, v in recorded.items())   # numpy's version too
    if same:
        assert rms == record["worst_rms_error_rad"], (rms, record, recorded, ran, env)
    else:
        assert rms == pytest.approx(record["worst_rms_error_rad"], rel=1e-12, abs=0.0), (rms, recorded, ran)


PRESET = """
import json, sys
sys.path.insert(0, sys.argv[2])
import preset_results
from pa10_dnbs.numeric_platform import numeric_platform
print(json.dumps({"arm": preset_results.arm_result(sys.argv[1], float(sys.argv[3])), "platform": numeric_platform()}))
"""


def test_the_recorded_preset_results_are_what_the_arm_gives_today():
    """One column of the README's results (the iiwa: the PA10's DNBS is the main job's, above) run again: a
    record made before a change of the numbers is caught here, bit for bit on the record's numeric platform."""
    rec = json.loads((ROOT / "benchmarks" / "preset_results.json").read_text())
    recorded, figs = rec["machine"]["numeric_platform"], rec["figures"]
    env = platform_env(recorded, numeric_platform())
    run_env = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
    if "NPY_DISABLE_CPU_FEATURES" in (env or {}):
        run_env.pop("NPY_ENABLE_CPU_FEATURES", None)
    r = subprocess.run([sys.executable, "-c", PRESET, "iiwa", str(ROOT / "scripts"), str(figs["duration_s"])],
                       cwd=ROOT, env=run_env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    ran = json.loads(r.stdout.splitlines()[-1])
    want = next(a for a in figs["arms"] if a["arm"] == "iiwa")
    if all(ran["platform"].get(k) == v for k, v in recorded.items()):
        assert ran["arm"] == want
    else:
        for kind in figs["controllers"]:
            assert ran["arm"][kind]["rms_rad"] == pytest.approx(want[kind]["rms_rad"], rel=1e-9, abs=0.0), kind
