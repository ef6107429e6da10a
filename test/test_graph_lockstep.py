"""The node graph in lockstep: ready, converging over ROS, bit-identical to in-process, clean shutdown.

One 3 s DNBS run, recorded into a bag (session fixture ``lockstep_run`` in conftest.py), is checked from
several sides; test_bag_graph.py checks its bag.
"""
import json

import numpy as np
import pytest
import yaml

from graph_harness import assert_no_leftovers, exit_codes
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.settings import replace_in
from pa10_dnbs.sim.closed_loop import simulate
from pa10_dnbs.run_data import RunData

from conftest import LOCKSTEP_DURATION_S as DURATION_S

pytestmark = pytest.mark.graph  # starts ROS processes


def test_every_node_reported_ready_and_ran(lockstep_run):
    assert lockstep_run["rc"] == 0, lockstep_run["output"]
    assert "launch: graph ready (every node printed READY)" in lockstep_run["output"]
    assert "launch: plant running" in lockstep_run["output"]
    logs = lockstep_run["out"] / "logs"
    # recorded with --record: the recorder is the observer, no wire monitor
    names = ["recorder", "reference", "plant"] + [f"joint_controller_{j}" for j in ("s1", "s2", "s3", "e1", "e2", "w1", "w2")]
    assert not (logs / "wire_monitor.log").exists()
    for n in names:
        assert "READY" in (logs / f"{n}.log").read_text(), n
    # dnbs.kernel: auto (the default) is resolved once, by the launcher, which says so in one line; every
    # joint controller runs what it wrote into config_used.yaml
    kernel = yaml.safe_load((lockstep_run["out"] / "config_used.yaml").read_text())["dnbs"]["kernel"]
    assert kernel in ("c", "numpy")
    assert lockstep_run["output"].count("dnbs.kernel: auto -> ") == 1
    assert f"launch: dnbs.kernel: auto -> {kernel}" in lockstep_run["output"]
    bank = {"c": "CompiledDNBSControllers", "numpy": "DNBSControllers"}[kernel]
    for n in names[3:]:
        assert f": {bank}" in (logs / f"{n}.log").read_text(), n
    # the start handshake: step 0 went out once every node but the plant had said ready on the ready topic
    handshake = [x for x in (logs / "plant.log").read_text().splitlines() if x.startswith("HANDSHAKE every node ready")]
    assert len(handshake) == 1 and set(handshake[0].split(": ")[1].split(", ")) == set(names) - {"plant"}, handshake
    for n in set(names) - {"plant"}:
        assert f"HANDSHAKE {n} ready after" in (logs / f"{n}.log").read_text(), n


def test_converges_over_ros_with_torques_in_table2(lockstep_run):
    run = RunData.load_npz(lockstep_run["out"] / "timeseries.npz")
    assert run.n_steps == int(DURATION_S * 1000)
    err = np.abs(run.error_rad)
    assert np.all(np.isfinite(err)) and err.max() < 0.5
    assert np.all(err[-1000:].max(axis=0) < err[:1000].max(axis=0) / 5)
    assert np.all(np.abs(run.torque_nm) <= run.torque_limit_nm + 1e-12)
    m = json.loads((lockstep_run["out"] / "metrics.json").read_text())
    assert m["mode"] == "lockstep" and m["source"] == "ros-graph"
    assert m["torques_within_limits"] and m["all_finite"]
    assert all(j["effort_timeouts"] == 0 for j in m["timing"]["joints"])


def test_bit_identical_to_in_process_simulation(lockstep_run, _default_cfg):
    wire = RunData.load_npz(lockstep_run["out"] / "timeseries.npz")
    local = simulate(_default_cfg, "dnbs", DURATION_S)
    for field in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"):
        a, b = getattr(local, field), getattr(wire, field)
        assert np.array_equal(a, b), f"{field}: max diff {np.abs(a - b).max()}"


def test_clean_shutdown(lockstep_run):
    codes = exit_codes(lockstep_run["output"])
    assert len(codes) == 10 and all(c == 0 for c in codes.values()), codes  # 9 nodes and the recorder
    assert_no_leftovers(lockstep_run["pids"].values(), lockstep_run["shm_before"])


def test_the_runs_command_lines_read_its_finished_folder(lockstep_run):
    """logs/commands.sh named the run's temporary folder (renamed at its end): its lines could not be run."""
    out = lockstep_run["out"]
    text = (out / "logs" / "commands.sh").read_text()
    assert ".partial-" not in text and f"--params-file {out}/ros_params.yaml" in text, text


def test_warm_start_over_ros_equals_the_in_process_warm_start(lockstep_run, _default_cfg, tmp_path, domain):
    """--init-from the session run's checkpoints: each node loads its joint's weights and P; the lockstep run
    equals simulate(init_states=...) bit for bit, and metrics.json says it was a warm start."""
    from graph_harness import Launcher

    from pa10_dnbs.arm import load_arm

    JOINT_NAMES = load_arm("pa10").joint_names
    from pa10_dnbs.core.checkpoint import load_joint_checkpoints

    la = Launcher("--duration", 1.0, "--init-from", lockstep_run["out"], "--out", tmp_path / "warm", domain_id=domain)
    try:
        rc = la.wait(timeout=300)
    finally:
        la.kill()
    assert rc == 0, la.output
    wire = RunData.load_npz(tmp_path / "warm" / "timeseries.npz")
    states = load_joint_checkpoints(lockstep_run["out"], JOINT_NAMES)
    local = simulate(_default_cfg, "dnbs", 1.0, init_states=states)
    for field in ("position_rad", "torque_nm"):
        assert np.array_equal(getattr(local, field), getattr(wire, field)), field
    m = json.loads((tmp_path / "warm" / "metrics.json").read_text())
    assert m["warm_start_from"].endswith("checkpoints")
    # an unrecorded lockstep run is best effort by default (a recorded one, the session run, reliable): the
    # bit-for-bit equality holds for both
    assert m["reliability"] == "best_effort"
    assert json.loads((lockstep_run["out"] / "metrics.json").read_text())["reliability"] == "reliable"
    cold = RunData.load_npz(lockstep_run["out"] / "timeseries.npz")
    assert not np.array_equal(cold.torque_nm[:1000], wire.torque_nm)


def test_the_nodes_on_the_compiled_kernel_give_the_numpy_bits(_default_cfg, tmp_path, domain):
    """``--config config/compiled.yaml``: every joint controller steps the compiled DNBS kernel, and the
    lockstep run is the in-process numpy run bit for bit. Run once: the start handshake closed the start-up
    race (a plant that replaced efforts because the reference node's first /clock messages were delayed by DDS
    discovery, seen in 1 of 65 runs before it), so a stall fails here."""
    from graph_harness import Launcher

    from pa10_dnbs.paths import share_path

    out = tmp_path / "c"
    rc, la = Launcher.to_end("--config", share_path("config", "compiled.yaml"), "--duration", 1.0, "--out", out,
                             domain_id=domain)
    assert rc == 0, la.output
    m = json.loads((out / "metrics.json").read_text())
    assert all(j["effort_timeouts"] == 0 for j in m["timing"]["joints"]), m["timing"]["joints"]
    logs = sorted((out / "logs").glob("joint_controller_*.log"))
    assert len(logs) == 7 and all("CompiledDNBSControllers" in log.read_text() for log in logs)
    wire = RunData.load_npz(out / "timeseries.npz")
    local = simulate(replace_in(_default_cfg, "dnbs.kernel", "numpy"), "dnbs", 1.0)
    assert type(local.extra["controllers"]).__name__ == "DNBSControllers"
    for field in ("torque_nm", "position_rad", "velocity_rad_s"):
        a, b = getattr(local, field), getattr(wire, field)
        assert np.array_equal(a, b), f"{field}: first (step, joint) that differs {np.argwhere(a != b)[:3].tolist()}"


def test_the_iiwa_graph_is_its_in_process_run_named_after_its_joints(tmp_path, domain):
    """``--arm iiwa``: one controller process per iiwa joint, named after it, in the /iiwa namespace; the
    recorded lockstep run equals the in-process run bit for bit, and ``analyse`` rebuilds it from the bag."""
    from graph_harness import Launcher

    from pa10_dnbs.arm import load_arm
    from pa10_dnbs.bag.bag_reader import Bag
    from pa10_dnbs.config import default_config_path

    iiwa = load_arm("iiwa")
    out, bag = tmp_path / "run", tmp_path / "bag"
    la = Launcher("--arm", "iiwa", "--duration", 1.0, "--out", out, "--record", bag, domain_id=domain)
    try:
        rc = la.wait(timeout=300)
    finally:
        la.kill()
    assert rc == 0, la.output
    logs = sorted(p.name for p in (out / "logs").glob("joint_controller_*.log"))
    assert logs == sorted(f"joint_controller_{j}.log" for j in iiwa.joint_names) and len(logs) == 7
    with Bag(bag) as b:
        assert {f"/iiwa/{j}/{kind}" for j in iiwa.joint_names for kind in ("state", "effort", "reference")} <= set(
            b.topics)
    m = json.loads((out / "metrics.json").read_text())
    assert all(j["effort_timeouts"] == 0 for j in m["timing"]["joints"]), m["timing"]["joints"]
    wire = RunData.load_npz(out / "timeseries.npz")
    local = simulate(build_settings(default_config_path(), arm="iiwa"), "dnbs", 1.0)
    assert tuple(wire.joint_names) == iiwa.joint_names
    for field in ("position_rad", "velocity_rad_s", "reference_rad", "torque_nm"):
        a, b = getattr(local, field), getattr(wire, field)
        assert np.array_equal(a, b), f"{field}: first (step, joint) that differs {np.argwhere(a != b)[:3].tolist()}"
    from cli_runner import run_cli

    r = run_cli("analyse", bag, "--out", tmp_path / "again")
    assert r.returncode == 0, r.stderr
    again = RunData.load_npz(tmp_path / "again" / "timeseries.npz")
    assert np.array_equal(again.position_rad, wire.position_rad) and tuple(again.joint_names) == iiwa.joint_names
