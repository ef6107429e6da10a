"""Figures like the paper's: tracking per joint (Figs. 4-10), errors (Fig. 11), torques."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..run_data import RunData  # noqa: E402
from .finite_view import drawable  # noqa: E402

_MAX_POINTS = 4000  # plotted samples per curve; the npz keeps every step
ROW_HEIGHT_IN = 13 / 7  # [in] of the start-up figure per joint (13 in for seven joints)


def _stride(n: int) -> int:
    return max(1, n // _MAX_POINTS)


def _grid(title: str, n: int):
    """Two columns of panels, one per joint (n of them), row by row; the unused panel hidden."""
    rows = max(1, -(-n // 2))
    fig, axes = plt.subplots(rows, 2, figsize=(11, 2.75 * rows), sharex=True, squeeze=False)
    fig.subplots_adjust(left=0.08, right=0.98, top=1 - 0.2 / rows, bottom=0.2 / rows, hspace=0.12, wspace=0.25)
    fig.suptitle(title)
    axes = axes.ravel()
    for ax in axes[n:]:
        ax.axis("off")
    for ax in _bottom(axes, n):
        ax.xaxis.set_tick_params(labelbottom=True)  # the panel above an empty one keeps its time axis
    return fig, axes


def _bottom(axes, n: int) -> list:
    """The lowest used panel of each column."""
    return [axes[j] for j in range(n) if j + 2 >= n]


def tracking_figure(run: RunData, path: Path) -> None:
    """Reference (solid) and actual (dashed) angle per joint, as Figs. 4-10."""
    run = drawable(run)
    s = _stride(run.n_steps)
    t = run.time_s[::s]
    fig, axes = _grid(f"Trajectory tracking ({run.controller.upper()})", len(run.joint_names))
    for j, name in enumerate(run.joint_names):
        ax = axes[j]
        ax.plot(t, run.reference_rad[::s, j], "-", color="k", lw=1.2, label="reference $x_{d}$")
        ax.plot(t, run.position_rad[::s, j], "--", color="tab:red", lw=1.2, label="actual $x_1$")
        ax.set_ylabel(f"{name} [rad]")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8)
    for ax in _bottom(axes, len(run.joint_names)):
        ax.set_xlabel("time [s]")
    fig.savefig(path, dpi=90)
    plt.close(fig)


def error_figure(runs: list[RunData], path: Path, window_s: tuple[float, float] | None = None,
                 settling_s: list[list[float | None]] | None = None) -> None:
    """Tracking error x_d - x1 per joint (Fig. 11); several runs are overlaid for comparison.

    ``settling_s``: per run, per joint, the settling time [s] (None: never), drawn as a dotted line.
    """
    runs = [drawable(r) for r in runs]
    fig, axes = _grid("Tracking errors " + " vs ".join(r.controller.upper() for r in runs), len(runs[0].joint_names))
    for i, run in enumerate(runs):
        s = _stride(run.n_steps)
        for j, name in enumerate(run.joint_names):
            line, = axes[j].plot(run.time_s[::s], run.error_rad[::s, j], lw=1.0, label=run.controller.upper())
            if settling_s is not None and settling_s[i][j] is not None:
                axes[j].axvline(settling_s[i][j], ls=":", color=line.get_color(), lw=1.0)
    for j, name in enumerate(runs[0].joint_names):
        ax = axes[j]
        ax.set_ylabel(f"{name} error [rad]")
        ax.grid(alpha=0.3)
        if window_s is not None:
            ax.axvspan(*window_s, color="0.9", zorder=0)
            lo, hi = window_s
            vals = [np.abs(r.error_rad[int(lo / r.dt_s):int(hi / r.dt_s), j]).max(initial=0) for r in runs]
            lim = 4 * max(vals) if max(vals) > 0 else None
            if lim and np.isfinite(lim):
                ax.set_ylim(-lim, lim)  # zoom on the metrics window; the transient runs off the top
    axes[0].legend(loc="upper right", fontsize=8)
    for ax in _bottom(axes, len(runs[0].joint_names)):
        ax.set_xlabel("time [s]")
    fig.savefig(path, dpi=90)
    plt.close(fig)


def torque_figure(run: RunData, path: Path) -> None:
    """Applied torque per joint with its limits (dotted)."""
    run = drawable(run)
    s = _stride(run.n_steps)
    t = run.time_s[::s]
    fig, axes = _grid(f"Applied torques ({run.controller.upper()}) and torque limits", len(run.joint_names))
    for j, name in enumerate(run.joint_names):
        ax = axes[j]
        ax.plot(t, run.torque_nm[::s, j], lw=1.0, color="tab:blue")
        lim = run.torque_limit_nm[j]
        ax.axhline(lim, ls=":", color="k")
        ax.axhline(-lim, ls=":", color="k")
        ax.set_ylim(-1.15 * lim, 1.15 * lim)
        ax.set_ylabel(f"{name} [N m]")
        ax.grid(alpha=0.3)
    for ax in _bottom(axes, len(run.joint_names)):
        ax.set_xlabel("time [s]")
    fig.savefig(path, dpi=90)
    plt.close(fig)


def startup_figure(run: RunData, path: Path, settle_band_rad: float, settling_s: list[float | None]) -> None:
    """The first seconds: error per joint with the settling band and settling time (dotted), torque with limits."""
    run = drawable(run)
    done = [t for t in settling_s if t is not None]
    t_show = min(run.n_steps * run.dt_s, max(1.0, 1.5 * max(done)) if len(done) == len(settling_s) else 5.0)
    n = max(2, int(round(t_show / run.dt_s)))
    t = run.time_s[:n]
    nj = len(run.joint_names)
    fig, axes = plt.subplots(nj, 2, figsize=(11, ROW_HEIGHT_IN * nj), sharex=True, squeeze=False)  # fixed layout: cheaper
    fig.subplots_adjust(left=0.08, right=0.98, top=1 - 0.28 / nj, bottom=0.28 / nj, hspace=0.12, wspace=0.25)
    fig.suptitle(f"Start-up ({run.controller.upper()}): error with the {settle_band_rad:g} rad band, torque with "
                 "its limits")
    for j, name in enumerate(run.joint_names):
        ax, at = axes[j, 0], axes[j, 1]
        ax.plot(t, run.error_rad[:n, j], lw=1.0, color="tab:blue")
        ax.axhspan(-settle_band_rad, settle_band_rad, color="0.9", zorder=0)
        if settling_s[j] is not None and settling_s[j] <= t_show:
            ax.axvline(settling_s[j], ls=":", color="k", lw=1.0)
            ax.text(settling_s[j], ax.get_ylim()[1], f" {settling_s[j]:.2f} s", va="top", fontsize=7)
        ax.set_ylabel(f"{name} e [rad]")
        lim = run.torque_limit_nm[j]
        at.plot(t, run.torque_nm[:n, j], lw=1.0, color="tab:red")
        at.axhline(lim, ls=":", color="k")
        at.axhline(-lim, ls=":", color="k")
        at.set_ylim(-1.15 * lim, 1.15 * lim)
        at.set_ylabel(f"{name} [N m]")
        for a in (ax, at):
            a.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    axes[-1, 1].set_xlabel("time [s]")
    fig.savefig(path, dpi=90)
    plt.close(fig)
