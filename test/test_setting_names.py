"""A library's error names the setting (`force`), never the flag: the command line says it as its flag
(setting_flags.py, config_error.said_as, ConfigError.named), a Python caller reads the setting it passed."""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import pa10_dnbs
from pa10_dnbs.config_error import SETTING_MARK, ConfigError, said_as
from pa10_dnbs.output_lock import held, release_all
from pa10_dnbs.report.outputs import OutputExistsError, check_output_dir
from pa10_dnbs.setting_flags import SETTING_FLAGS

PACKAGE = Path(pa10_dnbs.__file__).parent
#: the command line itself (its parser, its commands) and the two modules that are programs of their own
COMMAND_LINE = {"cli.py", "cli_values.py", "setting_flags.py", "ros/trajectory_sender.py", "ros/shm_cleanup.py"}
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z-]*")
ROS_ARGUMENTS = {"--ros-args", "--params-file", "--param", "--remap"}   # rcl's own, in a node's argv: not ours
#: library text that names a flag on purpose: (file, what the string opens with) -> why
FLAG_ON_PURPOSE = {
    ("output_mark.py", "Written by pa10-dnbs"): "the mark file a command writes into its output folder",
    ("ros/runtime.py", "--help"): "a node's own argument, before its --ros-args: its parameters, nothing started",
    ("report/outputs.py", "Figures not drawn"): "a note in the report.md a command writes",
    ("report/partial.py", "` lists them)"): "the banner of a command's partial report.md",
    ("tune/report.py", "): keep the start"): "the tune report a command writes",
    ("tune/report.py", ": the best may lie"): "the tune report a command writes",
    ("ros/params.py", "SCHED_BATCH on every"): "a parameter's description: the launcher's flag that sets it",
    ("ros/params.py", "SCHED_FIFO priority"): "a parameter's description: the launcher's flag that sets it",
    ("ros/player_node.py", ": nothing received them"): "the replay command's own warning (the player runs in it)",
}


def _docstrings(tree) -> set[int]:
    return {id(node.body[0].value) for node in ast.walk(tree)
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body
            and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}


def _library_texts():
    """(file, line, text) of every string of the library's code but docstrings: an error's message, a hint a
    command prints, a text built in a variable or returned; each part of an f-string between its fields."""
    for path in sorted(PACKAGE.rglob("*.py")):
        name = path.relative_to(PACKAGE).as_posix()
        if name in COMMAND_LINE or name.startswith("commands/"):
            continue
        tree = ast.parse(path.read_text())
        docs = _docstrings(tree)
        for c in ast.walk(tree):
            if isinstance(c, ast.Constant) and isinstance(c.value, str) and id(c) not in docs:
                yield name, c.lineno, c.value


def _on_purpose(name: str, text: str) -> bool:
    return any(f == name and text.startswith(opening) for f, opening in FLAG_ON_PURPOSE)


def test_no_library_text_names_a_flag():
    flags = sorted({(f, n, m) for f, n, text in _library_texts() for m in FLAG.findall(text)
                    if m not in ROS_ARGUMENTS and not _on_purpose(f, text)})
    assert not flags, flags
    used = {key for key in FLAG_ON_PURPOSE
            if any(f == key[0] and text.startswith(key[1]) for f, _, text in _library_texts())}
    assert used == set(FLAG_ON_PURPOSE), set(FLAG_ON_PURPOSE) - used   # no stale exemption


def test_every_setting_the_library_marks_has_a_flag():
    """A mark the command line could not say would reach its user as `name`."""
    marked = {(f, n, m) for f, n, text in _library_texts() for m in SETTING_MARK.findall(text)}
    assert {"force", "out", "config_path", "rt_priority", "real_time_factor", "mode"} <= {m for *_, m in marked}
    assert {m for _, _, m in marked} <= set(SETTING_FLAGS), [x for x in marked if x[2] not in SETTING_FLAGS]


def test_said_as_replaces_known_marks_only():
    names = {"force": "--force", "config_path": "--config"}
    assert said_as("pass `force`; leave `config_path` out", names) == "pass --force; leave --config out"
    assert said_as("`other` and ``force`` stay", names) == "`other` and ``force`` stay"   # unknown, reST literal
    exc = ConfigError("duration_s: too long for `jobs` workers", setting="duration_s")
    assert exc.named({"duration_s": "--duration", "jobs": "--jobs"}) == "--duration: too long for --jobs workers"
    assert exc.named({"duration_s": "parameter duration_s"}) == "parameter duration_s: too long for `jobs` workers"


def test_an_existing_output_names_force_as_a_setting_and_the_cli_as_its_flag(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "x").write_text("x")
    before = held()
    try:
        with pytest.raises(OutputExistsError) as err:
            check_output_dir(out, False)
        assert str(err.value) == f"output directory exists: {out} (use `force` to replace it)"
        assert said_as(str(err.value), SETTING_FLAGS) == f"output directory exists: {out} (use --force to replace it)"
        with pytest.raises(OutputExistsError) as err:
            check_output_dir(out, True, "record")
    finally:
        release_all(keep=before)   # the lock the check took, as the CLI drops it
    assert said_as(str(err.value), SETTING_FLAGS).startswith(f"--record: {out} holds files that are not a pa10-dnbs "
                                                     "output: --force replaces only an empty folder")
