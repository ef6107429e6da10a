"""The alpha network's initial weight spread (``dnbs.alpha_net.init_weight_std``): the rule layer gives 1e-6,
the PA10, iiwa and Panda arm files keep the 0.01 of their published runs, an arm file or a config sets it;
and the tracking floor it sets: the EKF learns the untrained output away only to about 2e-3 E1 x spread rad,
so the spread 0.01 leaves a floor of about 1e-5 rad that the spread 1e-6 removes (docs/arms.md, three layers).
"""
from pathlib import Path

import numpy as np

from arm_files import arm_file, quiet_settings
from pa10_dnbs.settings import replace_in
from pa10_dnbs.sim.closed_loop import simulate

ARM3 = Path(__file__).resolve().parent / "fixtures" / "urdf_intake" / "continuous_joint.urdf"


def _arm_file(tmp_path, spread: float | None = None) -> str:
    """The 3-joint fixture with a 0.1 kg m^2 rotor on each joint (an arm file, as the collection's)."""
    fields = {"rotor_inertia_kgm2": 0.1, "sources": {"urdf": "test fixture", "rotor_inertia_kgm2": "generic 0.1"}}
    if spread is not None:
        fields["settings"] = {"dnbs": {"alpha_net": {"init_weight_std": spread}}}
    return arm_file(tmp_path, ARM3, f"arm3_{spread}.yaml", **fields)


def test_the_spread_comes_from_the_rule_layer_and_the_presets_keep_theirs(tmp_path):
    assert set(quiet_settings(str(ARM3)).dnbs.alpha_net.init_weight_std) == {1e-6}  # a bare URDF: the rule
    for preset in ("pa10", "iiwa", "panda"):
        assert set(quiet_settings(preset).dnbs.alpha_net.init_weight_std) == {0.01}, preset
    assert set(quiet_settings(_arm_file(tmp_path, 0.001)).dnbs.alpha_net.init_weight_std) == {0.001}  # an arm file


def _window_rms(settings, spread: float) -> float:
    """Worst joint's RMS error [rad] over the second half of a 12 s DNBS run with the alpha spread ``spread``."""
    n = len(settings.arm.joint_names)
    run = simulate(replace_in(settings, "dnbs.alpha_net.init_weight_std", (spread,) * n), "dnbs", 12.0)
    e = run.error_rad[run.n_steps // 2:]
    return float(np.max(np.sqrt(np.mean(e ** 2, axis=0))))


def test_the_initial_spread_sets_the_tracking_floor(tmp_path):
    settings = quiet_settings(_arm_file(tmp_path))
    wide, tenth, narrow = (_window_rms(settings, s) for s in (0.01, 1e-3, 1e-6))
    assert 2e-6 < wide < 1e-4, wide  # the floor of the spread 0.01 (about 1e-5 rad on every arm)
    assert 0.05 < tenth / wide < 0.2, (tenth, wide)  # proportional to the spread (here 1.7e-5, 1.8e-6)
    assert narrow < wide / 20, (narrow, wide)  # 1e-6: below another floor (here 5.8e-7)
