"""<ns>/tracking (/pa10/tracking by default): per-joint tracking error and torque of one displayed frame (JSON, with its JSON schema).

One message per frame the live view shows, built from that frame's
/joint_states (stamp k T, x(k), and as effort the torque applied over step
k-1) and the reference x_d(k) from the reference batches. JSON has no NaN: a
value not known yet (no reference batch for the step) is null, which Foxglove's
plots skip.
"""
from __future__ import annotations

import json
import math

from ..wire.steps import NS_PER_S

SCHEMA_NAME = "pa10_dnbs/Tracking"

_ARRAY = {"type": "array", "items": {"type": ["number", "null"]}}
SCHEMA = {
    "title": SCHEMA_NAME,
    "description": "Tracking error and torque of every joint at one displayed step (order of joint_names).",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "description": "simulated time k T of the state",
                      "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
        "step": {"type": "integer", "description": "step k"},
        "joint_names": {"type": "array", "items": {"type": "string"}},
        "error_rad": {**_ARRAY, "description": "e = x_d(k) - x1(k) [rad]; null without a reference for k"},
        "abs_error_rad": {**_ARRAY, "description": "|e| [rad]"},
        "position_rad": {**_ARRAY, "description": "x1(k) [rad]"},
        "reference_rad": {**_ARRAY, "description": "x_d(k) [rad]"},
        "torque_nm": {**_ARRAY, "description": "torque applied over step k-1, after the torque-limit saturation [N m]"},
        "torque_limit_nm": {**_ARRAY, "description": "the joint's torque limit [N m]"},
        "torque_over_limit": {**_ARRAY, "description": "torque_nm / torque_limit_nm (the limits are -1 and 1)"},
        "torque_fraction_limits": {**_ARRAY, "description": "[-1, 1]: the torque limits on torque_over_limit"},
        "worst_abs_error_rad": {"type": ["number", "null"],
                                "description": "largest |e| over the frames shown so far [rad]"},
    },
}


def _num(v: float) -> float | None:
    return v if math.isfinite(v) else None


def tracking_message(stamp_ns: int, step: int, joint_names, position_rad, reference_rad, torque_nm,
                     torque_limit_nm, worst_abs_error_rad: float) -> dict:
    """The tracking message (a dict ready for JSON) of one frame; all sequences in joint order."""
    error = [xd - x for xd, x in zip(reference_rad, position_rad)]
    sec, nsec = divmod(int(stamp_ns), NS_PER_S)
    return {
        "timestamp": {"sec": sec, "nsec": nsec},
        "step": int(step),
        "joint_names": list(joint_names),
        "error_rad": [_num(v) for v in error],
        "abs_error_rad": [_num(abs(v)) for v in error],
        "position_rad": [_num(v) for v in position_rad],
        "reference_rad": [_num(v) for v in reference_rad],
        "torque_nm": [_num(v) for v in torque_nm],
        "torque_limit_nm": [float(v) for v in torque_limit_nm],
        "torque_over_limit": [_num(t / lim) for t, lim in zip(torque_nm, torque_limit_nm)],
        "torque_fraction_limits": [-1.0, 1.0],
        "worst_abs_error_rad": _num(worst_abs_error_rad),
    }


def encode(message: dict) -> bytes:
    """UTF-8 JSON (strict: no NaN)."""
    return json.dumps(message, allow_nan=False, separators=(",", ":")).encode()
