"""The Markdown report: metrics table(s) and the figures."""
from __future__ import annotations


def metrics_table(metrics: list[dict]) -> str:
    """One row per joint; one RMS / max column pair per run (e.g. DNBS and PID side by side)."""
    head = "| joint | " + " | ".join(
        f"{m['controller'].upper()} RMS [rad] | {m['controller'].upper()} max abs [rad] | "
        f"{m['controller'].upper()} max abs torque [N m] | sat. fraction" for m in metrics) + " | limit [N m] |"
    sep = "|---" * (1 + 4 * len(metrics) + 1) + "|"
    rows = [head, sep]
    for j, joint in enumerate(metrics[0]["joints"]):
        cells = [joint["name"]]
        for m in metrics:
            jm = m["joints"][j]
            cells += [f"{jm['rms_error_rad']:.3e}", f"{jm['max_abs_error_rad']:.3e}",
                      f"{jm['max_abs_torque_nm']:.1f}", f"{jm['saturated_fraction']:.4f}"]
        cells.append(f"{joint['torque_limit_nm']:g}")
        rows.append("| " + " | ".join(cells) + " |")
    worst = ["**worst RMS**"] + sum(([f"**{m['worst_rms_error_rad']:.3e}**", "", "", ""] for m in metrics), []) + [""]
    rows.append("| " + " | ".join(worst) + " |")
    return "\n".join(rows)


def report_markdown(metrics: list[dict], figures: list[tuple[str, str]], title: str, notes: list[str]) -> str:
    """Whole report; ``figures`` is a list of (caption, relative path)."""
    m0 = metrics[0]
    lines = [f"# {title}", ""]
    lines.append(f"Simulated {m0['duration_s']:g} s at T = {m0['dt_s'] * 1e3:g} ms; errors over "
                 f"t in [{m0['window_s'][0]:g}, {m0['window_s'][1]:g}) s, torques over the whole run.")
    lines.append("")
    for m in metrics:
        rtf = m.get("real_time_factor")
        lines.append(f"- **{m['controller'].upper()}**: worst-joint RMS {m['worst_rms_error_rad']:.3e} rad; "
                     f"all values finite: {m['all_finite']}; torques within Table 2: {m['torques_within_limits']}; "
                     f"wall time {m['wall_time_s']:.2f} s" + (f" ({rtf:.1f}x real time)" if rtf else ""))
    lines += [""] + [f"- {n}" for n in notes] + ["", "## Metrics", "", metrics_table(metrics), "", "## Figures", ""]
    for caption, path in figures:
        lines += [f"### {caption}", "", f"![{caption}]({path})", ""]
    return "\n".join(lines)
