"""A command whose standard output cannot be written (its reader gone: ``| head -1``; a full disk) goes on
and writes its outputs; before, it ended at its first line with ``[Errno 32] Broken pipe`` (exit 1, nothing
written)."""
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
NOTE = "pa10-dnbs: note: standard output cannot be written"


def _command(out: Path) -> list[str]:
    return [sys.executable, "-m", "pa10_dnbs.cli", "simulate", "--controller", "both", "--duration", "0.5",
            "--no-figures", "--out", str(out)]


def test_a_reader_gone_from_stdout_does_not_end_the_run(tmp_path):
    proc = subprocess.Popen(_command(tmp_path / "o"), stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=REPO,
                            env=dict(os.environ, PYTHONPATH=str(REPO)))
    proc.stdout.readline()   # as `| head -1`: one line, then the pipe is closed
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 0, err
    assert err.count(NOTE) == 1 and "Traceback" not in err and "Errno" not in err, err
    assert sorted(p.name for p in (tmp_path / "o").iterdir() if not p.name.startswith(".")) == \
        ["dnbs", "pid", "report.md", "summary.json"]


def test_a_full_stdout_does_not_end_the_run(tmp_path):
    if not os.path.exists("/dev/full"):
        import pytest
        pytest.skip("no /dev/full")
    with open("/dev/full", "w") as full:
        r = subprocess.run(_command(tmp_path / "o"), stdout=full, stderr=subprocess.PIPE, text=True, cwd=REPO,
                           env=dict(os.environ, PYTHONPATH=str(REPO)), timeout=120)
    assert r.returncode == 0 and r.stderr.count(NOTE) == 1 and "Traceback" not in r.stderr, r.stderr
    assert (tmp_path / "o" / "report.md").is_file()
