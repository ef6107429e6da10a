#!/usr/bin/env python3
"""Regenerate the README's results and figures blocks from the benchmark records in benchmarks/*.json.

The figures block is the part of README.md between the lines ``<!-- figures: begin (scripts/readme_figures.py) -->``
and ``<!-- figures: end -->``: a table with one row per recorded figure (the main job's lockstep real-time
factor and bag size, the in-process DNBS / PID cost, the bag writer's CPU, the node graph's realtime on-time
fraction, the test suite's count and time), each with the command that measured it, its date (UTC) and the
machine's load before and after. The results block (``<!-- results: begin ... -->`` to ``<!-- results: end -->``)
is the per-arm table of DNBS / PID / CTC that scripts/preset_results.py records; the equal-budget block, the tuned controllers of each arm side by side
(scripts/equal_budget.py's comparisons kept in benchmarks/equal_budget/<arm>/: their comparison.md and each
controller's tune.json; tune/comparison.py ``arms_table``). The records are written by the
benchmarks' ``--save-record FILE`` (scripts/bench_record.py), which also hold the commit and the machine;
nothing in either block is typed by hand.

    .venv/bin/python scripts/readme_figures.py            # rewrite the block
    .venv/bin/python scripts/readme_figures.py --check    # exit 1 if the block is not what the records give

Exit codes: 0 done (or up to date), 1 ``--check`` found a difference, 2 bad input (no markers, a record
without a key, a benchmark this script has no row for).
"""
from __future__ import annotations

import argparse
import difflib
import shlex
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import bench_record  # noqa: E402

from pa10_dnbs.atomic_file import atomic_path  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser  # noqa: E402

BEGIN = "<!-- figures: begin (scripts/readme_figures.py) -->"
END = "<!-- figures: end -->"
RESULTS_BEGIN = "<!-- results: begin (scripts/readme_figures.py) -->"
RESULTS_END = "<!-- results: end -->"
RESULTS = "preset_results"   # the benchmark of the results block (scripts/preset_results.py)
BUDGET_BEGIN = "<!-- equal budget: begin (scripts/readme_figures.py) -->"
BUDGET_END = "<!-- equal budget: end -->"
BUDGET = Path("equal_budget")   # under the records' folder: one comparison folder per arm
BUDGET_ORDER = ("pa10", "iiwa", "panda")   # the columns' order; other arms after them, by name
HEADER = ["| figure | measured | by | when (UTC), load avg before -> after |", "|---|---|---|---|"]


class BadInput(Exception):
    """A README without the markers, or a record this script cannot read."""


def short_command(command: str) -> str:
    """The command without the interpreter, the scripts/ folder and ``--save-record FILE``."""
    words = shlex.split(command)
    out, skip = [], False
    for w in words:
        if skip:
            skip = False
            continue
        if w == "--save-record":
            skip = True
            continue
        if w.startswith("--save-record="):
            continue
        out.append(w)
    if out and out[0].endswith("python"):
        out = out[1:]
    if out and out[0].startswith("scripts/") and out[0].endswith(".py"):
        out[0] = out[0][len("scripts/"):]
    return " ".join(shlex.quote(w) for w in out)


def when(rec: dict) -> str:
    """``2026-11-25 14:21, 3.4 -> 4.1 on 2 CPUs`` (1-minute load averages)."""
    date = rec["date_utc"].replace("T", " ")[:16]
    before, after = (f"{x[0]:.1f}" if x else "?" for x in (rec["load_before"], rec["load_after"]))
    return f"{date}, {before} -> {after} on {rec['machine']['nproc']} CPUs"


def _main_job(rec: dict) -> list[tuple[str, str]]:
    f = rec["figures"]
    policy = f"SCHED_FIFO {f['rt_priority']}" if f["rt_priority"] else "the default policy"
    return [(f"main job, {f['duration_s']:g} s of lockstep DNBS, recorded",
             f"**{f['real_time_factor']:.2f}x** real time ({policy}; {f['wall_time_total_s']:.0f} s in all); bag "
             f"{f['bag_mb']:.1f} MB zstd, {f['bag_mb_per_simulated_s']:.2f} MB per simulated second")]


def _bench_sim(rec: dict) -> list[tuple[str, str]]:
    f = rec["figures"]
    names = {"auto": "compiled (`auto`, the default)", "c": "compiled (`c`)", "numpy": "numpy"}
    ratios = ", ".join(f"{names.get(k, k)} **{f['dnbs_over_pid_median'][k]:.2f}x**" if k != "numpy"
                       else f"{names[k]} {f['dnbs_over_pid_median'][k]:.2f}x" for k in f["kernels"])
    return [("in-process DNBS run against PID run (wall time, medians)",
             f"{ratios} ({f['repeat']} x {f['duration_s']:g} s each)")]


def _bench_bag_writer(rec: dict) -> list[tuple[str, str]]:
    f = rec["figures"]
    return [(f"bag writer CPU, the main job's messages ({f['compression']})",
             f"{f['cpu_us_per_message']:.2f} us per message, {f['cpu_ms_per_simulated_s']:.0f} ms per simulated "
             f"second ({f['messages']} messages, best of {f['repeat']})")]


def _bench_graph(rec: dict) -> list[tuple[str, str]]:
    f = rec["figures"]
    runs = f"{f['repeat']} x {f['duration_s']:g} s runs, {f['policy']}, {f['controller'].upper()}, {f['config']}"
    rows = []
    if f.get("lockstep_factor_median") is not None:
        rows.append(("node graph: lockstep real-time factor", f"{f['lockstep_factor_median']:.2f}x ({runs})"))
    rt = f.get("realtime") or {}
    if rt:
        at, target = f.get("sustainable_factor"), f"{100 * f['on_time_target']:.0f} %"
        tried = ", ".join(f"R = {r}: {100 * v['on_time_fraction_median']:.2f} %" for r, v in rt.items())
        value = (f"highest factor tried with >= {target} on time: **{at:g}**" if at is not None
                 else f"no factor tried had >= {target} on time")
        rows.append(("node graph: realtime, ticks with every effort on time", f"{tried}; {value} ({runs})"))
    return rows


def _tests(rec: dict) -> list[tuple[str, str]]:
    f = rec["figures"]
    args = f["pytest_args"]
    marker = args[args.index("-m") + 1] if "-m" in args[:-1] else None
    tier = {None: "the full suite", "not graph": 'the fast tier, `-m "not graph"`'}.get(marker, f'`-m "{marker}"`')
    if "-n" in args[:-1]:
        tier += f", `-n {args[args.index('-n') + 1]}`"
    failed = f", **{f['failed'] + f['errors']} failed**" if f["failed"] + f["errors"] else ""
    return [(f"tests ({tier})", f"{f['passed']} passed{failed}, {f['skipped']} skipped; pytest "
             f"{_minutes(f['pytest_s'])}")]


def _minutes(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 100 else f"{int(seconds // 60)} min {seconds % 60:02.0f} s"


ROWS = {"main_job": _main_job, "bench_sim": _bench_sim, "bench_graph": _bench_graph,
        "bench_bag_writer": _bench_bag_writer, "tests": _tests}  # the table's order


def read_records(folder: Path) -> list[dict]:
    """Every record of ``folder``, in the table's order (then by file name)."""
    recs = []
    for path in sorted(folder.glob("*.json")):
        if not path.is_file():   # a pipe would hold the read forever
            raise BadInput(f"{path}: not a regular file")
        try:
            rec = bench_record.read(path)
        except (ValueError, OSError) as exc:  # json.JSONDecodeError is a ValueError
            raise BadInput(str(exc) if str(exc).startswith(str(path)) else f"{path}: {exc}") from None
        if rec["benchmark"] not in ROWS and rec["benchmark"] != RESULTS:
            raise BadInput(f"{path}: no README row for benchmark '{rec['benchmark']}' (scripts/readme_figures.py ROWS)")
        rec["_file"] = path.name
        recs.append(rec)
    order = list(ROWS) + [RESULTS]
    return sorted(recs, key=lambda r: (order.index(r["benchmark"]), r["_file"]))


def table(recs: list[dict]) -> list[str]:
    """The block's lines between the markers."""
    lines = list(HEADER)
    recs = [r for r in recs if r["benchmark"] != RESULTS]
    for rec in recs:
        try:
            rows = ROWS[rec["benchmark"]](rec)
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise BadInput(f"benchmarks/{rec['_file']}: cannot read its figures ({type(exc).__name__}: {exc})") \
                from None
        by = f"`{short_command(rec['figures'].get('ran') or rec['command'])}` ([record](benchmarks/{rec['_file']}))"
        for figure, value in rows:
            lines.append(f"| {figure} | {value} | {by} | {when(rec)} |")
    if not recs:
        lines.append("| (no records in benchmarks/) | | | |")
    return lines


#: the results block's rows: (label, field, number format, DNBS in bold)
RESULT_ROWS = [("settled into 1e-2 rad after [s]", "settled_s", "{:.2f}", True),
               ("max abs error over the run [rad]", "max_abs_error_rad", "{:.3f}", False),
               ("torque variation (sum abs d tau / limit)", "torque_variation", "{:.1f}", False),
               ("steps at a torque limit after {startup}", "steps_at_limit_after_startup", "{:d}", False),
               ("RMS error over {window} [rad]", "rms_rad", "{:.1e}", True)]


def _short_e(text: str) -> str:
    """``3.2e-05`` as ``3.2e-5`` (the README's form)."""
    mantissa, e, exponent = text.partition("e")
    return f"{mantissa}e{int(exponent)}" if e else text


def results_table(recs: list[dict], folder: str = "benchmarks") -> list[str]:
    """The results block's lines: one column per arm of the preset_results record, one row per figure, each
    cell DNBS / PID / CTC (``never`` for a run that did not settle, ``diverged`` for one without a figure), then the
    line naming the record."""
    found = [r for r in recs if r["benchmark"] == RESULTS]
    if len(found) != 1:
        raise BadInput(f"{folder}/ holds {len(found)} {RESULTS} records: the results block needs exactly one "
                       "(scripts/preset_results.py --save-record benchmarks/preset_results.json)")
    rec = found[0]
    try:
        arms, kinds = rec["figures"]["arms"], rec["figures"]["controllers"]
        first = arms[0]
        window = f"[{first['window_s'][0]:g}, {first['window_s'][1]:g}) s"
        startup = f"{first['startup_s']:g} s"
        heads = [f"{a['description'].split(' (')[0]} (`--arm {a['arm']}`{', default' if a['arm'] == 'pa10' else ''})"
                 for a in arms]
        lines = ["| | " + " | ".join(heads) + " |", "|---|" + "---|" * len(arms)]
        for label, field, fmt, bold in RESULT_ROWS:
            cells = []
            for a in arms:
                parts = []
                for k in kinds:
                    v = a[k][field]
                    text = (("never" if field == "settled_s" else "diverged") if v is None   # no value: why
                            else _short_e(fmt.format(v)))
                    parts.append(f"**{text}**" if bold and k == "dnbs" else text)
                cells.append(" / ".join(parts))
            lines.append(f"| {label.format(window=window, startup=startup)} | " + " | ".join(cells) + " |")
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise BadInput(f"benchmarks/{rec['_file']}: cannot read its figures ({type(exc).__name__}: {exc})") from None
    lines += ["", f"`{short_command(rec['command'])}` ([record](benchmarks/{rec['_file']})), {when(rec)}"]
    return lines


def budget_table(folder: Path) -> list[str]:
    """The equal-budget block's lines: the tuned controllers of every comparison in ``folder``/BUDGET side by side
    (tune/comparison.py ``arms_table``: refused unless the budgets are equal), then the line naming them."""
    from pa10_dnbs.tune.comparison import arms_table

    root = folder / BUDGET
    dirs = sorted((d for d in root.iterdir() if d.is_dir()) if root.is_dir() else [],
                  key=lambda d: (BUDGET_ORDER.index(d.name) if d.name in BUDGET_ORDER else len(BUDGET_ORDER), d.name))
    if not dirs:
        raise BadInput(f"{root}: no equal-budget comparison (scripts/equal_budget.py --out {root}/ARM)")
    try:
        lines = arms_table(dirs).rstrip("\n").split("\n")
    except (OSError, ValueError, KeyError, TypeError, IndexError) as exc:
        raise BadInput(f"{root}: cannot read the comparisons ({type(exc).__name__}: {exc})") from None
    links = ", ".join(f"[{d.name}](benchmarks/{BUDGET.as_posix()}/{d.name}/comparison.md)" for d in dirs)
    return lines + ["", f"Each arm's comparison, with its command and each controller's best point: {links}"]


def render(readme: str, block: list[str], begin: str = BEGIN, end: str = END, name: str = "figures") -> str:
    """``readme`` with the lines between the markers ``begin`` and ``end`` (its ``name`` block) replaced by
    ``block``."""
    lines = readme.split("\n")
    try:
        i, j = lines.index(begin), lines.index(end)
    except ValueError:
        raise BadInput(f"README.md has no {name} block: the lines '{begin}' and '{end}'") from None
    if j < i:
        raise BadInput(f"README.md: '{end}' comes before '{begin}'")
    return "\n".join(lines[:i + 1] + block + lines[j:])


def records_folder(text: str) -> Path:
    """``--records``' argparse type: an existing folder (a missing one would render an empty block)."""
    path = Path(text)
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not a folder of benchmark records")
    return path


def readme_file(text: str) -> Path:
    """``--readme``'s argparse type: an existing regular file (not a folder, nor a pipe that would hold the read)."""
    path = Path(text)
    if not text or not path.is_file():
        raise argparse.ArgumentTypeError(f"{text!r} is not a file")
    return path


def main(argv: list[str] | None = None) -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if the README's block differs from the records'")
    ap.add_argument("--readme", type=readme_file, default=bench_record.ROOT / "README.md")
    ap.add_argument("--records", type=records_folder, default=bench_record.RECORDS, help="the records' folder (benchmarks/)")
    args = ap.parse_args(argv)
    try:
        try:
            old = args.readme.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            raise BadInput(f"--readme: {args.readme}: cannot read it as text ({exc})") from None
        recs = read_records(args.records)
        new = render(render(old, table(recs)), results_table(recs, str(args.records)), RESULTS_BEGIN, RESULTS_END,
                     "results")
        new = render(new, budget_table(args.records), BUDGET_BEGIN, BUDGET_END, "equal budget")
    except (BadInput, OSError) as exc:
        print(f"readme_figures: {exc}", file=sys.stderr)
        return 2
    if args.check:
        if new == old:
            print(f"readme_figures: {args.readme.name}'s generated blocks match {args.records.name}/")
            return 0
        diff = difflib.unified_diff(old.splitlines(), new.splitlines(), "README.md", "from the records", lineterm="")
        print("\n".join(diff))
        print(f"readme_figures: {args.readme.name}'s blocks are not what {args.records.name}/*.json give: "
              "run .venv/bin/python scripts/readme_figures.py (and commit the records with it)", file=sys.stderr)
        return 1
    if new != old:
        with atomic_path(args.readme) as tmp:
            tmp.write_text(new)
        print(f"readme_figures: rewrote the blocks of {args.readme}")
    else:
        print(f"readme_figures: {args.readme.name} already up to date")
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "readme_figures", interrupted="the README is as it was: run the same command "
                                                                 "again"))
