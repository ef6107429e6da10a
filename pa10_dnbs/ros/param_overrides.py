"""The ``-p name:=value`` rules of a node's command line, checked before ``rclpy.init`` parses them.

rcl reads each value as YAML and takes a scalar or a list of scalars; anything else (``forward:``, a mapping;
``[1,``, not YAML) fails ``rclpy.init`` itself, outside a node's one-line error handling, as an RCLError
traceback after an rcl log line. Checked here first, the user's mistake is one line naming the rule (exit 2, as
every other bad parameter, docs/graph.md). No rclpy here.
"""
from __future__ import annotations

import json
from pathlib import PurePath

import yaml


def override_value(value) -> str:
    """``value`` as the VALUE of a ``-p NAME:=VALUE`` rule that rcl reads back as given: a path (PurePath) or each
    string of a list or tuple double-quoted (YAML; a path holding ``: ``, `` #``, ``'`` or a leading ``[`` read as
    a path, not as a mapping, a comment or a broken list), a bool as true/false, anything else as str() (numbers,
    and strings meant as YAML: names, ``'[...]'``)."""
    if isinstance(value, PurePath):
        return json.dumps(str(value), ensure_ascii=False)
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(json.dumps(str(v), ensure_ascii=False) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def param_rules(argv, flags: tuple[str, ...] = ("-p", "--param")):
    """(flag, rule) of each ``-p``/``--param`` rule (or of ``flags``: ``("-r", "--remap")``) of ``argv`` (a node's
    command line), in order; only those inside ``--ros-args`` ... (``--`` or the end) count."""
    argv = list(argv)
    inside = False
    for i, arg in enumerate(argv):
        if arg == "--ros-args":
            inside = True
        elif arg == "--":
            inside = False
        elif inside and arg in flags and i + 1 < len(argv):
            yield arg, argv[i + 1]


def bad_param_override(argv: list[str]) -> str | None:
    """What is wrong with the first ``-p``/``--param`` rule of ``argv`` (a node's command line) rcl cannot read,
    else None (:func:`param_rules`)."""
    for arg, rule in param_rules(argv):
        name, sep, value = rule.partition(":=")
        if not sep or not name:
            return f"parameter override '{arg} {rule}': expected name:=value"
        try:
            parsed = yaml.safe_load(value)
        except yaml.YAMLError:
            parsed = {}  # not YAML at all
        if isinstance(parsed, dict) or (isinstance(parsed, list)
                                         and any(isinstance(v, (dict, list)) for v in parsed)):
            return (f"parameter {name}: the override '{arg} {rule}' is not a value rcl can read (a scalar or a "
                    f"list of scalars, as YAML; quote a string holding ':' or '[': -p '{name}:=\"{value}\"')")
    return None
