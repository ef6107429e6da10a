#!/usr/bin/env python3
"""Compare the stamped messages of two bags byte for byte: the check of a re-drive (docs/bags.md).

For each topic (default: the arm's joint_states and its per-joint state topics, found in the first
bag), the messages are keyed by their header stamp [ns]; the line per topic says how many stamps both bags
hold, how many payloads differ, and the stamps only one bag has. Exit 0 when every topic is the same in both
(no difference, no stamp missing on either side), 1 otherwise, 2 for a bag that cannot be read.

    .venv/bin/python scripts/compare_bags.py BAG_A BAG_B [--topics /pa10/joint_states ...]
"""
from __future__ import annotations

import struct
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from pa10_dnbs.bag.analysis import bag_arm, bag_joint_names  # noqa: E402
from pa10_dnbs.bag.bag_reader import Bag, BagError  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser  # noqa: E402

STAMP = struct.Struct("<iI")  # std_msgs/Header stamp after the 4-byte CDR encapsulation: sec, nanosec


def stamped(bag: Bag, topic: str) -> dict[int, bytes]:
    """{stamp [ns]: payload} of ``topic`` (the last payload of a stamp sent twice, e.g. a resent state)."""
    out = {}
    for _, _, _, data in bag.messages([topic]):
        sec, nanosec = STAMP.unpack_from(bytes(data), 4)
        out[sec * 1_000_000_000 + nanosec] = bytes(data)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("bag_a", type=Path)
    ap.add_argument("bag_b", type=Path)
    ap.add_argument("--topics", nargs="+", default=None,
                    help="stamped topics to compare (default: joint_states and the per-joint states)")
    args = ap.parse_args(argv)
    same = True
    try:
        with Bag(args.bag_a) as a, Bag(args.bag_b) as b:
            arm = bag_arm(a)
            topics = args.topics or [arm.joint_states] + [arm.state(j) for j in bag_joint_names(a, arm)]
            for bag in (a, b):
                bag.require_topics(topics, "the comparison")
            for t in topics:
                x, y = stamped(a, t), stamped(b, t)
                both = x.keys() & y.keys()
                differ = sorted(k for k in both if x[k] != y[k])
                only_a, only_b = len(x.keys() - y.keys()), len(y.keys() - x.keys())
                same = same and not differ and not only_a and not only_b
                print(f"{t}: {len(differ)} of {len(both)} messages differ"
                      + (f" (first at stamp {differ[0]} ns)" if differ else "")
                      + (f"; {only_a} stamps only in {args.bag_a}" if only_a else "")
                      + (f"; {only_b} stamps only in {args.bag_b}" if only_b else ""))
    except BagError as exc:
        print(f"compare_bags: {exc}", file=sys.stderr)
        return 2
    print("the same, bit for bit" if same else "DIFFERENT")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(script_main.run(main, "compare_bags", interrupted="nothing compared: run the same command again"))
