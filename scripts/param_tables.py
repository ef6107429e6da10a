#!/usr/bin/env python3
"""Print the parameter tables of docs/graph.md (Markdown) from the nodes' descriptors (``PARAMS`` of each node).

    .venv/bin/python scripts/param_tables.py > /tmp/params.md
"""
from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)

NODES = [("plant", "plant.node"), ("joint_controller_<joint>", "joint_controller_node"), ("reference", "reference_node"),
         ("wire_monitor", "wire_monitor"), ("recorder", "recorder_node"), ("live_view", "live_observer_node")]


def table(params: dict) -> str:
    rows = ["| parameter | default | range | description |", "|---|---|---|---|"]
    for name, p in params.items():
        text = p.description.replace("<", "&lt;").replace(">", "&gt;")
        rows.append(f"| `{name}` | `{p.default_text()}` | {p.range_text()} | {text} |")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    from pa10_dnbs.cli_values import OneLineParser

    OneLineParser(description=__doc__.splitlines()[0]).parse_args(argv)  # --help; no options
    from pa10_dnbs.ros.shm_cleanup import remove_stale, shm_files

    before = shm_files()
    for name, module in NODES:
        params = importlib.import_module(f"pa10_dnbs.ros.{module}").PARAMS
        print(f"### `{name}` (`python -m pa10_dnbs.ros.{module}`)\n\n{table(params)}\n")
    # importing the nodes loads rclpy, whose LTTng-UST creates /dev/shm/lttng-ust-wait-* and leaves them
    remove_stale(shm_files() - before, frozenset({os.getpid()}))
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "param_tables", interrupted="the tables above are complete: run the same "
                                                              "command again"))
