"""Node parameters: declared in code with defaults and descriptors, valued from the command line or a params file.

Every parameter is a ``Param``: default, description (with the unit), read-only (all of ours: a node reads
its parameters once, at start), and an inclusive range where there is one (FloatingPointRange or
IntegerRange in the descriptor, so ``ros2 param describe`` shows it and rclpy refuses a value outside it).
A bad value (outside the range, of the wrong type, or refused by a node's own check) is a
``ParameterError``: one line on stderr and exit code 2 (``runtime.run_node``).

A node's settings (the sections of the config it runs, ``settings_params.py``) are declared the same way by
:func:`declare_settings`, which hands back the typed settings built from those parameters alone; a joint
controller's (the keys it runs, its joint's value of each per-joint key) by :func:`declare_joint_settings`.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.node import Node

from ..arm import ArmError, load_arm
from ..config import ConfigError, default_config_path
from ..run_settings import build_settings
from ..run_steps import run_steps
from ..settings import Settings
from .param_overrides import param_rules
from .settings_params import (ARM_FILE, ARM_FILE_DESCRIPTION, joint_node_settings, joint_params, joint_values,
                              node_settings, section_params, section_values)


#: the largest keep_last depth a node takes [messages]: a few minutes of 1 kHz messages; past 2^32 rclpy's QoS
#: refused it with a TypeError traceback, and DDS may reserve the depth's memory up front
MAX_QOS_DEPTH = 1_000_000


class ParameterError(ValueError):
    """A node parameter with a missing or bad value: reported in one line, exit code 2."""


@dataclass(frozen=True)
class Param:
    """One node parameter: ``default`` (its type is the parameter's), ``description`` with the unit, and an
    inclusive range [``lo``, ``hi``] (None: unbounded on that side; both None: no range)."""

    default: Any
    description: str
    lo: float | int | None = None
    hi: float | int | None = None
    read_only: bool = True
    writes: bool = False   # a path the node writes ('' = none): its folder must be there when the node starts
    topics: bool = False   # topic names ('' = the default), or a list of them, each may end in :pkg/msg/Type

    def descriptor(self) -> ParameterDescriptor:
        d = ParameterDescriptor(description=self.description, read_only=self.read_only)
        if self.lo is None and self.hi is None:
            return d
        numbers = list(self.default) if isinstance(self.default, (list, tuple)) else [self.default]
        if not numbers or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in numbers):
            raise TypeError(f"expected a number (or one per joint), got {self.default!r}")
        if isinstance(self.default, int):
            d.integer_range = [IntegerRange(from_value=int(-2**63 if self.lo is None else self.lo),
                                            to_value=int(2**63 - 1 if self.hi is None else self.hi), step=1)]
        else:
            d.floating_point_range = [FloatingPointRange(
                from_value=float(-1.7976931348623157e308 if self.lo is None else self.lo),
                to_value=float(1.7976931348623157e308 if self.hi is None else self.hi), step=0.0)]
        return d

    def default_text(self) -> str:
        """The default as ``-p NAME:=VALUE`` or a params file writes it: a string quoted, a switch true / false."""
        if isinstance(self.default, str):
            return repr(self.default)
        return str(self.default).lower() if isinstance(self.default, bool) else str(self.default)

    def range_text(self) -> str:
        """The range for docs: '[0, 1]', '>= 0', '' (none)."""
        if self.lo is None and self.hi is None:
            return ""
        lo, hi = (v if isinstance(v, int) or v is None else f"{v:g}" for v in (self.lo, self.hi))  # 1000000, 1e+06
        if self.hi is None:
            return f">= {lo}"
        if self.lo is None:
            return f"<= {hi}"
        return f"[{lo}, {hi}]"


def params_help(prog: str, specs: dict[str, Param]) -> str:
    """A node's ``--help``: how it is started and its own parameters, one per line (name, default, range,
    description); the settings a node also takes as parameters (its config sections) are in docs/graph.md."""
    width = max(map(len, specs), default=0)
    lines = [f"usage: {prog} [--ros-args [-r __ns:=NS] [-p NAME:=VALUE ...] [--params-file FILE]]", "",
             "a ROS 2 node; its parameters (-p NAME:=VALUE; read-only, read once at start; docs/graph.md lists them "
             "with the settings it also takes):"]
    for name, spec in specs.items():
        bounds = f" {spec.range_text()}" if spec.range_text() else ""
        lines.append(f"  {name:<{width}}  {spec.default_text()}{bounds}: {spec.description}")
    return "\n".join(lines)


def declare(node: Node, specs: dict[str, Param]) -> dict:
    """Declare every parameter of ``specs`` with its descriptor and return their current values; a value
    rclpy refuses (type, range) raises ParameterError naming the parameter."""
    for name, spec in specs.items():
        try:
            node.declare_parameter(name, spec.default, spec.descriptor())
        except (ParameterException, TypeError) as exc:  # TypeError: a value of the wrong type for a ranged key
            raise ParameterError(f"parameter {name}: {_one_line(exc)} ({spec.description})") from None
    values = {name: node.get_parameter(name).value for name in specs}
    for name, spec in specs.items():
        if spec.writes and values[name]:
            check_writable(name, values[name])
        if spec.topics:
            check_topic_names(node, name, values[name])
    return values


def check_topic_names(node: Node, name: str, value) -> None:
    """ParameterError naming parameter ``name`` unless each topic ``value`` names (a name or a list of names, ''
    skipped, a ``:pkg/msg/Type`` tail ignored) is a valid name once expanded in ``node``'s namespace: rcl refused
    ``bad name`` or ``/a//b`` only when the endpoint was made, as a traceback."""
    from rclpy.exceptions import NameValidationException
    from rclpy.expand_topic_name import expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name

    for topic in [value] if isinstance(value, str) else value:
        topic = topic.split(":", 1)[0]
        if not topic:
            continue
        try:
            validate_full_topic_name(expand_topic_name(topic, node.get_name(), node.get_namespace()))
        except (NameValidationException, ValueError) as exc:
            why = _one_line(exc).removesuffix(" ^").split(", at /")[0]
            raise ParameterError(f"parameter {name}: {why}") from None


def check_writable(name: str, path: str) -> None:
    """ParameterError naming parameter ``name`` unless the folder of ``path`` is there to write it in: found at
    the start, not when the node writes it at its end (after the whole run)."""
    folder = Path(os.path.abspath(path)).parent
    if not folder.is_dir():
        raise ParameterError(f"parameter {name}: {path}: no folder {folder} to write it in")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ParameterError(f"parameter {name}: {path}: its folder {folder} is not writable here")


def _one_line(exc: Exception) -> str:
    return " ".join(str(exc).split())


def cli_parameter(argv, name: str) -> str | None:
    """The value of ``-p name:=value`` (or ``--param``) among the ROS arguments of ``argv``, else None (what a
    node needs before it exists, e.g. for its name; a params file is not read here)."""
    for _, rule in param_rules(argv):
        key, sep, value = rule.partition(":=")
        if sep and key == name:
            return value.strip("'\"")
    return None


def load_node_config(path: str, arm: str | None = None, arm_param: str = ARM_FILE) -> Settings:
    """The settings a node runs with, built once from its config file (every value resolved; '' means the
    shipped default) and the arm it names (``arm``: another one, given by parameter ``arm_param``). A bad file
    is a ParameterError naming the parameter (config_file, or ``arm_param`` when that arm is bad)."""
    try:
        return build_settings(path or default_config_path(), arm=arm or None)
    except ConfigError as exc:
        name = arm_param if arm and isinstance(exc, ArmError) else "config_file"
        raise ParameterError(f"parameter {name}: {_one_line(exc)}") from None


def declare_settings(node: Node, sections, config_file: str = "", arm: str | None = None, arm_param: str = ARM_FILE):
    """Declare ``arm_file`` and every key of ``sections`` (``settings_params.NODE_SECTIONS``) as read-only
    parameters, with unit and range, and return the typed settings built from their values alone
    (``settings_params.node_settings``); the arm is read once, from ``arm_file``.

    Their values come from the run's params file (the launcher's ros_params.yaml) or ``-p``; only when some
    are not given there, their defaults are the settings of ``config_file`` ('' = the shipped default) for the
    arm ``arm`` (else the config's). A bad value is a ParameterError naming the parameter."""
    def from_config(arm_file: str | None) -> dict:
        return section_values(load_node_config(config_file, arm_file or arm, ARM_FILE if arm_file else arm_param),
                              sections)

    values, the_arm = _declare_with_arm(node, section_params(sections), from_config)
    try:
        return node_settings(the_arm, values, sections)
    except ConfigError as exc:
        raise ParameterError(f"parameter {exc}") from None


def declare_joint_settings(node: Node, controller: str, joint: str, config_file: str = ""):
    """Declare ``arm_file`` and every setting joint ``joint``'s ``controller`` ('dnbs' or 'pid') runs
    (``settings_params.JOINT_CONTROLLER_KEYS``; a per-joint key holds this joint's value, one double) as read-only
    parameters, with unit and range; return (its settings built from their values alone, the joint's index in
    the arm). The arm is read once, from ``arm_file``.

    Their values come from the run's params file or ``-p``; only when some are not given there, their defaults
    are the settings of ``config_file`` ('' = the shipped default), which is then read. A bad value, or a joint
    the arm has not, is a ParameterError naming the parameter."""
    def from_config(arm_file: str | None) -> dict:
        settings = load_node_config(config_file, arm_file, ARM_FILE)
        check_choice("joint", joint, settings.arm.joint_names)
        return joint_values(settings, controller, settings.arm.index(joint))

    values, the_arm = _declare_with_arm(node, joint_params(controller), from_config)
    check_choice("joint", joint, the_arm.joint_names)
    try:
        return joint_node_settings(the_arm, values, controller), the_arm.index(joint)
    except ConfigError as exc:
        raise ParameterError(f"parameter {exc}") from None


def _declare_with_arm(node: Node, specs: dict, from_config) -> tuple[dict, object]:
    """Declare ``arm_file`` and ``specs`` (name -> SettingParam) read-only, defaults from what the params file
    and ``-p`` give the node, or else from ``from_config(arm_file given or None)`` (a config file is read only
    then); return their values and the arm, read once from ``arm_file``."""
    names = [ARM_FILE, *specs]
    given = node._parameter_overrides  # what the params file and -p give this node (rclpy keeps no public view)
    if all(name in given for name in names):
        defaults = {name: _plain_value(given[name].value) for name in names}
    else:
        defaults = from_config(_text(given.get(ARM_FILE)))
    params = {ARM_FILE: Param(defaults[ARM_FILE], ARM_FILE_DESCRIPTION)}
    params.update({key: Param(defaults[key], s.description, s.lo, s.hi) for key, s in specs.items()})
    values = declare(node, params)
    try:
        return values, load_arm(values[ARM_FILE])
    except ConfigError as exc:
        raise ParameterError(f"parameter {ARM_FILE}: {_one_line(exc)}") from None


def _plain_value(value):
    return value.tolist() if hasattr(value, "tolist") else list(value) if isinstance(value, tuple) else value


def _text(parameter) -> str | None:
    return parameter.value if parameter is not None and isinstance(parameter.value, str) else None


def duration_steps(duration_s: float, dt_s: float, name: str = "duration_s") -> int:
    """The steps of ``dt_s`` [s] in the node parameter ``name``'s duration ``duration_s`` [s] (> 0), counted as
    the launcher counts them (``run_steps``): ParameterError naming the parameter for a duration too long to count
    (1e308 s: an infinite step count, an OverflowError once rounded) or shorter than two steps."""
    try:
        return run_steps(duration_s, dt_s, f"parameter {name}")
    except ConfigError as exc:
        raise ParameterError(str(exc)) from None


def check_choice(name: str, value, choices) -> None:
    if value not in choices:
        raise ParameterError(f"parameter {name} must be one of {', '.join(map(str, choices))}, got {value!r}")


SETTINGS_DEFAULTS = Param("", "the YAML config (config/default.yaml and its units) whose values are the defaults of "
                              "the settings parameters the params file does not give; '' = the shipped default")
SCHED_BATCH = Param(False, "SCHED_BATCH on every thread: the node's wake-ups do not preempt the plant (the "
                           "launcher's --sched-batch sets it on every node but the plant); false = the default policy")
RT_PRIORITY = Param(0, "SCHED_FIFO priority 1..99 on every thread, where the OS allows it (the launcher's "
                         "--rt-priority); 0 = off", 0, 99)
