#!/usr/bin/env python3
"""Run the test suite (``bash scripts/run_tests.sh``) and record how many tests ran and how long it took.

The figures come from pytest's own JUnit XML report (``--junitxml``): tests, passed, failed, errors, skipped,
pytest's time [s], plus the wall time of the whole command (venv check included) and the pytest arguments
that chose the tier (e.g. ``-m "not graph"``, the fast tier; none: the full suite). Pytest's output is printed
as it comes. Exit code: pytest's; the record is written either way (its figures say what failed).

    .venv/bin/python scripts/record_tests.py [--save-record benchmarks/tests_fast.json] [-- pytest args]
"""
from __future__ import annotations

import shlex
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import bench_record  # noqa: E402

from pa10_dnbs.cli_values import OneLineParser  # noqa: E402


def junit_figures(xml_file: Path) -> dict:
    """tests, passed, failed, errors, skipped and pytest's time [s], summed over the report's test suites."""
    root = ET.parse(xml_file).getroot()
    suites = [root] if root.tag == "testsuite" else root.findall("testsuite")
    total = {k: sum(int(s.get(k, 0)) for s in suites) for k in ("tests", "failures", "errors", "skipped")}
    seconds = sum(float(s.get("time", 0.0)) for s in suites)
    return {"tests": total["tests"], "passed": total["tests"] - total["failures"] - total["errors"] - total["skipped"],
            "failed": total["failures"], "errors": total["errors"], "skipped": total["skipped"],
            "pytest_s": round(seconds, 1)}


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    bench_record.add_argument(ap)
    ap.add_argument("pytest_args", nargs="*", help="passed to scripts/run_tests.sh (after --), e.g. -m 'not graph'")
    args = ap.parse_args()
    shown = ["bash", "scripts/run_tests.sh", *args.pytest_args]
    record = bench_record.Record.start("tests", command=" ".join(shlex.quote(c) for c in shown))
    with tempfile.TemporaryDirectory(prefix="pa10_tests_") as tmp:
        xml_file = Path(tmp) / "junit.xml"
        rc = script_main.wait_child(script_main.start_child([*shown, f"--junitxml={xml_file}"], second_stop=False,
                                                         cwd=bench_record.ROOT))   # pytest: killed at a 2nd Ctrl-C
        if not xml_file.is_file():
            print(f"record_tests: pytest exited {rc} without a report: no record", file=sys.stderr)
            return rc or 1
        figs = junit_figures(xml_file)
    figs["pytest_args"] = args.pytest_args
    figs["tier"] = "full" if not args.pytest_args else " ".join(args.pytest_args)
    figs["exit_code"] = rc
    record.save(args.save_record, figs)
    print(f"tests: {figs['tests']} ({figs['passed']} passed, {figs['failed']} failed, {figs['errors']} errors, "
          f"{figs['skipped']} skipped), pytest {figs['pytest_s']:.0f} s")
    return rc


if __name__ == "__main__":
    sys.exit(script_main.run(main, "record_tests", interrupted="no record written: run the same command again"))
