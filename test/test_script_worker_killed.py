"""A pool worker of scripts/ablation.py or scripts/arm_collection.py killed (``kill -9``, the OOM killer's way):
one line naming the script's own flag and how the worker died, exit 2; the collection keeps its completed rows
as for a Ctrl-C. Both ended in a traceback of the pool's PoolBroken (exit 1) before."""
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

pytestmark = pytest.mark.slow
REPO = Path(__file__).resolve().parent.parent
FIXTURE = REPO / "test" / "fixtures" / "urdf_intake" / "xarm7_no_meshes.urdf"
WAIT_S = 90.0   # a bound on any wait here (the runs take seconds)

# arm_collection.py without the 131 MB collection: its root is the fixtures' folder, its two "arms" one fixture
COLLECTION_DRIVER = f"""
import sys
from pathlib import Path
sys.path.insert(0, {str(REPO / "test")!r})
from script_module import load_script
script = load_script("arm_collection")
script.collection_root = lambda: Path({str(FIXTURE.parent)!r})
script.ARMS = {{"a": ({FIXTURE.name!r}, "A"), "b": ({FIXTURE.name!r}, "B")}}
sys.exit(script.main(sys.argv[1:]))
"""


def _run_and_kill_a_worker(argv: list[str]) -> tuple[int, str, str]:
    """Run ``python ARGV``; once it has two pool workers (and 0.5 s more) SIGKILL one; (rc, stdout, stderr). The
    runs must last well beyond that (seconds each), or there is no worker left to kill."""
    proc = subprocess.Popen([sys.executable, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        t0 = time.monotonic()
        while len(psutil.Process(proc.pid).children()) < 2:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() - t0 < WAIT_S, "the pool never started"
            time.sleep(0.05)
        time.sleep(0.5)
        workers = psutil.Process(proc.pid).children()
        assert proc.poll() is None and workers, "the runs ended before a worker could be killed: make them longer"
        os.kill(workers[0].pid, signal.SIGKILL)
        out, err = proc.communicate(timeout=WAIT_S)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    return proc.returncode, out, err


def test_ablation_whose_worker_is_killed_says_one_line_naming_workers():
    rc, out, err = _run_and_kill_a_worker([str(REPO / "scripts" / "ablation.py"), "--only", "0", "--long-s", "200",
                                           "--workers", "2"])
    assert rc == 2 and out == "" and re.fullmatch(
        r"ablation: error: --workers: a local worker process died \(killed by SIGKILL\) \(out of memory\? fewer "
        r"--workers need less\), so its run cannot finish; nothing printed \(the table comes whole, once every run "
        r"is done\): run the same command again\n", err), (rc, err)


def test_arm_collection_whose_worker_is_killed_keeps_its_completed_rows(tmp_path):
    out = tmp_path / "c.json"
    rc, _, err = _run_and_kill_a_worker(["-c", COLLECTION_DRIVER, "--modes", "bare", "--duration", "30",
                                         "--jobs", "2", "--out", str(out)])
    m = re.fullmatch(r"arm_collection: error: --jobs: a local worker process died \(killed by SIGKILL\) \(out of "
                     r"memory\? fewer --jobs need less\), so its run cannot finish; (\d) of 2 rows kept in (\S+)\n",
                     err.splitlines(keepends=True)[-1] if err else "")
    assert rc == 2 and m and m.group(2) == str(out), (rc, err)
    table = json.loads(out.read_text())
    assert table["meta"]["rows_done"] == len(table["rows"]) == int(m.group(1)) < 2
    assert out.with_suffix(".md").is_file()
