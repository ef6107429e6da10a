"""JSON as strict readers take it (RFC 8259: no NaN, no Infinity): the one encoder of the files a command
writes (metrics.json, summary.json, study.json, tune.json, the partial marks and the stats files).

A figure that is not finite (a diverged run's RMS, a wall time a bag does not hold) is written ``null``;
the file says why beside it (``"diverged"``, the report's note).
"""
from __future__ import annotations

import json
import math


def _strict(obj):
    """``obj`` with every non-finite float (numpy's included) replaced by None; lists, tuples and dicts walked."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_strict(v) for v in obj]
    return obj


def json_text(obj, indent: int | None = 2) -> str:
    """``obj`` as strict JSON text, ending in a newline; non-finite floats are ``null``."""
    return json.dumps(_strict(obj), indent=indent, allow_nan=False) + "\n"
