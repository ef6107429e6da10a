"""A run's typed settings (pa10_dnbs/settings.py, run_settings.py): built once, frozen, checked when made and
again when changed; a config file alone is parsed and checked without reading the arm or running a rule."""
import dataclasses
import pickle

import pytest

from pa10_dnbs.config import ConfigError, default_config_path, load_config
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.settings import PlantSettings, Settings, replace_in


def test_a_change_is_checked_again_and_names_the_key(cfg):
    changed = replace_in(cfg, "plant.payload_kg", 2)
    assert changed.plant.payload_kg == 2.0 and type(changed.plant.payload_kg) is float  # as a config file gives it
    assert cfg.plant.payload_kg == 0.0  # the original is untouched
    with pytest.raises(ConfigError, match=r"^plant\.payload_kg: must be >= 0, got -1\.0$"):
        replace_in(cfg, "plant.payload_kg", -1.0)
    with pytest.raises(ConfigError, match=r"^pid\.kp: expected 7 values \(one per joint of the arm\), got 2$"):
        replace_in(cfg, "pid.kp", (1.0, 2.0))
    with pytest.raises(ConfigError, match=r"^faults\.effort\.drop_fraction\[2\]: must be < 1, got 2\.0$"):
        replace_in(cfg, "faults.effort.drop_fraction", (0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ConfigError, match=r"^dnbs\.remedies\.projection\.weight_bound: must be > 0"):
        replace_in(cfg, "dnbs.remedies.projection.weight_bound", 0.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.plant.payload_kg = 3.0


def test_a_section_alone_is_checked_when_it_is_made(cfg):
    fields = dataclasses.asdict(cfg.plant)
    with pytest.raises(ConfigError, match=r"^plant\.gravity_mps2: must be finite"):
        PlantSettings(**dict(fields, gravity_mps2=float("nan")))


def test_the_config_mapping_round_trips(cfg):
    assert Settings.of(cfg.to_config(), cfg.arm) == cfg
    assert cfg.to_config()["arm"] == str(cfg.arm.file)


def test_load_config_only_parses_and_checks_what_the_file_gives(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_text(f"extends: {default_config_path()}\narm: no_such_arm\n")
    assert load_config(p)["arm"] == "no_such_arm"  # no arm file read here: that is the next step's
    with pytest.raises(ConfigError, match="no_such_arm"):
        build_settings(p)
    p.write_text("simulation: {dt_s: -1}\n")
    with pytest.raises(ConfigError, match=r"^simulation\.dt_s: must be >= 1e-05, got -1$"):
        load_config(p)
    p.write_text("plant: {payload: 1}\n")
    with pytest.raises(ConfigError, match=r"^plant\.payload: unknown key"):
        load_config(p)


def test_settings_travel_to_a_worker_as_the_arm_file(cfg):
    data = pickle.dumps(cfg)
    assert len(data) < 20_000  # no URDF chain in it
    assert pickle.loads(data).arm is cfg.arm  # one Arm per file per process


def test_the_arm_stays_one_object_however_many_arms_the_process_read(cfg, tmp_path):
    """The cache held 16 files: a process that had read 16 others (the test suite did) got a second PA10 Arm
    from a pickle, and `is` failed in test_settings_travel_to_a_worker_as_the_arm_file."""
    from chain_urdf import chain_urdf
    from pa10_dnbs.arm import load_arm

    for k in range(20):
        (tmp_path / f"a{k}.urdf").write_text(chain_urdf(2, name=f"a{k}"))
        load_arm(tmp_path / f"a{k}.urdf")
    assert pickle.loads(pickle.dumps(cfg)).arm is cfg.arm
