"""Bad files and addresses a user can give: one line naming the flag, key or file, exit 2, nothing written.

Warm-start checkpoints (``--init-from``) that are truncated, of another network or not finite; config files that
are not text, not YAML, give a key twice or extend a missing file; a bag whose metadata.yaml lists no file names;
a ``--scheduler`` that is no Dask scheduler's address (run as a process: no noise on stderr after the exit).
"""
import glob
import math
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
import yaml
from cli_runner import run_cli

from pa10_dnbs.config import ConfigError, load_config
from pa10_dnbs.config_yaml import StrictConfigLoader

REPO = Path(__file__).resolve().parent.parent
DEFAULT = REPO / "config" / "default.yaml"
TINY = ("--duration", "0.02", "--no-figures")


def _one_line_error(r, *words):
    """Exit 2, one error line holding ``words``, no traceback anywhere."""
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    err = r.stderr.strip()
    assert err.startswith("pa10-dnbs: error:") and "\n" not in err, err
    assert "Traceback" not in r.stdout + r.stderr and "Exception ignored" not in r.stderr, r.stderr
    for w in words:
        assert str(w) in err, err


@pytest.fixture(scope="module")
def checkpoints(tmp_path_factory):
    """The checkpoints of a tiny DNBS run with the default config (one <joint>.npz per joint)."""
    run = tmp_path_factory.mktemp("ck") / "run"
    r = run_cli("simulate", "--controller", "dnbs", *TINY, "--out", run)
    assert r.returncode == 0, r.stderr
    return run / "checkpoints"


def _copy(src: Path, dst: Path) -> Path:
    dst.mkdir()
    for f in src.glob("*.npz"):
        (dst / f.name).write_bytes(f.read_bytes())
    return dst


def _warm_start(tmp_path, ck, *extra):
    """simulate and launch with ``--init-from ck``: both must refuse before anything starts."""
    for command in ("simulate", "launch"):
        out = tmp_path / f"out_{command}"
        r = run_cli(command, "--controller", "dnbs", *TINY, "--init-from", ck, "--out", out, *extra)
        yield r
        assert not out.exists()


def test_truncated_checkpoint(tmp_path, checkpoints):
    ck = _copy(checkpoints, tmp_path / "ck")
    f = ck / "s1.npz"
    f.write_bytes(f.read_bytes()[:300])
    for r in _warm_start(tmp_path, ck):
        _one_line_error(r, "--init-from", f, "not a readable checkpoint")


def test_one_joints_checkpoint_file_as_init_from_says_to_give_its_folder(tmp_path, checkpoints):
    """--init-from CK/s1.npz (an existing file) said 'no such checkpoint directory' (review rev_f, 12)."""
    out = tmp_path / "out"
    r = run_cli("simulate", "--controller", "dnbs", *TINY, "--init-from", checkpoints / "s1.npz", "--out", out)
    _one_line_error(r, "--init-from", f"{checkpoints / 's1.npz'}: a file; give the folder", f"({checkpoints} here)")
    assert not out.exists()


def test_a_npy_file_named_npz_is_not_a_checkpoint(tmp_path, checkpoints):
    """np.save's output renamed <joint>.npz: a TypeError traceback (np.load returned an array); now one line."""
    ck = _copy(checkpoints, tmp_path / "ck")
    with open(ck / "s1.npz", "wb") as f:
        np.save(f, np.zeros(3))
    out = tmp_path / "out"
    r = run_cli("simulate", "--controller", "dnbs", *TINY, "--init-from", ck, "--out", out)
    _one_line_error(r, "--init-from", ck / "s1.npz", "not a checkpoint (.npz)", ".npy")
    assert not out.exists()


def test_checkpoint_of_another_network(tmp_path, checkpoints):
    cfg = tmp_path / "degree0.yaml"
    cfg.write_text(f"extends: {DEFAULT}\ndnbs:\n  alpha_net:\n    max_degree: 0\n")
    for r in _warm_start(tmp_path, checkpoints, "--config", cfg):
        _one_line_error(r, "--init-from", checkpoints / "s1.npz", "alpha network", "dnbs.alpha_net", "max_degree 0")


def test_misshaped_checkpoint(tmp_path, checkpoints):
    ck = _copy(checkpoints, tmp_path / "ck")
    state = dict(np.load(ck / "e1.npz"))
    state["torque_P"] = state["torque_P"][:-1]
    np.savez(ck / "e1.npz", **state)
    for r in _warm_start(tmp_path, ck):
        _one_line_error(r, "--init-from", ck / "e1.npz", "torque network")


@pytest.mark.parametrize("key,value", [("alpha_w", np.nan), ("torque_P", np.inf), ("alpha_w0", -np.inf)])
def test_nonfinite_checkpoint(tmp_path, checkpoints, key, value):
    ck = _copy(checkpoints, tmp_path / "ck")
    state = dict(np.load(ck / "s2.npz"))
    state[key] = state[key].copy()
    state[key].flat[0] = value
    np.savez(ck / "s2.npz", **state)
    for r in _warm_start(tmp_path, ck):
        _one_line_error(r, "--init-from", ck / "s2.npz", "not all finite")


@pytest.mark.parametrize("key,change", [("torque_P", "negative"), ("alpha_P", "asymmetric")])
def test_a_covariance_that_is_not_symmetric_positive_definite_is_refused(tmp_path, checkpoints, key, change):
    """Finite, so it was accepted, and the guard reset that network at the first step: the warm start silently
    thrown away (the graph's metrics counted an EKF reset, the in-process run said nothing)."""
    ck = _copy(checkpoints, tmp_path / "ck")
    state = dict(np.load(ck / "s2.npz"))
    P = state[key].copy()
    if change == "negative":
        P = -np.eye(len(P))
    else:
        P[0, 1] += 5.0
    state[key] = P
    np.savez(ck / "s2.npz", **state)
    for r in _warm_start(tmp_path, ck):
        _one_line_error(r, "--init-from", ck / "s2.npz", "covariance is not symmetric positive definite")


def _simulate_with(tmp_path, cfg):
    out = tmp_path / "out"
    r = run_cli("simulate", "--controller", "pid", *TINY, "--config", cfg, "--out", out)
    assert not out.exists()
    return r


def test_binary_config(tmp_path):
    cfg = tmp_path / "binary.yaml"
    cfg.write_bytes(bytes(range(128, 256)) * 4)
    _one_line_error(_simulate_with(tmp_path, cfg), cfg, "not UTF-8")
    child = tmp_path / "child.yaml"
    child.write_text("extends: binary.yaml\n")
    _one_line_error(_simulate_with(tmp_path, child), cfg, "not UTF-8")


def test_extends_missing_file(tmp_path):
    cfg = tmp_path / "child.yaml"
    cfg.write_text("extends: nosuch.yaml\n")
    _one_line_error(_simulate_with(tmp_path, cfg), cfg, "extends: nosuch.yaml", "config file not found")


def test_a_chain_of_extends_too_long_names_the_chain_not_a_file_in_it(tmp_path):
    """1200 files each extending the one before: 'c227.yaml: not valid YAML: nested too deeply' (Python's recursion
    limit, blamed on a valid file; review rev_f, finding 9). 100 files read; more: one line naming the chain."""
    from pa10_dnbs.config import MAX_EXTENDS, default_config_path
    (tmp_path / "c0.yaml").write_text(f"extends: {default_config_path()}\n")
    for i in range(1, 1200):
        (tmp_path / f"c{i}.yaml").write_text(f"extends: c{i - 1}.yaml\n")
    top = tmp_path / "c1199.yaml"
    _one_line_error(_simulate_with(tmp_path, top), f"{top}: extends: a chain of more than {MAX_EXTENDS} files")
    ok = tmp_path / f"c{MAX_EXTENDS - 2}.yaml"   # itself, c0 and the default: MAX_EXTENDS files
    r = run_cli("arm", "--config", ok)
    assert r.returncode == 0, r.stderr


def test_a_config_that_does_not_extend_the_default_names_its_file(tmp_path):
    """It said ``checkpoint: missing key`` without the file: now the file, the key and what to add."""
    cfg = tmp_path / "alone.yaml"
    cfg.write_text("simulation:\n  seed: 3\n")
    _one_line_error(_simulate_with(tmp_path, cfg), f"{cfg}: checkpoint: missing key", "extends:")
    child = tmp_path / "child.yaml"
    child.write_text("extends: alone.yaml\n")   # the file given is named; the message says what it extends
    _one_line_error(_simulate_with(tmp_path, child), f"{child}: checkpoint: missing key", "a file it extends")


def test_invalid_yaml_one_line_with_its_line(tmp_path):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  seed: 3\n  duration_s: [1\n")
    _one_line_error(_simulate_with(tmp_path, cfg), f"{cfg}:", "not valid YAML")
    cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  seed: 3\n   dt_s: 0.001\n")
    _one_line_error(_simulate_with(tmp_path, cfg), f"{cfg}:4", "not valid YAML")


def test_duplicate_key_refused(tmp_path):
    cfg = tmp_path / "dup.yaml"
    cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  seed: 3\nsimulation:\n  duration_s: 2.0\n")
    _one_line_error(_simulate_with(tmp_path, cfg), f"{cfg}:4", "'simulation' given twice", "line 2")
    cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  seed: 3\n  seed: 4\n")
    _one_line_error(_simulate_with(tmp_path, cfg), f"{cfg}:4", "'seed' given twice")


def test_exponent_without_dot_is_a_number(tmp_path):
    for text, value in (("1e-3", 1e-3), ("1E-3", 1e-3), ("2.5e-3", 2.5e-3), ("5e-4", 5e-4), ("1.0e-3", 1e-3)):
        cfg = tmp_path / "exp.yaml"
        cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  dt_s: {text}\n")
        dt = load_config(cfg)["simulation"]["dt_s"]
        assert isinstance(dt, float) and dt == value, (text, dt)
    cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  dt_s: '1e-3'\n")   # quoted: a string, refused
    with pytest.raises(ConfigError):
        load_config(cfg)


def test_sexagesimal_is_not_a_number(tmp_path):
    """YAML 1.1 read ``1:30`` as the integer 90 (base 60) and ``1:30.5`` as 90.5: now a string, refused by the
    key's check (naming the key); an explicit ``!!int 1:30`` is one line naming the file; other numbers as before."""
    from pa10_dnbs.config_yaml import load_strict
    assert load_strict("a: [1:30, -1:30, 190:20:30.15, 1:30: 2]") == {"a": ["1:30", "-1:30", "190:20:30.15",
                                                                               {"1:30": 2}]}
    assert load_strict("a: [1_000, 0x1F, 017, 0b11, -3, 1.5, 1e-3, .inf]") == {
        "a": [1000, 31, 15, 3, -3, 1.5, 1e-3, math.inf]}
    cfg = tmp_path / "sexagesimal.yaml"
    cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  duration_s: 1:30\n")
    _one_line_error(_simulate_with(tmp_path, cfg), "simulation.duration_s", "'1:30'")
    cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  seed: !!int 1:30\n")
    _one_line_error(_simulate_with(tmp_path, cfg), f"{cfg}:3", "base-60")


def _same(a, b) -> bool:
    """Equal, of the same types, floats bit for bit."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float):
        return math.isnan(a) and math.isnan(b) or a.hex() == b.hex()
    return a == b


def test_every_shipped_yaml_reads_as_before():
    """The strict reader gives every YAML file of the repository the values PyYAML's safe_load gives."""
    files = [f for f in glob.glob(str(REPO / "**" / "*.yaml"), recursive=True) if "/.venv/" not in f]
    assert any(f.endswith("config/default.yaml") for f in files)
    for f in files:
        text = Path(f).read_text()
        assert _same(yaml.safe_load(text), yaml.load(text, Loader=StrictConfigLoader)), f


def _bag_with_files(tmp_path, field, value):
    from test_bag_files import _write_bag

    bag = _write_bag(tmp_path / "b")
    meta_path = bag / "metadata.yaml"
    meta = yaml.safe_load(meta_path.read_text())
    meta["rosbag2_bagfile_information"][field] = value
    meta_path.write_text(yaml.safe_dump(meta))
    return bag


@pytest.mark.parametrize("field,value", [("relative_file_paths", [5]), ("relative_file_paths", "b_0.mcap"),
                                         ("relative_file_paths", {"a": 1}), ("message_count", "many"),
                                         ("custom_data", [1, 2])])
def test_bag_metadata_field_of_the_wrong_kind(tmp_path, field, value):
    bag = _bag_with_files(tmp_path, field, value)
    for r in (run_cli("analyse", bag, "--out", tmp_path / "out"), run_cli("replay", bag)):
        _one_line_error(r, "metadata.yaml", field)
    assert not (tmp_path / "out").exists()


def _study_process(tmp_path, scheduler):
    """``pa10-dnbs study --scheduler`` as its own process: what it prints until it has exited."""
    out = tmp_path / "study"
    r = subprocess.run([sys.executable, "-m", "pa10_dnbs.cli", "study", "--scenarios", "nominal", "--controllers",
                        "pid", "--seeds", "1", "--duration", "0.02", "--no-progress", "--scheduler", scheduler,
                        "--out", str(out)], capture_output=True, text=True, timeout=120, cwd=REPO)
    assert not out.exists()
    return r


@pytest.mark.parametrize("address", ["bogus", "", "http://x", "tcp://127.0.0.1", "tcp://127.0.0.1:99999"])
def test_scheduler_address_of_the_wrong_form(tmp_path, address):
    _one_line_error(_study_process(tmp_path, address), "--scheduler", "not the address of a Dask scheduler")


@pytest.fixture
def not_dask_server():
    """A real TCP server on 127.0.0.1 that answers every connection as an HTTP server would, then closes it."""
    srv = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve():
        srv.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = srv.accept()
            except OSError:
                continue
            with conn:
                conn.sendall(b"HTTP/1.0 400 Bad Request\r\nContent-Type: text/html\r\n\r\n<html>bad request</html>")
    t = threading.Thread(target=serve, daemon=True)
    t.start()
    yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    stop.set()
    t.join(5)
    srv.close()


def test_scheduler_that_is_not_dask(tmp_path, not_dask_server):
    _one_line_error(_study_process(tmp_path, not_dask_server), "--scheduler", not_dask_server)


def test_scheduler_refused(tmp_path):
    with socket.create_server(("127.0.0.1", 0)) as s:
        port = s.getsockname()[1]   # a port nobody listens on once closed
    _one_line_error(_study_process(tmp_path, f"tcp://127.0.0.1:{port}"), "--scheduler", "refused")


def test_scheduler_address_of_a_dask_worker(tmp_path):
    """A real Dask worker answers the handshake, but it is not the scheduler: refused, naming what it is."""
    from dask_cluster import local_cluster
    from distributed import Client

    with local_cluster(tmp_path / "cluster", n_workers=1) as cluster:
        with Client(cluster.address, timeout=30) as client:
            worker = next(iter(client.scheduler_info(n_workers=-1)["workers"]))
        _one_line_error(_study_process(tmp_path, worker), "--scheduler", worker, "not a Dask scheduler (a Worker)")


@pytest.mark.parametrize("settings, words", [
    ("  reference:\n    amplitude_rad: -3\n", ("settings.reference.amplitude_rad: must be >= 0",)),
    ("  foo: 1\n", ("settings.foo: unknown key",)),
    ("  arm: pa10\n", ("settings.arm: unknown key",)),
])
def test_a_bad_key_in_an_arm_files_settings_is_named_as_the_arm_files(tmp_path, settings, words):
    """It was said as the config's key (``reference.amplitude_rad: ...``), and ``arm`` was offered as allowed."""
    arm = _arm_file_with(tmp_path, settings)   # the iiwa's file ends in its settings: these lines join them
    r = run_cli("simulate", "--arm", arm, "--controller", "pid", *TINY, "--out", tmp_path / "o")
    _one_line_error(r, f"{arm}: ", *words)
    assert "allowed: arm" not in r.stderr and not (tmp_path / "o").exists()


@pytest.mark.parametrize("value, words", [("null", "arm: empty"), ("''", "arm: expected a non-empty string"),
                                          ("'  '", "arm: empty")])
def test_an_empty_arm_key_says_so(tmp_path, value, words):
    """``arm: null`` said "no arm called 'None'"."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"extends: {DEFAULT}\narm: {value}\n")
    r = run_cli("simulate", "--config", cfg, "--controller", "pid", *TINY, "--out", tmp_path / "o")
    _one_line_error(r, words)


# --- YAML/JSON that parses but Python cannot hold; the one strict reader for configs, arm files, trajectories ---

BIG_INT = "1" * 5000              # past Python's 4300-digit limit on int(str): ValueError in the constructor
DEEP = "[" * 50_000 + "]" * 50_000  # past the recursion limit of PyYAML's composer (and of json.loads)


def _arm_file_with(tmp_path, line: str) -> Path:
    """The iiwa's arm file (its URDF by absolute path) with ``line`` appended (its last key is ``settings``)."""
    text = (REPO / "urdf" / "iiwa" / "arm.yaml").read_text()
    text = text.replace("urdf: iiwa14.urdf", f"urdf: {REPO / 'urdf' / 'iiwa' / 'iiwa14.urdf'}")
    path = tmp_path / "arm.yaml"
    path.write_text(text + line)
    return path


@pytest.mark.parametrize("value, words", [(BIG_INT, "4300"), (DEEP, "nested too deeply")], ids=["big_int", "deep"])
def test_unusable_yaml_is_one_line_naming_the_file(tmp_path, value, words):
    """A 5000-digit integer or 50k-deep nesting was a traceback (ValueError, RecursionError) in each reader."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"extends: {DEFAULT}\nsimulation:\n  seed: {value}\n")
    _one_line_error(_simulate_with(tmp_path, cfg), cfg, words)
    _one_line_error(run_cli("arm", "--config", cfg), cfg, words)
    from test_bag_files import _write_run_bag
    bag = _write_run_bag(tmp_path / "b", n=3)
    _one_line_error(run_cli("analyse", bag, "--config", cfg, "--out", tmp_path / "o"), cfg, words)
    arm = _arm_file_with(tmp_path, f"extra: {value}\n")
    _one_line_error(run_cli("simulate", "--arm", arm, "--controller", "pid", *TINY, "--out", tmp_path / "o"),
                    arm, words)
    traj = tmp_path / "t.yaml"
    traj.write_text(f"joint_names: {value}\npoints: []\n")
    _one_line_error(run_cli("simulate", "--trajectory", traj, "--controller", "pid", *TINY, "--out", tmp_path / "o"),
                    "trajectory", traj, words)
    assert not (tmp_path / "o").exists()


def test_a_json_trajectory_from_json_dump_reads(tmp_path):
    """json.dump writes 1e-05 and 1e+300 (no dot): plain safe_load read them as strings and refused the file."""
    import json
    from pa10_dnbs.arm import load_arm
    from pa10_dnbs.trajectory_file import load_trajectory_file, read_trajectory
    arm = load_arm("pa10")
    f = tmp_path / "t.json"
    points = [{"time_from_start": 1e-05, "positions": [0.0] * 7}, {"time_from_start": 2.0, "positions": [0.1] * 7}]
    f.write_text(json.dumps({"joint_names": list(arm.joint_names), "points": points}))
    assert "1e-05" in f.read_text()
    assert load_trajectory_file(f, arm).time_from_start_s.tolist() == [1e-05, 2.0]
    points[1]["time_from_start"] = 1e+300
    f.write_text(json.dumps({"joint_names": list(arm.joint_names), "points": points}))
    assert read_trajectory(f).time_from_start_s.tolist() == [1e-05, 1e300]
    with pytest.raises(ConfigError) as err:   # a number now, refused as too far, not as "got '1e+300'"
        load_trajectory_file(f, arm)
    assert "'1e+300'" not in str(err.value), err.value
    f.write_text('{"joint_names": ["s1"], "joint_names": ["s2"], "points": []}')
    with pytest.raises(ConfigError, match="'joint_names' given twice"):
        load_trajectory_file(f, arm)


def test_an_arm_file_is_read_strictly(tmp_path):
    """rotor_inertia_kgm2: [1e-3, ...] was refused ("got '1e-3'"); a key given twice passed silently."""
    from pa10_dnbs.arm.arm_file import _load
    arm = _arm_file_with(tmp_path, "")
    arm.write_text(arm.read_text().replace("rotor_inertia_kgm2: [3.38176, 3.38176,", "rotor_inertia_kgm2: [1e-3, 2e-3,"))
    assert _load(str(arm)).rotor_inertia_kgm2[:2].tolist() == [1e-3, 2e-3]
    dup = arm.rename(tmp_path / "dup.yaml")
    dup.write_text(dup.read_text() + "description: twice\n")
    r = run_cli("simulate", "--arm", dup, "--controller", "pid", *TINY, "--out", tmp_path / "o")
    _one_line_error(r, dup, "'description' given twice")


def test_two_merge_keys_in_one_mapping_are_a_duplicate(tmp_path):
    cfg = tmp_path / "merge.yaml"
    cfg.write_text(f"extends: {DEFAULT}\na: &a {{seed: 1}}\nb: &b {{seed: 2}}\nsimulation:\n  <<: *a\n  <<: *b\n")
    _one_line_error(_simulate_with(tmp_path, cfg), f"{cfg}:6", "'<<' given twice")


@pytest.mark.parametrize("key, value, words", [
    ("step", np.array([1, 2]), "step is not a whole number"), ("step", np.array(np.inf), "step is not a whole"),
    ("step", np.array("x"), "step is not a whole"), ("step", np.array(np.nan), "step is not a whole"),
    ("joint", np.array(1j), "joint index is not a whole"), ("joint", np.array(np.inf), "joint index is not"),
    ("joint", np.array("s1"), "joint index is not a whole")])
def test_checkpoint_step_or_joint_not_a_whole_number(tmp_path, checkpoints, key, value, words):
    """A vector or inf step, a complex or inf joint were tracebacks; a string or NaN did not name the file."""
    ck = _copy(checkpoints, tmp_path / "ck")
    state = dict(np.load(ck / "s1.npz"))
    state[key] = value
    np.savez(ck / "s1.npz", **state)
    for r in _warm_start(tmp_path, ck):
        _one_line_error(r, "--init-from", ck / "s1.npz", words)


@pytest.mark.parametrize("n", [0, 1])
def test_a_bag_with_too_few_joint_states(tmp_path, n):
    """1 or 2 joint states: the metrics' window held no sample (a ValueError traceback)."""
    from test_bag_files import _write_run_bag
    bag = _write_run_bag(tmp_path / "b", n=n)
    r = run_cli("analyse", bag, "--out", tmp_path / "o")
    _one_line_error(r, bag, f"the bag holds {n + 1} joint state", "at least 3 joint states")
    assert not (tmp_path / "o").exists()


def test_a_bag_stamped_by_a_wall_clock(tmp_path):
    """Stamps near 2^31 s imply ~2e12 steps: numpy's MemoryError (109 TiB) was a traceback."""
    from rosbags.typesys import Stores, get_typestore
    from test_bag_files import QOS, _write_run_bag
    from pa10_dnbs.bag.bag_reader import Bag
    from pa10_dnbs.bag.bag_writer import BagWriter
    from pa10_dnbs.wire import joint_state_cdr
    ok = _write_run_bag(tmp_path / "ok", n=3)
    store = get_typestore(Stores.ROS2_JAZZY)
    bag = tmp_path / "wall"
    w = BagWriter(bag)
    with Bag(ok) as src:
        for name, topic in src.topics.items():
            w.add_topic(name, topic.msgtype, [QOS])
        for name, _, t, data in src.messages():
            if name.endswith("joint_states"):
                sec, nanosec, jn, pos, vel, eff = joint_state_cdr.decode(bytes(data))
                data = joint_state_cdr.encode(2**31 - 10, nanosec, list(jn), pos, vel, eff)
            w.write(name, t, bytes(data))
    w.close()
    r = run_cli("analyse", bag, "--out", tmp_path / "o")
    _one_line_error(r, bag, "4 joint states", "wall clock")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("value", [BIG_INT, DEEP], ids=["big_int", "deep"])
def test_a_bags_stored_config_that_json_cannot_hold(tmp_path, value):
    from test_bag_files import _write_run_bag
    bag = _write_run_bag(tmp_path / "b", n=3, custom_data={"pa10_dnbs.config": f'{{"x": {value}}}'})
    _one_line_error(run_cli("analyse", bag, "--out", tmp_path / "o"), bag, "pa10_dnbs.config", "not valid JSON")


def test_every_shipped_arm_trajectory_and_docs_yaml_reads_as_before():
    """The one strict reader (config_yaml.read_yaml, now also behind the arm files and trajectories) gives every
    YAML file of the repository (urdf/*/arm.yaml, config/trajectory_example.yaml, ...) and every ```yaml block of
    the docs that PyYAML reads the values safe_load gives; the shipped arms and the example trajectory load."""
    import re
    from pa10_dnbs.arm import load_arm
    from pa10_dnbs.arm.arm_file import preset_names
    from pa10_dnbs.config_yaml import read_yaml
    from pa10_dnbs.trajectory_file import read_trajectory
    files = [Path(f) for f in glob.glob(str(REPO / "**" / "*.yaml"), recursive=True) if "/.venv/" not in f]
    assert {"arm.yaml", "trajectory_example.yaml"} <= {f.name for f in files}
    for f in files:
        assert _same(yaml.safe_load(f.read_text()), read_yaml(f)), f
    blocks = 0
    for md in [REPO / "README.md", *REPO.glob("docs/**/*.md")]:
        for block in re.findall(r"```ya?ml\n(.*?)```", md.read_text(), flags=re.S):
            try:
                before = yaml.safe_load(block)
            except yaml.YAMLError:
                continue
            blocks += 1
            assert _same(before, yaml.load(block, Loader=StrictConfigLoader)), (md, block)
    assert blocks > 0
    for name in preset_names():
        assert load_arm(name).joint_names, name
    assert len(read_trajectory(REPO / "config" / "trajectory_example.yaml").time_from_start_s) == 5


def test_init_from_the_output_of_a_run_of_several_controllers_finds_its_dnbs_checkpoints(tmp_path):
    """``simulate --controller all`` keeps DNBS's checkpoints in DIR/dnbs/checkpoints; ``--init-from DIR`` (its
    output directory, as --help and docs/controller.md say) warm-starts from them (was: "DIR/s1.npz: missing")."""
    run = tmp_path / "all"
    assert run_cli("simulate", "--controller", "both", *TINY, "--out", run).returncode == 0
    r = run_cli("simulate", "--controller", "dnbs", *TINY, "--init-from", run, "--out", tmp_path / "warm")
    assert r.returncode == 0, r.stderr
    report = (tmp_path / "warm" / "report.md").read_text()
    assert "DNBS warm-started from the checkpoints in" in report and str(run) in report


@pytest.mark.parametrize("kind, words", [("long", "File name too long"), ("loop", "a loop of symbolic links"),
                                         ("folder", "a folder, not a file"),
                                         ("fifo", "not a regular file (a pipe or a device)")])
def test_a_config_path_the_os_refuses_is_one_line(tmp_path, kind, words):
    """A name too long for the OS (it was exit 1, the flag unnamed), a loop of symbolic links (a RuntimeError
    traceback), a folder, or a pipe (bash's ``--config <(...)``: was "config file not found: /proc/N/fd/pipe:[M]"):
    one line naming the file, exit 2, for --config and for a config's extends; said as --arm says it."""
    if kind == "fifo":
        bad = tmp_path / "fifo"
        os.mkfifo(bad)
    elif kind == "long":
        bad = tmp_path / ("x" * 300 + ".yaml")
    elif kind == "loop":
        (tmp_path / "a").symlink_to(tmp_path / "b")
        (tmp_path / "b").symlink_to(tmp_path / "a")
        bad = tmp_path / "a"
    else:
        bad = tmp_path
    _one_line_error(run_cli("arm", "--config", bad), "config file", words)
    cfg = tmp_path / "extends.yaml"
    cfg.write_text(f"extends: {bad}\n")
    _one_line_error(run_cli("arm", "--config", cfg), f"{cfg}: extends: ", words)


def test_init_from_a_name_too_long_for_the_os_is_one_line(tmp_path):
    """ENAMETOOLONG from the checkpoint folder's look-up was exit 1, the flag unnamed."""
    _one_line_error(run_cli("simulate", "--controller", "dnbs", *TINY, "--init-from", tmp_path / ("x" * 300),
                            "--out", tmp_path / "out"), "--init-from", "File name too long")
    assert not (tmp_path / "out").exists()
