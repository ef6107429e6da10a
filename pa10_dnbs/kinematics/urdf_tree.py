"""What a URDF must be before anything loads it: one tree of uniquely named links and well-formed joints.

PyBullet's importer kills the process (SIGSEGV, no message) on a duplicate joint name, a link that is the
child of two joints or a second root link, and stops with "Cannot load URDF file." on an undefined link, a
duplicate link name or a malformed vector. So :class:`~pa10_dnbs.kinematics.urdf_chain.UrdfChain` refuses
them here first, each with a :class:`UrdfError` naming the joint or link. Standard library only.

Names and magnitudes are checked here too (:func:`check_name`, :func:`check_link`): a joint or link name that is
blank or has leading/trailing whitespace (a ROS joint name or /tf frame cannot carry it, and ``" j2"`` would
silently differ from ``"j2"``), and numbers finite but absurd, which later overflowed (an origin of 1e300 m ended
in a traceback from the eigen-solver) or ran as nonsense (a 1e300 kg link). The bounds, each far past any real
arm yet far from where float64 loses the precision a run needs:

- ``MAX_OFFSET_M``: every origin's xyz (joint, inertial, visual, collision) within 1 km. The largest serial arms
  reach 4-5 m and a gantry tens of metres; at 1 km a float64 position still resolves 1e-13 m, and m d^2 with
  the mass bound stays 1e11 kg m^2, far inside float64;
- ``MAX_MASS_KG``: a link's mass in [0, 1e5 kg] (the heaviest industrial arms weigh about 10 t in all);
- ``MAX_INERTIA_KGM2``: each inertia entry within 1e7 kg m^2 (1e5 kg at 10 m);
- rpy: finite (any angle is meaningful; it is reduced modulo 2 pi);
- ``MAX_AXIS``: each component of a joint's ``<axis xyz>`` within 1e6. An axis is a direction, written as a unit
  vector or small numbers; its length is divided out, and past ~1e154 its square overflows float64 (an axis of
  1e160 ended in a traceback from the inertia sweep).
"""
from __future__ import annotations

import math

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")  # the URDF spec's
MAX_OFFSET_M = 1e3        # |x|, |y|, |z| of any <origin xyz> [m]
MAX_MASS_KG = 1e5         # a link's <mass value> [kg]
MAX_INERTIA_KGM2 = 1e7    # |each <inertia> entry| [kg m^2]
MAX_AXIS = 1e6            # |each component of a joint's <axis xyz>| (a direction: unitless)
INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


class UrdfError(ValueError):
    """A URDF that is not one tree of links and joints, or a malformed joint; the message names it."""


def vector3(el, attr: str, default: str, joint: str, bound: float | None = None,
            owner: str = "joint") -> tuple[float, float, float]:
    """The 3 finite numbers of attribute ``attr`` (xyz, rpy) of element ``el`` (``default`` when either is
    absent or empty) of joint ``joint`` (of link ``joint`` when ``owner`` is "link"), each within +/-``bound``
    when given; UrdfError naming the joint or link, the element and the text."""
    text = el.get(attr) if el is not None else None
    try:
        values = tuple(float(v) for v in (text or default).split())
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise UrdfError(f'{owner} {joint!r}: <{el.tag} {attr}="{text}">: expected 3 finite numbers')
    if bound is not None and max(abs(v) for v in values) > bound:
        raise UrdfError(f'{owner} {joint!r}: <{el.tag} {attr}="{text}">: each must be within +/-{bound:g} m '
                        f'(no arm is larger; see pa10_dnbs/kinematics/urdf_tree.py)')
    return values


def number(el, attr: str, joint: str, owner: str = "joint") -> float:
    """Attribute ``attr`` of element ``el`` of joint ``joint`` (of link ``joint`` when ``owner`` is "link") as
    a float (inf and nan pass: the callers test ranges); UrdfError naming it, the element and the text."""
    text = el.get(attr)
    try:
        return float(text)
    except (TypeError, ValueError):
        raise UrdfError(f'{owner} {joint!r}: <{el.tag} {attr}="{text}">: expected a number') from None


def check_name(kind: str, name: str | None, i: int) -> str:
    """``name`` of the ``i``-th ``<kind>`` (joint, link): UrdfError if it is missing, blank or has leading or
    trailing whitespace."""
    if not name:
        raise UrdfError(f"<{kind}> number {i} has no name")
    if name != name.strip():
        raise UrdfError(f"{kind} {name!r}: a name that is blank or has leading/trailing whitespace (ROS joint "
                        f"names and /tf frames cannot carry it)")
    return name


def check_link(el, i: int) -> str:
    """The name of the ``i``-th ``<link>`` element, checked: a name (:func:`check_name`), every origin's xyz
    finite within ``MAX_OFFSET_M`` and rpy finite, a ``<mass value>`` finite in [0, ``MAX_MASS_KG``], each
    ``<inertia>`` entry finite within ``MAX_INERTIA_KGM2``. UrdfError naming the link, the element and the text."""
    name = check_name("link", el.get("name"), i)
    for origin in el.iter("origin"):
        vector3(origin, "xyz", "0 0 0", name, MAX_OFFSET_M, owner="link")
        vector3(origin, "rpy", "0 0 0", name, owner="link")
    for mass in el.findall("inertial/mass"):
        if mass.get("value") is None:
            continue   # no value: the arm's own check names it where the mass matters (a moved link)
        value = number(mass, "value", name, owner="link")
        if not 0.0 <= value <= MAX_MASS_KG:
            raise UrdfError(f'link {name!r}: <mass value="{mass.get("value")}">: expected a finite mass in '
                            f'[0, {MAX_MASS_KG:g}] kg')
    for inertia in el.findall("inertial/inertia"):
        for key in INERTIA_KEYS:
            if inertia.get(key) is None:
                continue
            value = number(inertia, key, name, owner="link")
            if not abs(value) <= MAX_INERTIA_KGM2:
                raise UrdfError(f'link {name!r}: <inertia {key}="{inertia.get(key)}">: expected a finite value '
                                f'within +/-{MAX_INERTIA_KGM2:g} kg m^2')
    return name


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
                world = ("; Gazebo and Drake read 'world' as the world frame, the URDF spec (and urdfdom) as a link it "
                         "must define: add <link name=\"world\"/>" if (role, link) == ("parent", "world") else "")
                raise UrdfError(f"joint {name!r}: its {role} link {link!r} is not defined (no <link name={link!r}>)"
                                f"{world}")
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
