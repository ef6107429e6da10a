"""scripts/intake_timing.py runs end to end on tiny inputs and prints one figure per input (figures only: the
speed itself is the benchmark's to print, not a test's to time)."""
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_benchmark_prints_a_figure_per_chain_and_per_trajectory_file():
    done = subprocess.run([sys.executable, "scripts/intake_timing.py", "--joints", "3", "--points", "1e2", "--yaml"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert re.fullmatch(r"pa10-dnbs arm,\s+3-joint chain \(10 N m joints\):\s+\d+\.\d\d s", lines[1])
    assert [re.fullmatch(r"trajectory file,\s+100 points \((json|yaml), 0\.0 MB\):\s+\d+\.\d\d s", x).group(1)
            for x in lines[2:4]] == ["json", "yaml"]
    assert lines[0].startswith("load average before:") and lines[-1].startswith("load average after:")
