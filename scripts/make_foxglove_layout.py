#!/usr/bin/env python3
"""Write config/foxglove_layout.json, the Foxglove layout of the live view (pa10_dnbs/live/layout.py), from the
arm's joint names, its torque limits and its URDF's root link.

    .venv/bin/python scripts/make_foxglove_layout.py [--config FILE] [--arm iiwa] [--namespace NS] [--out FILE]

``--arm``: the arm (default: the config's, the PA10, whose layout is config/foxglove_layout.json);
``--namespace``: the arm's namespace the layout shows (the launcher's --namespace; default /<arm name>).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from bench_record import record_path  # noqa: E402
from pa10_dnbs.arm.arm_file import ArmError  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser  # noqa: E402
from pa10_dnbs.config import ConfigError, default_config_path  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.live.layout import layout_json  # noqa: E402
from pa10_dnbs.wire.topics import arm_topics, check_namespace, default_namespace  # noqa: E402


def namespace(text: str) -> str:
    """``--namespace``'s argparse type: a ROS namespace by the graph's rule (wire/topics.py)."""
    try:
        return check_namespace(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def main() -> int:
    ap = OneLineParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--config", type=Path, default=default_config_path())
    ap.add_argument("--arm", default=None, help="an arm preset or arm file (default: the config's, pa10)")
    ap.add_argument("--namespace", type=namespace, default=None,
                    help="the arm's namespace (default /<arm name>, /pa10)")
    ap.add_argument("--out", type=record_path, default=ROOT / "config" / "foxglove_layout.json")
    args = ap.parse_args()
    try:
        settings = build_settings(args.config, arm=args.arm)
    except ConfigError as exc:  # a bad config file or arm, in one line naming the flag
        ap.error(f"argument {'--arm' if isinstance(exc, ArmError) and args.arm else '--config'}: {exc}")
    arm = settings.arm
    text = layout_json(arm.joint_names, settings.plant.torque_limit_nm, arm.description, arm.chain.root_link,
                       arm_topics(args.namespace or default_namespace(arm.name)))
    args.out.write_text(text)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
