"""Node parameters: declared in code with defaults, valued from the command line or a params file."""
from __future__ import annotations

from rclpy.node import Node

from ..config import ConfigError, default_config_path, load_config


class ParameterError(ValueError):
    """A node parameter with a missing or bad value: reported in one line, exit code 2."""


def declare(node: Node, defaults: dict) -> dict:
    """Declare every parameter of ``defaults`` and return their current values."""
    for name, value in defaults.items():
        node.declare_parameter(name, value)
    return {name: node.get_parameter(name).value for name in defaults}


def cli_parameter(argv, name: str) -> str | None:
    """The value of ``-p name:=value`` (or ``--param``) among the ROS arguments of ``argv``, else None (what a
    node needs before it exists, e.g. for its name; a params file is not read here)."""
    in_ros = False
    argv = list(argv)
    for i, a in enumerate(argv):
        if a == "--ros-args":
            in_ros = True
        elif a == "--":
            in_ros = False
        elif in_ros and a in ("-p", "--param") and i + 1 < len(argv):
            key, sep, value = argv[i + 1].partition(":=")
            if sep and key == name:
                return value.strip("'\"")
    return None


def load_node_config(path: str) -> dict:
    """The numeric config (config/*.yaml) a node runs with; '' means the shipped default."""
    try:
        return load_config(path or default_config_path())
    except ConfigError as exc:
        raise SystemExit(f"config error: {exc}") from None


def check_choice(name: str, value, choices) -> None:
    if value not in choices:
        raise ParameterError(f"parameter {name} must be one of {', '.join(map(str, choices))}, got {value!r}")
