"""``pa10-dnbs robot``: the arm simulated by MuJoCo as an external robot on the standard robot interface
(docs/your_robot.md, docs/engines.md), a ROS 2 node of its own (``ros/mujoco_robot_node.py``).

The arguments and the config are checked here (one line, exit 2), then the node runs as a child process: SIGINT
and SIGTERM are passed on to it, and once it has ended the shared-memory files its DDS participant left in
/dev/shm are removed (nodes leave without tearing DDS down, ``ros/runtime.py``), as the launcher does. Never
imports rclpy.
"""
from __future__ import annotations

import math
import signal
import subprocess
import sys
from pathlib import Path

from ..config import ConfigError, default_config_path
from ..run_settings import build_settings
from ..launch.shm_cleanup import remove_stale, shm_files
from ..wire.clock_schedule import check_clock_hz

ROBOT_MODES = ("lockstep", "paced")


def robot_argv(config_path: Path | None, arm: str | None, mode: str, duration_s: float | None, state_topic: str,
               command_topic: str, clock_hz: float) -> list[str]:
    """The node's argv after every check (ConfigError naming the flag or key)."""
    config_path = Path(config_path) if config_path else default_config_path()
    settings = build_settings(config_path, arm=arm)
    if mode not in ROBOT_MODES:
        raise ConfigError(f"--mode: must be one of {', '.join(ROBOT_MODES)}, got {mode!r}")
    duration_s = 0.0 if duration_s is None else duration_s
    if not (math.isfinite(duration_s) and duration_s >= 0):
        raise ConfigError(f"--duration: must be >= 0 seconds (0: until Ctrl-C), got {duration_s}")
    try:
        check_clock_hz(clock_hz, settings.simulation.dt_s)
    except ValueError as exc:
        raise ConfigError(f"--clock-hz: {exc}") from None
    for flag, topic in (("--state-topic", state_topic), ("--command-topic", command_topic)):
        if not topic or " " in topic:
            raise ConfigError(f"{flag}: expected a topic name, got {topic!r}")
    params = {"config_file": config_path.resolve(), "arm": settings.arm.file, "mode": mode, "duration_s": duration_s,
              "state_topic": state_topic, "command_topic": command_topic, "clock_hz": float(clock_hz)}
    args = [sys.executable, "-m", "pa10_dnbs.ros.mujoco_robot_node", "--ros-args", "-r", "__node:=mujoco_robot"]
    for k, v in params.items():
        args += ["-p", f"{k}:={v}"]
    return args


def run_robot(config_path: Path | None, arm: str | None, mode: str, duration_s: float | None, state_topic: str,
              command_topic: str, clock_hz: float) -> int:
    """Check the arguments, run the robot node until it ends (its exit code; 0 after Ctrl-C)."""
    argv = robot_argv(config_path, arm, mode, duration_s, state_topic, command_topic, clock_hz)
    before = shm_files()
    sys.stdout.flush()
    sys.stderr.flush()
    child = subprocess.Popen(argv)
    passed_on = {sig: signal.signal(sig, lambda signum, _f: child.send_signal(signum))
                 for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        code = child.wait()
    finally:
        for sig, handler in passed_on.items():
            signal.signal(sig, handler)
        remove_stale(shm_files() - before)
    return code
