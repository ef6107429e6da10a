#!/usr/bin/env python3
"""The plant's M(q), bias torques and forward dynamics against MuJoCo's, arm by arm: one Markdown table.

    .venv/bin/python scripts/dynamics_check.py pa10 iiwa path/to/arm.urdf   # arms by preset name or path
    .venv/bin/python scripts/dynamics_check.py --collection                 # every serial arm of example-robot-data

Each arm is read as ``--arm`` reads it (chain, locked gripper, cleaned copy for PyBullet); MuJoCo reads the
URDF as written (``pa10_dnbs/plant/dynamics_check.py``). Figures: the largest relative difference over
``--states`` seeded random states. ``--collection`` needs example-robot-data installed (131 MB, not in
requirements.txt: ``pip install example-robot-data==6.0.0``); exit 2 naming it otherwise. Exit 1 when an
arm differs by more than ``--tolerance``; exit 2, after the table, when an arm was refused (not checked).
"""
from __future__ import annotations

import sys
import sysconfig
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from pa10_dnbs.arm import load_arm  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, positive, whole_in  # noqa: E402
from pa10_dnbs.config_error import ConfigError  # noqa: E402
from pa10_dnbs.plant.dynamics_check import compare_with_mujoco  # noqa: E402

COLLECTION_ARMS = (  # every serial arm of example-robot-data 6.0.0 (URDF paths under its robots/)
    "ur_description/urdf/ur3_joint_limited_robot.urdf", "ur_description/urdf/ur5_joint_limited_robot.urdf",
    "ur_description/urdf/ur10_joint_limited_robot.urdf", "kinova_description/robots/kinova.urdf",
    "xarm_description/urdf/xarm7.urdf", "z1_description/urdf/z1.urdf", "so_arm_description/urdf/so100.urdf",
    "so_arm_description/urdf/so101.urdf", "talos_data/robots/talos_left_arm.urdf",
    "panda_description/urdf/panda.urdf", "asr_twodof_description/urdf/TwoDofs.urdf")
TOLERANCE = 1e-8  # PyBullet diagonalises an off-diagonal inertia (threshold 1e-6): M to 1e-10, qdd to 3e-9


def collection_root() -> Path | None:
    """example-robot-data's robots/ folder in this interpreter's site-packages, or None when not installed."""
    root = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
    return root if root.is_dir() else None


def main(argv: list[str] | None = None) -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("arms", nargs="*", help="preset names, arm files or URDFs")
    ap.add_argument("--collection", action="store_true", help="every serial arm of example-robot-data")
    ap.add_argument("--states", type=whole_in(1), default=20, help="random states per arm (default 20)")
    ap.add_argument("--tolerance", type=positive, default=TOLERANCE, help=f"largest relative difference allowed "
                    f"(default {TOLERANCE:g})")
    args = ap.parse_args(argv)
    specs: list[str] = list(args.arms)
    if args.collection:
        root = collection_root()
        if root is None:
            print("error: --collection: example-robot-data is not installed (pip install example-robot-data==6.0.0)",
                  file=sys.stderr)
            return 2
        specs += [str(root / p) for p in COLLECTION_ARMS]
    if not specs:
        ap.error("give arms or --collection")
    print(f"| arm | joints (locked) | M(q) | bias torques | forward dynamics |\n|---|---|---|---|---|")
    worst, refused = 0.0, []
    for spec in specs:
        try:
            arm = load_arm(spec)
        except ConfigError as exc:
            print(f"| {Path(spec).name} | refused: {exc} | | | |")
            refused.append(spec)
            continue
        d = compare_with_mujoco(arm, states=args.states)
        worst = max(worst, d.worst)
        locked = f" ({', '.join(arm.locked_joints)})" if arm.locked_joints else ""
        print(f"| {arm.name} | {arm.n_joints}{locked} | {d.mass_matrix:.1e} | {d.bias_torque:.1e} | "
              f"{d.forward_dynamics:.1e} |")
    if len(refused) < len(specs):
        print(f"\nlargest relative difference {worst:.1e} (tolerance {args.tolerance:g}, {args.states} states per "
              "arm)")
    if refused:   # a mistyped arm is no pass
        print(f"dynamics_check: error: {len(refused)} of {len(specs)} arms refused, not checked: "
              f"{', '.join(refused)}", file=sys.stderr)
        return 2
    return 0 if worst <= args.tolerance else 1


if __name__ == "__main__":
    sys.exit(script_main.run(main, "dynamics_check", interrupted="the table is not finished: run the same command "
                                                                 "again"))
