"""The files a command writes are strict JSON: a non-finite figure is null, never NaN or Infinity."""
import json
import math

import numpy as np
import pytest

from pa10_dnbs.atomic_file import write_json
from pa10_dnbs.json_text import json_text


def _refuse(name):
    raise ValueError(f"{name} is not JSON")


def test_non_finite_floats_are_null_at_every_depth_finite_ones_exact():
    obj = {"a": math.inf, "b": [1.0, -math.inf, {"c": math.nan}], "d": (np.float64("nan"), np.float64(0.1)),
           "e": 0.1 + 0.2, "f": None, "g": "NaN", "h": 3, "i": True}
    back = json.loads(json_text(obj), parse_constant=_refuse)
    assert back == {"a": None, "b": [1.0, None, {"c": None}], "d": [None, 0.1], "e": 0.1 + 0.2, "f": None,
                    "g": "NaN", "h": 3, "i": True}
    assert json_text(obj).endswith("}\n")


def test_the_input_is_left_as_it_was():
    obj = {"x": [math.inf]}
    json_text(obj)
    assert obj["x"][0] == math.inf


def test_write_json_writes_strict_json(tmp_path):
    write_json(tmp_path / "s.json", {"latency_s": [math.nan, 0.001]})
    assert json.loads((tmp_path / "s.json").read_text(), parse_constant=_refuse) == {"latency_s": [None, 0.001]}


def test_what_json_cannot_hold_is_still_refused():
    with pytest.raises(TypeError):
        json_text({"x": object()})
