"""A joint controller's settings as ROS parameters (ros/settings_params.py: JOINT_CONTROLLER_KEYS): one double per
per-joint key (its joint's value), settings rebuilt from them alone that run the joint bit for bit as the run's
settings do, and the params file's values coming back bit for bit (no ROS started)."""
import numpy as np
import pytest
import yaml

from pa10_dnbs.config_error import ConfigError
from pa10_dnbs.controller_factory import build_guarded_controllers
from pa10_dnbs.core.reference import ReferenceSample
from pa10_dnbs.supervisor.params_file import params_document, params_yaml
from pa10_dnbs.ros.settings_params import (ARM_FILE, joint_node_settings, joint_params, joint_values,
                                           section_params)
from pa10_dnbs.settings import replace_in


def _flat(tree: dict, prefix: str = "") -> dict:
    out = {}
    for key, value in tree.items():
        dotted = f"{prefix}{key}"
        out.update(_flat(value, dotted + ".") if isinstance(value, dict) else {dotted: value})
    return out


def _odd(cfg):
    """Settings whose per-joint values differ from joint to joint and need 17 significant digits."""
    s = replace_in(cfg, "dnbs.alpha_net.error_scale_rad", tuple(0.01 + 0.02 * k / 3.0 for k in range(7)))
    s = replace_in(s, "dnbs.torque_net.q", tuple(1e-3 * (1.0 + k / 7.0) for k in range(7)))
    return replace_in(s, "dnbs.alpha_net.init_weight_std", tuple(0.1 + 0.2 * k / 3.0 for k in range(7)))


def test_every_per_joint_key_holds_the_joints_value_and_the_rest_as_they_are(cfg):
    for row, joint in enumerate(cfg.arm.joint_names):
        values = joint_values(cfg, "dnbs", row)
        assert values[ARM_FILE] == str(cfg.arm.file)
        assert values["dnbs.alpha_net.error_scale_rad"] == cfg.dnbs.alpha_net.error_scale_rad[row]
        assert values["dnbs.torque_net.init_weight_std"] == cfg.dnbs.torque_net.init_weight_std[row]
        assert values["plant.torque_limit_nm"] == cfg.plant.torque_limit_nm[row]
        assert values["faults.effort.drop_fraction"] == cfg.faults.effort.drop_fraction[row]
        assert values["dnbs.alpha_net.input_scale"] == list(cfg.dnbs.alpha_net.input_scale)  # per input: a list
        assert values["simulation.seed"] == cfg.simulation.seed and values["dnbs.kernel"] == cfg.dnbs.kernel
    pid = joint_values(cfg, "pid", 1)
    assert pid["pid.kp"] == cfg.pid.kp[1] and pid["pid.anti_windup"] == cfg.pid.anti_windup
    assert not any(k.startswith(("dnbs.", "checkpoint.")) for k in pid)  # a PID node runs no DNBS setting
    # only what it runs: not the plant's physics, the reference's shape or the state links' faults
    assert not any(k.startswith(("plant.gravity", "reference.amplitude", "faults.state.", "simulation.duration"))
                   for k in joint_values(cfg, "dnbs", 0))


def test_every_parameter_has_its_unit_and_the_keys_range():
    params = joint_params("dnbs")
    assert params["dnbs.alpha_net.error_scale_rad"].description.endswith("this node's joint's value [rad]; > 0")
    assert params["dnbs.alpha_net.error_scale_rad"].lo == 0.0
    assert (params["dnbs.alpha_net.eta"].lo, params["dnbs.alpha_net.eta"].hi) == (0.0, 1.0)
    assert "[N m]" in params["plant.torque_limit_nm"].description
    assert "[N m/rad]" in joint_params("pid")["pid.kp"].description
    # the same keys as a whole-arm node's, whose per-joint values are lists
    assert "one value per joint" in section_params(("pid",))["pid.kp"].description


def test_its_settings_run_the_joint_bit_for_bit_as_the_runs_do(cfg):
    settings = _odd(cfg)
    for kind in ("dnbs", "pid"):
        doc = yaml.safe_load(params_yaml(params_document(settings, kind, "/pa10")))
        for row, joint in enumerate(cfg.arm.joint_names):
            values = _flat(doc[f"/pa10/joint_controller_{joint}"]["ros__parameters"])
            assert values == joint_values(settings, kind, row)  # the YAML text gives back every bit
            node = joint_node_settings(cfg.arm, values, kind)
            ours, runs = (build_guarded_controllers(s, kind, [row]) for s in (node, settings))
            rng = np.random.default_rng(row)
            for _ in range(20):  # small errors: torques within the limit, where another joint's gains differ
                q = rng.normal(0, 0.3, 1)
                x1, x2 = q + rng.normal(0, 0.002, 1), rng.normal(0, 0.01, 1)
                ref = ReferenceSample(q, rng.normal(0, 0.01, 1), q + rng.normal(0, 0.001, 1))
                assert ours.step(x1, x2, ref).tobytes() == runs.step(x1, x2, ref).tobytes(), (kind, joint)
            if kind == "dnbs":
                a, b = ours.controllers.state_dict(0), runs.controllers.state_dict(0)
                assert all(np.array_equal(a[k], b[k]) for k in b), joint


def test_it_runs_nothing_but_its_parameters(cfg):
    node = joint_node_settings(cfg.arm, joint_values(cfg, "pid", 0), "pid")
    with pytest.raises(AttributeError, match="no plant.gravity_mps2"):
        node.plant.gravity_mps2
    with pytest.raises(AttributeError, match="no dnbs section"):
        node.dnbs
    assert node.plant.torque_limit_nm == (cfg.plant.torque_limit_nm[0],) * 7  # broadcast to every row


def test_a_bad_value_is_refused_naming_its_key(cfg):
    values = joint_values(cfg, "dnbs", 2)
    with pytest.raises(ConfigError, match=r"^dnbs.alpha_net.error_scale_rad: must be > 0"):
        joint_node_settings(cfg.arm, {**values, "dnbs.alpha_net.error_scale_rad": 0.0}, "dnbs")
    with pytest.raises(ConfigError, match=r"^dnbs.kernel: must be one of"):
        joint_node_settings(cfg.arm, {**values, "dnbs.kernel": "fortran"}, "dnbs")
