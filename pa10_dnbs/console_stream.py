"""The command's standard output when it can no longer be written: its reader went away (``| head -1``: a
broken pipe) or its file is full (ENOSPC). The lines a command prints are a courtesy; its results are the files
it writes, so a run goes on with its lines dropped (said once on stderr) instead of ending on ``[Errno 32]``
with its work lost. Installed by ``cli.main`` for a process that is the command, not for an in-process call."""
from __future__ import annotations

import io
import os
import sys


class ForgivingStream(io.TextIOBase):
    """``stream`` (a text stream with a file descriptor); once a write or flush fails with an OSError, its
    descriptor is pointed at /dev/null (no error again, also not at the interpreter's exit) and text is dropped."""

    def __init__(self, stream, name: str = "standard output"):
        super().__init__()
        self._stream, self._name, self.dropped = stream, name, False

    def write(self, text: str) -> int:
        if not self.dropped:
            try:
                return self._stream.write(text)
            except OSError as exc:
                self._drop(exc)
        return len(text)

    def flush(self) -> None:
        if not self.dropped:
            try:
                self._stream.flush()
            except OSError as exc:
                self._drop(exc)

    def _drop(self, exc: OSError) -> None:
        self.dropped = True
        try:
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, self._stream.fileno())
            os.close(null)
        except (OSError, ValueError):
            pass
        try:
            print(f"pa10-dnbs: note: {self._name} cannot be written ({exc.strerror or exc}); the command goes on "
                  "without its lines", file=sys.stderr, flush=True)
        except (OSError, ValueError):
            pass

    def fileno(self) -> int:
        return self._stream.fileno()

    def isatty(self) -> bool:
        return self._stream.isatty()

    def writable(self) -> bool:
        return True

    @property
    def encoding(self) -> str:
        return self._stream.encoding

    @property
    def errors(self) -> str | None:
        return self._stream.errors


def forgive_stdout() -> None:
    """Make ``sys.stdout`` a :class:`ForgivingStream` (a closed stdout, None, stays as it is)."""
    if sys.stdout is not None and not isinstance(sys.stdout, ForgivingStream):
        sys.stdout = ForgivingStream(sys.stdout)


def forgive_stderr() -> None:
    """Make ``sys.stderr`` a :class:`ForgivingStream` too: once the terminal has hung up (SIGHUP: the terminal
    closed, the ssh session dropped; every write then fails with EIO) the stop's line cannot be written, and the
    error of writing it must not replace the command's exit code (an interrupted launch then exited 1, not 130)."""
    if sys.stderr is not None and not isinstance(sys.stderr, ForgivingStream):
        sys.stderr = ForgivingStream(sys.stderr, "standard error")
