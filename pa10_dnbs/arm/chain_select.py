"""Which joints of a URDF an arm actuates: the movable joints on the chain from the root to the tip.

Numpy-free and pybullet-free: reads the parsed :class:`UrdfChain` only.
"""
from __future__ import annotations

import re

from ..kinematics.urdf_chain import UrdfChain, UrdfJoint

ACTUATABLE = ("revolute", "continuous")
GRIPPER_NAME = re.compile(r"grip|finger|jaw|claw", re.IGNORECASE)
FINGER_DEPTH_MAX = 4   # movable joints on a finger's longest path (Robotiq's 3-finger gripper: 4); an arm has more
MAX_ACTUATED = 64     # joints one arm may actuate: the rules cost n^3 per pose (`arm` on 80 joints: 7.6 s measured)


def chain_joints(chain: UrdfChain, tip_link: str | None = None) -> list[UrdfJoint]:
    """Joints from the root link to ``tip_link``, in order. With no tip, the chain of movable joints from the
    root: at each link, child branches that hold only fixed joints (base, tool, flange and sensor frames) are
    skipped and the branch with the most movable joints on its longest path is followed; where several tie
    and one of them is a gripper's (:func:`_gripper_fork`: fingers) the chain ends before them. Raises
    ValueError if ``tip_link`` is not a link of the URDF, or if the tree forks into equal branches that are
    not a gripper's (two arms, legs, wheels, a hand's fingers): which one is the arm only ``tip_link`` says."""
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
    depth = _movable_depth(chain, by_parent)
    path, link = [], chain.root_link
    while True:
        scores = [(j, (j.kind != "fixed") + depth[j.child]) for j in by_parent.get(link, ())]
        best = max((s for _, s in scores), default=0)
        top = [j for j, s in scores if s == best]
        if best == 0:
            return path
        if len(top) > 1:
            after = sum(j.kind != "fixed" for j in path)
            names = ", ".join(j.name for j in top)
            if _gripper_fork(top, by_parent, best):
                if after:
                    return path   # the arm ends at its gripper
                raise ValueError(f"the chain from {chain.root_link} forks at link {link!r} into a gripper's "
                                 f"fingers ({names}) before any arm joint: not an arm (tip_link in an arm file "
                                 f"drives one finger's joints as one)")
            raise ValueError(f"the chain from {chain.root_link} forks at link {link!r}"
                             f"{f' after {_joints(after)}' if after else ''} into {len(top)} branches of "
                             f"{_joints(best)} each (first joints: {names}): name the arm's last link with "
                             f"tip_link in an arm file (docs/arms.md)")
        path.append(top[0])
        link = top[0].child


def _joints(n: int) -> str:
    return f"{n} movable joint{'s' if n != 1 else ''}"


def _gripper_fork(branches: list[UrdfJoint], by_parent: dict[str, list[UrdfJoint]], depth: int) -> bool:
    """Whether tied ``branches`` (``depth`` movable joints each on their longest path) are a gripper's: one of
    them starts (its joint, or the first movable joint below a fixed one) with a finger-like joint; or they are
    short (at most FINGER_DEPTH_MAX) and hold one anywhere (Robotiq's 2F-85: knuckles first, fingers below).
    Finger-like: prismatic, a ``<mimic>`` (a linkage driven by one motor), or named *grip*, *finger*, *jaw* or
    *claw*. Two arms are neither: longer, and their first joints are shoulders."""
    for j in branches:
        while j.kind == "fixed" and len(by_parent.get(j.child, ())) == 1:
            if GRIPPER_NAME.search(j.name):
                return True
            j = by_parent[j.child][0]
        if _finger_like(j):
            return True
    return depth <= FINGER_DEPTH_MAX and any(_finger_like(k) for j in branches for k in _below(j, by_parent))


def _finger_like(j: UrdfJoint) -> bool:
    return j.kind == "prismatic" or j.mimics is not None or bool(GRIPPER_NAME.search(j.name))


def _below(joint: UrdfJoint, by_parent: dict[str, list[UrdfJoint]]) -> list[UrdfJoint]:
    """``joint`` and every joint below it."""
    out, todo = [], [joint]
    while todo:
        j = todo.pop()
        out.append(j)
        todo += by_parent.get(j.child, ())
    return out


def _movable_depth(chain: UrdfChain, by_parent: dict[str, list[UrdfJoint]]) -> dict[str, int]:
    """Link -> the most movable joints on any path from it down to a leaf (0 for a leaf or fixed frames)."""
    depth: dict[str, int] = {}
    for j in reversed(_top_down(chain, by_parent)):
        depth[j.child] = max(((k.kind != "fixed") + depth[k.child] for k in by_parent.get(j.child, ())), default=0)
    return depth


def _top_down(chain: UrdfChain, by_parent: dict[str, list[UrdfJoint]]) -> list[UrdfJoint]:
    """Every joint reachable from the root, each after its parent's joint (breadth first)."""
    order, frontier = [], [chain.root_link]
    while frontier:
        joints = [j for link in frontier for j in by_parent.get(link, ())]
        order += joints
        frontier = [j.child for j in joints]
    return order


def gripper_joints(on_chain: list[UrdfJoint]) -> list[UrdfJoint]:
    """The gripper at the end of the chain: the trailing movable joints that are prismatic or whose name says
    gripper, finger, jaw or claw (docs/arms.md)."""
    tail = []
    for j in reversed(on_chain):
        if j.kind != "prismatic" and not GRIPPER_NAME.search(j.name):
            break
        tail.append(j)
    return tail[::-1]


def actuated_joints(chain: UrdfChain, exclude: tuple[str, ...] = (), tip_link: str | None = None,
                    names: tuple[str, ...] | None = None,
                    keep_gripper: bool = False) -> tuple[list[UrdfJoint], list[UrdfJoint]]:
    """(actuated joints in chain order, every other movable joint of the URDF: the locked ones).

    ``names``: the actuated joints given explicitly (each must be a movable joint on the chain, in chain
    order); else every movable chain joint not in ``exclude`` and, unless ``keep_gripper``, not in the
    gripper at the chain's end (:func:`gripper_joints`). Raises ValueError naming the joint for an
    unknown name, or an actuated joint that is not revolute or continuous (prismatic, floating, planar) or
    that mimics another (a URDF ``<mimic>``: a coupled joint with no actuator of its own); and for more than
    MAX_ACTUATED joints to actuate.
    """
    if not chain.joints:
        raise ValueError("the URDF has no joints")
    on_chain = [j for j in chain_joints(chain, tip_link) if j.kind != "fixed"]
    gripper: set[str] = set()
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
        gripper = set() if keep_gripper else {j.name for j in gripper_joints(on_chain)}
        actuated = [j for j in on_chain if j.name not in exclude and j.name not in gripper]
    for j in actuated:
        if j.kind not in ACTUATABLE:
            raise ValueError(f"joint {j.name!r} is {j.kind}: only revolute or continuous joints can be actuated "
                             f"(list it in exclude_joints to lock it)")
        if j.mimics is not None:  # its motor is another joint's: driving it on its own is not this robot
            absent = "" if j.mimics in known else ", which is not in the URDF"
            raise ValueError(f"joint {j.name!r} mimics joint {j.mimics!r}{absent} (<mimic>): it has no actuator of "
                             f"its own and cannot be controlled as one (list it in exclude_joints to lock it)")
    if not actuated:
        raise ValueError(_none_left(chain.root_link, on_chain, exclude, gripper, names))
    if len(actuated) > MAX_ACTUATED:
        raise ValueError(f"{len(actuated)} joints to actuate on the chain from {chain.root_link}, more than "
                         f"{MAX_ACTUATED}, the most one arm may have here (one controller process per joint on the "
                         "graph; the gain rule sweeps the n x n mass matrix at every pose, n^3 each: 80 joints take "
                         "8 s, 300 minutes); name fewer with joints or tip_link, or lock some with exclude_joints")
    chosen = {j.name for j in actuated}
    locked = [j for j in chain.movable if j.name not in chosen]
    return actuated, locked


def _none_left(root: str, on_chain: list[UrdfJoint], exclude: tuple[str, ...], gripper: set[str],
               names: tuple[str, ...] | None) -> str:
    """Why no joint of the chain from ``root`` is left to actuate: ``joints`` empty, no movable joint, none
    revolute, or every revolute one locked (as the gripper, by ``exclude_joints``), naming them and the remedy."""
    if names is not None:
        return "joints: empty (name the revolute joints to actuate, in chain order)"
    revolute = [j for j in on_chain if j.kind in ACTUATABLE]
    if not revolute:
        other = ", ".join(f"{j.name} ({j.kind})" for j in on_chain)
        why = f": its movable joints are {other} (only revolute or continuous joints can be actuated)" if other else ""
        return f"no revolute joint on the chain from {root}{why}"
    held = [j.name for j in revolute if j.name in gripper and j.name not in exclude]
    excluded = [j.name for j in revolute if j.name in exclude]
    if not held:
        return f"exclude_joints locks every revolute joint on the chain from {root} ({', '.join(excluded)})"
    by_exclude = f", {', '.join(excluded)} by exclude_joints" if excluded else ""
    if all(j.kind in ACTUATABLE for j in on_chain if j.name in gripper):
        how = "keep_gripper: true in an arm file keeps them actuated"
    else:   # the gripper holds a prismatic joint too: keep_gripper would actuate it (refused); name the joints
        how = f"name the ones to actuate in an arm file (joints: [{', '.join(held)}])"
    return (f"every revolute joint on the chain from {root} is locked: {', '.join(held)} as the chain's gripper "
            f"(its trailing joints that are prismatic or named *grip*, *finger*, *jaw* or *claw*){by_exclude}: {how}")
