"""Computed torque at its torque limits (pa10_dnbs/sim/computed_torque.py, ``ctc.on_saturation``): on a light,
coupled arm without rotor inertia (the xArm7 of example-robot-data, fixture without meshes) clipping each joint
diverges from the 0.1 rad start offset while scaling the feedback tracks; ``clip`` is the textbook law bit for
bit; the key's layers (rule: scale_feedback; the presets' arm files: clip) and its check."""
from pathlib import Path

import numpy as np
import pytest

from arm_files import arm_file, quiet_settings
from cli_runner import run_cli
from pa10_dnbs.config import default_config_path
from pa10_dnbs.core.reference import ReferenceSample
from pa10_dnbs.plant.engines import open_plant
from pa10_dnbs.sim.closed_loop import simulate
from pa10_dnbs.sim.computed_torque import ComputedTorqueController

XARM7 = Path(__file__).resolve().parent / "fixtures" / "urdf_intake" / "xarm7_no_meshes.urdf"


def _xarm7_file(tmp_path, mode: str | None) -> str:
    fields = {"sources": {"urdf": "example-robot-data 6.0.0, meshes removed"}}
    if mode is not None:
        fields["settings"] = {"ctc": {"on_saturation": mode}}
    return arm_file(tmp_path, XARM7, f"arm_{mode}.yaml", **fields)


def test_on_a_light_coupled_arm_clipping_diverges_and_scaling_the_feedback_tracks(tmp_path):
    errors = {}
    for mode in ("clip", "scale_feedback"):
        with np.errstate(all="ignore"):
            run = simulate(quiet_settings(_xarm7_file(tmp_path, mode)), "ctc", 1.0)
        errors[mode] = run.error_rad
        assert np.all(np.abs(run.torque_nm) <= np.asarray(run.torque_limit_nm) + 1e-9), mode
    assert np.nanmax(np.abs(errors["clip"][-300:])) > 1.0  # diverged: joints 1-4 saturate from step 1
    tail = errors["scale_feedback"][500:]
    assert np.abs(errors["scale_feedback"]).max() <= 0.1 + 1e-9  # never beyond the start offset
    assert np.sqrt(np.mean(tail ** 2, axis=0)).max() < 1e-4


def test_clip_is_the_textbook_law_bit_for_bit_and_scale_feedback_only_differs_where_it_saturates(tmp_path):
    cfg = quiet_settings(_xarm7_file(tmp_path, "clip"))
    plant, close = open_plant(cfg)
    try:
        lim = np.asarray(cfg.plant.torque_limit_nm)
        kp, kd = np.asarray(cfg.ctc.kp_per_s2), np.asarray(cfg.ctc.kd_per_s)
        clip = ComputedTorqueController(plant, kp, kd, lim, "clip")
        scale = ComputedTorqueController(plant, kp, kd, lim, "scale_feedback")
        rng = np.random.default_rng(3)
        saturated = 0
        for k in range(40):
            q, qd = rng.uniform(-1, 1, 7), rng.uniform(-0.5, 0.5, 7)
            offset = 0.1 if k % 2 else 1e-4  # half of the states saturate, half do not
            ref = ReferenceSample(position_rad=q + offset, velocity_rad_s=qd, position_ahead_rad=q + offset,
                                  acceleration_rad_s2=rng.uniform(-0.1, 0.1, 7))
            v = ref.acceleration_rad_s2 + kd * (ref.velocity_rad_s - qd) + kp * (ref.position_rad - q)
            raw = plant.mass_matrix(q) @ v + plant.bias_torque(q, qd) + plant.step_friction_torque(qd, v)
            textbook = np.minimum(np.maximum(raw, -lim), lim)
            assert np.array_equal(clip.step(q, qd, ref), textbook)
            u = scale.step(q, qd, ref)
            assert np.all(np.abs(u) <= lim)
            if np.all(np.abs(raw) <= lim):
                assert scale.last_scale == 1.0 and np.array_equal(u, textbook)
            else:
                saturated += 1
                assert scale.last_scale < 1.0
                if scale.last_scale > 0.0:  # the feasible boundary: one joint at its limit, none beyond
                    assert np.max(np.abs(u) / lim) > 1 - 1e-6
        assert 10 <= saturated <= 30
    finally:
        close()


def test_the_key_comes_from_the_rule_layer_the_presets_clip_and_a_bad_value_is_one_line(tmp_path):
    assert quiet_settings(str(XARM7)).ctc.on_saturation == "scale_feedback"  # a bare URDF: the rule layer
    for preset in ("pa10", "iiwa", "panda"):
        assert quiet_settings(preset).ctc.on_saturation == "clip", preset  # their published numbers
    assert quiet_settings(_xarm7_file(tmp_path, "clip")).ctc.on_saturation == "clip"  # an arm file sets it
    bad = tmp_path / "bad.yaml"
    bad.write_text(f"extends: {default_config_path()}\nctc: {{on_saturation: scale}}\n")
    r = run_cli("simulate", "--config", bad, "--arm", "pa10", "--duration", "0.01", "--out", tmp_path / "o")
    assert r.returncode == 2 and not (tmp_path / "o").exists()
    assert "ctc.on_saturation: must be one of scale_feedback, clip" in r.stderr
    assert len([ln for ln in r.stderr.splitlines() if ln.strip()]) == 1, r.stderr
    with pytest.raises(ValueError, match="on_saturation"):
        ComputedTorqueController(None, 1.0, 1.0, [1.0], "scale")
