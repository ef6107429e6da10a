"""A benchmark's record: the figures it measured with when, how, where and on how busy a machine.

One JSON file per benchmark in ``benchmarks/`` (``--save-record FILE`` of the benchmark scripts), read by
``scripts/readme_figures.py`` to regenerate the README's results and figures blocks. A record holds:

- ``benchmark``: the benchmark's name (``bench_sim``, ``main_job``, ...);
- ``date_utc``: when it started, ISO 8601 in UTC to the second; ``wall_s``: how long it ran [s];
- ``command``: the command line as run (relative to the checkout), ``git_commit`` and ``git_dirty``
  (tracked files other than benchmarks/ changed against that commit), both taken when it started;
- ``machine``: ``nproc`` (usable CPUs), ``model_name`` (/proc/cpuinfo), ``python``, ``numeric_platform``
  (pa10_dnbs/numeric_platform.py: the BLAS kernels and numpy SIMD loops, on which a result's last bits hold);
- ``load_before`` and ``load_after``: the 1, 5 and 15 minute load averages (/proc/loadavg), the figures
  mean little on a busy machine;
- ``figures``: the benchmark's own figures (names with their units).

    rec = Record.start("bench_sim")
    ...  # measure
    rec.save(path, {"dnbs_over_pid": 1.14, ...})
"""
from __future__ import annotations

import argparse
import contextlib
import datetime as dt
import json
import os
import platform
import shlex
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pa10_dnbs.numeric_platform import numeric_platform  # noqa: E402

RECORDS = ROOT / "benchmarks"
KEYS = ("benchmark", "date_utc", "wall_s", "command", "git_commit", "git_dirty", "machine", "load_before",
        "load_after", "figures")


def load_average() -> list[float]:
    """The 1, 5 and 15 minute load averages ([] where /proc/loadavg is not readable)."""
    try:
        return [float(x) for x in Path("/proc/loadavg").read_text().split()[:3]]
    except OSError:
        return []


def machine() -> dict:
    """nproc (CPUs this process may use), the CPU's model name, the Python version, the numeric platform."""
    model = "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"nproc": len(os.sched_getaffinity(0)), "model_name": model, "python": platform.python_version(),
            "numeric_platform": numeric_platform()}


def _git(*args: str) -> str:
    out = subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True)
    return out.stdout.strip() if out.returncode == 0 else ""


def git_state() -> tuple[str, bool]:
    """(HEAD's commit, whether tracked files outside benchmarks/ differ from it)."""
    commit = _git("rev-parse", "HEAD") or "?"
    dirty = bool(_git("status", "--porcelain", "--untracked-files=no", "--", ".", ":(exclude)benchmarks"))
    return commit, dirty


def command_line(argv: list[str] | None = None) -> str:
    """The command as run: ``python <script relative to the checkout> <arguments>``."""
    argv = list(sys.argv if argv is None else argv)
    script = Path(argv[0]).resolve()
    try:
        argv[0] = str(script.relative_to(ROOT))
    except ValueError:
        pass
    return " ".join(shlex.quote(a) for a in [".venv/bin/python", *argv])


class Record:
    """Started before the measurement (date, load before), saved after it (load after, figures)."""

    def __init__(self, benchmark: str, command: str | None = None):
        self.benchmark = benchmark
        self.command = command if command is not None else command_line()
        self.date_utc = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
        self.git_commit, self.git_dirty = git_state()  # of the code measured, so taken before it runs
        self.load_before = load_average()
        self.t0 = time.monotonic()

    @classmethod
    def start(cls, benchmark: str, command: str | None = None) -> "Record":
        return cls(benchmark, command)

    def as_dict(self, figures: dict) -> dict:
        return {"benchmark": self.benchmark, "date_utc": self.date_utc,
                "wall_s": round(time.monotonic() - self.t0, 1), "command": self.command,
                "git_commit": self.git_commit, "git_dirty": self.git_dirty, "machine": machine(),
                "load_before": self.load_before, "load_after": load_average(), "figures": figures}

    def save(self, path: Path | str | None, figures: dict) -> dict:
        """Write the record to ``path`` (nothing when ``path`` is None) and return it."""
        rec = self.as_dict(figures)
        if path is not None:
            path = Path(path)
            tmp = path.with_suffix(path.suffix + ".tmp")
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
                tmp.write_text(json.dumps(rec, indent=2, default=_plain) + "\n")
                tmp.replace(path)
            except OSError as exc:   # checked writable when parsed; refused now all the same (root, a full disk)
                with contextlib.suppress(OSError):
                    tmp.unlink()
                raise SystemExit(f"{Path(sys.argv[0]).stem}: error: --save-record: cannot write {path}: "
                                 f"{exc.strerror or exc}") from None
            print(f"record written: {path}", flush=True)
        return rec


def _plain(value):
    """A numpy scalar as its Python value (json cannot write numpy's types)."""
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serializable")


def read(path: Path | str) -> dict:
    """A record from its file; ValueError naming the file and the first missing key."""
    rec = json.loads(Path(path).read_text())
    if not isinstance(rec, dict):
        raise ValueError(f"{path}: not a benchmark record: not a JSON object")
    for key in KEYS:
        if key not in rec:
            raise ValueError(f"{path}: not a benchmark record: no '{key}'")
    return rec


def record_path(text: str) -> Path:
    """``--save-record``'s argparse type: a file to write in an existing, writable directory.

    Checked when the flag is parsed, before the benchmark runs: a directory, a missing or unwritable parent,
    a path through a file, or one that is not a regular file (a device, a pipe: the write replaces the path, so
    /dev/null would become a file) is refused in one line (argparse: exit 2), not after minutes of measuring."""
    path = Path(text)
    if not text or text.endswith("/") or path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a directory, not a file to write")
    if path.exists() and not path.is_file():
        raise argparse.ArgumentTypeError(f"{text!r} is not a regular file (a device, pipe or socket): not replaced")
    parent = path.parent
    if not parent.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: its directory {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise argparse.ArgumentTypeError(f"{text!r}: not writable")
    return path


def add_argument(ap) -> None:
    """``--save-record FILE`` on a benchmark's argument parser (its path checked as it is parsed)."""
    ap.add_argument("--save-record", type=record_path, default=None, metavar="FILE",
                    help="also write the figures, with date, command, commit, machine and load, as a JSON record "
                         "(e.g. benchmarks/<name>.json; scripts/readme_figures.py reads them)")
