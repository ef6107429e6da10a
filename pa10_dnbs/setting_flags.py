"""How the command line names each setting a library message can name (config_error.SETTING_MARK): the flag
that sets it, or the positional argument. The CLI and its commands say a library's message with it
(``ConfigError.named``, ``config_error.said_as``); a library never names a flag itself."""
from __future__ import annotations

#: setting (an options dataclass's field, commands/options.py) -> how the command line gives it
SETTING_FLAGS = {
    "arm": "--arm", "bag_path": "BAG", "clock_hz": "--clock-hz", "config_path": "--config",
    "controller": "--controller", "duration_s": "--duration", "force": "--force", "init_from": "--init-from",
    "jobs": "--jobs", "live_host": "--live-host", "live_hz": "--live-hz", "live_port": "--live",
    "mode": "--mode", "netns": "--netns", "no_figures": "--no-figures", "out": "--out", "params": "--params",
    "plant": "--plant", "real_time_factor": "--rtf", "record": "--record", "robot": "--robot",
    "robot_command": "--robot-command", "robot_command_topic": "--robot-command-topic",
    "robot_state_topic": "--robot-state-topic", "robot_timeout": "--robot-timeout", "rt_priority": "--rt-priority",
    "scenarios": "--scenarios", "scheduler": "--scheduler", "seed": "--seed", "seeds": "--seeds",
    "storage": "--storage", "trajectory": "--trajectory"}
