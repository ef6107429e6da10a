"""SCHED_BATCH for the nodes the plant's messages wake, SCHED_FIFO for every node, and the probe (loop/scheduling.py);
who gets them (node_specs)."""
import subprocess
import sys
from pathlib import Path

from pa10_dnbs.arm import load_arm
from pa10_dnbs.supervisor.graph_options import GraphOptions
from pa10_dnbs.supervisor.node_specs import node_commands

JOINT_NAMES = load_arm("pa10").joint_names

CHILD = """
import os, threading, time
from pa10_dnbs.loop.scheduling import apply_batch, policy_name
before = threading.Thread(target=time.sleep, args=(1,)); before.start()
ok, msg = apply_batch()
after = threading.Thread(target=time.sleep, args=(1,)); after.start()
tids = sorted(int(t) for t in os.listdir("/proc/self/task"))
print(ok, ",".join(policy_name(t) for t in tids), msg, sep="|")
"""


def test_batch_is_set_on_every_thread_and_inherited():
    """In a child process (the policy stays with it): every thread, the one started before included, and a
    thread started after it inherit SCHED_BATCH; no privilege is needed."""
    out = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, check=True).stdout.strip()
    applied, policies, msg = out.split("|")
    assert applied == "True", msg
    assert policies.split(",") == ["SCHED_BATCH"] * 3, policies  # main, the thread before, the thread after
    assert msg == "sched_batch: SCHED_BATCH on 2 threads"


def _param(argv, name):
    values = [argv[i + 1].split(":=", 1)[1] for i, a in enumerate(argv[:-1]) if a == "-p"
              and argv[i + 1].startswith(f"{name}:=")]
    return values[0] if values else None


def test_every_node_but_the_plant_is_asked_for_batch(tmp_path):
    opt = GraphOptions(config_path=Path("config/default.yaml"), joint_names=JOINT_NAMES, live_port=0, sched_batch=True)
    cmds = dict(node_commands(opt, tmp_path / "stats.json", tmp_path / "wire.npz"))
    assert {"plant", "reference", "wire_monitor", "live_view", "joint_controller_s1"} <= set(cmds)
    for name, argv in cmds.items():
        assert _param(argv, "sched_batch") == (None if name == "plant" else "true"), name
    off = dict(node_commands(GraphOptions(config_path=Path("config/default.yaml"), joint_names=JOINT_NAMES,  # the default: off
                                          record_bag=tmp_path / "bag"), tmp_path / "s.json", tmp_path / "w.npz"))
    assert "recorder" in off
    for name, argv in off.items():
        assert _param(argv, "sched_batch") == (None if name == "plant" else "false"), name


def test_every_node_of_the_graph_gets_the_rt_priority(tmp_path):
    """One scheduling class for the whole graph: with the loop alone under SCHED_FIFO an observer starved."""
    for record in (None, tmp_path / "bag"):
        opt = GraphOptions(config_path=Path("config/default.yaml"), joint_names=JOINT_NAMES, live_port=0, rt_priority=50, record_bag=record)
        cmds = dict(node_commands(opt, tmp_path / "stats.json", tmp_path / "wire.npz"))
        assert {"plant", "reference", "live_view", "joint_controller_w2"} <= set(cmds)
        assert ("recorder" if record else "wire_monitor") in cmds
        for name, argv in cmds.items():
            assert _param(argv, "rt_priority") == "50", name


PROBE = """
import os, threading
from pa10_dnbs.loop.scheduling import apply_fifo, fifo_permitted, policy_name
def policy(tid):
    try:
        return policy_name(tid)
    except ProcessLookupError:  # the thread ended between the listing and the question
        return "SCHED_OTHER"
permitted, why = fifo_permitted(7)
unchanged = all(policy(int(t)) == "SCHED_OTHER" for t in os.listdir("/proc/self/task"))
applied, _ = apply_fifo(7)
print(permitted, unchanged, applied, why, sep="|")
"""


def test_the_fifo_probe_answers_what_apply_fifo_then_does_and_changes_no_thread():
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, check=True).stdout.strip()
    permitted, unchanged, applied, why = out.split("|")
    assert unchanged == "True"        # the probe's own thread gave the policy back and ended
    assert permitted == applied, why  # root here: both True; an unprivileged user: both False, and why says so
    assert ("SCHED_FIFO permitted" in why) if permitted == "True" else ("not permitted here" in why)
