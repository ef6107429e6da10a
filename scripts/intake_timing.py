#!/usr/bin/env python3
"""Benchmark: what the intake costs on big inputs, before any run: long arms and long trajectory files.

Prints wall seconds (best of ``--repeat``) for
- ``pa10-dnbs arm --arm chainN.urdf`` (a subprocess: the whole command) for N in ``--joints``: a synthetic
  chain of 0.5 kg links and 10 N m joints (test/chain_urdf.py) that cannot hold the rule's reference, so the
  reference rule's torque search runs (arm/reference_rule.py, plant/reference_torque.py);
- loading a trajectory file of M points for the PA10 for M in ``--points`` (test/long_trajectory.py, 10 ms
  apart): read, checked, interpolated and its quintics checked against the limits
  (controller_factory.load_reference_trajectory, in-process), as JSON, and with ``--yaml`` as YAML too.
Figures only; asserts nothing (the machine is shared: the load average is printed before and after).

    python scripts/intake_timing.py [--joints 7,20,40] [--points 1e3,1e4,1e5] [--repeat 1] [--yaml]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "test"))
sys.path.insert(0, str(ROOT / "scripts"))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import yaml  # noqa: E402

from chain_urdf import chain_urdf  # noqa: E402
from flag_values import list_of  # noqa: E402
from long_trajectory import long_trajectory  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, positive, whole_in  # noqa: E402
from pa10_dnbs.config import default_config_path  # noqa: E402
from pa10_dnbs.controller_factory import load_reference_trajectory  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402

CHAIN_EFFORT_NM = 10.0


def _load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def _best(repeat: int, run) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return min(times)


def _arm_seconds(urdf: Path, repeat: int) -> float:
    cmd = [sys.executable, "-m", "pa10_dnbs.cli", "arm", "--arm", str(urdf)]

    def run():
        done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=900)
        if done.returncode != 0:
            raise SystemExit(f"intake_timing: {' '.join(cmd)} failed: {done.stderr.strip().splitlines()[-1:]}")
    return _best(repeat, run)


MAX_JOINTS = 1000       # a chain far longer than any arm's
MAX_POINTS = 10**7      # a trajectory file of about 2 GB as JSON


def _point_count(text: str) -> int:
    """A trajectory length: a whole number in [1, MAX_POINTS], written plainly or as 1e4."""
    v = positive(text)
    if v > MAX_POINTS or v != int(v):
        raise argparse.ArgumentTypeError(f"must be a whole number of points up to {MAX_POINTS:.0e}, got {text!r}")
    return int(v)


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--joints", type=list_of(whole_in(1, MAX_JOINTS), allow_empty=True), default="7,20,40",
                    help="comma-separated chain lengths ('' for none)")
    ap.add_argument("--points", type=list_of(_point_count, allow_empty=True), default="1e3,1e4,1e5",
                    help="comma-separated trajectory lengths ('' for none)")
    ap.add_argument("--repeat", type=whole_in(1), default=1)
    ap.add_argument("--yaml", action="store_true", help="also time each trajectory written as YAML (slow)")
    args = ap.parse_args()
    joints, points = args.joints, args.points
    print(f"load average before: {_load()}")
    with tempfile.TemporaryDirectory(prefix="intake_timing_") as tmp:
        tmp = Path(tmp)
        for n in joints:
            urdf = tmp / f"chain{n}.urdf"
            urdf.write_text(chain_urdf(n, effort_nm=CHAIN_EFFORT_NM, name=f"chain{n}"))
            print(f"pa10-dnbs arm, {n:3d}-joint chain ({CHAIN_EFFORT_NM:g} N m joints): "
                  f"{_arm_seconds(urdf, args.repeat):7.2f} s", flush=True)
        if points:
            settings = build_settings(default_config_path())
            arm = settings.arm
        for m in points:
            doc = long_trajectory(arm.joint_names, arm.lower_rad, arm.upper_rad, m, seed=1)
            forms = [("json", json.dumps)] + ([("yaml", yaml.safe_dump)] if args.yaml else [])
            for suffix, dump in forms:
                path = tmp / f"trajectory{m}.{suffix}"
                path.write_text(dump(doc))
                seconds = _best(args.repeat, lambda: load_reference_trajectory(settings, path))
                print(f"trajectory file, {m:7d} points ({suffix}, {path.stat().st_size / 1e6:.1f} MB): "
                      f"{seconds:7.2f} s", flush=True)
    print(f"load average after: {_load()}")
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "intake_timing", interrupted="the lines above are complete: run the same "
                                                                "command again for the rest"))
