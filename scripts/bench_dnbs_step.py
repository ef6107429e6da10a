#!/usr/bin/env python3
"""Benchmark: where the time of one in-process step goes, and what it leaves for the DNBS controller.

Replays the joint states of a default-config DNBS run (``--duration`` s, in-process) through fresh
controller banks and times, per 1 ms step (best of ``--repeat`` passes over the same states):
- the plant alone (PyBullet step under the run's torques) and the PID bank of seven (behind its guard);
- the DNBS bank of seven and a bank of one (what a joint-controller node runs), split into the answer
  (guard, both regressors, both outputs), the EKF update of both networks, the EKF guard and the rest of
  the training (remedies, bookkeeping);
then the run-level ratio DNBS/PID these give, and the DNBS step a given ratio would allow. From the banks
of one and seven, step(n) = fixed + n x per_joint: the fixed part is the cost of the step's sequence of
small numpy calls, which does not depend on the number of joints; it sets the floor of the ratio. The same
for the compiled kernel (``dnbs.kernel: c``), whose training is one call: answer and training only.
Figures only; asserts nothing (shared, noisy machines: the load average is printed).

    python scripts/bench_dnbs_step.py [--duration 5] [--repeat 5] [--target 1.5] [--kernels numpy,c]
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import numpy as np  # noqa: E402
from flag_values import names_in  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, positive, seconds, whole_in  # noqa: E402

from pa10_dnbs.config import default_config_path  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.settings import replace_in  # noqa: E402
from pa10_dnbs.controller_factory import build_guarded_controllers, build_reference  # noqa: E402
from pa10_dnbs.core.reference import ReferenceSample  # noqa: E402
from pa10_dnbs.plant.from_config import open_client, plant_from_settings  # noqa: E402
from pa10_dnbs.sim.closed_loop import simulate  # noqa: E402


def _load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


class _Timed:
    """Wraps a bound method and adds its wall time [s] to ``total`` (about 0.1 us per call of its own)."""

    def __init__(self, method):
        self.method, self.total = method, 0.0

    def __call__(self, *args, **kwargs):
        t = time.perf_counter()
        result = self.method(*args, **kwargs)
        self.total += time.perf_counter() - t
        return result


def _references(cfg, n: int, rows):
    ref = build_reference(cfg)
    steps = np.arange(n)
    cols = (ref.position(steps)[:, rows], ref.velocity(steps)[:, rows],
            ref.position(steps + ref.preview_steps)[:, rows])
    return [ReferenceSample(p, v, a, None) for p, v, a in zip(*cols)]


def _dnbs_pass(cfg, run, rows, kernel: str = "numpy"):
    """One pass of a fresh DNBS bank of joints ``rows`` over the run's states: (seconds per part, the bank).

    kernel "c" (the compiled step, one call for the whole training): only the answer and the training."""
    cfg = replace_in(cfg, "dnbs.kernel", kernel)
    guarded = build_guarded_controllers(cfg, "dnbs", rows)
    c = guarded.controllers
    ekf_update, ekf_guard = _Timed(c.ekf.update), _Timed(c._guard)
    if kernel == "numpy":
        c.ekf.update, c._guard = ekf_update, ekf_guard  # instance attributes: the controller calls these
    q, qd = run.position_rad[:, rows], run.velocity_rad_s[:, rows]
    refs = _references(cfg, run.n_steps, rows)
    answer = learn = 0.0
    for k in range(run.n_steps):
        t0 = time.perf_counter()
        guarded.answer(q[k], qd[k], refs[k])
        t1 = time.perf_counter()
        guarded.learn()
        t2 = time.perf_counter()
        answer += t1 - t0
        learn += t2 - t1
    if kernel != "numpy":
        return {"answer": answer, "training": learn, "step": answer + learn}, c
    return {"answer": answer, "ekf update": ekf_update.total, "ekf guard": ekf_guard.total,
            "rest of training": learn - ekf_update.total - ekf_guard.total, "step": answer + learn}, c


def _pid_pass(cfg, run) -> float:
    guarded = build_guarded_controllers(cfg, "pid")
    refs = _references(cfg, run.n_steps, list(range(cfg.arm.n_joints)))
    t = time.perf_counter()
    for k in range(run.n_steps):
        guarded.step(run.position_rad[k], run.velocity_rad_s[k], refs[k])
    return time.perf_counter() - t


def _plant_pass(cfg, run) -> float:
    client = open_client()
    try:
        plant = plant_from_settings(cfg, client)
        t = time.perf_counter()
        for k in range(run.n_steps):
            plant.state  # noqa: B018  (read as the loop reads it)
            plant.step(run.torque_nm[k])
            plant.applied_torque_nm  # noqa: B018
        return time.perf_counter() - t
    finally:
        client.disconnect()


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=seconds, default=5.0, help="simulated seconds of the replayed run")
    ap.add_argument("--repeat", type=whole_in(1), default=5, help="passes per part; the best is printed")
    ap.add_argument("--target", type=positive, default=1.5, help="a DNBS/PID run ratio to show the budget of")
    ap.add_argument("--kernels", type=names_in(("numpy", "c")), default="numpy,c",
                    help="DNBS kernels to time (numpy: parts of the step; c: compiled)")
    args = ap.parse_args()
    cfg = build_settings(default_config_path())
    run = simulate(cfg, "dnbs", args.duration)
    n = run.n_steps
    print(f"per 1 ms step, best of {args.repeat} passes over {n} states of a default DNBS run; "
          f"load average {_load()}")
    us = lambda s: s / n * 1e6  # noqa: E731
    plant = min(us(_plant_pass(cfg, run)) for _ in range(args.repeat))
    pid = min(us(_pid_pass(cfg, run)) for _ in range(args.repeat))
    joint_names = cfg.arm.joint_names
    nj = len(joint_names)
    one_rows = (0, nj - 1)  # the first and the last joint, each alone as in its node
    print(f"  plant (PyBullet step, state, torques)   {plant:6.1f} us")
    print(f"  PID bank of 7, guarded                  {pid:6.1f} us")
    steps = {}
    for kernel in args.kernels:
        banks = {}
        for label, rows in ((f"bank of {nj}", list(range(nj))),
                            *((f"bank of 1 ({joint_names[j]})", [j]) for j in one_rows)):
            passes = [_dnbs_pass(cfg, run, rows, kernel)[0] for _ in range(args.repeat)]
            best = min(passes, key=lambda p: p["step"])
            banks[label] = {k: us(v) for k, v in best.items()}
        print(f"  DNBS ({kernel}), guarded".ljust(39) + "".join(f"{label:>17s}" for label in banks))
        for part in banks[f"bank of {nj}"]:
            print(f"    {part:35s}" + "".join(f"{banks[label][part]:14.1f} us" for label in banks))
        steps[kernel] = banks[f"bank of {nj}"]["step"], banks[f"bank of 1 ({joint_names[0]})"]["step"]
    for kernel, (dnbs7, one) in steps.items():
        _ratios(kernel, plant, pid, dnbs7, one, nj, args.target)
    print(f"load average at the end {_load()}")
    return 0


def _ratios(kernel: str, plant: float, pid: float, dnbs7: float, one: float, nj: int, target: float) -> None:
    """The run-level ratio one kernel's parts give, its fixed and per-joint cost, and a target's budget."""
    print(f"{kernel}:")
    pid_run, dnbs_run = plant + pid, plant + dnbs7
    fixed, per_joint = (nj * one - dnbs7) / (nj - 1), (dnbs7 - one) / (nj - 1)  # step(n) = fixed + n per_joint
    print(f"  step(n) = {fixed:.1f} us + n x {per_joint:.1f} us: {fixed / dnbs7:.0%} of the bank of seven's step "
          f"does not depend on the number of joints (the cost of each call)")
    print(f"  run ratio from these parts: DNBS/PID = ({plant:.1f} + {dnbs7:.1f}) / ({plant:.1f} + {pid:.1f}) "
          f"= {dnbs_run / pid_run:.2f}")
    budget = target * pid_run - plant
    print(f"  a ratio of {target:g} leaves the DNBS bank of seven {budget:.1f} us per step: "
          f"{budget / dnbs7:.0%} of this step, {budget / fixed:.0%} of its fixed part")


if __name__ == "__main__":
    sys.exit(script_main.run(main, "bench_dnbs_step", {"duration_s": "--duration"},
                             interrupted="no record written: run the same command again"))
