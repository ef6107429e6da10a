"""A run's settings as ROS parameters, and back (no rclpy: the launcher writes them, the nodes declare them).

Each node runs some sections of the settings (``NODE_SECTIONS``: the plant its physics, initial state and
state faults; the reference node eq. 27 ...). Every key of those sections is one parameter named by its dotted
config key (``plant.gravity_mps2``, ``faults.state.drop_fraction``), holding its value: a number, a flag, a
string, or a list of doubles for a per-joint value, a pair or a tuple (one value per joint, chain order), plus
``arm_file``, the arm file (or URDF) the node reads its arm from. Descriptions carry the unit, ranges are the
keys' bounds in ``config.SCHEMA``. :func:`node_settings` rebuilds the typed sections from the values and
validates them as a config file's would be (ConfigError naming the key).

A joint controller runs one joint, so its parameters are the keys it runs (``JOINT_CONTROLLER_KEYS``) under the
same dotted names, with one rule of its own: **every per-joint key holds its own joint's value, one double**
(``pid.kp``, ``dnbs.alpha_net.error_scale_rad``); scalars and per-input tuples are as elsewhere.
:func:`joint_values` gives them, :func:`joint_node_settings` rebuilds the node's settings from them alone (each
per-joint number broadcast to every row, as a config file's single number is: the node runs only its own row).
"""
from __future__ import annotations

import dataclasses

from ..arm import Arm
from ..config import SCHEMA, Flag, Joints, Num, Pair, Text, check_value
from ..config_error import ConfigError
from ..settings import SECTIONS, Settings

ARM_FILE = "arm_file"
ARM_FILE_DESCRIPTION = ("the arm file (urdf/<arm>/arm.yaml) or URDF this node's arm is read from: it names the "
                        "URDF, parsed once at start [path]")

#: node name (as the launcher starts it) -> the sections of the settings it runs
NODE_SECTIONS: dict[str, tuple[str, ...]] = {
    "plant": ("simulation", "reference", "plant", "faults"),       # physics, initial state, state-link faults
    "joint_bus": ("simulation", "plant", "faults"),                # in the plant's place: no physics of its own
    "mujoco_robot": ("simulation", "reference", "plant"),          # physics and initial state
    "reference": ("simulation", "reference"),                      # eq. 27 and its preview, at dt
    "wire_monitor": ("simulation",),                               # dt and the run's length
    "live_view": ("simulation", "plant"),                          # dt and the torque limits on display
    "recorder": tuple(SECTIONS),                                   # the whole run: written into the bag
}

#: units of keys whose name does not end in one (suffix -> unit: see _unit)
UNITS = {"pid.kp": "N m/rad", "pid.ki": "N m/(rad s)", "pid.kd": "N m s/rad"}
_SUFFIXES = (("_nms_per_rad", "N m s/rad"), ("_kgm2", "kg m^2"), ("_mps2", "m/s^2"), ("_per_s3", "1/s^3"),
             ("_per_s2", "1/s^2"), ("_per_s", "1/s"), ("_rad_s", "rad/s"), ("_rad", "rad"), ("_nm", "N m"),
             ("_ms", "ms"), ("_kg", "kg"), ("_s", "s"), ("_steps", "steps"), ("_every", "steps"))


@dataclasses.dataclass(frozen=True)
class SettingParam:
    """What the node declares for one key: description (with the unit) and its inclusive range [lo, hi]
    (None: unbounded; a strict bound, > 0, is checked again by :func:`node_settings`)."""

    description: str
    lo: float | int | None = None
    hi: float | int | None = None


def _leaves(spec: dict, prefix: str):
    for key, sub in spec.items():
        dotted = f"{prefix}.{key}"
        if isinstance(sub, dict):
            yield from _leaves(sub, dotted)
        else:
            yield dotted, sub


def _unit(key: str, spec) -> str:
    if isinstance(spec, (Flag, Text, tuple)):  # a tuple: one value per input, each in that input's unit
        return ""
    if key in UNITS:
        return UNITS[key]
    leaf = key.rsplit(".", 1)[-1]
    for suffix, unit in _SUFFIXES:
        if leaf.endswith(suffix) or leaf == suffix[1:]:
            return unit
    return "1"


def _describe(key: str, spec, one_joint: bool = False) -> SettingParam:
    unit = _unit(key, spec)
    shape = {Joints: "this node's joint's value" if one_joint else "one value per joint, chain order",
             Pair: "[t0, t1]", tuple: "one value per input, in its unit"}.get(type(spec))
    if isinstance(spec, Text) and spec.choices:
        shape = "one of " + ", ".join(spec.choices)
    text = (f"{key} of the run's settings (config/default.yaml)" + (f", {shape}" if shape else "")
            + (f" [{unit}]" if unit else ""))
    if isinstance(spec, Pair):
        return SettingParam(text, 0.0, None)
    num = spec.num if isinstance(spec, Joints) else spec[0] if isinstance(spec, tuple) else spec
    if not isinstance(num, Num):  # a flag or a string
        return SettingParam(text)
    if num.strict and num.low is not None:
        text += f"; > {num.low:g}"
    return SettingParam(text, num.low, num.high)


def section_params(sections) -> dict[str, SettingParam]:
    """Every parameter of ``sections`` (names of ``settings.SECTIONS``): dotted key -> SettingParam."""
    return {key: _describe(key, spec) for name in sections for key, spec in _leaves(SCHEMA[name], name)}


#: controller kind -> the settings a joint controller runs (a section or subsection: every key under it)
JOINT_CONTROLLER_KEYS: dict[str, tuple[str, ...]] = {
    "dnbs": ("simulation.dt_s", "simulation.seed", "reference.preview_steps", "plant.torque_limit_nm", "dnbs",
             "guards", "checkpoint", "faults.seed", "faults.effort", "faults.kill_controller_at_s"),
    "pid": ("simulation.dt_s", "reference.preview_steps", "plant.torque_limit_nm", "pid",
            "guards.position_margin_rad", "guards.max_speed_rad_s", "guards.on_bad_state",
            "faults.seed", "faults.effort", "faults.kill_controller_at_s"),
}


def _spec_of(dotted: str):
    spec = SCHEMA
    for part in dotted.split("."):
        spec = spec[part]
    return spec


def _joint_leaves(controller: str):
    """(dotted key, spec) of every setting a ``controller`` joint controller runs, in JOINT_CONTROLLER_KEYS order."""
    for key in JOINT_CONTROLLER_KEYS[controller]:
        spec = _spec_of(key)
        if isinstance(spec, dict):
            yield from _leaves(spec, key)
        else:
            yield key, spec


def joint_params(controller: str) -> dict[str, SettingParam]:
    """Every settings parameter of a ``controller`` ('dnbs' or 'pid') joint controller: dotted key ->
    SettingParam (a per-joint key described as the node's joint's value)."""
    return {key: _describe(key, spec, one_joint=True) for key, spec in _joint_leaves(controller)}


def _setting(settings, key: str):
    """The value at a dotted ``key`` of ``settings``."""
    node = settings
    for part in key.split("."):
        node = getattr(node, part)
    return node


def joint_values(settings: Settings, controller: str, row: int) -> dict[str, object]:
    """The parameters' values of joint ``row``'s ``controller`` node, ``arm_file`` first: a per-joint key's value
    of that row as one float, everything else as :func:`section_values` gives it."""
    out: dict[str, object] = {ARM_FILE: str(settings.arm.file)}
    for key, spec in _joint_leaves(controller):
        value = _setting(settings, key)
        out[key] = float(value[row]) if isinstance(spec, Joints) else _ros_value(spec, value)
    return out


class _Part:
    """The keys of a section a node runs when it runs only some of them; reading another is an AttributeError
    naming it (the node runs nothing but its parameters)."""

    def __init__(self, key: str, fields: dict):
        self._key = key
        self.__dict__.update(fields)

    def __getattr__(self, name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        raise AttributeError(f"this node's parameters hold no {self._key}.{name} (ros/settings_params.py)")


def _section_classes() -> dict[str, type]:
    """Dotted key -> the typed class of every section and subsection (``faults.effort`` ->
    EffortLinkFaultSettings)."""
    import typing

    out: dict[str, type] = {}
    todo = list(SECTIONS.values())
    while todo:
        cls = todo.pop()
        out[cls.KEY] = cls
        todo.extend(t for t in typing.get_type_hints(cls).values()
                    if isinstance(t, type) and dataclasses.is_dataclass(t))
    return out


def _complete(spec: dict, tree: dict) -> bool:
    return set(tree) == set(spec) and all(_complete(spec[k], v) for k, v in tree.items() if isinstance(v, dict))


def _typed(key: str, spec: dict, tree: dict, classes: dict):
    """The (sub)section ``key`` from its checked ``tree``: its typed class when every key is there, else a
    :class:`_Part` of what is there."""
    if _complete(spec, tree):
        return classes[key].of(tree)
    return _Part(key, {k: _typed(f"{key}.{k}", spec[k], v, classes) if isinstance(v, dict) else v
                       for k, v in tree.items()})


def _listed(value):
    """A parameter's value as a config file holds it: arrays and tuples as lists."""
    return list(value) if isinstance(value, (list, tuple)) or hasattr(value, "tolist") else value


def _put(trees: dict, key: str, value) -> None:
    """``value`` placed at the dotted ``key`` of the nested mapping ``trees`` (its first part: the section)."""
    *parents, leaf = key.split(".")
    node = trees
    for part in parents:
        node = node.setdefault(part, {})
    node[leaf] = value


def joint_node_settings(arm: Arm, values: dict, controller: str) -> NodeSettings:
    """A ``controller`` joint controller's settings from its parameter ``values`` (dotted key -> value, a
    per-joint key one number) for ``arm``: every number checked as a config file's (ConfigError naming the key)
    and broadcast to every joint's row; a section it runs whole is typed, the others hold only its keys."""
    trees: dict[str, dict] = {}
    for key, spec in _joint_leaves(controller):
        _put(trees, key, check_value(key, _listed(values[key]), spec, arm.n_joints))
    classes = _section_classes()
    return NodeSettings(arm, {name: _typed(name, SCHEMA[name], tree, classes) for name, tree in trees.items()})


def _ros_value(spec, value):
    """A setting's value as its parameter holds it: float, int, bool, str, or a list of floats."""
    if isinstance(spec, (Joints, Pair, tuple)):
        return [float(v) for v in value]
    if isinstance(spec, Num):
        return int(value) if spec.integer else float(value)
    return value


def section_values(settings, sections) -> dict[str, object]:
    """The parameters' values of ``sections`` of ``settings`` (Settings or NodeSettings), ``arm_file`` first."""
    out: dict[str, object] = {ARM_FILE: str(settings.arm.file)}
    for name in sections:
        for key, spec in _leaves(SCHEMA[name], name):
            out[key] = _ros_value(spec, _setting(settings, key))
    return out


class NodeSettings:
    """The settings one node runs: its arm and the sections its parameters give (typed, validated as a config
    file's: every per-joint value has one value per joint of the arm). A section the node was not given is an
    AttributeError naming it: a node runs nothing but its parameters."""

    def __init__(self, arm: Arm, sections: dict):
        # every value was checked for the arm's joints as the sections were made (node_settings,
        # joint_node_settings): only what spans two keys is left
        sim = sections.get("simulation")
        if dataclasses.is_dataclass(sim) and sim.window_s[1] > sim.duration_s + 1e-12:
            raise ConfigError(f"simulation.window_s: ends at {sim.window_s[1]:g} s, after "
                              f"simulation.duration_s = {sim.duration_s:g} s")
        self.arm = arm
        self.sections = tuple(sections)
        self.__dict__.update(sections)

    def __getattr__(self, name: str):
        if name in SECTIONS:
            raise AttributeError(f"this node's parameters hold no {name} section (ros/settings_params.py)")
        raise AttributeError(name)

    @property
    def n_joints(self) -> int:
        return self.arm.n_joints


def node_settings(arm: Arm, values: dict, sections) -> Settings | NodeSettings:
    """The typed sections ``sections`` from parameter ``values`` (dotted key -> value), for ``arm``: a whole
    ``Settings`` when every section is there, else a :class:`NodeSettings`. ConfigError naming the key when a
    value is bad."""
    typed = {}
    for name in sections:
        trees: dict = {}
        for key, _spec in _leaves(SCHEMA[name], name):
            _put(trees, key, _listed(values[key]))
        checked = check_value(name, trees[name], SCHEMA[name], arm.n_joints)
        typed[name] = SECTIONS[name].of(checked)
    if set(typed) == set(SECTIONS):
        return Settings(arm=arm, **typed)
    return NodeSettings(arm, typed)
