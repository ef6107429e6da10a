"""Link inertias no real arm link has, said once at intake (numpy-free; a warning, the plant moves them as written).

A URDF's placeholder values (``<inertia ixx="1" iyy="1" izz="1">`` on a 10 g servo horn) pass every check of a
physical tensor but make a link of a hobby arm weigh like a flywheel 300 m across. The test: the radius of
gyration sqrt(I_max / m) of a link the actuated joints move is beyond GYRATION_MAX_M (a 3 m rod about its end:
1.7 m; the widest link of the presets and of example-robot-data's arms: 0.42 m, the UR5's wrist_2_link).
"""
from __future__ import annotations

import math

GYRATION_MAX_M = 2.0


def placeholder_inertias(chain, inertials: dict, first_moving_link: str) -> list[str]:
    """One line per link at or below ``first_moving_link`` (in ``chain``, a UrdfChain) whose ``inertials`` entry
    (link name -> its <inertial> element, or None) gives a radius of gyration beyond GYRATION_MAX_M."""
    below: dict[str, list[str]] = {}
    for j in chain.joints:
        below.setdefault(j.parent, []).append(j.child)
    out, todo = [], [first_moving_link]
    while todo:
        link = todo.pop(0)
        todo += below.get(link, [])
        inertial = inertials.get(link)
        try:
            mass = float(inertial.find("mass").get("value"))
            moment = max(float(inertial.find("inertia").get(k, 0.0)) for k in ("ixx", "iyy", "izz"))
        except (AttributeError, TypeError, ValueError):   # none, or checked elsewhere
            continue
        if mass > 0.0 and moment > mass * GYRATION_MAX_M ** 2:
            out.append(f"link {link!r}: inertia {moment:.3g} kg m^2 on a mass of {mass:.3g} kg is a radius of "
                       f"gyration of {math.sqrt(moment / mass):.3g} m, wider than any arm's link (a placeholder?); "
                       f"the plant moves it as written")
    return out
