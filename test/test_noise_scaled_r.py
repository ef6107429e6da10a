"""scripts/noise_scaled_r.py, the experiment behind docs/arms.md's noise-scaled R: its wrapper leaves a run without
noise bit for bit as it is and raises R under the study's encoder noise; the script prints a row per arm."""
from __future__ import annotations

import subprocess
import sys

from script_module import SCRIPTS, load_script


def test_the_noise_scaled_r_leaves_a_run_without_noise_as_it_is_and_raises_r_under_noise():
    from pa10_dnbs.config import default_config_path
    from pa10_dnbs.run_settings import build_settings

    m = load_script("noise_scaled_r")
    settings = build_settings(default_config_path(), "pa10", report=False)
    plain, _ = m.run(settings, "nominal", "dnbs", 0, 0.5, None)
    watched, w = m.run(settings, "nominal", "dnbs", 0, 0.5, (1e-5, 0.5), scale=False)
    scaled, s = m.run(settings, "nominal", "dnbs", 0, 0.5, (1e-5, 0.5))
    assert watched == plain == scaled and 0 < s.largest_factor.max() < 1, (plain, scaled, s.largest_factor)
    noisy, _ = m.run(settings, "encoder_noise", "dnbs", 0, 0.5, None)
    noisy_scaled, s = m.run(settings, "encoder_noise", "dnbs", 0, 0.5, (1e-5, 0.5))
    # (1e-4 / 1e-5)^2 = 100 once the estimate has settled: the factor's whole size is the noise's, not the motion's
    assert 50 < s.largest_factor.max() < 200 and noisy_scaled != noisy, s.largest_factor


def test_the_script_prints_a_row_per_arm():
    done = subprocess.run([sys.executable, str(SCRIPTS / "noise_scaled_r.py"), "--arms", "pa10", "--seeds", "1",
                           "--duration", "0.3"], capture_output=True, text=True, timeout=300)
    rows = [ln for ln in done.stdout.splitlines() if ln.startswith("| pa10 |")]
    assert done.returncode == 0 and len(rows) == 1, done.stderr
