"""A run's settings as ROS parameters (ros/settings_params.py) and the run's params file (supervisor/params_file.py):
every node's sections, values that come back bit for bit, and the launcher's arguments (no ROS started)."""
from pathlib import Path

import pytest
import yaml

from pa10_dnbs.config_error import ConfigError
from pa10_dnbs.supervisor.graph_options import GraphOptions
from pa10_dnbs.supervisor.node_specs import node_commands
from pa10_dnbs.supervisor.params_file import params_document, params_yaml
from pa10_dnbs.ros.settings_params import (ARM_FILE, NODE_SECTIONS, NodeSettings, node_settings, section_params,
                                           section_values)
from pa10_dnbs.settings import Settings, replace_in

JOINTS = ("s1", "s2", "s3", "e1", "e2", "w1", "w2")


def test_values_give_back_the_same_typed_sections(cfg):
    for node, sections in NODE_SECTIONS.items():
        values = section_values(cfg, sections)
        built = node_settings(cfg.arm, values, sections)
        assert section_values(built, sections) == values, node
        for name in sections:
            assert getattr(built, name) == getattr(cfg, name), (node, name)
    assert isinstance(node_settings(cfg.arm, section_values(cfg, NODE_SECTIONS["recorder"]),
                                    NODE_SECTIONS["recorder"]), Settings)  # every section: the whole settings


def test_a_node_runs_only_the_sections_it_declares(cfg):
    ref = node_settings(cfg.arm, section_values(cfg, NODE_SECTIONS["reference"]), NODE_SECTIONS["reference"])
    assert isinstance(ref, NodeSettings) and ref.reference == cfg.reference
    with pytest.raises(AttributeError, match="no plant section"):
        ref.plant


def test_a_bad_value_is_refused_naming_its_key(cfg):
    sections = NODE_SECTIONS["plant"]
    values = section_values(cfg, sections)
    with pytest.raises(ConfigError, match=r"plant.torque_limit_nm\[0\]: must be > 0"):
        node_settings(cfg.arm, {**values, "plant.torque_limit_nm": [0.0] + values["plant.torque_limit_nm"][1:]},
                      sections)
    with pytest.raises(ConfigError, match="plant.rotor_inertia_kgm2: expected 7 values"):
        node_settings(cfg.arm, {**values, "plant.rotor_inertia_kgm2": [0.1, 0.2]}, sections)
    with pytest.raises(ConfigError, match="simulation.window_s"):
        node_settings(cfg.arm, {**values, "simulation.window_s": [0.0, 99.0]}, sections)


def test_every_parameter_has_a_unit_and_the_keys_range():
    params = section_params(("simulation", "reference", "plant", "faults", "dnbs", "pid"))
    assert params["plant.torque_limit_nm"].description.endswith("[N m]; > 0") and params["plant.torque_limit_nm"].lo == 0
    assert "[m/s^2]" in params["plant.gravity_mps2"].description
    assert "[N m s/rad]" in params["plant.viscous_nms_per_rad"].description
    assert "[kg m^2]" in params["plant.rotor_inertia_kgm2"].description
    assert "[rad/s]" in params["reference.frequency_rad_s"].description
    assert (params["simulation.dt_s"].lo, params["simulation.dt_s"].hi) == (1e-5, 0.1)
    assert (params["reference.preview_steps"].lo, params["reference.preview_steps"].hi) == (0, 100)
    assert "[N m/rad]" in params["pid.kp"].description
    assert "one of nan, inf, out_of_range" in params["faults.state.corrupt_kind"].description


def test_the_params_file_gives_back_every_value_bit_for_bit(cfg):
    """17 significant digits survive the YAML text; strings are quoted (ROS would read a bare nan as a double)."""
    odd = tuple(0.1 + 0.2 * k / 3.0 for k in range(7))  # repr needs 17 digits for most of them
    settings = replace_in(cfg, "simulation.initial_position_offset_rad", odd)
    text = params_yaml(params_document(settings, "dnbs", "/pa10"))
    doc = yaml.safe_load(text)
    plant = doc["/pa10/plant"]["ros__parameters"]
    assert tuple(plant["simulation"]["initial_position_offset_rad"]) == odd
    assert [v.hex() for v in plant["simulation"]["initial_position_offset_rad"]] == [v.hex() for v in odd]
    assert plant[ARM_FILE] == str(cfg.arm.file)
    assert "corrupt_kind: 'nan'" in text and "arm_file: '" in text
    assert set(doc) == {f"/pa10/joint_controller_{j}" for j in JOINTS} | {f"/pa10/{n}" for n in NODE_SECTIONS}
    assert doc["/pa10/joint_controller_s1"]["ros__parameters"]["plant"]["torque_limit_nm"] == 232.0


def test_with_a_params_file_the_nodes_get_it_and_the_runs_config_for_what_it_lacks(tmp_path):
    used = tmp_path / "config_used.yaml"
    opt = GraphOptions(config_path=used, joint_names=JOINTS, live_port=0,
                       params_file=tmp_path / "ros_params.yaml", record_bag=tmp_path / "bag")
    cmds = dict(node_commands(opt, tmp_path / "stats.json", tmp_path / "wire.npz"))
    assert set(cmds) == {"recorder", "live_view", "reference", "plant"} | {f"joint_controller_{j}" for j in JOINTS}
    for name, argv in cmds.items():
        assert argv[-2:] == ["--params-file", str(tmp_path / "ros_params.yaml")], name
        # read only for a key the params file lacks: the run's own config, never the shipped default
        assert f'config_file:="{used}"' in argv, (name, argv)
    without = dict(node_commands(GraphOptions(config_path=Path("config/default.yaml"), joint_names=JOINTS),
                                 tmp_path / "stats.json", tmp_path / "wire.npz"))
    assert 'config_file:="config/default.yaml"' in without["plant"] and "--params-file" not in without["plant"]
    assert 'config_file:="config/default.yaml"' in without["joint_controller_s1"]


@pytest.mark.parametrize("odd", ["it's run", "a #b", "c: d", "[e]", "ü f"])
def test_every_path_a_node_gets_reads_back_as_that_path(tmp_path, odd):
    """rcl reads a -p value as YAML: an --out holding "'" broke the recorder's custom_data list (the graph had
    started: exit 1, a .failed folder), " #" cut config_file and stats_file short (the plant wrote its stats to a
    stray file '.a' in the working folder), ": " made a mapping of them. Each value now reads back as given."""
    import yaml

    from pa10_dnbs.ros.param_overrides import bad_param_override, param_rules

    run = tmp_path / odd
    opt = GraphOptions(config_path=run / "config_used.yaml", joint_names=JOINTS, live_port=0,
                       record_bag=tmp_path / f"bag {odd}", trajectory_file=run / "t.yaml", init_from=run / "init")
    for name, argv in node_commands(opt, run / "stats.json", run / "wire.npz"):
        assert bad_param_override(argv) is None, (name, argv)
        values = {k: yaml.safe_load(v) for k, _, v in (rule.partition(":=") for _, rule in param_rules(argv))}
        for key, value in values.items():
            if key.endswith("_file") or key in ("bag",):
                assert isinstance(value, str) and (odd in value), (name, key, value)
        if name == "recorder":
            assert f"config_file={run / 'config_used.yaml'}" in values["custom_data"], values["custom_data"]
            assert values["bag"] == str(tmp_path / f"bag {odd}")
        if name == "joint_controller_s1":
            assert values["init_file"] == str(run / "init" / "s1.npz")
