"""The run's ROS params file: each joint controller's resolved gains as ``<node>: ros__parameters: ...``.

Written by the launcher next to config_used.yaml and passed to every joint controller with
``--ros-args --params-file``; the node declares each of them read-only, with its unit and range, so
``ros2 param get /<ns>/joint_controller_<joint> pid.kp`` (or the node's ``get_parameters`` service) reads
what it runs. Never imports rclpy.
"""
from __future__ import annotations

from pathlib import Path

import yaml

from ..controller_gains import joint_gains
from ..settings import Settings


def controller_node_name(namespace: str, joint: str) -> str:
    """The fully qualified name of joint ``joint``'s controller node in ``namespace``."""
    return f"{namespace.rstrip('/')}/joint_controller_{joint}"


def params_document(settings: Settings, controller: str, namespace: str) -> dict:
    """{node: {"ros__parameters": {...}}} for every joint controller of the arm: each gain under its config key,
    nested as ROS nests a dotted parameter name (``pid: {kp: ...}`` is the parameter ``pid.kp``)."""
    return {controller_node_name(namespace, joint): {"ros__parameters": _nested(joint_gains(settings, controller, row))}
            for row, joint in enumerate(settings.arm.joint_names)}


def _nested(flat: dict) -> dict:
    out: dict = {}
    for key, value in flat.items():
        *parents, leaf = key.split(".")
        node = out
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return out


def write_params_file(path: Path, settings: Settings, controller: str, namespace: str) -> Path:
    """Write :func:`params_document` to ``path`` (YAML: every float as Python writes it, so the node reads the
    same bits back)."""
    path.write_text(yaml.safe_dump(params_document(settings, controller, namespace), sort_keys=False))
    return path
