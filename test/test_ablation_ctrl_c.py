"""scripts/ablation.py stopped by a Ctrl-C (SIGINT to its process group, as a terminal sends it): one line, exit
130, its worker processes gone; it was a KeyboardInterrupt traceback and a death by the signal."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pa10_dnbs.interrupt import child_pids

pytestmark = pytest.mark.slow
REPO = Path(__file__).resolve().parent.parent


def test_ablation_ctrl_c_says_one_line_and_stops_its_workers(tmp_path):
    proc = subprocess.Popen([sys.executable, str(REPO / "scripts" / "ablation.py"), "--only", "0,1", "--long-s",
                             "20", "--workers", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        t0 = time.monotonic()
        while len(child_pids(proc.pid)) < 2:
            assert proc.poll() is None and time.monotonic() - t0 < 60, proc.communicate()
            time.sleep(0.05)
        workers = child_pids(proc.pid)
        time.sleep(0.5)
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=15)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 130 and out == "" and err == (
        "ablation: interrupted; nothing printed (the table comes whole, once every run is done): run the same "
        "command again\n"), (proc.returncode, err)
    time.sleep(0.3)
    assert not [p for p in workers if Path(f"/proc/{p}").exists()], "workers left"
