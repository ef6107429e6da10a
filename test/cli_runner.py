"""Run ``pa10-dnbs`` in the test process (no interpreter start-up per call): exit code, stdout, stderr."""
from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass

from pa10_dnbs.cli import main


@dataclass
class CliResult:
    returncode: int
    stdout: str
    stderr: str


def run_cli(*args) -> CliResult:
    """``pa10-dnbs ARGS`` as ``main()`` runs it; argparse's own exits (bad flags) become return codes."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in args])
        except SystemExit as exc:
            rc = exc.code if isinstance(exc.code, int) else 2
    return CliResult(rc, out.getvalue(), err.getvalue())
