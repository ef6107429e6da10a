"""Realtime mode (deadline-synchronous) against lockstep (the realtime loss smoke run: test_graph_faults.py).

A realtime tick applies exactly the efforts answering its state that came before the deadline, so a
realtime run in which no effort missed is the lockstep run bit for bit. At a low real-time factor (0.1: a
10 ms tick for 1 ms of simulated time) misses are rare even on a busy machine; if one happens the runs are
compared up to it, and the test says so (pytest -rA shows it).
"""
import json

import numpy as np
import pytest

from graph_harness import Launcher, exit_codes
from pa10_dnbs.arm import load_arm
JOINT_NAMES = load_arm("pa10").joint_names
from pa10_dnbs.supervisor.realtime_advice import ON_TIME_TARGET
from pa10_dnbs.loop.scheduling import DEFAULT_RT_PRIORITY, fifo_permitted
from pa10_dnbs.run_data import RunData

pytestmark = pytest.mark.graph  # starts ROS processes

RTF = 0.1
DURATION_S = 1.0


def _realtime(tmp_path, domain, *args, name="rt"):
    out = tmp_path / name
    la = Launcher("--mode", "realtime", "--duration", DURATION_S, "--out", out, *args, domain_id=domain)
    try:
        rc = la.wait(timeout=300)
    finally:
        la.kill()
    assert rc == 0, la.output
    assert all(c == 0 for c in exit_codes(la.output).values())
    stats = json.loads((out / "plant_stats.json").read_text())
    assert (f"realtime --rtf {stats['target_real_time_factor']:g}: every effort before the deadline on "
            f"{100 * stats['on_time_fraction']:.2f} % of ticks, late tick starts {stats['late_start_ticks']}"
            in la.output)  # the launcher says it, not only report.md
    # and advises a lower factor exactly when the run fell short of the sustainable fraction
    hint = f"realtime --rtf {stats['target_real_time_factor']:g}: below 99 % on time"
    assert (hint in la.output) == (stats["on_time_fraction"] < ON_TIME_TARGET)
    # the nodes ran with the policy asked for: SCHED_FIFO 50 by default wherever the OS grants it (it replaces
    # --sched-batch); else --sched-batch's SCHED_BATCH for every node but the plant (no privilege needed), else
    # the default policy. The controllers say so at exit.
    timing = json.loads((out / "metrics.json").read_text())["timing"]
    fifo = "--rt-priority" not in args and fifo_permitted(DEFAULT_RT_PRIORITY)[0]
    policy = "SCHED_FIFO" if fifo else "SCHED_BATCH" if "--sched-batch" in args else "SCHED_OTHER"
    assert timing["rt_priority_applied"] is fifo and timing["rt_priority"] == (DEFAULT_RT_PRIORITY if fifo else 0)
    assert timing["sched_batch"] is ("--sched-batch" in args) and timing["controller_sched_policies"] == [policy], \
        timing
    return out, stats


def test_realtime_without_misses_equals_lockstep_bit_for_bit(lockstep_run, tmp_path, domain):
    # --effort-timeout bounds only the start-up handshake in realtime (ticks never wait past their deadline):
    # generous, so that first answers slowed by a loaded machine are not misses at step 0
    # the launcher's default policy (SCHED_FIFO where allowed) with --sched-batch, which SCHED_FIFO replaces where
    # it is granted and which is the policy end to end where it is not: a run without misses is lockstep bit for bit
    out, stats = _realtime(tmp_path, domain, "--rtf", RTF, "--effort-timeout", 10, "--sched-batch")
    n = int(round(DURATION_S * 1000))
    assert stats["steps"] == n and stats["completed"] and stats["target_real_time_factor"] == RTF
    firsts = [j["first_missed_step"] for j in stats["joints"] if j["first_missed_step"] is not None]
    m = min(firsts, default=n)  # torques [0, m) and states [0, m] are those of a run without misses
    rt = RunData.load_npz(out / "timeseries.npz")
    ls = RunData.load_npz(lockstep_run["out"] / "timeseries.npz")
    if m == n:
        print(f"realtime at factor {RTF}: no effort missed its deadline; all {n} steps compared")
    else:
        missed = [j["name"] for j in stats["joints"] if j["first_missed_step"] == m]
        print(f"realtime at factor {RTF}: first miss at step {m} ({', '.join(missed)}); on-time fraction "
              f"{stats['on_time_fraction']:.4f}; compared torques of steps [0, {m}) and states [0, {m}]")
    assert m > 0, "every joint missed the very first deadline: nothing to compare"
    # a run's RunData holds states 0..n-1; state m (the last one a miss cannot have touched) exists when m < n
    states = min(m + 1, n)
    for field, upto in (("torque_nm", m), ("position_rad", states), ("velocity_rad_s", states)):
        a, b = getattr(rt, field)[:upto], getattr(ls, field)[:upto]
        assert a.shape == (upto, len(JOINT_NAMES)) and b.shape == a.shape, (field, a.shape, b.shape)
        assert np.array_equal(a, b), f"{field}: max diff {np.abs(a - b).max()} before the first miss"
    if m < n:  # the missed effort was replaced by the joint's last torque (hold, the default)
        for name in missed:
            j = JOINT_NAMES.index(name)
            assert rt.torque_nm[m, j] == rt.torque_nm[m - 1, j], name
