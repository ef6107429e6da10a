"""The study's feasibility check (study/feasibility.py): before it runs, a scenario whose reference asks a joint
for more than its torque limit on the scenario's plant (inverse dynamics with gravity) is named in one line and
not run; every feasible scenario runs as before. Fixture: test/fixtures/study_feasibility/weak_two_link.urdf
(15 N m joints; a 5 kg payload needs 28 N m at the shoulder) and the same arm at 100 N m."""
import json
from pathlib import Path

import pytest

from cli_runner import run_cli

from pa10_dnbs.config import default_config_path
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.study.collection import study_table
from pa10_dnbs.study.feasibility import infeasible_scenarios, scenario_peak_torque
from pa10_dnbs.study.scenarios import SCENARIOS

WEAK = Path(__file__).resolve().parent / "fixtures" / "study_feasibility" / "weak_two_link.urdf"


@pytest.fixture(scope="module")
def strong(tmp_path_factory):
    path = tmp_path_factory.mktemp("strong") / "strong_two_link.urdf"
    path.write_text(WEAK.read_text().replace('effort="15"', 'effort="100"'))
    return path


def _cfg(arm):
    return build_settings(default_config_path(), arm=str(arm))


def test_a_weak_arm_is_told_a_5kg_payload_is_infeasible_naming_joint_torque_and_limit():
    cfg = _cfg(WEAK)
    bad = infeasible_scenarios(cfg, list(SCENARIOS), 1.0)
    assert set(bad) == {"payload_5kg"}   # 2 kg: 14.7 N m, within 15; the rest far below
    line = bad["payload_5kg"]
    assert "\n" not in line and "joint shoulder" in line and "needs 28 N m" in line and "limit is 15 N m" in line
    assert scenario_peak_torque(cfg, "payload_5kg", 1.0)[0] == pytest.approx(5.0 * 9.81 * 0.45 + 9.81 * 0.6, rel=0.02)


def test_a_strong_arm_has_every_scenario_feasible(strong):
    assert infeasible_scenarios(_cfg(strong), list(SCENARIOS), 1.0) == {}


@pytest.mark.parametrize("arm", ["pa10", "iiwa", "panda"])
def test_every_preset_scenario_is_feasible_over_a_full_run(arm):
    assert infeasible_scenarios(_cfg(arm), list(SCENARIOS), 20.0) == {}


def _study(arm, scenarios, out):
    return run_cli("study", "--arm", arm, "--scenarios", scenarios, "--controllers", "dnbs", "--seeds", 1,
                   "--duration", 0.3, "--jobs", 1, "--out", out)


def test_the_study_reports_the_infeasible_scenario_and_runs_the_feasible_ones(tmp_path, strong):
    r = _study(WEAK, "nominal,payload_5kg", tmp_path / "weak")
    assert r.returncode == 0, r.stderr
    assert "study: payload_5kg: infeasible on arm" in r.stdout and "1 scenario(s) infeasible" in r.stdout
    data = json.loads((tmp_path / "weak" / "study.json").read_text())
    assert [x["scenario"] for x in data["rows"]] == ["nominal"] and "joint shoulder" in data["infeasible"]["payload_5kg"]
    md = (tmp_path / "weak" / "study.md").read_text()
    assert "## payload_5kg" in md and "**Not run**" in md and "n/a: infeasible" in md
    r = _study(strong, "nominal,payload_5kg", tmp_path / "strong")   # the same scenarios on a strong arm: both run
    assert r.returncode == 0, r.stderr
    data = json.loads((tmp_path / "strong" / "study.json").read_text())
    assert [x["scenario"] for x in data["rows"]] == ["nominal", "payload_5kg"] and "infeasible" not in data


def test_a_study_of_infeasible_scenarios_only_exits_2_with_one_line(tmp_path):
    r = _study(WEAK, "payload_5kg", tmp_path / "s")
    assert r.returncode == 2 and "every scenario chosen is infeasible" in r.stderr
    errors = [x for x in r.stderr.splitlines() if "error" in x]   # the rest is the gain rule's derivation
    assert len(errors) == 1 and "Traceback" not in r.stderr and not (tmp_path / "s").exists()


def test_the_collection_table_names_the_infeasible_scenarios():
    line = ("payload_5kg: infeasible on arm w: joint shoulder needs 28 N m along the reference (...), its limit is "
            "15 N m: no torque-limited controller can track it; not run")
    st = {"seeds": 3, "scenarios": {"nominal": {"dnbs_worst_rad": 1e-5, "pid_best_rad": 1e-4, "dnbs_below_pid": True,
                                                "dnbs_diverged": 0}, "payload_5kg": {"infeasible": line}}}
    table = study_table([{"arm": "w", "study": st}])
    assert "| w | 1 of 1 | 0 of 3 | - | 1.0e-05 | payload_5kg (shoulder needs 28 N m, limit 15) |" in table
