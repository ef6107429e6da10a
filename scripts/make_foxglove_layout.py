#!/usr/bin/env python3
"""Write config/foxglove_layout.json, the Foxglove layout of the live view (pa10_dnbs/live/layout.py), from the
arm's joint names, its torque limits and its URDF's root link.

    .venv/bin/python scripts/make_foxglove_layout.py [--config FILE] [--arm iiwa] [--namespace NS] [--out FILE]

``--arm``: the arm (default: the config's, the PA10, whose layout is config/foxglove_layout.json);
``--namespace``: the arm's namespace the layout shows (the launcher's --namespace; default /<arm name>).
``--out`` may be left out only for the PA10 at /pa10 (config/foxglove_layout.json is its layout).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from bench_record import record_path  # noqa: E402
from pa10_dnbs.atomic_file import atomic_path  # noqa: E402
from pa10_dnbs.arm.arm_file import ArmError  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser  # noqa: E402
from pa10_dnbs.config import ConfigError, default_config_path  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.live.layout import layout_json  # noqa: E402
from pa10_dnbs.wire.topics import arm_topics, check_namespace, default_namespace  # noqa: E402


PA10_LAYOUT = ROOT / "config" / "foxglove_layout.json"   # the shipped layout (the live view's default)


def namespace(text: str) -> str:
    """``--namespace``'s argparse type: a ROS namespace by the graph's rule (wire/topics.py)."""
    try:
        return check_namespace(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _keep_pa10_layout(ap: argparse.ArgumentParser, what: str) -> None:
    """Refuse (exit 2) a layout of ``what`` (another arm or namespace) into the shipped PA10 layout."""
    ap.error(f"argument --out: {PA10_LAYOUT.relative_to(ROOT)} is the PA10's layout at /pa10; give the file for "
             f"{what}")


def main() -> int:
    ap = OneLineParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--config", type=Path, default=default_config_path())
    ap.add_argument("--arm", default=None, help="an arm preset or arm file (default: the config's, pa10)")
    ap.add_argument("--namespace", type=namespace, default=None,
                    help="the arm's namespace (default /<arm name>, /pa10)")
    ap.add_argument("--out", type=record_path, default=None,
                    help=f"the layout file (default, for the PA10 at /pa10 only: {PA10_LAYOUT.relative_to(ROOT)})")
    args = ap.parse_args()
    if args.out is None and (args.arm not in (None, "pa10") or args.namespace not in (None, "/pa10")):
        _keep_pa10_layout(ap, " at ".join(w for w in (args.arm or "the config's arm", args.namespace) if w))
    try:
        settings = build_settings(args.config, arm=args.arm)
    except ConfigError as exc:  # a bad config file or arm, in one line naming the flag
        arm_flag = isinstance(exc, ArmError) and args.arm is not None
        ap.error(exc.named({"arm": "argument --arm"}) if arm_flag else f"argument --config: {exc}")
    arm = settings.arm
    ns = args.namespace or default_namespace(arm.name)
    if args.out is None and (arm.name, ns) != ("pa10", "/pa10"):   # a config of another arm
        _keep_pa10_layout(ap, f"{arm.name} at {ns}")
    out = args.out or PA10_LAYOUT
    text = layout_json(arm.joint_names, settings.plant.torque_limit_nm, arm.description, arm.chain.root_link,
                       arm_topics(ns))
    with atomic_path(out) as tmp:
        tmp.write_text(text)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "make_foxglove_layout"))
