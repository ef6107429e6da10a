"""Each command's options: one dataclass (commands/options.py) built by cli.py from the parsed flags; its
defaults are the flags' own, and a library's error names a setting the command line can say as a flag."""
from dataclasses import fields
from pathlib import Path

import pytest

from pa10_dnbs import cli
from pa10_dnbs.commands import options as opts
from pa10_dnbs.config_error import ConfigError

MINIMAL = {  # the fewest flags each command takes, and its options with only those given
    "simulate": (["simulate", "--out", "o"], opts.SimulateOptions(out=Path("o"))),
    "launch": (["launch", "--out", "o"], opts.LaunchOptions(out=Path("o"))),
    "robot": (["robot"], opts.RobotCommandOptions()),
    "study": (["study", "--out", "o"], opts.StudyOptions(out=Path("o"))),
    "tune": (["tune", "--controller", "pid", "--out", "o"], opts.TuneOptions(controller="pid", out=Path("o"))),
    "arm": (["arm"], opts.ArmInfoOptions()),
    "analyse": (["analyse", "b", "--out", "o"], opts.AnalyseOptions(bag_path=Path("b"), out=Path("o"))),
    "replay": (["replay", "b"], opts.ReplayOptions(bag_path=Path("b"))),
}


def test_every_command_has_its_options_and_their_defaults_are_the_flags():
    assert set(MINIMAL) == set(cli.COMMANDS)
    for name, (argv, expected) in MINIMAL.items():
        built = cli.command_options(cli.build_parser().parse_args(argv))
        assert built == expected, (name, [f.name for f in fields(built)
                                          if getattr(built, f.name) != getattr(expected, f.name)])


def test_launch_options_carry_the_fault_flags_not_the_namespace():
    args = cli.build_parser().parse_args(["launch", "--out", "o", "--drop-states", "0.1", "--kill", "s1@2",
                                          "--fault-seed", "3"])
    built = cli.command_options(args)
    assert built.faults == opts.FaultFlags(drop_states=0.1, kill=("s1@2",), fault_seed=3)
    with pytest.raises(ConfigError, match="^--rtf: only with --mode realtime"):
        cli.command_options(cli.build_parser().parse_args(["launch", "--out", "o", "--rtf", "0.5"]))
    for flag in ("--rtf", "--deadline-fraction"):  # rev_e 8: a paced robot's next state is the deadline
        with pytest.raises(ConfigError, match=f"^{flag}: not with --robot external"):
            cli.command_options(cli.build_parser().parse_args(["launch", "--out", "o", "--mode", "realtime",
                                                               "--robot", "external", flag, "0.5"]))


def test_each_setting_a_library_names_has_a_flag_on_the_command_line():
    parser = cli.build_parser()
    actions = [a for sub in parser._subparsers._group_actions[0].choices.values() for a in sub._actions]
    flags = {s for a in actions for s in a.option_strings} | {a.metavar for a in actions if not a.option_strings}
    assert set(cli.SETTING_FLAGS.values()) <= flags, set(cli.SETTING_FLAGS.values()) - flags
    exc = ConfigError("duration_s: 1e12 s is 1e15 steps", setting="duration_s")
    assert exc.named(cli.SETTING_FLAGS) == "--duration: 1e12 s is 1e15 steps"
    assert str(exc) == "duration_s: 1e12 s is 1e15 steps"   # what a library caller sees
    assert ConfigError("plant.payload_kg: must be >= 0").named({"plant": "--x"}) == "plant.payload_kg: must be >= 0"
