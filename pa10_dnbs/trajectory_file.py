"""A JointTrajectory file (YAML or JSON: the same fields as trajectory_msgs/JointTrajectory) -> JointTrajectory.

Format (docs/trajectories.md; example: config/trajectory_example.yaml)::

    joint_names: [s1, s2, s3, e1, e2, w1, w2]   # any order: matched by name
    points:
      - time_from_start: 1.0                    # [s], or {sec: 1, nanosec: 0}
        positions: [0.1, 0.2, 0.0, 0.3, 0.0, 0.2, 0.0]   # [rad]
        velocities: [...]                       # optional [rad/s], for every point or none
        accelerations: [...]                    # optional [rad/s^2], for every point or none

JSON is read by the same strict YAML parser as the config (config_yaml.py: ``1e-05`` is a number, a key given
twice is refused). ``load_trajectory_file`` checks the file against the arm as
``TrajectoryReference.start`` will (names, limits, timing) and raises ConfigError with one line naming the
file and what is wrong (a point past ``MAX_TIME_FROM_START_S`` included).
"""
from __future__ import annotations

from pathlib import Path

import yaml

from .config_error import ConfigError
from .config_yaml import load_strict
from .core.joint_trajectory import JointTrajectory, TrajectoryError, check_trajectory, trajectory_from_mapping
from .core.trajectory_reference import check_span


def read_trajectory(path: Path) -> JointTrajectory:
    """The file's JointTrajectory (shapes and types checked), or TrajectoryError / OSError."""
    try:
        data = load_strict(Path(path).read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise TrajectoryError(f"not YAML or JSON{where}: {getattr(exc, 'problem', None) or exc}") from None
    except UnicodeDecodeError:
        raise TrajectoryError("not a text file") from None
    return trajectory_from_mapping(data)


def load_trajectory_file(path: Path, arm) -> JointTrajectory:
    """The file's trajectory, checked against ``arm`` (an Arm: joint names, URDF limits); ConfigError
    ``trajectory <path>: <what is wrong>`` (setting ``trajectory``) otherwise."""
    try:
        traj = read_trajectory(path)
        check_trajectory(traj, arm.joint_names, arm.lower_rad, arm.upper_rad)
        check_span(traj)
    except TrajectoryError as exc:
        raise ConfigError(f"trajectory {path}: {exc}", setting="trajectory") from None
    except OSError as exc:
        raise ConfigError(f"trajectory {path}: {exc.strerror or exc}", setting="trajectory") from None
    return traj
