#!/usr/bin/env python3
"""Fingerprint the controllers' results bit for bit, to show that a speed-up changed no result bit.

Runs fixed scenarios in-process and prints one SHA-256 per scenario (of the raw bytes of every array it
produced, in a fixed order):
- ``default`` and ``paper``: the closed loop of config/default.yaml and config/paper.yaml, DNBS, 3 s;
- ``noisy``: the default config with encoder noise and a 2-step torque delay, 2 s;
- ``remedies``, ``printed``, ``bare``: a DNBS bank of seven and seven banks of one stepped directly on
  seeded random states for 400 steps, with every remedy on (untrusted rows, saturation and one EKF
  reset included), with the paper's printed sign of e2, and with no remedy; torques, virtual controls,
  final weights, covariances and reset counts.
``--save FILE`` writes the fingerprints (JSON); ``--compare FILE`` exits 1 naming each scenario whose
fingerprint differs from the file's; Ctrl-C is one line, exit 130, nothing saved. Typical use around a change
that must not move a bit:

    .venv/bin/python scripts/result_fingerprint.py --save /tmp/before.json     # on the old commit
    .venv/bin/python scripts/result_fingerprint.py --compare /tmp/before.json  # on the new one

``--kernel`` sets the DNBS step (``dnbs.kernel``) of every scenario; the default, ``auto`` as in
config/default.yaml, is the compiled step where it builds (the line it prints says which). ``--kernel c``
compared with ``--kernel numpy`` fingerprints shows that the kernel gives the reference's bits.

Fingerprints depend on the numeric platform (pa10_dnbs/numeric_platform.py, printed first): the closed-loop
scenarios on OpenBLAS's kernels (the plant's solve) and numpy's SIMD loops, the banks on numpy's tanh. ``--save``
keeps the platform's line (key ``platform``) and ``--compare`` says when it differs: compare on one machine,
or set ``OPENBLAS_CORETYPE`` (and ``NPY_DISABLE_CPU_FEATURES``) to the other run's platform.
"""
from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from pa10_dnbs.interrupt import EXIT_INTERRUPTED, STOP_SIGNALS, on_second_sigint, say, two_stage_sigint  # noqa: E402

INTERRUPTED = "result_fingerprint: interrupted before the fingerprints were done: nothing saved or compared"


def _interrupted_while_loading(signum, frame) -> None:
    """A stop before main runs: the one line and exit 130 at once (a traceback from an import otherwise)."""
    os.write(2, (INTERRUPTED + "\n").encode())
    os._exit(EXIT_INTERRUPTED)


if __name__ == "__main__":   # Ctrl-C while numpy and the simulator load: the one line, not an import traceback
    for _sig in STOP_SIGNALS:
        signal.signal(_sig, _interrupted_while_loading)

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import hashlib  # noqa: E402
import json  # noqa: E402

import numpy as np  # noqa: E402

from bench_record import record_path  # noqa: E402
from pa10_dnbs.accel.choice import KERNELS, auto_kernel  # noqa: E402
from pa10_dnbs.atomic_file import atomic_path  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.settings import replace_in  # noqa: E402
from pa10_dnbs.controller_factory import dnbs_params  # noqa: E402
from pa10_dnbs.core.dnbs_controller import DNBSControllers, Remedies  # noqa: E402
from pa10_dnbs.core.reference import ReferenceSample  # noqa: E402
from pa10_dnbs.numeric_platform import numeric_platform, platform_line  # noqa: E402
from pa10_dnbs.paths import share_path  # noqa: E402
from pa10_dnbs.sim.closed_loop import Disturbances, simulate  # noqa: E402

ALL_REMEDIES = Remedies(robust_term=True, velocity_feedforward=True, alpha_gain_per_s=5.0,
                        torque_gain_nms_per_rad=np.array([50.0, 50.0, 20.0, 20.0, 1.0, 1.0, 1.0]),
                        anti_windup=True, dead_zone=True, dead_zone_rad=1e-4, dead_zone_rad_s=1e-3,
                        e_modification=True, e_modification_sigma=1e-3, projection=True, weight_bound=0.5,
                        learning_ramp=True, learning_ramp_s=0.05, covariance_bound=True, p_max=1.5)


def digest(arrays: list[np.ndarray]) -> str:
    """SHA-256 of the arrays' shapes and raw bytes, in order."""
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(repr((a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def run_arrays(run) -> list[np.ndarray]:
    """Every float array of a RunData, by field name."""
    return [v for _, v in sorted(vars(run).items()) if isinstance(v, np.ndarray) and v.dtype.kind == "f"]


def closed_loop(config: Path, duration_s: float, disturbances: Disturbances | None = None,
                kernel: str = "auto") -> list[np.ndarray]:
    settings = replace_in(build_settings(config), "dnbs.kernel", kernel)
    return run_arrays(simulate(settings, "dnbs", duration_s, disturbances=disturbances))


def banks(params, steps: int = 400, seed: int = 1, kernel: str = "numpy") -> list[np.ndarray]:
    """A bank of seven and seven banks of one, stepped on the same seeded random inputs."""
    rng = np.random.default_rng(seed)
    bank = DNBSControllers
    if kernel == "auto":
        kernel = auto_kernel().kernel
    if kernel == "c":
        from pa10_dnbs.accel.compiled_dnbs import CompiledDNBSControllers as bank
    seven = bank(params, 7, range(7))
    ones = [bank(params.select([j]), 7, [j]) for j in range(7)]
    rows7, rows1 = [], []
    for k in range(steps):
        x1, x2 = rng.normal(0.0, 0.5, 7), rng.normal(0.0, 2.0, 7)
        if k % 97 == 5:
            x1[3] = 50.0        # a large error: the torque saturates (anti-windup)
        if k == 211:
            x1[2] = np.inf      # a non-finite training error: the EKF guard resets the row
        ref = ReferenceSample(rng.normal(0.0, 0.5, 7), rng.normal(0.0, 1.0, 7), rng.normal(0.0, 0.5, 7))
        active = None if k % 3 else (rng.random(7) > 0.3).astype(float)
        with np.errstate(invalid="ignore"):
            u7 = seven.step(x1, x2, ref, active)
            u1 = [b.step(x1[j:j + 1], x2[j:j + 1],
                         ReferenceSample(*(a[j:j + 1] for a in (ref.position_rad, ref.velocity_rad_s,
                                                                 ref.position_ahead_rad))),
                         None if active is None else active[j:j + 1])[0] for j, b in enumerate(ones)]
        rows7.append(np.concatenate([u7, seven.alpha, seven.torque_unsaturated]))
        rows1.append(np.array(u1))
    resets = np.concatenate([seven.ekf_resets["alpha"], seven.ekf_resets["torque"]])
    return [np.array(rows7), np.array(rows1), seven.ekf.w, seven.ekf.P, resets]


def fingerprints(kernel: str = "auto") -> dict[str, str]:
    default = share_path("config", "default.yaml")
    p = dnbs_params(build_settings(default))
    scenarios = {
        "default": lambda: closed_loop(default, 3.0, kernel=kernel),
        "paper": lambda: closed_loop(share_path("config", "paper.yaml"), 3.0, kernel=kernel),
        "noisy": lambda: closed_loop(default, 2.0, Disturbances(1e-4, 1e-3, 2, 3), kernel=kernel),
        "remedies": lambda: banks(dataclasses.replace(p, remedies=ALL_REMEDIES), kernel=kernel),
        "printed": lambda: banks(dataclasses.replace(p, e2_sign="printed"), kernel=kernel),
        "bare": lambda: banks(dataclasses.replace(p, remedies=Remedies()), kernel=kernel),
    }
    return {name: digest(make()) for name, make in scenarios.items()}


def saved_prints(text: str) -> dict[str, str]:
    """``--compare``'s argparse type: the {scenario: digest} a --save wrote, read before the runs start (not from a
    pipe or a device: a pipe no one writes is read forever)."""
    path = Path(text)
    if path.exists() and not (path.is_file() or path.is_dir()):
        raise argparse.ArgumentTypeError(f"{text!r} is not a regular file (a pipe, device or socket): not read")
    try:
        before = json.loads(path.read_text())
    except IsADirectoryError:
        raise argparse.ArgumentTypeError(f"{text!r} is a directory, not a file written by --save") from None
    except OSError as exc:
        raise argparse.ArgumentTypeError(f"cannot read {text!r}: {exc.strerror}") from None
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise argparse.ArgumentTypeError(f"{text!r} is not a JSON file written by --save") from None
    if not (isinstance(before, dict) and before and all(isinstance(k, str) and isinstance(v, str)
                                                        for k, v in before.items())):
        raise argparse.ArgumentTypeError(f"{text!r} is not a file written by --save (scenario: digest)")
    return before


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    group = ap.add_mutually_exclusive_group()
    group.add_argument("--save", type=record_path, help="write the fingerprints to this JSON file")
    group.add_argument("--compare", type=saved_prints,
                       help="compare with a file written by --save; exit 1 on a difference")
    ap.add_argument("--kernel", choices=KERNELS, default="auto", help="the DNBS step's kernel (dnbs.kernel)")
    args = ap.parse_args()
    platform = platform_line(numeric_platform())
    print(f"numeric platform: {platform}")
    if args.kernel == "auto":
        print(auto_kernel().line)
    prints = fingerprints(args.kernel)
    for name, h in prints.items():
        print(f"{name:10s} {h}")
    if args.save:
        try:
            with atomic_path(args.save) as tmp:   # a failed write (a full disk) leaves the file as it was
                tmp.write_text(json.dumps(dict(prints, platform=platform), indent=1) + "\n")
        except OSError as exc:
            print(f"result_fingerprint: error: --save {args.save}: cannot write it: {exc.strerror or exc}; nothing "
                  "written", file=sys.stderr)
            return 1
    if args.compare:
        before = dict(args.compare)
        saved_on = before.pop("platform", None)
        if saved_on is not None and saved_on != platform:
            print(f"note: saved on another numeric platform ({saved_on}): the closed-loop scenarios can differ "
                  f"with no change of the code")
        differ = sorted(n for n in prints.keys() | before.keys() if prints.get(n) != before.get(n))
        print(f"{len(prints)} scenarios, {len(differ)} differ" + (f": {', '.join(differ)}" if differ else ""))
        return 1 if differ else 0
    return 0


def interruptible_main() -> int:
    """``main`` with Ctrl-C (or SIGTERM) done right: one line, exit 130, nothing saved; a second one ends at once
    (pa10_dnbs/interrupt.py). Outside it the stop signals are ignored: the modules are loaded, and once it has
    returned its exit code stands."""
    for sig in STOP_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    try:
        with two_stage_sigint():
            on_second_sigint("result_fingerprint: interrupted again: stopped at once; nothing saved")
            return main()
    except KeyboardInterrupt:
        say(INTERRUPTED)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(interruptible_main())
