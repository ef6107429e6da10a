"""``pa10-dnbs study``: names checked before any work, the files and the row schema of a small study."""
import json
import pytest

from cli_runner import run_cli

from pa10_dnbs.study.scenarios import SCENARIOS, scenario_settings

ROW_KEYS = {"scenario", "controller", "seed", "worst_rms_error_rad", "worst_settling_time_s",
            "worst_max_abs_error_run_rad", "worst_torque_variation", "diverged", "guard_events"}


def _cli(*args):
    return run_cli("study", *args)


@pytest.mark.parametrize("flag, value, valid", [("--scenarios", "nominal,moon", "payload_5kg"),
                                                ("--controllers", "dnbs,lqr", "ctc")])
def test_bad_names_exit_2_listing_the_valid_ones(tmp_path, flag, value, valid):
    r = _cli(flag, value, "--out", tmp_path / "s")
    assert r.returncode == 2, r.stderr
    assert flag in r.stderr and valid in r.stderr and ("moon" in r.stderr or "lqr" in r.stderr)
    assert not (tmp_path / "s").exists()


def test_small_study_writes_rows_table_and_figure(tmp_path):
    r = _cli("--scenarios", "nominal,delay_1_tick", "--controllers", "dnbs,pid", "--seeds", 2, "--duration", 1.0,
             "--workers", 2, "--out", tmp_path / "s")
    assert r.returncode == 0, r.stderr
    rows = json.loads((tmp_path / "s" / "study.json").read_text())["rows"]
    assert len(rows) == 8 and all(set(row) == ROW_KEYS for row in rows)
    assert [(x["scenario"], x["controller"], x["seed"]) for x in rows][:3] == [
        ("nominal", "dnbs", 0), ("nominal", "dnbs", 1), ("nominal", "pid", 0)]
    assert not any(x["diverged"] for x in rows)
    dnbs = [x["worst_rms_error_rad"] for x in rows if x["controller"] == "dnbs" and x["scenario"] == "nominal"]
    assert dnbs[0] != dnbs[1]  # the seed sets the initial weights
    md = (tmp_path / "s" / "study.md").read_text()
    assert "## delay_1_tick" in md and "## Targets" in md and (tmp_path / "s" / "study.png").stat().st_size > 0


def test_scenarios_change_what_they_name(cfg):
    names = {n: scenario_settings(cfg, n, 3) for n in SCENARIOS}
    assert names["payload_5kg"][0].plant.payload_kg == 5.0 and names["nominal"][0].plant.payload_kg == 0
    assert names["coulomb"][0].plant.coulomb_nm[0] == pytest.approx(0.05 * 232)
    assert names["fast_reference"][0].reference.frequency_rad_s[0] == pytest.approx(1.5 * 0.285)
    assert names["delay_1_tick"][1].torque_delay_steps == 1 and names["encoder_noise"][1].seed == 3
    assert all(c.simulation.seed == 3 for c, _ in names.values())
    assert cfg.plant.payload_kg == 0.0  # the caller's config is left alone
