"""What a URDF must be before anything loads it: one tree of uniquely named links and well-formed joints.

PyBullet's importer kills the process (SIGSEGV, no message) on a duplicate joint name, a link that is the
child of two joints or a second root link, and stops with "Cannot load URDF file." on an undefined link, a
duplicate link name or a malformed vector. So :class:`~pa10_dnbs.kinematics.urdf_chain.UrdfChain` refuses
them here first, each with a :class:`UrdfError` naming the joint or link. Standard library only.
"""
from __future__ import annotations

import math

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")  # the URDF spec's


class UrdfError(ValueError):
    """A URDF that is not one tree of links and joints, or a malformed joint; the message names it."""


def vector3(el, attr: str, default: str, joint: str) -> tuple[float, float, float]:
    """The 3 finite numbers of attribute ``attr`` (xyz, rpy) of element ``el`` (``default`` when either is
    absent or empty) of joint ``joint``; UrdfError naming the joint, the element and the text."""
    text = el.get(attr) if el is not None else None
    try:
        values = tuple(float(v) for v in (text or default).split())
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise UrdfError(f'joint {joint!r}: <{el.tag} {attr}="{text}">: expected 3 finite numbers')
    return values


def number(el, attr: str, joint: str) -> float:
    """Attribute ``attr`` of element ``el`` of joint ``joint`` as a float (inf and nan pass: the callers test
    ranges); UrdfError naming the joint, the element and the text."""
    text = el.get(attr)
    try:
        return float(text)
    except ValueError:
        raise UrdfError(f'joint {joint!r}: <{el.tag} {attr}="{text}">: expected a number') from None


def tree_root(links: list[str], joints: list[tuple[str, str, str]]) -> str:
    """The root link of the tree ``joints`` (name, parent link, child link) make of ``links`` (every link's
    name, in file order). UrdfError naming the joint or link for: a link or joint name given twice, a joint
    whose parent or child is not a link, a link that is the child of two joints, a kinematic loop, or not
    exactly one root (a link that is the child of no joint)."""
    seen: set[str] = set()
    for link in links:
        if link in seen:
            raise UrdfError(f"link {link!r} is defined twice (link names must be unique)")
        seen.add(link)
    names: set[str] = set()
    parent_joint: dict[str, tuple[str, str, str]] = {}
    for joint in joints:
        name, parent, child = joint
        if name in names:
            raise UrdfError(f"joint {name!r} is defined twice (joint names must be unique)")
        names.add(name)
        for role, link in (("parent", parent), ("child", child)):
            if link not in seen:
                raise UrdfError(f"joint {name!r}: its {role} link {link!r} is not defined (no <link name={link!r}>)")
        if child in parent_joint:
            raise UrdfError(f"link {child!r} is the child of two joints, {parent_joint[child][0]!r} and {name!r} "
                            f"(a URDF is a tree: one parent joint per link)")
        parent_joint[child] = joint
    roots = [link for link in links if link not in parent_joint]
    if len(roots) > 1:
        raise UrdfError(f"two root links, {roots[0]!r} and {roots[1]!r} (each the child of no joint): "
                        f"a URDF is one tree")
    children: dict[str, list[str]] = {}
    for _, parent, child in joints:
        children.setdefault(parent, []).append(child)
    reached, frontier = set(roots), list(roots)
    while frontier:
        frontier = [c for link in frontier for c in children.get(link, ())]
        reached.update(frontier)
    stray = [link for link in links if link not in reached]
    if stray:  # every such link has one parent joint and no root above it: following parents goes round a loop
        loop = _loop(stray[0], parent_joint)
        where = "no root link" if not roots else f"not reachable from the root link {roots[0]!r}"
        raise UrdfError(f"a kinematic loop through link {loop[0]!r} ({' -> '.join(loop + loop[:1])}; {where}): "
                        f"a URDF is a tree")
    if not roots:  # no links at all
        return ""
    return roots[0]


def _loop(start: str, parent_joint: dict[str, tuple[str, str, str]]) -> list[str]:
    """The links of the loop reached by following parent joints up from ``start``, parent to child."""
    path, link = [], start
    while link not in path:
        path.append(link)
        link = parent_joint[link][1]
    return path[path.index(link):][::-1]
