"""Arms: presets and their files, the reference and gain rules, bad arms, an arm of three joints, locked joints."""
import math

import numpy as np
import pytest
import yaml

from cli_runner import run_cli
from pa10_dnbs.arm import ArmError, load_arm, preset_names
from pa10_dnbs.arm.gain_rule import RHO
from pa10_dnbs.arm.reference_rule import reference_rule
from pa10_dnbs.config import ConfigError, default_config_path
from pa10_dnbs.run_settings import build_settings

# the PA10's Table 1, typed in from the paper (not read from the code)
TABLE1_C = [math.pi / 2, math.pi / 3] * 3 + [math.pi / 2]
TABLE1_D = [0.001, 0.001, 0.01, 0.01, 0.01, 0.01, 0.01]
TABLE1_W = [0.285, 0.435, 0.555, 0.645, 0.345, 0.615, 0.465]


def _link(name, mass=1.0, inertia=0.01, inertial=True):
    body = (f'<inertial><origin xyz="0 0 0.1"/><mass value="{mass}"/><inertia ixx="{inertia}" ixy="0" ixz="0" '
            f'iyy="{inertia}" iyz="0" izz="{inertia}"/></inertial>') if inertial else ""
    return f'<link name="{name}">{body}</link>'


def _joint(name, parent, child, kind="revolute", effort=50.0, z=0.2, axis="0 1 0"):
    limit = f'<limit lower="-2" upper="2" effort="{effort}" velocity="2"/>' if kind != "fixed" else ""
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="0 0 {z}"/><axis xyz="{axis}"/>{limit}</joint>')


def three_link_urdf(gripper: bool = False) -> str:
    """A 3R arm (yaw, pitch, pitch) and a flange; with ``gripper``, a prismatic finger after the flange."""
    parts = [_link("base"), _link("l1", 4.0, 0.05), _link("l2", 3.0, 0.03), _link("l3", 2.0, 0.01),
             _link("flange", inertial=False),
             _joint("j1", "base", "l1", axis="0 0 1", z=0.1), _joint("j2", "l1", "l2"), _joint("j3", "l2", "l3"),
             _joint("flange_joint", "l3", "flange", kind="fixed")]
    if gripper:
        parts += [_link("finger", 0.2, 0.001), _joint("finger_joint", "flange", "finger", kind="prismatic",
                                                       axis="1 0 0", z=0.05)]
    return '<robot name="three">' + "".join(parts) + "</robot>"


def write_arm(tmp_path, urdf: str, **facts) -> str:
    (tmp_path / "arm.urdf").write_text(urdf)
    doc = {"name": "three", "urdf": "arm.urdf", "rotor_inertia_kgm2": [0.05, 0.05, 0.02],
           "viscous_nms_per_rad": 0.5, "coulomb_nm": 0.0,
           "sources": {"urdf": "a test arm", "rotor_inertia_kgm2": "made up", "viscous_nms_per_rad": "made up",
                       "coulomb_nm": "none"}}
    doc.update(facts)
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump(doc))
    return str(tmp_path / "arm.yaml")


def test_the_presets_are_whole_and_every_fact_has_its_source():
    assert {"pa10", "iiwa", "panda"} <= set(preset_names())
    for name, first in (("pa10", "s1"), ("iiwa", "a1"), ("panda", "panda_joint1")):
        arm = load_arm(name)
        assert arm.n_joints == 7 and arm.joint_names[0] == first and arm.locked_joints == ()
        for key in ("urdf", "torque_limit_nm", "rotor_inertia_kgm2", "viscous_nms_per_rad", "coulomb_nm"):
            assert arm.sources[key].strip(), (name, key)
        assert np.all(arm.rotor_inertia_kgm2 > 0), name   # every geared arm has reflected rotor inertia
    assert load_arm("iiwa").torque_limit_nm.tolist() == [320, 320, 176, 176, 110, 40, 40]   # the data sheet
    assert load_arm("panda").torque_limit_nm.tolist() == [87, 87, 87, 87, 12, 12, 12]       # Franka's docs


def test_the_reference_rule_gives_table1_on_the_pa10_and_stays_inside_any_arm_limits():
    pa10 = load_arm("pa10")
    r = reference_rule(pa10.lower_rad, pa10.upper_rad)
    assert r["amplitude_rad"] == TABLE1_C and r["envelope_rate_per_s3"] == TABLE1_D
    assert r["frequency_rad_s"] == TABLE1_W and r["centre_rad"] == [0.0] * 7
    assert build_settings(default_config_path()).reference.amplitude_rad == tuple(TABLE1_C)
    panda = load_arm("panda")   # joint 4 lives in [-3.07, -0.07], joint 6 in [-0.02, 3.75]
    r = reference_rule(panda.lower_rad, panda.upper_rad)
    for lo, hi, c, x0 in zip(panda.lower_rad, panda.upper_rad, r["amplitude_rad"], r["centre_rad"]):
        assert lo + (hi - lo) / 6 - 1e-12 <= x0 - c and x0 + c <= hi - (hi - lo) / 6 + 1e-12


def test_the_gain_rule_keeps_every_loop_inside_its_discrete_time_margin(capsys):
    """The rule's gains: T k_u / J_light = RHO on every joint, and the coupled figure well below 2."""
    cfg = build_settings(default_config_path(), arm="iiwa")
    err = capsys.readouterr().err
    assert "gains by the rule of docs/arms.md" in err and "a1" in err
    figure = float(err.split("(figure ")[1].split()[0])
    assert RHO <= figure < 1.0
    k_u = np.array(cfg.dnbs.remedies.robust_term.torque_gain_nms_per_rad)
    assert np.array_equal(np.array(cfg.pid.kd), k_u)
    assert np.all(np.array(cfg.dnbs.torque_net.output_scale_nm) == load_arm("iiwa").torque_limit_nm)


def test_the_pa10_settings_come_from_its_arm_file_and_nothing_is_derived(capsys):
    cfg = build_settings(default_config_path())
    assert capsys.readouterr().err == ""
    assert cfg.dnbs.remedies.robust_term.torque_gain_nms_per_rad == (400, 400, 120, 120, 3, 3, 3)
    assert cfg.pid.kp == (25500, 25500, 10200, 10200, 766, 766, 766)


def test_a_config_value_beats_the_arm_file_and_the_rule(tmp_path):
    p = tmp_path / "mine.yaml"
    p.write_text(f"extends: {default_config_path()}\npid:\n  kd: 7.0\n")
    assert build_settings(p, arm="iiwa").pid.kd == (7.0,) * 7
    assert build_settings(p).pid.kd == (7.0,) * 7


@pytest.mark.parametrize("change, facts, message", [
    ({"<robot": "<robt"}, {}, r"the URDF does not parse"),
    ({}, {"joints": ["j1", "j9"]}, r"joint 'j9' is not in the URDF"),
    ({}, {"exclude_joints": ["nope"]}, r"joint 'nope' is not in the URDF"),
    ({'name="j2" type="revolute"': 'name="j2" type="prismatic"'}, {}, r"joint 'j2' is prismatic"),
    ({'name="j3" type="revolute"': 'name="j3" type="floating"'}, {}, r"joint 'j3' is floating"),
    ({'effort="50.0"': 'effort="0"'}, {}, r"joint 'j1' has effort 0, not a finite limit > 0: give torque_limit_nm"),
    ({'effort="50.0"': 'effort="inf"'}, {}, r"joint 'j1' has effort inf, not a finite limit > 0: give torque_limit_nm"),
    ({'<link name="l2"><inertial>': '<link name="l2"><foo>', '</inertial></link><link name="l3">':
      '</foo></link><link name="l3">'}, {}, r"link 'l2' \(moved by 'j2'\) has no <inertial>"),
    ({}, {"rotor_inertia_kgm2": [0.1, 0.1]}, r"rotor_inertia_kgm2: expected 3 values"),
    ({}, {"torque_limit_nm": [10.0, 10.0, 10.0]}, r"sources.torque_limit_nm: missing"),
    ({}, {"color": "red"}, r"color: unknown key"),
])
def test_a_bad_arm_is_one_line_naming_it_exit_2_nothing_written(tmp_path, change, facts, message):
    arm = write_arm(tmp_path, _apply(three_link_urdf(), change), **facts)
    with pytest.raises(ArmError, match=message):
        load_arm(arm)
    out = tmp_path / "out"
    r = run_cli("simulate", "--arm", arm, "--duration", "0.1", "--out", out)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "error:" in r.stderr
    assert not out.exists()


@pytest.mark.parametrize("settings, message", [
    ({"pid": {"kp": [1.0, 2.0]}}, "settings.pid.kp: expected 3 values (one per joint of the arm), got 2"),
    ({"dnbs": {"remedies": {"robust_term": {"alpha_gain_per_s": [1.0]}}}},
     "settings.dnbs.remedies.robust_term.alpha_gain_per_s: expected 3 values"),
    ({"pid": {"kp": None}}, "settings.pid.kp: null"),
])
def test_an_arm_files_setting_of_the_wrong_length_or_null_names_the_arm_file(tmp_path, settings, message):
    """Checked with the arm's joint count where the arm file is known (it was said as a bare config key, as if
    the user's config gave it)."""
    arm = write_arm(tmp_path, three_link_urdf(), settings=settings)
    r = run_cli("simulate", "--arm", arm, "--duration", "0.1", "--out", tmp_path / "out")
    assert r.returncode == 2 and r.stderr.startswith(f"pa10-dnbs: error: {arm}: {message}"), r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("settings, key", [
    ({"guards": {"max_speed_rad_s": 0.001}}, "guards.max_speed_rad_s"),
    ({"simulation": {"duration_s": 0.5, "seed": 99}}, "simulation.duration_s"),
    ({"pid": {"kp": [1.0, 2.0, 3.0]}, "dnbs": {"alpha_net": {"eta": 0.5}}}, "dnbs.alpha_net.eta"),
])
def test_an_arm_files_setting_that_the_default_config_overrides_is_refused(tmp_path, settings, key):
    """Such a value was checked and then silently replaced by the config's: the run ignored it (a 0.5 s
    duration ran 20 s). A rule key (pid.kp) beside it is still taken."""
    arm = write_arm(tmp_path, three_link_urdf(), settings=settings)
    r = run_cli("simulate", "--arm", arm, "--duration", "0.1", "--out", tmp_path / "out")
    assert r.returncode == 2 and r.stderr.startswith(f"pa10-dnbs: error: {arm}: settings.{key}: the default "
                                                     f"config gives this key"), r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "out").exists()


def _apply(text, changes):
    for old, new in changes.items():
        text = text.replace(old, new)
    return text


def test_an_unknown_preset_names_the_presets():
    with pytest.raises(ConfigError, match=r"no arm called 'ur5' \(presets: .*iiwa.*pa10"):
        build_settings(default_config_path(), arm="ur5")


def test_an_arm_of_three_joints_from_a_bare_urdf_runs_every_controller(tmp_path):
    """A bare URDF: joints from the chain, limits from <limit effort>, no rotor inertia (the rule warns where
    the effective inertia varies much); every per-joint list has three values."""
    (tmp_path / "three.urdf").write_text(three_link_urdf())
    cfg = build_settings(default_config_path(), arm=tmp_path / "three.urdf")
    assert len(cfg.pid.kp) == 3 and cfg.plant.torque_limit_nm == (50.0, 50.0, 50.0)
    out = tmp_path / "out"
    r = run_cli("simulate", "--arm", tmp_path / "three.urdf", "--controller", "all", "--duration", "3",
                "--out", out, "--no-figures")
    assert r.returncode == 0, r.stderr
    assert "j1" in r.stderr and "joint" in r.stderr
    import json
    for kind in ("dnbs", "pid", "ctc"):
        m = json.loads((out / kind / "metrics.json").read_text())
        assert m["all_finite"] and m["torques_within_limits"] and len(m["joints"]) == 3, kind
    assert json.loads((out / "dnbs" / "metrics.json").read_text())["worst_rms_error_rad"] < 1e-2


def test_a_locked_finger_is_held_exactly(tmp_path):
    """A prismatic finger left out of the actuated joints: the plant's M and h are those of the same arm with
    the finger welded on, to machine precision."""
    from pa10_dnbs.plant.from_config import arm_plant_params, open_client
    from pa10_dnbs.plant.pybullet_plant import PyBulletArmPlant

    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    locked = load_arm(write_arm(tmp_path / "a", three_link_urdf(gripper=True), exclude_joints=["finger_joint"]))
    welded = load_arm(write_arm(tmp_path / "b", three_link_urdf(gripper=True).replace(
        'name="finger_joint" type="prismatic"', 'name="finger_joint" type="fixed"')))
    assert locked.joint_names == welded.joint_names == ("j1", "j2", "j3")
    assert locked.locked_joints == ("finger_joint",) and welded.locked_joints == ()
    client = open_client()
    try:
        a, b = (PyBulletArmPlant(client, arm, arm_plant_params(arm)) for arm in (locked, welded))
        rng = np.random.default_rng(3)
        for _ in range(20):
            q, qd = rng.uniform(-1.5, 1.5, 3), rng.uniform(-2, 2, 3)
            np.testing.assert_allclose(a.mass_matrix(q), b.mass_matrix(q), rtol=1e-12, atol=1e-14)
            np.testing.assert_allclose(a.bias_torque(q, qd), b.bias_torque(q, qd), rtol=1e-12, atol=1e-12)
    finally:
        client.disconnect()


def test_the_arm_command_prints_its_report_once_on_stdout():
    """``pa10-dnbs arm`` is a report: facts, sources, the inertia sweep and the rule's gains, all on stdout (a user
    keeps it with ``> arm.txt``), the table once (the rules' build-time copy on stderr doubled it)."""
    r = run_cli("arm", "--arm", "iiwa")
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert r.stdout.count("J light-heavy [kg m^2]") == 1 and "sources:" in r.stdout and "runs with:" in r.stdout


def test_the_arm_command_names_every_gain_the_arm_file_sets(tmp_path):
    """An arm file's k_a was run but ``arm`` said "runs with: the rule's gains" (it compared k_u alone)."""
    arm = write_arm(tmp_path, three_link_urdf(),
                    settings={"dnbs": {"remedies": {"robust_term": {"alpha_gain_per_s": [8.0, 20.0, 20.0]}}}})
    r = run_cli("arm", "--arm", arm)
    assert r.returncode == 0, r.stderr
    tail = r.stdout.splitlines()[-2:]
    assert tail == ["runs with: its own values where they differ from the rule's:",
                    "  dnbs.remedies.robust_term.alpha_gain_per_s: j1 8, j2 20, j3 20"], r.stdout


def test_the_rules_table_keeps_its_columns_under_long_joint_names(tmp_path):
    """The names column is as wide as the longest name (a UR's shoulder_lift_joint pushed its row 12 columns
    right of the headings)."""
    urdf = three_link_urdf().replace('name="j2"', 'name="a_rather_long_joint_name"')
    r = run_cli("arm", "--arm", write_arm(tmp_path, urdf))
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    head = next(i for i, line in enumerate(lines) if "J light-heavy" in line)
    column = lines[head].index("limits [rad]")
    assert [line.index("[") for line in lines[head + 1:head + 4]] == [column] * 3, lines[head:head + 4]
