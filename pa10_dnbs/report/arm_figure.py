"""The arm in 3D: link chain at a few instants and the flange's path, from the URDF forward kinematics."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..kinematics.urdf_chain import UrdfChain  # noqa: E402
from ..run_data import RunData  # noqa: E402

N_POSES = 6        # stick figures drawn
PATH_POINTS = 1000  # samples of the flange path


def _chain_points(chain: UrdfChain, q: np.ndarray, names) -> np.ndarray:
    """Origins [m] of the root link and of every link down the chain, shape (n_links, 3)."""
    poses = chain.link_poses(dict(zip(names, q.tolist())))
    order = [chain.root_link] + [j.child for j in chain.joints]
    return np.array([poses[link][0] for link in order])


def _flange_path(chain: UrdfChain, q_rad: np.ndarray, names, idx: np.ndarray) -> np.ndarray:
    """Position [m] of the last link at the steps ``idx``, shape (len(idx), 3)."""
    tip = chain.joints[-1].child
    return np.array([chain.link_poses(dict(zip(names, q_rad[k].tolist())))[tip][0] for k in idx]).reshape(-1, 3)


def arm_figure(run: RunData, chain: UrdfChain, path: Path) -> None:
    """Stick figures of the arm at N_POSES instants (coloured by time), the flange path and its reference.
    Samples with a non-finite angle are left out (a diverged run: the figure ends where the run went)."""
    tip = chain.joints[-1].child
    finite = np.flatnonzero(np.all(np.isfinite(run.position_rad), axis=1) & np.all(np.isfinite(run.reference_rad),
                                                                                    axis=1))
    last = int(finite[-1]) if finite.size else 0
    idx = np.unique(np.linspace(0, last, PATH_POINTS).astype(int))
    idx = idx[np.isin(idx, finite)]
    flange = _flange_path(chain, run.position_rad, run.joint_names, idx)
    desired = _flange_path(chain, run.reference_rad, run.joint_names, idx)
    fig = plt.figure(figsize=(8, 8), constrained_layout=True)
    ax = fig.add_subplot(projection="3d")
    ax.plot(desired[:, 0], desired[:, 1], desired[:, 2], "--", color="tab:red", lw=1.0,
            label=f"{tip} path of the reference")
    ax.plot(flange[:, 0], flange[:, 1], flange[:, 2], color="0.35", lw=1.0, label=f"{tip} path")
    cmap = plt.get_cmap("viridis")
    points = [flange, desired]
    for i, k in enumerate(np.linspace(0, last, N_POSES).astype(int)):
        if not np.all(np.isfinite(run.position_rad[k])):
            continue
        pts = _chain_points(chain, run.position_rad[k], run.joint_names)
        points.append(pts)
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], "-o", color=cmap(i / max(1, N_POSES - 1)), lw=3, ms=4,
                label=f"t = {k * run.dt_s:.1f} s")
    # a cube around everything drawn, so lengths are not distorted
    allp = np.vstack(points)
    allp = allp[np.all(np.isfinite(allp), axis=1)]
    if allp.size == 0:
        allp = np.zeros((1, 3))
    centre = 0.5 * (allp.min(axis=0) + allp.max(axis=0))
    half = 0.5 * float(np.max(allp.max(axis=0) - allp.min(axis=0))) + 0.05
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(max(0.0, centre[2] - half), max(0.0, centre[2] - half) + 2 * half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"{chain.robot_name or 'arm'} ({run.controller.upper()}): poses over the run and the {tip} path")
    ax.legend(loc="upper left", fontsize=8)
    fig.savefig(path, dpi=90)
    plt.close(fig)
