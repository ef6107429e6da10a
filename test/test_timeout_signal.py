"""``timeout`` (GNU) sends its signal to the command and then to the command's whole process group: the command
gets it twice, microseconds apart (SIGTERM, or SIGINT with ``-s INT``), and its pool workers get it too. That is
one stop, as a Ctrl-C (docs/tuning.md, "Interrupting": the completed runs kept, one line, exit 130), not a second
Ctrl-C that drops them; and no thread traceback from the pool whose workers the group's signal ended."""
import json
import os
import re
import signal
import time

import pytest

from test_misuse_interrupt import BOUND_S, Command, one_line, wait_until

from pa10_dnbs.interrupt import child_pids

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["timeout", "timeout -s INT"])
def test_timeouts_signal_to_the_command_then_its_group_is_one_stop(tmp_path, sig):
    c = Command("study", "--scenarios", "nominal,payload_2kg", "--controllers", "pid", "--seeds", 20, "--duration",
                30, "--jobs", 2, "--no-progress", "--out", tmp_path / "s")   # 40 runs of ~1.3 s: 26 s on 2 workers
    try:
        wait_until(lambda: len(child_pids(c.proc.pid)) == 2, "two pool workers", proc=c)
        time.sleep(2.0)   # some runs complete, never all (8 runs took 5.8 s here: too few for a 3x faster machine)
        c.t_sigint = time.monotonic()
        os.kill(c.proc.pid, sig)          # timeout's kill(pid, sig) ...
        time.sleep(0.02)                  # (its handler has run: the race the two sends lose now and then)
        os.killpg(c.proc.pid, sig)        # ... then kill(0, sig): the group, the command again and its workers
        rc, seconds, err = c.end()
    finally:
        c.kill()
    assert rc == 130 and seconds < BOUND_S, (rc, seconds, err)
    m = re.fullmatch(r"pa10-dnbs: interrupted after (\d+) of 40 runs; (kept their rows in \S+/s/study\.partial\.md "
                     r".*|nothing written to .*)", one_line(err))
    assert m and "Exception in thread" not in err, err
    if int(m.group(1)):
        assert len(json.loads((tmp_path / "s" / "study.partial.json").read_text())["rows"]) == int(m.group(1))
