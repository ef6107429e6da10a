"""The Markdown report: metrics tables and the figures."""
from __future__ import annotations

import math

from .metrics_file import diverged_text, guard_text


def _settle(v) -> str:
    return "never" if v is None else f"{v:.3f}"


def _settled_after(v) -> str:
    """'after 0.190 s', or 'never' (a run that did not settle)."""
    return "never" if v is None else f"after {_settle(v)} s"


def metrics_table(metrics: list[dict]) -> str:
    """Window figures: one row per joint, RMS / max |e| / max |torque| per run side by side."""
    tags = [m["controller"].upper() for m in metrics]
    head = "| joint | " + " | ".join(f"{t} RMS [rad] | {t} max abs [rad] | {t} max abs torque [N m]" for t in tags)
    rows = [head + " | limit [N m] |", "|---" * (2 + 3 * len(metrics)) + "|"]
    for j, joint in enumerate(metrics[0]["joints"]):
        cells = [joint["name"]]
        for m in metrics:
            jm = m["joints"][j]
            cells += [f"{jm['rms_error_rad']:.3e}", f"{jm['max_abs_error_rad']:.3e}", f"{jm['max_abs_torque_nm']:.1f}"]
        rows.append("| " + " | ".join(cells + [f"{joint['torque_limit_nm']:g}"]) + " |")
    worst = ["**worst**"] + sum(([f"**{m['worst_rms_error_rad']:.3e}**", "", ""] for m in metrics), []) + [""]
    rows.append("| " + " | ".join(worst) + " |")
    return "\n".join(rows)


def startup_table(metrics: list[dict]) -> str:
    """Whole-run figures: settling time, max |e| over the run, torque variation, time at the limit."""
    m0 = metrics[0]
    tags = [m["controller"].upper() for m in metrics]
    head = "| joint | " + " | ".join(
        f"{t} settled [s] | {t} max abs run [rad] | {t} torque variation | {t} at limit after {m0['startup_s']:g} s"
        for t in tags) + " |"
    rows = [head, "|---" * (1 + 4 * len(metrics)) + "|"]
    for j, joint in enumerate(m0["joints"]):
        cells = [joint["name"]]
        for m in metrics:
            jm = m["joints"][j]
            cells += [_settle(jm["settling_time_s"]), f"{jm['max_abs_error_run_rad']:.4f}", f"{jm['torque_variation']:.2f}",
                      f"{jm['saturated_fraction_after_s']:.4f}"]
        rows.append("| " + " | ".join(cells) + " |")
    worst = ["**worst**"] + sum(([f"**{_settle(m['worst_settling_time_s'])}**", f"**{m['worst_max_abs_error_run_rad']:.4f}**",
                                  f"**{m['worst_torque_variation']:.2f}**",
                                  f"**{m['worst_saturated_fraction_after_s']:.4f}**"] for m in metrics), [])
    rows.append("| " + " | ".join(worst) + " |")
    return "\n".join(rows)


def _wall_time(wall_s, rtf) -> str:
    """The run's wall time, or what is true when it is not known (a run rebuilt from a bag: NaN)."""
    if wall_s is None or not math.isfinite(wall_s):
        return "wall time not known (the run was rebuilt from a record that does not hold it)"
    return f"wall time {wall_s:.2f} s" + (f" ({rtf:.1f}x real time)" if rtf and math.isfinite(rtf) else "")


def _diverged(m: dict) -> str:
    """'; **diverged**: ... from step k ...' for a run that diverged (one that went non-finite: its figures end
    there), else ''."""
    if not m.get("diverged"):
        return ""
    return (f"; **diverged**: {diverged_text(m)}"
            + (" running away (the figures end there; its undefined figures are inf)"
               if m.get("non_finite_from_step") is not None else ""))


def _guards(m: dict) -> str:
    """'; **guards acted**: ...' for a run whose state guard refused states (answered by the held or zero torque,
    not trained on), replaced non-finite torques or reset an EKF; else ''."""
    text = guard_text(m)
    return f"; **guards acted** (docs/faults.md): {text}" if text else ""


def report_markdown(metrics: list[dict], figures: list[tuple[str, str]], title: str, notes: list[str]) -> str:
    """Whole report; ``figures`` is a list of (caption, relative path)."""
    m0 = metrics[0]
    lines = [f"# {title}", ""]
    lines.append(f"Simulated {m0['duration_s']:g} s at T = {m0['dt_s'] * 1e3:g} ms; errors over "
                 f"t in [{m0['window_s'][0]:g}, {m0['window_s'][1]:g}) s, torques over the whole run.")
    lines.append("")
    for m in metrics:
        rtf = m.get("real_time_factor")
        lines.append(f"- **{m['controller'].upper()}**: worst-joint RMS {m['worst_rms_error_rad']:.3e} rad; settled "
                     f"(|e| < {m['settle_band_rad']:g} rad) {_settled_after(m['worst_settling_time_s'])}; "
                     f"all values finite: {m['all_finite']}; torques within the limits: {m['torques_within_limits']}; "
                     + _wall_time(m['wall_time_s'], rtf) + _diverged(m) + _guards(m))
    lines += [""] + [f"- {n}" for n in notes]
    lines += ["", f"## Tracking over [{m0['window_s'][0]:g}, {m0['window_s'][1]:g}) s", "", metrics_table(metrics)]
    lines += ["", "## Start-up: the whole run", "", startup_table(metrics), "",
              f"Steps at a torque limit after {m0['startup_s']:g} s (any joint): "
              + ", ".join(f"{m['controller'].upper()} {m['steps_at_limit_after_s']}" for m in metrics)
              + ".", "", "## Figures", ""]
    for caption, path in figures:
        lines += [f"### {caption}", "", f"![{caption}]({path})", ""]
    return "\n".join(lines)
