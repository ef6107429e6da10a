"""The mark of an interrupted command's partial outputs (docs/tuning.md, "Interrupting").

A command stopped by Ctrl-C (``study``, ``simulate --controller all``) writes what it completed into ``--out``,
atomically like a whole output, with ``interrupted.json`` at the top: ``{"interrupted": true, "completed": k,
"total": n, "missing": [...], "command": ...}``. The complete outputs' files that other tools read
(``study.json``, ``summary.json``) are not written, so a partial folder cannot be read as a complete one; a rerun
into it is refused like any existing output, with a line that says it is partial (``--force`` replaces it).
"""
from __future__ import annotations

import json
from pathlib import Path

from ..json_text import json_text

PARTIAL_FILE = "interrupted.json"


def write_partial_mark(directory: Path, command: str, completed: int, total: int, missing: list[str]) -> None:
    """``directory/interrupted.json``: ``completed`` of ``total`` units (runs, controllers) done; ``missing``
    names the others."""
    (directory / PARTIAL_FILE).write_text(json_text(
        {"interrupted": True, "completed": completed, "total": total, "missing": missing, "command": command}))


def partial_mark(out: Path) -> dict | None:
    """The mark of ``out`` if it holds an interrupted command's partial outputs, else None."""
    try:
        mark = json.loads((Path(out) / PARTIAL_FILE).read_text())
    except (OSError, ValueError):
        return None
    return mark if isinstance(mark, dict) and mark.get("interrupted") is True else None


def partial_banner(completed: int, total: int, unit: str) -> str:
    """The first lines of a partial report (Markdown)."""
    return (f"**PARTIAL: interrupted (Ctrl-C) after {completed} of {total} {unit}.** Only the completed {unit} "
            f"are here; the others were stopped or never started (`{PARTIAL_FILE}` lists them). Not a complete "
            "result: rerun the command with `--force` to replace this folder with a complete one.")
