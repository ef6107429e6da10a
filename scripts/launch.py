#!/usr/bin/env python3
"""Start the PA10 node graph: same arguments as ``pa10-dnbs launch``.

    python scripts/launch.py --mode lockstep --controller dnbs --duration 20 --out runs/graph
"""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from pa10_dnbs.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main(["launch", *sys.argv[1:]]))
