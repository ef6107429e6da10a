"""Numbers that used to hang a command or end in a traceback: each is refused in ONE line naming its flag or
config key, exit 2, nothing written, and quickly.

A trajectory whose last point lies far in time (its limits check sampled every step up to there), a start
position outside the joint limits, a reference whose frequency, envelope or amplitude make it non-finite, a
duration of 1e308 s (an infinite step count) or shorter than two steps, ``robot --duration 0`` (ran forever)
and ``replay --clock 1e308`` (hung), ``replay --rate 1e-300`` or ``--wait-for-subscribers 1e308`` (accepted), a
study scenario's reference past the Nyquist rate (run), a node's ``-p duration_s:=1e308`` (a traceback). Fast tier.
"""
from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from cli_runner import run_cli

import pa10_dnbs.core.trajectory_reference as trajectory_reference
from pa10_dnbs.config import default_config_path
from pa10_dnbs.core.joint_trajectory import JointTrajectory, TrajectoryError
from pa10_dnbs.core.reference import Reference
from pa10_dnbs.core.trajectory_reference import TrajectoryReference

REPO = Path(__file__).resolve().parent.parent
EXAMPLE = REPO / "config" / "trajectory_example.yaml"
CLI = Path(sys.executable).parent / "pa10-dnbs"


def _assert_refused(r, name: str, tmp_path: Path, before: set) -> None:
    """Exit 2, one line on stderr naming ``name``, no traceback, nothing written into ``tmp_path``."""
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert len(lines) == 1 and name in lines[0], r.stderr[-2000:]
    assert "Traceback" not in r.stderr + r.stdout
    assert {p.name for p in tmp_path.iterdir()} == before, "a refused command wrote something"


def _config(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(f"extends: {default_config_path()}\n{text}\n")
    return path


def _refused(tmp_path: Path, name: str, *words) -> None:
    before = {p.name for p in tmp_path.iterdir()}
    _assert_refused(run_cli(*words), name, tmp_path, before)


def _trajectory(tmp_path: Path, last_s: float, hold: bool = False) -> Path:
    """The example trajectory with its last point at ``last_s`` [s] (``hold``: every point at rest, the last at
    the one before's position, so the long last segment does not move)."""
    data = yaml.safe_load(EXAMPLE.read_text())
    data["points"][-1]["time_from_start"] = float(last_s)
    if hold:
        data["points"][-1]["positions"] = list(data["points"][-2]["positions"])
        for point in data["points"]:
            point["velocities"] = point["accelerations"] = [0.0] * len(point["positions"])
    path = tmp_path / f"far_{last_s:g}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


# --- 1. a trajectory's far end: the limits check costs the same for any length; absurd times refused ---

@pytest.mark.parametrize("last_s", [1.0e9, 1.0e12, 1.0e20, 1.0e308])
def test_far_trajectory_refused_in_one_line_quickly(tmp_path, last_s):
    traj = _trajectory(tmp_path, last_s)
    before = {p.name for p in tmp_path.iterdir()}
    t0 = time.monotonic()
    r = subprocess.run(["timeout", "60", str(CLI), "simulate", "--duration", "0.2", "--controller", "pid",
                        "--trajectory", str(traj), "--out", str(tmp_path / "run"), "--no-progress"],
                       capture_output=True, text=True)
    _assert_refused(r, "time_from_start", tmp_path, before)
    assert "past the longest trajectory followed" in r.stderr
    assert time.monotonic() - t0 < 30


def test_long_trajectory_within_bound_is_checked_quickly(tmp_path):
    """A last point at 1e6 s (the longest followed; 1e9 steps): checked at its turning points, not every step
    (the old check sampled them all: about 17 s per 1e5 s)."""
    traj = _trajectory(tmp_path, 1.0e6, hold=True)
    t0 = time.monotonic()
    r = subprocess.run(["timeout", "120", str(CLI), "simulate", "--duration", "0.05", "--controller", "pid",
                        "--trajectory", str(traj), "--out", str(tmp_path / "run"), "--no-progress",
                        "--no-figures"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    assert (tmp_path / "run" / "report.md").is_file()
    assert time.monotonic() - t0 < 60


def _start(traj: JointTrajectory, lo, hi) -> str | None:
    n = lo.size
    base = Reference(np.zeros(n), np.ones(n), np.zeros(n), dt_s=1e-3)
    try:
        TrajectoryReference(base, traj.joint_names, lo, hi).start(traj, 0)
        return None
    except TrajectoryError as exc:
        return str(exc)


def test_limits_checked_at_turning_points_decides_as_every_step(monkeypatch):
    """On random trajectories, sampling only next to the knots and the quintics' turning points accepts and
    refuses exactly what sampling every step does (the turning points replaced by every step's time), naming the
    same first step beyond."""
    rng = np.random.default_rng(3)
    names = ("a", "b", "c")
    lo, hi = -np.ones(3), np.ones(3)
    refused = 0
    for _ in range(150):
        m = int(rng.integers(1, 5))
        traj = JointTrajectory(names, np.cumsum(rng.uniform(0.01, 0.5, m)), rng.uniform(-0.97, 0.97, (m, 3)))
        turning = _start(traj, lo, hi)
        with monkeypatch.context() as mp:
            mp.setattr(trajectory_reference, "extremum_times", lambda s: np.arange(0.0, s.end_s + 5e-3, 5e-3))
            every = _start(traj, lo, hi)
        assert turning == every  # the same first step, joint and value when refused
        refused += turning is not None
    assert 5 < refused < 145  # both outcomes exercised


# --- 2. a start position outside the joint limits ---

START_CASES = [("simulation: {initial_position_offset_rad: 100}", "simulation.initial_position_offset_rad"),
               ("simulation: {initial_position_offset_rad: -100}", "simulation.initial_position_offset_rad"),
               ("reference: {centre_rad: 5}", "reference.centre_rad")]
COMMANDS = [("simulate", "--controller", "pid", "--duration", "0.05"),
            ("simulate", "--controller", "pid", "--engine", "mujoco", "--duration", "0.05"),
            ("study", "--controllers", "pid", "--duration", "0.05"),
            ("tune", "--controller", "pid", "--trials", "1", "--duration", "0.05")]


@pytest.mark.parametrize("text,key", START_CASES, ids=[k for _, k in START_CASES])
@pytest.mark.parametrize("words", COMMANDS, ids=[" ".join(w[:3]) for w in COMMANDS])
def test_start_outside_limits_refused(tmp_path, text, key, words):
    cfg = _config(tmp_path, text)
    _refused(tmp_path, key, *words, "--config", cfg, "--out", tmp_path / "run", "--no-progress")


@pytest.mark.parametrize("text,key", START_CASES, ids=[k for _, k in START_CASES])
def test_robot_start_outside_limits_refused(tmp_path, text, key):
    _refused(tmp_path, key, "robot", "--config", _config(tmp_path, text), "--duration", "1")


# --- 3. a reference that is not finite or cannot be sampled ---

REFERENCE_CASES = [("reference: {frequency_rad_s: 1.0e+308}", "reference.frequency_rad_s"),
                   ("reference: {frequency_rad_s: 3200}", "reference.frequency_rad_s"),   # above pi / 1 ms
                   ("reference: {envelope_rate_per_s3: 1.0e+308}", "reference.envelope_rate_per_s3"),
                   ("reference: {amplitude_rad: 1.0e+308}", "reference.amplitude_rad")]


@pytest.mark.parametrize("text,key", REFERENCE_CASES, ids=[t for t, _ in REFERENCE_CASES])
def test_reference_out_of_bounds_refused(tmp_path, text, key):
    cfg = _config(tmp_path, text)
    _refused(tmp_path, key, "simulate", "--controller", "all", "--duration", "0.05", "--config", cfg,
             "--out", tmp_path / "run", "--no-progress")
    _refused(tmp_path, key, "arm", "--config", cfg)


def test_study_and_tune_with_ctc_refuse_a_huge_frequency(tmp_path):
    cfg = _config(tmp_path, "reference: {frequency_rad_s: 1.0e+308}")
    _refused(tmp_path, "reference.frequency_rad_s", "study", "--controllers", "ctc", "--duration", "0.05",
             "--config", cfg, "--out", tmp_path / "run", "--no-progress")
    _refused(tmp_path, "reference.frequency_rad_s", "tune", "--controller", "ctc", "--trials", "1", "--duration",
             "0.05", "--config", cfg, "--out", tmp_path / "run", "--no-progress")


# --- 4-6. durations: an infinite step count, shorter than two steps, zero ---

DURATION_CASES = [("simulate", "--controller", "pid", "--duration", "1e308"),
                  ("study", "--controllers", "pid", "--duration", "1e308"),
                  ("tune", "--controller", "pid", "--trials", "1", "--duration", "1e308"),
                  ("launch", "--duration", "1e308"),
                  ("study", "--controllers", "pid", "--duration", "1e-9"),
                  ("study", "--controllers", "pid", "--duration", "0.001")]


@pytest.mark.parametrize("words", DURATION_CASES, ids=[" ".join(w) for w in DURATION_CASES])
def test_duration_refused(tmp_path, words):
    _refused(tmp_path, "--duration", *words, "--out", tmp_path / "run", "--no-progress")


@pytest.mark.parametrize("arm", ["pa10", "iiwa"])
def test_config_duration_of_infinite_steps_refused(tmp_path, arm):
    cfg = _config(tmp_path, "simulation: {duration_s: 1.0e+308}")
    _refused(tmp_path, "simulation.duration_s", "simulate", "--arm", arm, "--controller", "pid", "--config", cfg,
             "--out", tmp_path / "run", "--no-progress")


@pytest.mark.parametrize("value", ["0", "1e308"])
def test_robot_duration_refused(tmp_path, value):
    """Under ``timeout``: 0 started a robot node that ran until Ctrl-C."""
    before = {p.name for p in tmp_path.iterdir()}
    r = subprocess.run(["timeout", "-s", "INT", "60", str(CLI), "robot", "--duration", value], capture_output=True,
                       text=True, cwd=tmp_path)
    _assert_refused(r, "--duration", tmp_path, before)


# --- 7. replay --clock ---

@pytest.mark.parametrize("value", ["1e308", "1e7", "1001"])
def test_replay_clock_bounded(tmp_path, value):
    bag = tmp_path / "bag"
    bag.mkdir()
    _refused(tmp_path, "--clock", "replay", bag, "--clock", value)


def test_replay_clock_at_its_bound_passes_the_flag_check(tmp_path):
    bag = tmp_path / "bag"
    bag.mkdir()
    for words in (["--clock", "1000"], ["--clock"]):
        r = run_cli("replay", bag, *words)
        assert r.returncode == 2 and "--clock" not in r.stderr and "Traceback" not in r.stderr, r.stderr


# --- 8. replay --rate and --wait-for-subscribers (1e-300 and 1e308 were accepted) ---

@pytest.mark.parametrize("flag,value", [("--rate", "1e-300"), ("--rate", "0.0009"), ("--rate", "1001"),
                                        ("--wait-for-subscribers", "1e308"), ("--wait-for-subscribers", "3601"),
                                        ("--wait-for-subscribers", "-1")])
def test_replay_rate_and_wait_bounded(tmp_path, flag, value):
    bag = tmp_path / "bag"
    bag.mkdir()
    _refused(tmp_path, flag, "replay", bag, flag, value)


def test_replay_rate_and_wait_at_their_bounds_pass_the_flag_check(tmp_path):
    bag = tmp_path / "bag"
    bag.mkdir()
    for flag, value in (("--rate", "0.001"), ("--rate", "1000"), ("--wait-for-subscribers", "3600"),
                        ("--wait-for-subscribers", "0")):
        r = run_cli("replay", bag, flag, value)   # refused for the bag (not one), not for the flag
        assert r.returncode == 2 and flag not in r.stderr and "Traceback" not in r.stderr, r.stderr


# --- 9. a study scenario's reference past the Nyquist rate (fast_reference's x1.5 was not checked) ---

def test_a_scenario_reference_past_the_nyquist_rate_is_refused_before_any_run(tmp_path):
    """2500 rad/s is below pi / T = 3141.6 rad/s; fast_reference's x1.5, 3750 rad/s, is not: study and tune
    refuse in one line naming the scenario (the study ran it); the nominal scenario alone still passes the check."""
    cfg = _config(tmp_path, "reference:\n  frequency_rad_s: 2500\n  amplitude_rad: 0.001")
    common = ("--config", cfg, "--seeds", "1", "--duration", "0.2", "--jobs", "1", "--no-progress")
    _refused(tmp_path, "scenario fast_reference", "study", "--scenarios", "nominal,fast_reference",
             "--controllers", "pid", *common, "--out", tmp_path / "s")
    _refused(tmp_path, "scenario fast_reference", "tune", "--controller", "pid", "--trials", "1",
             "--scenarios", "fast_reference", *common, "--out", tmp_path / "t")
    before = {p.name for p in tmp_path.iterdir()}
    r = run_cli("tune", "--controller", "pid", "--trials", "1", "--scenarios", "nominal", *common,
                "--out", tmp_path / "t")
    _assert_refused(r, "--held-out-seeds 0", tmp_path, before)   # its held-out runs take every scenario
    from pa10_dnbs.run_settings import build_settings
    from pa10_dnbs.study.scenarios import check_scenario_references
    check_scenario_references(build_settings(cfg, report=False), ["nominal"])


# --- 10. a node started by hand with -p duration_s:=1e308 (an OverflowError traceback; the launcher refuses it) ---

NODE_TIMEOUT_S = 60


@pytest.mark.parametrize("value,words", [("1e308", "more than can be counted"), ("0.001", "shorter than two steps")])
def test_a_nodes_duration_is_counted_as_the_launcher_counts_it(tmp_path, domain, value, words):
    """The plant, wire monitor, reference and MuJoCo robot nodes (each in its own process, on the test's own
    domain, in parallel): exit 2, one line naming the parameter, no traceback (run_steps' check)."""
    from graph_harness import REPO as ROOT, ros_env
    nodes = [("plant.node", ()), ("wire_monitor", (f"out_file:={tmp_path / 'wire.npz'}",)), ("reference_node", ()),
             ("mujoco_robot_node", ())]
    procs = [subprocess.Popen(["timeout", "-k", "5", str(NODE_TIMEOUT_S), sys.executable, "-m", f"pa10_dnbs.ros.{m}",
                               "--ros-args", "-p", f"duration_s:={value}", *[a for p in extra for a in ("-p", p)]],
                              cwd=ROOT, env=ros_env(domain), text=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
             for m, extra in nodes]
    try:
        for (module, _), p in zip(nodes, procs):
            out, err = p.communicate(timeout=NODE_TIMEOUT_S + 10)
            lines = [ln for ln in err.splitlines() if ln.strip()]
            assert p.returncode == 2 and "Traceback" not in err, (module, p.returncode, out, err[-2000:])
            assert len(lines) == 1 and "parameter duration_s" in lines[0] and words in lines[0], (module, err)
    finally:   # a node that ran (the old code) must not outlive the test on its domain: SIGINT, then wait
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
        for p in procs:
            p.communicate(timeout=NODE_TIMEOUT_S + 10)
    assert not (tmp_path / "wire.npz").exists()


LINK_CASES = [("--delay-states", "1e308"), ("--jitter-efforts", "1e308"), ("--delay-efforts", "1000.5"),
              ("--jitter-states", "nan")]


@pytest.mark.parametrize("flag,value", LINK_CASES, ids=[" ".join(c) for c in LINK_CASES])
def test_launch_link_delay_and_jitter_bounded(tmp_path, flag, value):
    """1e308 ms was accepted: every lockstep step then waited --effort-timeout (a 0.5 s run took ~500 s). A delay
    or jitter is at most 1000 ms (config.py LINK_DELAY_MAX_MS; later is a lost message, --drop-*)."""
    _refused(tmp_path, flag, "launch", "--duration", "0.5", flag, value, "--out", tmp_path / "run", "--no-progress")


def test_config_link_delay_bounded(tmp_path):
    cfg = _config(tmp_path, "faults: {state: {delay_ms: 1.0e+308}}")
    _refused(tmp_path, "faults.state.delay_ms", "launch", "--duration", "0.5", "--config", cfg,
             "--out", tmp_path / "run", "--no-progress")


@pytest.mark.parametrize("value", ["1e308", "inf", "0.5", "7"])
def test_launch_kill_time_within_the_run(tmp_path, value):
    """``--kill s1@1e308`` started the graph, then the joint's controller raised OverflowError (rc 1, a .failed
    folder): a kill time is finite and within the run, 0 <= SECONDS < duration, checked before any node."""
    _refused(tmp_path, "--kill", "launch", "--duration", "0.5", "--kill", f"s1@{value}", "--out", tmp_path / "run",
             "--no-progress")


def test_config_kill_time_within_the_run(tmp_path):
    cfg = _config(tmp_path, "faults: {kill_controller_at_s: [1.0e+308, -1, -1, -1, -1, -1, -1]}")
    _refused(tmp_path, "faults.kill_controller_at_s", "launch", "--duration", "0.5", "--config", cfg,
             "--out", tmp_path / "run", "--no-progress")


def test_launch_kill_of_one_joint_twice_refused(tmp_path):
    """``--kill s1@0.1 --kill s1@0.2`` silently kept only the last."""
    _refused(tmp_path, "--kill", "launch", "--duration", "0.5", "--kill", "s1@0.1", "--kill", "s1@0.2", "--restart",
             "--out", tmp_path / "run", "--no-progress")
