"""The run's ROS params file: every node's resolved settings as ``<node>: ros__parameters: ...``.

Written by the launcher next to config_used.yaml and passed to every node with ``--ros-args --params-file``:

- each joint controller: ``arm_file`` and every setting it runs (``ros/settings_params.py``:
  ``JOINT_CONTROLLER_KEYS``), a per-joint key holding that joint's value, one double;
- the plant (or the joint bus), the MuJoCo robot, the reference node, the observers: ``arm_file`` and every key
  of the sections of the settings they run (``ros/settings_params.py``: ``NODE_SECTIONS``).

Each node declares them read-only, with unit and range, and runs their values, so ``ros2 param get
/<ns>/joint_controller_<joint> pid.kp`` or ``ros2 param dump /<ns>/plant`` (or the node's ``get_parameters``
service) reads what it runs. Floats are written as Python's repr (17 significant digits at most), so a node
reads the same bits back; strings are quoted (an unquoted ``nan`` would be a double to ROS). Never imports rclpy.
"""
from __future__ import annotations

from pathlib import Path

import yaml

from ..ros.settings_params import NODE_SECTIONS, joint_values, section_values
from ..settings import Settings


def controller_node_name(namespace: str, joint: str) -> str:
    """The fully qualified name of joint ``joint``'s controller node in ``namespace``."""
    return f"{namespace.rstrip('/')}/joint_controller_{joint}"


def node_name(namespace: str, node: str) -> str:
    """The fully qualified name of ``node`` in ``namespace``."""
    return f"{namespace.rstrip('/')}/{node}"


def params_document(settings: Settings, controller: str, namespace: str) -> dict:
    """{node: {"ros__parameters": {...}}} for every joint controller of the arm (every setting it runs, its
    joint's value of each per-joint key) and every other node that runs settings (``NODE_SECTIONS``), nested as
    ROS nests a dotted parameter name (``pid: {kp: ...}`` is the parameter ``pid.kp``)."""
    doc = {controller_node_name(namespace, joint):
           {"ros__parameters": _nested(joint_values(settings, controller, row))}
           for row, joint in enumerate(settings.arm.joint_names)}
    for node, sections in NODE_SECTIONS.items():
        doc[node_name(namespace, node)] = {"ros__parameters": _nested(section_values(settings, sections))}
    return doc


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
    path.write_text(params_yaml(params_document(settings, controller, namespace)))
    return path


class _Dumper(yaml.SafeDumper):
    """Every string value single-quoted: ROS's params parser reads a bare ``nan``, ``inf`` or ``yes`` as a number
    or a flag (keys stay plain)."""

    def choose_scalar_style(self):
        if self.event.tag == "tag:yaml.org,2002:str" and not self.simple_key_context:
            return "'"
        return super().choose_scalar_style()


_Dumper.add_representer(list, lambda dumper, items: dumper.represent_sequence("tag:yaml.org,2002:seq", items,
                                                                           flow_style=True))


def params_yaml(document: dict) -> str:
    """A params document as YAML for ROS: floats as Python's repr, string values quoted, lists on one line."""
    return yaml.dump(document, Dumper=_Dumper, sort_keys=False, default_flow_style=False, width=1000)
