"""A library's error names the setting (`force`), never the flag: the command line says it as its flag
(setting_flags.py, ConfigError.named, Refused.named), a Python caller reads the setting it passed."""
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
ROS_ARGUMENTS = {"--ros-args", "--params-file"}   # rcl's own, in a node's argv: not one of ours
ERROR_CALL = re.compile(r"(Error|Refused|Lost|Broken|Failure|Fault)$")


def _library_error_texts():
    """(file, line, text) of every string in a library error: a ``raise``'s expression, or a call of an error
    type (``OutputExistsError(...)``, returned to be raised)."""
    for path in sorted(PACKAGE.rglob("*.py")):
        name = path.relative_to(PACKAGE).as_posix()
        if name in COMMAND_LINE or name.startswith("commands/"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            exprs = [node.exc] if isinstance(node, ast.Raise) and node.exc is not None else []
            if isinstance(node, ast.Call):
                f = node.func
                if ERROR_CALL.search(f.id if isinstance(f, ast.Name) else getattr(f, "attr", "")):
                    exprs.append(node)
            for expr in exprs:
                for c in ast.walk(expr):
                    if isinstance(c, ast.Constant) and isinstance(c.value, str):
                        yield name, c.lineno, c.value


def test_no_library_error_names_a_flag():
    flags = sorted({(f, n, m) for f, n, text in _library_error_texts() for m in FLAG.findall(text)
                    if m not in ROS_ARGUMENTS})
    assert not flags, flags


def test_every_setting_a_library_error_marks_has_a_flag():
    """A mark the command line could not say would reach its user as `name`."""
    marked = {(f, n, m) for f, n, text in _library_error_texts() for m in SETTING_MARK.findall(text)}
    assert marked, "the scan found no mark: it no longer reads the errors"
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
        assert err.value.named(SETTING_FLAGS) == f"output directory exists: {out} (use --force to replace it)"
        with pytest.raises(OutputExistsError) as err:
            check_output_dir(out, True, "record")
    finally:
        release_all(keep=before)   # the lock the check took, as the CLI drops it
    assert err.value.named(SETTING_FLAGS).startswith(f"--record: {out} holds files that are not a pa10-dnbs "
                                                     "output: --force replaces only an empty folder")
