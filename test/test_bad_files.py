"""Bad files and addresses a user can give: one line naming the flag, key or file, exit 2, nothing written.

Warm-start checkpoints (``--init-from``) that are truncated, of another network or not finite; config files that
are not text, not YAML, give a key twice or extend a missing file; a bag whose metadata.yaml lists no file names;
a ``--scheduler`` that is no Dask scheduler's address (run as a process: no noise on stderr after the exit).
"""
import glob
import math
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
    _one_line_error(_simulate_with(tmp_path, cfg), cfg, "extends: nosuch.yaml", "no such config file")


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


def _iiwa_arm_file(tmp_path, settings: str) -> Path:
    """The iiwa's arm file (its URDF by absolute path) with ``settings`` lines appended under its settings."""
    text = (REPO / "urdf" / "iiwa" / "arm.yaml").read_text()
    text = text.replace("urdf: iiwa14.urdf", f"urdf: {REPO / 'urdf' / 'iiwa' / 'iiwa14.urdf'}")
    path = tmp_path / "arm.yaml"
    path.write_text(text + settings)
    return path


@pytest.mark.parametrize("settings, words", [
    ("  reference:\n    amplitude_rad: -3\n", ("settings.reference.amplitude_rad: must be >= 0",)),
    ("  foo: 1\n", ("settings.foo: unknown key",)),
    ("  arm: pa10\n", ("settings.arm: unknown key",)),
])
def test_a_bad_key_in_an_arm_files_settings_is_named_as_the_arm_files(tmp_path, settings, words):
    """It was said as the config's key (``reference.amplitude_rad: ...``), and ``arm`` was offered as allowed."""
    arm = _iiwa_arm_file(tmp_path, settings)
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
