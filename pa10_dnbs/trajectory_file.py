"""A JointTrajectory file (YAML or JSON: the same fields as trajectory_msgs/JointTrajectory) -> JointTrajectory.

Format (docs/trajectories.md; example: config/trajectory_example.yaml)::

    joint_names: [s1, s2, s3, e1, e2, w1, w2]   # any order: matched by name
    points:
      - time_from_start: 1.0                    # [s], or {sec: 1, nanosec: 0}
        positions: [0.1, 0.2, 0.0, 0.3, 0.0, 0.2, 0.0]   # [rad]
        velocities: [...]                       # optional [rad/s], for every point or none
        accelerations: [...]                    # optional [rad/s^2], for every point or none

JSON is read by the same strict YAML parser as the config (config_yaml.py: ``1e-05`` is a number, a key given
twice is refused), or, when it is plain JSON, by ``json`` with the same rules (:func:`plain_json`: the same
values, ~100x faster: 1e5 points in 0.3 s instead of ~35 s). ``load_trajectory_file`` checks the file against the arm as
``TrajectoryReference.start`` will (names, limits, timing) and raises ConfigError with one line naming the
file and what is wrong (a point past ``MAX_TIME_FROM_START_S`` included).
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import yaml

from .config_error import ConfigError
from .config_yaml import AliasBombError, load_strict
from .core.joint_trajectory import JointTrajectory, TrajectoryError, check_trajectory, trajectory_from_mapping
from .core.trajectory_reference import MAX_TIME_FROM_START_S, check_span
from .file_path import NOT_REGULAR, PathProblem, file_or_folder
from .run_size import say_note

SAY_YAML_BYTES = 1_000_000   # a YAML trajectory text longer than this is announced before it is read


#: A character outside printable ASCII (and tabs and line breaks: JSON whitespace), or a backslash: ``plain_json``
#: leaves such a text to the YAML reader (it refuses some of them, e.g. DEL, and reads escapes and line separators
#: its own way). A tab is JSON's whitespace (``json.dumps(d, indent="\t")``, ``jq --tab``) but not YAML's
#: indentation: ``json`` reads it (a tab inside a string is refused by ``json`` and left to the YAML reader).
_NOT_PLAIN = re.compile(r"[^\t\n\r\x20-\x7e]|\\")


class _NotPlain(Exception):
    """A JSON document the strict YAML reader must read: a key given twice, NaN or Infinity."""


def _once(pairs: list) -> dict:
    keys = [k for k, _ in pairs]
    if len(set(keys)) != len(keys):
        raise _NotPlain
    return dict(pairs)


def _no_constant(name: str):
    raise _NotPlain


def plain_json(text: str):
    """``text``'s document read by ``json`` when it is plain JSON: printable ASCII or tabs without a backslash, no key
    given twice in an object, no NaN or Infinity, not nested past Python's recursion limit, no integer past its
    4300 digits; else None (read it with config_yaml.load_strict). load_strict reads such a document to the same
    values (test/test_trajectory_intake_exact.py): numbers alike (an int, or a float of the same bits: ``-0.0``,
    ``1e5``, ``1e999``), strings with nothing to unescape, true / false / null; the valid JSON layouts PyYAML
    refuses (a key and its ':' on two lines, a key of over 1024 characters, tabs between tokens) are read.
    ~100x faster."""
    if _NOT_PLAIN.search(text) is not None:
        return None
    try:
        return json.loads(text, object_pairs_hook=_once, parse_constant=_no_constant)
    except (ValueError, RecursionError, _NotPlain):   # not JSON (YAML), or what only load_strict says in one line
        return None


def _not_special(path: Path) -> None:
    """TrajectoryError for a pipe or a device, as --config and --arm refuse them (file_path.file_or_folder): a FIFO
    without a writer blocked the read forever, /dev/zero filled memory. Other faults are the read's to say."""
    try:
        file_or_folder(path)
    except PathProblem as exc:
        if exc.special:
            raise TrajectoryError(NOT_REGULAR) from None


def read_trajectory(path: Path, say=None) -> JointTrajectory:
    """The file's JointTrajectory (shapes and types checked), or TrajectoryError / OSError; ``say(line)``: told
    before a YAML text of over SAY_YAML_BYTES is read (the YAML reader is pure Python, ~2 s per MB). A pipe or a
    device (bash's ``<(...)`` too) is refused unread."""
    _not_special(Path(path))
    try:
        text = Path(path).read_text(encoding="utf-8")
        data = plain_json(text)
        if data is None:
            if say is not None and len(text) > SAY_YAML_BYTES:
                say(f"trajectory {path}: {len(text) / 1e6:.0f} MB of YAML: the YAML reader takes about 2 s per MB "
                    f"(the same points as plain JSON read in about 0.1 s per MB)")
            data = load_strict(text)
    except AliasBombError as exc:
        raise TrajectoryError(exc.problem) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise TrajectoryError(f"not YAML or JSON{where}: {getattr(exc, 'problem', None) or exc}") from None
    except UnicodeDecodeError:
        raise TrajectoryError("not a text file") from None
    return trajectory_from_mapping(data)


def check_times(traj: JointTrajectory) -> None:
    """TrajectoryError (one line) for a time_from_start that ``load_trajectory_file`` refuses whatever the arm:
    not finite, before 0, or past ``MAX_TIME_FROM_START_S`` (every point, in any order)."""
    t = np.asarray(traj.time_from_start_s, dtype=float)
    bad = ~((t >= 0) & (t <= MAX_TIME_FROM_START_S))   # NaN included
    if np.any(bad):
        i = int(np.argmax(bad))
        raise TrajectoryError(f"points[{i}].time_from_start = {t[i]:g} s is out of range (finite, from 0 to the "
                              f"longest trajectory followed, {MAX_TIME_FROM_START_S:g} s)")


def read_sendable(path: Path) -> JointTrajectory:
    """The file's trajectory for the trajectory sender, read as ``--trajectory`` reads it (``read_trajectory``)
    with its times checked (``check_times``): the checks against an arm are the receiving node's. TrajectoryError
    ``trajectory <path>: <what is wrong>`` or OSError otherwise."""
    try:
        traj = read_trajectory(path)
        check_times(traj)
    except TrajectoryError as exc:
        raise TrajectoryError(f"trajectory {path}: {exc}") from None
    return traj


def load_trajectory_file(path: Path, arm, say=say_note) -> JointTrajectory:
    """The file's trajectory, checked against ``arm`` (an Arm: joint names, URDF limits); ConfigError
    ``trajectory <path>: <what is wrong>`` (setting ``trajectory``) otherwise. ``say``: a long read's note."""
    try:
        traj = read_trajectory(path, say)
        check_trajectory(traj, arm.joint_names, arm.lower_rad, arm.upper_rad)
        check_span(traj)
    except TrajectoryError as exc:
        raise ConfigError(f"trajectory {path}: {exc}", setting="trajectory") from None
    except OSError as exc:
        raise ConfigError(f"trajectory {path}: {exc.strerror or exc}", setting="trajectory") from None
    return traj
