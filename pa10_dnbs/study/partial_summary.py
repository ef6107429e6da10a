"""An interrupted study's outputs: the completed runs' rows, marked partial (report/partial.py).

``study.partial.json`` (the rows, as in study.json, plus ``interrupted``, ``completed``, ``total``, ``missing``),
``study.partial.md`` (one line per completed run, then the runs not complete) and ``interrupted.json``. No
study.json / study.md / study.png: their medians, worst cases and targets need every run.
"""
from __future__ import annotations

from pathlib import Path

from ..json_text import json_text

from ..report.partial import partial_banner, write_partial_mark


def run_name(scenario: str, controller: str, seed: int) -> str:
    return f"{scenario}/{controller}/seed {seed}"


def _fmt(v, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def write_partial_study(directory: Path, rows: list[dict], all_runs: list[tuple[str, str, int]], command: str,
                        head: dict) -> None:
    """Write the completed ``rows`` (one per finished run of ``all_runs``) into ``directory``; ``head``: the
    fields study.json carries before its rows (config_file, arm, duration_s)."""
    by_key = {(r["scenario"], r["controller"], r["seed"]): r for r in rows}
    kept = [by_key[k] for k in all_runs if k in by_key]
    missing = [run_name(*k) for k in all_runs if k not in by_key]
    total = len(all_runs)
    (directory / "study.partial.json").write_text(json_text(
        {"interrupted": True, "completed": len(kept), "total": total, **head, "missing": missing, "rows": kept}))
    lines = ["# Robustness study: PARTIAL (interrupted)", "", partial_banner(len(kept), total, "runs"), "",
             f"`{command}`", "",
             "| scenario | controller | seed | worst RMS [rad] | settled [s] | max abs [rad] | torque variation | "
             "diverged |", "|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r['scenario']} | {r['controller']} | {r['seed']} | {_fmt(r['worst_rms_error_rad'], '.3e')} | "
              f"{_fmt(r['worst_settling_time_s'], '.3f')} | {_fmt(r['worst_max_abs_error_run_rad'], '.4f')} | "
              f"{_fmt(r['worst_torque_variation'], '.2f')} | {'yes' if r['diverged'] else 'no'} |" for r in kept]
    lines += ["", f"Not complete (stopped or never started, {len(missing)}): "
              + (", ".join(missing) if missing else "none"), ""]
    (directory / "study.partial.md").write_text("\n".join(lines))
    write_partial_mark(directory, command, len(kept), total, missing)
