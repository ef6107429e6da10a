"""The Foxglove layout of the live view (config/foxglove_layout.json), built from the joints and their torque limits.

Written in the layout JSON the Foxglove app exports and imports (``configById``
panel settings + a ``layout`` split tree): a 3D panel with the URDF arm from
<ns>/robot_description posed by /tf, a plot of every joint's tracking error, a plot
of every joint's torque as a fraction of its limit with the limits at
-1 and 1, and the /diagnostics summary and detail panels. The same layout
works for a live connection and for a recorded bag (which holds /tf and the
URDF, but no <ns>/tracking: its plots then stay empty; see docs/live_view.md).
"""
from __future__ import annotations

import json

from ..wire.topics import DIAGNOSTICS, ArmTopics

# one colour per joint (s1 .. w2), the same in both plots
COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2")
LIMIT_COLOUR = "#ff0000"


def _series(topic: str, field: str, j: int, label: str, colour: str) -> dict:
    return {"value": f"{topic}.{field}[{j}]", "enabled": True, "timestampMethod": "receiveTime",
            "label": label, "color": colour}


def _plot(title: str, paths: list[dict], y_min=None, y_max=None) -> dict:
    panel = {"foxglovePanelTitle": title, "paths": paths, "showXAxisLabels": True, "showYAxisLabels": True,
           "showLegend": True, "legendDisplay": "floating", "showPlotValuesInLegend": True, "isSynced": True,
           "xAxisVal": "timestamp", "followingViewWidth": 10, "sidebarDimension": 240}
    if y_min is not None:
        panel["minYValue"], panel["maxYValue"] = y_min, y_max
    return panel


def layout(joint_names, torque_limit_nm, title: str, root_frame: str = "base_link",
           arm: ArmTopics = ArmTopics()) -> dict:
    """The layout of ``arm``'s topics as a JSON-ready dict (``title``: the arm's, on the 3D panel)."""
    errors = [_series(arm.tracking, "error_rad", j, name, COLOURS[j % len(COLOURS)]) for j, name in enumerate(joint_names)]
    torques = [_series(arm.tracking, "torque_over_limit", j, f"{name} (limit {lim:g} N m)", COLOURS[j % len(COLOURS)])
               for j, (name, lim) in enumerate(zip(joint_names, torque_limit_nm))]
    torques += [_series(arm.tracking, "torque_fraction_limits", i, f"torque limit ({sign})", LIMIT_COLOUR)
                for i, sign in enumerate(("-", "+"))]
    three_d = {
        "foxglovePanelTitle": f"{title}: URDF from {arm.robot_description}, posed by /tf",
        "cameraState": {"perspective": True, "distance": 3.5, "phi": 60, "thetaOffset": 45,
                        "targetOffset": [0, 0, 0.8], "target": [0, 0, 0], "targetOrientation": [0, 0, 0, 1],
                        "fovy": 45, "near": 0.01, "far": 500},
        "followMode": "follow-pose", "followTf": root_frame,
        "scene": {"transforms": {"showLabel": False, "axisScale": 0.5}},
        "transforms": {},
        "topics": {arm.robot_description: {"visible": True}},
        "layers": {"grid": {"visible": True, "frameLocked": True, "label": "Grid", "instanceId": "grid",
                            "layerId": "foxglove.Grid", "frameId": root_frame, "size": 4, "divisions": 20,
                            "lineWidth": 1, "color": "#8c8c8c80", "position": [0, 0, 0], "rotation": [0, 0, 0],
                            "order": 1}},
        "imageMode": {},
    }
    config = {
        "3D!arm": three_d,
        "Plot!errors": _plot(f"Tracking error e = x_d - x [rad] ({arm.tracking})", errors),
        "Plot!torques": _plot("Torque / torque limit (limits at -1 and +1)", torques, -1.1, 1.1),
        "DiagnosticSummary!diagnostics": {"topicToRender": DIAGNOSTICS, "minLevel": 0, "pinnedIds": [],
                                   "hardwareIdFilter": "", "sortByLevel": True},
        "DiagnosticStatusPanel!diagnostics": {"topicToRender": DIAGNOSTICS, "collapsedSections": [],
                                       "selectedHardwareId": "plant"},
    }
    tree = {
        "first": "3D!arm",
        "second": {
            "first": {"first": "Plot!errors", "second": "Plot!torques", "direction": "column",
                      "splitPercentage": 50},
            "second": {"first": "DiagnosticSummary!diagnostics", "second": "DiagnosticStatusPanel!diagnostics",
                       "direction": "row", "splitPercentage": 50},
            "direction": "column", "splitPercentage": 72,
        },
        "direction": "row", "splitPercentage": 45,
    }
    return {"configById": config, "globalVariables": {}, "userNodes": {}, "playbackConfig": {"speed": 1},
            "layout": tree}


def layout_json(joint_names, torque_limit_nm, title: str, root_frame: str = "base_link",
                arm: ArmTopics = ArmTopics()) -> str:
    """The layout as the JSON file Foxglove imports (``title``: the arm's, on the 3D panel)."""
    return json.dumps(layout(joint_names, torque_limit_nm, title, root_frame, arm), indent=2) + "\n"
