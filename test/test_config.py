"""Config validation: every bad value is rejected with the key named."""
import copy
import dataclasses
import math
from pathlib import Path

import pytest
import yaml
from cli_runner import run_cli

from pa10_dnbs.config import ConfigError, default_config_path, load_config
from pa10_dnbs.run_settings import build_settings


def _write(tmp_path, raw):
    p = tmp_path / "c.yaml"
    p.write_text(yaml.safe_dump(raw))
    return p


@pytest.fixture
def raw():
    return yaml.safe_load(default_config_path().read_text())


def test_default_config_is_valid():
    cfg = build_settings(default_config_path())
    assert cfg.simulation.dt_s == 0.001
    assert len(cfg.dnbs.torque_net.eta) == 7


@pytest.mark.parametrize("kernel", ["auto", "numpy", "c"])
def test_every_dnbs_kernel_setting_loads_and_auto_is_the_default(tmp_path, raw, kernel):
    assert build_settings(default_config_path()).dnbs.kernel == "auto"
    d = copy.deepcopy(raw)
    d["dnbs"]["kernel"] = kernel
    assert build_settings(_write(tmp_path, d)).dnbs.kernel == kernel


@pytest.mark.parametrize("path,value,match", [
    (("dnbs", "torque_net", "eta"), -1.0, r"dnbs\.torque_net\.eta: must be > 0"),
    (("dnbs", "alpha_net", "p0"), 0, r"dnbs\.alpha_net\.p0: must be > 0"),
    (("simulation", "dt_s"), float("nan"), r"simulation\.dt_s: must be finite"),
    (("plant", "torque_limit_nm"), [232, 232, 100, 100, 14.5, 14.5, math.inf], r"plant\.torque_limit_nm\[6\]: must be finite"),
    (("plant", "viscous_nms_per_rad"), "ten", r"plant\.viscous_nms_per_rad: expected a number"),
    (("simulation", "seed"), 1.5, r"simulation\.seed: expected an integer"),
    (("dnbs", "remedies", "anti_windup", "enabled"), "yes", r"dnbs\.remedies\.anti_windup\.enabled: expected true"),
    (("dnbs", "torque_net", "eta"), 3.0, r"dnbs\.torque_net\.eta: must be <= 1"),
    (("dnbs", "e2_sign"), "minus", r"dnbs\.e2_sign: must be one of stable, printed"),
    (("dnbs", "kernel"), "fast", r"dnbs\.kernel: must be one of auto, numpy, c"),
    (("dnbs", "kernel"), "C", r"dnbs\.kernel: must be one of auto, numpy, c"),
    (("metrics", "settle_band_rad"), 0.0, r"metrics\.settle_band_rad: must be > 0"),
    (("plant", "payload_kg"), -1.0, r"plant\.payload_kg: must be >= 0"),
    (("pid", "kp"), [1, 2, 3], r"pid\.kp: expected 7 values"),
    (("simulation", "window_s"), [5.0, 2.0], r"simulation\.window_s: t1 must be greater"),
    (("simulation", "duration_s"), 5.0, r"simulation\.window_s: ends at 20 s, after simulation\.duration_s"),
    (("simulation", "initial_velocity_rad_s"), True, r"simulation\.initial_velocity_rad_s: expected a number"),
    (("faults", "state", "drop_fraction"), 1.0, r"faults\.state\.drop_fraction: must be < 1"),  # nothing arrives
])
def test_bad_values_name_the_key(tmp_path, raw, path, value, match):
    d = copy.deepcopy(raw)
    node = d
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    with pytest.raises(ConfigError, match=match):
        build_settings(_write(tmp_path, d))


def test_unknown_and_missing_keys(tmp_path, raw):
    d = copy.deepcopy(raw)
    d["dnbs"]["torque_net"]["etta"] = 1.0
    with pytest.raises(ConfigError, match=r"dnbs\.torque_net\.etta: unknown key"):
        build_settings(_write(tmp_path, d))
    d = copy.deepcopy(raw)
    del d["plant"]["gravity_mps2"]
    with pytest.raises(ConfigError, match=r"plant\.gravity_mps2: missing key"):
        build_settings(_write(tmp_path, d))


def test_missing_arm_and_missing_file(tmp_path, raw):
    d = copy.deepcopy(raw)
    d["arm"] = "nowhere/arm.yaml"
    with pytest.raises(ConfigError, match=r"arm: file not found: .*nowhere/arm\.yaml"):
        build_settings(_write(tmp_path, d))
    d["arm"] = "no_such_arm"
    with pytest.raises(ConfigError, match=r"arm: no arm called 'no_such_arm' \(presets: .*pa10"):
        build_settings(_write(tmp_path, d))
    with pytest.raises(ConfigError, match="config file not found"):
        build_settings(tmp_path / "absent.yaml")


def test_not_yaml(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("simulation: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        build_settings(p)


def test_extends_merges_over_the_base_and_resolves_paths_where_they_are_written(tmp_path):
    (tmp_path / "sub").mkdir()
    p = tmp_path / "sub" / "mine.yaml"
    p.write_text(f"extends: {default_config_path()}\nsimulation:\n  seed: 11\ndnbs:\n  remedies:\n"
                 "    robust_term: {enabled: false}\n")
    cfg = build_settings(p)
    base = build_settings(default_config_path())
    assert cfg.simulation.seed == 11 and cfg.simulation.dt_s == base.simulation.dt_s
    assert cfg.dnbs.remedies.robust_term.enabled is False
    assert cfg.dnbs.remedies.robust_term.alpha_gain_per_s == base.dnbs.remedies.robust_term.alpha_gain_per_s
    assert cfg.arm == base.arm


def test_extends_errors(tmp_path):
    a, b = tmp_path / "a.yaml", tmp_path / "b.yaml"
    a.write_text("extends: b.yaml\n")
    b.write_text("extends: a.yaml\n")
    with pytest.raises(ConfigError, match="circular"):
        build_settings(a)
    a.write_text("extends: nowhere.yaml\n")
    with pytest.raises(ConfigError, match=r"a.yaml: extends: nowhere.yaml: config file not found: .*nowhere.yaml$"):
        build_settings(a)


def test_shipped_presets_are_valid():
    from pa10_dnbs.paths import share_path

    assert build_settings(share_path("config", "compiled.yaml")).dnbs.kernel == "c"
    paper = build_settings(share_path("config", "paper.yaml"))
    on = [f.name for f in dataclasses.fields(paper.dnbs.remedies) if getattr(paper.dnbs.remedies, f.name).enabled]
    assert on == ["anti_windup"]  # the paper's law as the project first ran it


def test_a_configs_arm_path_is_relative_to_it_and_a_symlink_loop_is_one_line(tmp_path):
    """``arm: robot.xml`` (a URDF by its XML root) is taken relative to the config; ``arm:`` naming a loop of
    symbolic links was a RuntimeError traceback from resolving it."""
    repo = Path(__file__).resolve().parent.parent
    (tmp_path / "robot.xml").write_text((repo / "urdf" / "pa10" / "pa10_7ce.urdf").read_text())
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"extends: {default_config_path()}\narm: robot.xml\n")
    assert load_config(cfg)["arm"] == str(tmp_path / "robot.xml")
    (tmp_path / "a").symlink_to(tmp_path / "b")
    (tmp_path / "b").symlink_to(tmp_path / "a")
    cfg.write_text(f"extends: {default_config_path()}\narm: ./a\n")
    r = run_cli("arm", "--config", cfg)
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip() == f"pa10-dnbs: error: arm: {tmp_path / 'a'}: a loop of symbolic links", r.stderr


@pytest.mark.parametrize("text, said", [
    ("1: 2\nfoo: 3\n", "foo: unknown key"),
    ("~: 1\nfoo: 2\n", "foo: unknown key"),
    ("1: 2\n", "1 (a number, not a name): unknown key"),
    ("simulation: {1: 2, a: 3}\n", "simulation.a: unknown key"),
    ("simulation: {~: 2}\n", "simulation.null (not a name): unknown key"),
])
def test_a_key_that_is_not_a_name_is_one_line(tmp_path, text, said):
    """Keys of mixed types (YAML reads ``1:`` as a number, ``~:`` as null) were a TypeError traceback from sorting
    them to name the first unknown one; a key that is not a name is named so."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(text)
    r = run_cli("arm", "--config", cfg)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
    assert r.stderr.startswith(f"pa10-dnbs: error: {said} (allowed: "), r.stderr


@pytest.mark.parametrize("key", ["seed", "duration_s"])
def test_a_whole_number_too_large_for_a_float_is_one_line(tmp_path, key):
    """``seed: <401 digits>`` was an OverflowError traceback (math.isfinite of an int past the largest float)."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"extends: {default_config_path()}\nsimulation:\n  {key}: {'9' * 401}\n")
    r = run_cli("arm", "--config", cfg)
    assert r.returncode == 2 and r.stderr == (f"pa10-dnbs: error: simulation.{key}: a whole number of 401 digits is "
                                              f"too large (at most ~1.8e308)\n"), r.stderr


ALIAS_BOMB_WORDS = "refused: its aliases (*name) expand it to 1.23e+07 nodes"


def test_a_yaml_alias_bomb_is_refused_before_it_is_built(tmp_path):
    """Nine levels of anchors, each ten aliases of the one below, were a 600-byte config whose error message
    (``simulation.window_s: expected [t0, t1], got <repr>``) took all memory; now one line naming the file."""
    from yaml_bomb import alias_bomb
    cfg = tmp_path / "c.yaml"
    cfg.write_text("simulation:\n  window_s:\n" + alias_bomb(indent="    "))
    r = run_cli("arm", "--config", cfg)
    assert r.returncode == 2 and len(r.stderr) < 300, r.stderr[:300]
    assert r.stderr.startswith(f"pa10-dnbs: error: {cfg}: {ALIAS_BOMB_WORDS}"), r.stderr[:300]


def test_ordinary_anchors_and_aliases_still_read(tmp_path):
    """A merge key (``<<: *base``) and aliases of lists read as before; a document holding itself counts once."""
    from pa10_dnbs.config_yaml import StrictConfigLoader, expanded_nodes, load_strict
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"extends: {default_config_path()}\nsimulation:\n  window_s: &w [1.0, 2.0]\n"
                   "pid: {kp: &g [1, 2, 3, 4, 5, 6, 7], kd: *g}\n")
    raw = load_config(cfg)
    assert raw["simulation"]["window_s"] == [1.0, 2.0] and raw["pid"]["kd"] == [1, 2, 3, 4, 5, 6, 7]
    assert load_strict("base: &b {x: 1}\nover: {<<: *b, y: 2}\n")["over"] == {"x": 1, "y": 2}
    node = yaml.compose("a: &a [1, 2]\nb: [*a, *a]\n", Loader=StrictConfigLoader)
    assert expanded_nodes(node) == (13, 7)   # (with the aliases expanded, written): each alias of a is 3 nodes
    cyclic = load_strict("a: &a [*a]\n")
    assert cyclic["a"][0] is cyclic["a"]


def test_a_long_value_in_a_message_is_cut_to_one_readable_line(tmp_path):
    """``{value!r}`` showed a value whole (a list of 10000 numbers: 60 kB on one line); now its first 80 characters."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"extends: {default_config_path()}\nsimulation:\n  window_s: {list(range(10000))}\n")
    r = run_cli("arm", "--config", cfg)
    assert r.returncode == 2 and r.stderr.startswith("pa10-dnbs: error: simulation.window_s: expected [t0, t1], got "
                                                     "[0, 1, 2, 3,"), r.stderr[:300]
    assert r.stderr.endswith("...\n") and len(r.stderr) < 200, r.stderr[:300]


@pytest.mark.parametrize("dt", ["1.0e-300", "0", "9.0e-6"])
def test_a_step_too_short_names_dt_s_not_the_duration(tmp_path, dt):
    """``dt_s: 1e-300`` with ``--duration 0.3`` blamed "simulation.duration_s: 20 s is 2e+301 steps ..."; the step
    is what is absurd: below 10 us (a 100 kHz loop) it is refused by its own key."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"extends: {default_config_path()}\nsimulation:\n  dt_s: {dt}\n")
    r = run_cli("simulate", "--config", cfg, "--duration", "0.3", "--out", tmp_path / "o")
    assert r.returncode == 2 and r.stderr.startswith("pa10-dnbs: error: simulation.dt_s: must be >= 1e-05, got "), \
        r.stderr
    assert len(r.stderr.splitlines()) == 1 and not (tmp_path / "o").exists()


def test_a_step_of_10_us_is_accepted(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"extends: {default_config_path()}\nsimulation:\n  dt_s: 1.0e-5\n")
    assert build_settings(cfg).simulation.dt_s == 1e-5


def test_an_empty_section_is_said_as_empty_not_as_a_python_type(tmp_path):
    """``simulation:`` with nothing under it was "expected a mapping, got NoneType"."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("simulation:\n")
    r = run_cli("arm", "--config", cfg)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
    assert r.stderr.strip() == "pa10-dnbs: error: simulation: expected a mapping, got nothing (an empty section)"
