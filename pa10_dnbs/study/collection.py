"""The collection benchmark: every serial arm of example-robot-data, bare and with an arm file.

One row per (arm, mode): accepted or refused (the one line the intake gives), the rule's warnings, and per
controller (DNBS, PID, CTC) the worst joint's RMS error over the window [rad], settling time into 1e-2 rad [s],
torque variation, steps at a torque limit after 0.2 s, max |e| [rad] and whether the run diverged (non-finite,
or |e| > 1 rad, the study's mark). :func:`targets` checks a row against the issue's targets;
:func:`markdown_table` writes the table docs/arms.md shows. scripts/arm_collection.py runs it.
"""
from __future__ import annotations

import contextlib
import io
import math
import sysconfig
import time
from pathlib import Path

import numpy as np

#: example-robot-data's version the benchmark is pinned to (requirements-collection.txt).
COLLECTION_VERSION = "6.0.0"
CONTROLLERS = ("dnbs", "pid", "ctc")

#: key -> (URDF under example-robot-data's robots/, what it is). Every serial arm of 6.0.0.
ARMS = {
    "ur3": ("ur_description/urdf/ur3_joint_limited_robot.urdf", "Universal Robots UR3"),
    "ur5": ("ur_description/urdf/ur5_joint_limited_robot.urdf", "Universal Robots UR5"),
    "ur10": ("ur_description/urdf/ur10_joint_limited_robot.urdf", "Universal Robots UR10"),
    "kinova": ("kinova_description/robots/kinova.urdf", "Kinova Jaco 2 j2s6s200"),
    "xarm7": ("xarm_description/urdf/xarm7.urdf", "UFACTORY xArm7"),
    "z1": ("z1_description/urdf/z1.urdf", "Unitree Z1"),
    "so100": ("so_arm_description/urdf/so100.urdf", "SO-100 (SO-ARM100)"),
    "so101": ("so_arm_description/urdf/so101.urdf", "SO-101"),
    "talos_left_arm": ("talos_data/robots/talos_left_arm.urdf", "PAL TALOS left arm"),
    "panda": ("panda_description/urdf/panda.urdf", "Franka Emika Panda (no armature)"),
    "twodof": ("asr_twodof_description/urdf/TwoDofs.urdf", "ASR 2-DOF arm"),
    "double_pendulum": ("double_pendulum_description/urdf/double_pendulum_continuous.urdf", "double pendulum"),
}
MODES = ("bare", "arm_file")

# The targets
BARE_CTC_RMS = 1e-4
AIM_SETTLE_S, AIM_RMS = 1.0, 1e-4
FILE_SETTLE_S, FILE_RMS, FILE_TV, FILE_LIMIT_STEPS = 0.5, 2e-5, 10.0, 0


def collection_root() -> Path | None:
    """example-robot-data's robots/ folder in this interpreter's site-packages, or None when not installed."""
    root = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
    return root if root.is_dir() else None


def arm_file(key: str) -> Path:
    """The shipped arm file of ``key``: urdf/collection/<key>/arm.yaml."""
    from ..paths import share_path
    return share_path("urdf", "collection", key, "arm.yaml")


def _controller_figures(run, settings, duration_s: float) -> dict:
    from ..report.metrics_file import metrics_dict, metrics_settings

    m = metrics_dict(run, metrics_settings(settings, duration_s))
    err = run.error_rad
    max_abs = float(np.nanmax(np.abs(err))) if np.any(np.isfinite(err)) else math.inf

    def num(x):
        return float(x) if x is not None and math.isfinite(x) else None

    return {"rms_rad": num(m["worst_rms_error_rad"]), "settled_s": num(m["worst_settling_time_s"]),
            "torque_variation": num(m["worst_torque_variation"]),
            "steps_at_limit_after_startup": m["steps_at_limit_after_s"],
            "max_abs_error_rad": max_abs if math.isfinite(max_abs) else None,
            "diverged": m["diverged"] is not None,
            "worst_rms_joint": max(m["joints"], key=lambda j: j["rms_error_rad"]
                                   if math.isfinite(j["rms_error_rad"]) else math.inf)["name"]}


def run_row(key: str, mode: str, spec: str, duration_s: float) -> dict:
    """One row: the arm ``spec`` (URDF or arm file) loaded as ``--arm`` would, then each controller for
    ``duration_s``. A refused arm is a row with its one line; an exception that is not a refusal is a row too
    (status ``error``), so one arm cannot stop the table."""
    from ..accel.choice import resolve_kernel
    from ..config import ConfigError, default_config_path
    from ..run_settings import build_settings
    from ..sim.closed_loop import simulate

    row = {"arm": key, "mode": mode, "spec": spec, "status": "accepted", "reason": "", "warnings": []}
    t0 = time.perf_counter()
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            settings = resolve_kernel(build_settings(default_config_path(), arm=spec))
    except ConfigError as exc:
        row.update(status="refused", reason=str(exc).splitlines()[0])
        return row
    except Exception as exc:  # noqa: BLE001 - a row says what went wrong instead of ending the table
        row.update(status="error", reason=f"{type(exc).__name__}: {exc}".splitlines()[0])
        return row
    row["warnings"] = [line.split(": ", 2)[-1] for line in err.getvalue().splitlines() if line.startswith("warning:")]
    row["n_joints"] = settings.n_joints
    for kind in CONTROLLERS:
        try:
            with np.errstate(all="ignore"), contextlib.redirect_stderr(io.StringIO()):
                run = simulate(settings, kind, duration_s)
            row[kind] = _controller_figures(run, settings, duration_s)
        except Exception as exc:  # noqa: BLE001
            row[kind] = {"error": f"{type(exc).__name__}: {exc}".splitlines()[0]}
    row["wall_time_s"] = time.perf_counter() - t0
    return row


def targets(row: dict) -> dict:
    """{target: True/False} of the issue's targets that apply to ``row`` (empty for a refused row)."""
    if row["status"] != "accepted" or any("error" in row.get(k, {}) for k in CONTROLLERS):
        return {}
    d, p, c = row["dnbs"], row["pid"], row["ctc"]

    def below(x, y):
        return x is not None and y is not None and x <= y

    if row["mode"] == "bare":
        return {"CTC <= 1e-4 rad": below(c["rms_rad"], BARE_CTC_RMS),
                "DNBS never diverges": not d["diverged"],
                "aim: DNBS settles by 1 s": below(d["settled_s"], AIM_SETTLE_S),
                "aim: DNBS RMS <= 1e-4 rad": below(d["rms_rad"], AIM_RMS),
                "aim: DNBS ahead of PID": d["rms_rad"] is not None and (p["rms_rad"] is None or d["rms_rad"] < p["rms_rad"])}
    return {"DNBS settles by 0.5 s": below(d["settled_s"], FILE_SETTLE_S),
            "DNBS RMS <= 2e-5 rad": below(d["rms_rad"], FILE_RMS),
            "DNBS torque variation <= 10": below(d["torque_variation"], FILE_TV),
            "DNBS 0 steps at a limit after 0.2 s": d["steps_at_limit_after_startup"] == FILE_LIMIT_STEPS,
            "DNBS never diverges": not d["diverged"]}


def _g(x, fmt="{:.1e}") -> str:
    return "-" if x is None else fmt.format(x)


def _cell(row: dict, field: str, fmt: str) -> str:
    parts = []
    for k in CONTROLLERS:
        f = row.get(k, {})
        if "error" in f:
            parts.append("error")
        elif field == "settled_s" and f.get("settled_s") is None:
            parts.append("never")
        else:
            v = f.get(field)
            parts.append(_g(v, fmt) + ("!" if field == "rms_rad" and f.get("diverged") else ""))
    return " / ".join(parts)


def markdown_table(rows: list[dict]) -> str:
    """The table of docs/arms.md: one line per (arm, mode); ``!`` marks a diverged run."""
    out = ["| arm | mode | result | RMS over the window [rad] DNBS / PID / CTC | settled [s] | torque variation | "
           "steps at limit after 0.2 s | targets missed |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["status"] != "accepted":
            reason = r["reason"].replace("|", "/")
            root = collection_root()
            if root is not None:
                reason = reason.replace(str(root) + "/", "")
            out.append(f"| {r['arm']} | {r['mode']} | {r['status']}: {reason} | | | | | |")
            continue
        missed = [t for t, ok in targets(r).items() if not ok]
        out.append(f"| {r['arm']} | {r['mode']} | accepted ({r['n_joints']} joints) | {_cell(r, 'rms_rad', '{:.1e}')} | "
                   f"{_cell(r, 'settled_s', '{:.2f}')} | {_cell(r, 'torque_variation', '{:.1f}')} | "
                   f"{_cell(r, 'steps_at_limit_after_startup', '{:d}')} | {'; '.join(missed) or 'none'} |")
    return "\n".join(out) + "\n"


def compact_table(rows: list[dict]) -> str:
    """The README's table: one line per arm, the worst joint's RMS [rad] DNBS / PID / CTC bare and with the arm
    file, and DNBS's settling time [s] in each mode (``!``: diverged)."""
    out = ["| arm | bare: RMS DNBS / PID / CTC [rad] | arm file: RMS DNBS / PID / CTC [rad] | DNBS settled [s] "
           "bare / arm file |", "|---|---|---|---|"]
    for key in dict.fromkeys(r["arm"] for r in rows):
        by = {r["mode"]: r for r in rows if r["arm"] == key}

        def rms(mode):
            r = by.get(mode)
            if r is None:
                return "-"
            return _cell(r, "rms_rad", "{:.1e}") if r["status"] == "accepted" else "refused"

        def settled(mode):
            r = by.get(mode)
            if r is None or r["status"] != "accepted" or "error" in r.get("dnbs", {}):
                return "-"
            return _g(r["dnbs"].get("settled_s"), "{:.2f}") if r["dnbs"].get("settled_s") is not None else "never"
        out.append(f"| {key} | {rms('bare')} | {rms('arm_file')} | {settled('bare')} / {settled('arm_file')} |")
    return "\n".join(out) + "\n"


STUDY_CONTROLLERS = ("dnbs", "pid")
STUDY_SEEDS = 3


def study_summary(key: str, duration_s: float, jobs: int) -> dict:
    """Every study scenario x DNBS and PID x STUDY_SEEDS seeds on ``key``'s arm file (study/runner.py): per
    scenario DNBS's worst seed and PID's best seed (worst joint's RMS [rad]) and DNBS's diverged runs; a scenario
    the arm cannot track (study/feasibility.py) is not run: its entry holds its one line under ``infeasible``."""
    from ..config import default_config_path
    from ..run_settings import build_settings
    from .feasibility import infeasible_scenarios
    from .runner import run_study
    from .scenarios import SCENARIOS

    with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
        settings = build_settings(default_config_path(), arm=str(arm_file(key)))
    t0 = time.perf_counter()
    infeasible = infeasible_scenarios(settings, list(SCENARIOS), duration_s)
    feasible = [sc for sc in SCENARIOS if sc not in infeasible]
    rows = run_study(settings, feasible, STUDY_CONTROLLERS, STUDY_SEEDS, duration_s, workers=jobs) if feasible else []
    out = {"seeds": STUDY_SEEDS, "scenarios": {}, "wall_time_s": round(time.perf_counter() - t0, 1)}
    for sc in SCENARIOS:
        if sc in infeasible:
            out["scenarios"][sc] = {"infeasible": infeasible[sc]}
            continue
        d = [r for r in rows if r["scenario"] == sc and r["controller"] == "dnbs"]
        p = [r for r in rows if r["scenario"] == sc and r["controller"] == "pid"]
        dw = max((r["worst_rms_error_rad"] if r["worst_rms_error_rad"] is not None else math.inf) for r in d)
        pb = min((r["worst_rms_error_rad"] if r["worst_rms_error_rad"] is not None else math.inf) for r in p)
        out["scenarios"][sc] = {"dnbs_worst_rad": dw if math.isfinite(dw) else None,
                                "pid_best_rad": pb if math.isfinite(pb) else None,
                                "dnbs_below_pid": dw < pb, "dnbs_diverged": sum(r["diverged"] for r in d)}
    return out


def _infeasible_note(line: str) -> str:
    """'payload_5kg (joint4 needs 31.2 N m, limit 30)' from a feasibility line."""
    import re

    m = re.match(r"(\S+): infeasible on arm \S+: joint (\S+) needs (\S+) N m .*its limit is (\S+) N m", line)
    return f"{m[1]} ({m[2]} needs {m[3]} N m, limit {m[4]})" if m else line.split(":")[0]


def study_table(rows: list[dict]) -> str:
    """One line per arm with a study: in how many feasible scenarios DNBS's worst seed is below PID's best, and
    the scenarios the arm cannot track (not run: the joint, the torque it needs and its limit)."""
    out = ["| arm (arm file) | feasible scenarios where DNBS's worst seed < PID's best | DNBS runs diverged | "
           "feasible scenarios where not | DNBS worst RMS over the feasible scenarios [rad] | "
           "infeasible for the arm (not run) |", "|---|---|---|---|---|---|"]
    for r in rows:
        st = r.get("study")
        if not st:
            continue
        sc = {k: v for k, v in st["scenarios"].items() if "infeasible" not in v}
        bad = [v["infeasible"] for v in st["scenarios"].values() if "infeasible" in v]
        below = [k for k, v in sc.items() if v["dnbs_below_pid"]]
        worst = max(((v["dnbs_worst_rad"] or math.inf) for v in sc.values()), default=None)
        out.append(f"| {r['arm']} | {len(below)} of {len(sc)} | {sum(v['dnbs_diverged'] for v in sc.values())} of "
                   f"{len(sc) * st['seeds']} | {', '.join(k for k in sc if k not in below) or '-'} | {_g(worst)} | "
                   f"{'; '.join(_infeasible_note(b) for b in bad) or '-'} |")
    return "\n".join(out) + "\n" if len(out) > 2 else ""
