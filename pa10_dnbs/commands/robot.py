"""``pa10-dnbs robot``: the arm simulated by MuJoCo as an external robot on the standard robot interface
(docs/your_robot.md, docs/engines.md), a ROS 2 node of its own (``ros/mujoco_robot_node.py``), in the arm's
namespace (/pa10 for the PA10), where ``launch --robot external``'s joint bus runs: a relative topic name resolves
the same for both.

The arguments and the config are checked here (one line, exit 2), then the node runs as a child process: SIGINT,
SIGTERM and SIGHUP (interrupt.stop_signals) are passed on to it, and once it has ended the shared-memory files its
DDS participant left in /dev/shm are removed (nodes leave without tearing DDS down, ``ros/runtime.py``), as the
launcher does. Never imports rclpy.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

from ..config import ConfigError, default_config_path
from ..interrupt import LAUNCHER_PID_ENV, stop_signals
from .options import RobotCommandOptions
from ..run_settings import built_settings_held, say_rules
from ..supervisor.domain_ids import shell_domain
from ..supervisor.rmw_check import check_rmw
from ..run_steps import run_steps
from ..ros.param_overrides import override_value
from ..ros.shm_cleanup import remove_stale, shm_files
from ..wire.clock_schedule import checked_clock_hz
from ..wire.topics import check_free_topic, check_not_the_graphs, check_topic_name, default_namespace, resolve


def robot_argv(options: RobotCommandOptions) -> list[str]:
    """The node's argv after the checks that depend on the settings (ConfigError naming the flag or key)."""
    o = options
    config_path = Path(o.config_path) if o.config_path else default_config_path()
    settings, rules = built_settings_held(config_path, arm=o.arm)   # the rules' table said once all is accepted
    duration_s = 0.0 if o.duration_s is None else o.duration_s
    if o.duration_s is not None:
        run_steps(o.duration_s, settings.simulation.dt_s)  # > 0 (the flag), countable and two steps at least
    clock_hz = checked_clock_hz(o.clock_hz, settings.simulation.dt_s)   # None: the default, which dt may not fit
    namespace = default_namespace(settings.arm.name)  # the bus's (launch's default): relative names meet there
    for flag, topic in (("--state-topic", o.state_topic), ("--command-topic", o.command_topic)):
        try:
            check_not_the_graphs(check_free_topic(check_topic_name(topic), namespace), namespace)
        except ValueError as exc:
            raise ConfigError(f"{flag}: {exc}") from None
    if resolve(o.state_topic, namespace) == resolve(o.command_topic, namespace):
        same = "" if o.state_topic == o.command_topic else (f", {o.state_topic!r} is "
                                                              f"{resolve(o.state_topic, namespace)} in {namespace}")
        raise ConfigError(f"--command-topic: must differ from --state-topic (both {o.command_topic!r}{same}): the "
                          "robot would read its own states as commands")
    say_rules(rules)
    params = {"config_file": Path(config_path).resolve(), "arm": Path(settings.arm.file), "mode": o.mode,
              "duration_s": duration_s,
              "state_topic": o.state_topic, "command_topic": o.command_topic, "clock_hz": float(clock_hz)}
    args = [sys.executable, "-m", "pa10_dnbs.ros.mujoco_robot_node", "--ros-args", "-r", "__node:=mujoco_robot",
            "-r", f"__ns:={namespace}"]
    for k, v in params.items():
        args += ["-p", f"{k}:={override_value(v)}"]
    return args


def run_robot(options: RobotCommandOptions) -> int:
    """Check the arguments, run the robot node until it ends (its exit code; 0 after Ctrl-C)."""
    # the node joins this shell's domain with its RMW: a bad one is one line here, not the DDS's error or rcl's 102
    shell_domain("the robot's domain")
    check_rmw()
    argv = robot_argv(options)
    before = shm_files()
    for stream in (sys.stdout, sys.stderr):   # None when closed at start (>&-)
        if stream is not None:
            stream.flush()
    child = subprocess.Popen(argv, env={**os.environ, LAUNCHER_PID_ENV: str(os.getpid())})   # dies with this one
    passed_on = {sig: signal.signal(sig, lambda signum, _f: child.send_signal(signum))
                 for sig in stop_signals()}
    try:
        code = child.wait()
    finally:
        for sig, handler in passed_on.items():
            signal.signal(sig, handler)
        remove_stale(shm_files() - before)
    return code
