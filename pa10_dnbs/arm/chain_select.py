"""Which joints of a URDF an arm actuates: the movable joints on the chain from the root to the tip.

Numpy-free and pybullet-free: reads the parsed :class:`UrdfChain` only.
"""
from __future__ import annotations

from ..kinematics.urdf_chain import UrdfChain, UrdfJoint

ACTUATABLE = ("revolute", "continuous")


def chain_joints(chain: UrdfChain, tip_link: str | None = None) -> list[UrdfJoint]:
    """Joints from the root link to ``tip_link``, in order; with no tip, the chain is followed from the root
    while each link has exactly one child joint (it ends at a leaf or where it branches, e.g. at a gripper's
    fingers). Raises ValueError if ``tip_link`` is not a link of the URDF."""
    by_parent: dict[str, list[UrdfJoint]] = {}
    by_child: dict[str, UrdfJoint] = {}
    for j in chain.joints:
        by_parent.setdefault(j.parent, []).append(j)
        by_child[j.child] = j
    if tip_link is not None:
        if tip_link != chain.root_link and tip_link not in by_child:
            raise ValueError(f"tip_link {tip_link!r} is not a link of the URDF")
        path, link = [], tip_link
        while link in by_child:
            path.append(by_child[link])
            link = by_child[link].parent
        return path[::-1]
    path, link = [], chain.root_link
    while len(by_parent.get(link, ())) == 1:
        j = by_parent[link][0]
        path.append(j)
        link = j.child
    return path


def actuated_joints(chain: UrdfChain, exclude: tuple[str, ...] = (), tip_link: str | None = None,
                    names: tuple[str, ...] | None = None) -> tuple[list[UrdfJoint], list[UrdfJoint]]:
    """(actuated joints in chain order, every other movable joint of the URDF: the locked ones).

    ``names``: the actuated joints given explicitly (each must be a movable joint on the chain, in chain
    order); else every movable chain joint not in ``exclude``. Raises ValueError naming the joint for an
    unknown name, or an actuated joint that is not revolute or continuous (prismatic, floating, planar).
    """
    on_chain = [j for j in chain_joints(chain, tip_link) if j.kind != "fixed"]
    known = {j.name for j in chain.joints}
    for name in tuple(exclude) + tuple(names or ()):
        if name not in known:
            raise ValueError(f"joint {name!r} is not in the URDF (its joints: {', '.join(sorted(known))})")
    if names is not None:
        order = [j.name for j in on_chain]
        missing = [n for n in names if n not in order]
        if missing:
            raise ValueError(f"joint {missing[0]!r} is not a movable joint on the chain from "
                             f"{chain.root_link} (the chain: {', '.join(order)})")
        if [n for n in order if n in names] != list(names):
            raise ValueError(f"joints: list them in chain order ({', '.join(n for n in order if n in names)})")
        actuated = [j for j in on_chain if j.name in names]
    else:
        actuated = [j for j in on_chain if j.name not in exclude]
    for j in actuated:
        if j.kind not in ACTUATABLE:
            raise ValueError(f"joint {j.name!r} is {j.kind}: only revolute or continuous joints can be actuated "
                             f"(list it in exclude_joints to lock it)")
    if not actuated:
        raise ValueError(f"no revolute joint on the chain from {chain.root_link}")
    chosen = {j.name for j in actuated}
    locked = [j for j in chain.movable if j.name not in chosen]
    return actuated, locked
