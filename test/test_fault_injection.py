"""Fault injection: seeded, at the configured rates, delays delivered late, flags validated."""
import re
import argparse
import math
import threading
import time

import pytest

from pa10_dnbs.config import ConfigError
from pa10_dnbs.faults.delay_line import DelayLine
from pa10_dnbs.faults.link_faults import FaultInjector, LinkFaults
from pa10_dnbs.arm import load_arm
from pa10_dnbs.commands.fault_flags import FaultFlags, add_fault_arguments, apply_fault_flags, faults_active

JOINT_NAMES = load_arm("pa10").joint_names


def _fates(faults, seed, n):
    inj = FaultInjector(faults, seed)
    return [inj.next_fate() for _ in range(n)], inj


def test_injector_is_seeded_and_hits_the_rates():
    f = LinkFaults(drop_fraction=0.01, corrupt_fraction=0.02, delay_s=0.001, jitter_s=0.002)
    a, inj = _fates(f, (0, 3, 1), 100_000)
    b, _ = _fates(f, (0, 3, 1), 100_000)
    c, _ = _fates(f, (1, 3, 1), 100_000)
    assert a == b and a != c
    assert inj.dropped == sum(x.drop for x in a) and 900 < inj.dropped < 1100
    assert inj.corrupted == sum(x.corrupt for x in a) and 1800 < inj.corrupted < 2200
    assert all(0.001 <= x.delay_s <= 0.003 for x in a if not x.drop)
    assert inj.delayed == 100_000 - inj.dropped


@pytest.mark.parametrize("kind, check", [("nan", math.isnan), ("inf", math.isinf), ("out_of_range", lambda v: v == 1000.0)])
def test_corrupt_values(kind, check):
    inj = FaultInjector(LinkFaults(corrupt_fraction=1.0, corrupt_kind=kind), 0)
    inj.next_fate()
    assert check(inj.corrupt_value(100.0))


def test_delay_line_delivers_late_and_in_due_order():
    got, lock = [], threading.Lock()

    def deliver(p):
        with lock:
            got.append((p, time.monotonic()))
    line = DelayLine(deliver)
    t0 = time.monotonic()
    line.send("slow", 0.08)
    line.send("fast", 0.02)
    time.sleep(0.2)
    line.send("never", 5.0)
    line.close()
    assert [p for p, _ in got] == ["fast", "slow"]
    assert got[0][1] - t0 >= 0.02 and got[1][1] - t0 >= 0.08
    assert line.lost_at_close == 1


def _args(*argv):
    p = argparse.ArgumentParser()
    add_fault_arguments(p)
    return FaultFlags.of(p.parse_args(list(argv)))


def test_flags_override_the_chosen_joints(cfg):
    assert not faults_active(cfg.faults)
    out = apply_fault_flags(cfg, _args("--fault-joints", "s2,w1", "--drop-efforts", "0.01", "--corrupt-states",
                                       "inf:0.5", "--kill", "e1@5", "--fault-seed", "7"))
    f = out.faults
    assert f.effort.drop_fraction == (0.0, 0.01, 0.0, 0.0, 0.0, 0.01, 0.0)
    assert f.state.corrupt_kind == "inf" and f.state.corrupt_fraction[1] == 0.5
    assert f.kill_controller_at_s[3] == 5.0 and f.seed == 7 and faults_active(out.faults)
    assert not faults_active(cfg.faults)  # the input settings are left alone


@pytest.mark.parametrize("argv, flag", [
    (("--drop-states", "1.5"), "--drop-states"), (("--corrupt-efforts", "zero:0.1"), "--corrupt-efforts"),
    (("--kill", "e1"), "--kill"), (("--fault-joints", "s9"), "--fault-joints"),
    (("--delay-efforts", "-1"), "--delay-efforts"), (("--kill", "e1@-2"), "--kill")])
def test_bad_flags_name_themselves(cfg, argv, flag):
    with pytest.raises(ConfigError, match=flag):
        apply_fault_flags(cfg, _args(*argv))


@pytest.mark.parametrize("argv, said", [
    (("--fault-joints", "s2"), "--fault-joints: it picks the joints of --drop-*, --delay-*, --jitter-* and "
                               "--corrupt-*, and none of them is given"),
    (("--fault-joints", "s2", "--kill", "s1@1"), "--fault-joints: it picks the joints of"),   # --kill names its own
    (("--fault-seed", "3"), "--fault-seed: no fault is injected")])
def test_a_flag_that_would_do_nothing_is_refused(cfg, argv, said):
    """Before, each was accepted and did nothing: a run the user believed faulty, or seeded, was neither."""
    with pytest.raises(ConfigError, match=re.escape(said)):
        apply_fault_flags(cfg, _args(*argv))


def test_the_seed_alone_applies_to_the_configs_faults(cfg):
    faulty = apply_fault_flags(cfg, _args("--drop-states", "0.1"))
    assert apply_fault_flags(faulty, _args("--fault-seed", "3")).faults.seed == 3
    assert apply_fault_flags(cfg, _args("--fault-seed", "3", "--kill", "s1@1")).faults.seed == 3
