"""/clock and /joint_states QoS: a reader whose side of the match completes late still gets every message.

DDS discovery is two-sided: the plant can count the reference node's /clock reader as matched and publish
before that reader has matched the plant back. A volatile reader then dropped the first 200 steps' clocks and
the lockstep graph stalled for two effort timeouts (the full suite, 2026-11-24). The probe creates the reader
after the messages went out, the extreme case of that race.
"""
import json
import os
import subprocess
import sys

import pytest

from graph_harness import REPO

pytestmark = pytest.mark.graph  # starts a ROS process

N = 20


def test_a_reader_created_after_the_clock_went_out_still_receives_every_clock(domain):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    out = subprocess.run([sys.executable, str(REPO / "test" / "late_reader_probe.py"), str(domain), str(N), "20"],
                         capture_output=True, text=True, env=env, timeout=60, check=True)
    got = json.loads(out.stdout)
    sent = [k * 10_000_000 for k in range(N)]
    assert got["early"] == sent, "the reader that matched first lost messages"
    assert got["late"] == sent, f"the late reader received {len(got['late'])} of {N} (volatile durability?)"
