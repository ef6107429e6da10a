"""The docs' shell commands, run as written: every fenced ``bash`` / ``sh`` block of the project's Markdown files
(README.md, docs/*.md, urdf/README.md: every ``*.md`` git tracks outside test/) is a test.

Sybil (pinned in requirements.txt) parses the Markdown: its fenced code blocks, and the ``skip`` directive
in an HTML comment before a block that cannot run in CI, which must give its reason::

    <!-- skip: next "real multi-host: needs a second machine" -->
    <!-- skip: next if(not AS_ROOT, reason="network namespaces need root") -->

Each block runs with bash (``set -euo pipefail``) in a temporary folder, one per document, shared by its
blocks in their order (a later block may use an earlier one's ``runs/``), holding links to the checkout's
files (``.venv``, ``scripts``, ``config``, ...), on a leased ROS_DOMAIN_ID with discovery on this host only.
The blocks' durations are shortened by the rewrites of ``SHORTEN`` (docs/architecture.md, "Docs tests"): the
test prints the block as run when it fails. A block must leave no process behind.

Markers: every block is ``docs``; a block that starts ROS processes (``GRAPH``) is ``graph`` as well, so the fast
tier (``-m "not graph"``) keeps only the blocks that start none.
"""
from __future__ import annotations

import os
import re
import signal
import subprocess
import time
import unittest
from pathlib import Path

import pytest
from sybil import Sybil
from sybil.parsers.markdown import CodeBlockParser, SkipParser

ROOT = Path(__file__).resolve().parent.parent
SHELL_LANGUAGES = ("bash", "sh", "shell")
BLOCK_TIMEOUT_S = 600.0      # one block, all its commands [s of wall time]
CAP_S = 1.0                  # simulated seconds a docs test runs at most
NOT_LINKED = {".git", "runs", "bags", "build", "install", "log", ".pytest_cache", "__pycache__"}
# a block that starts ROS processes: the launcher, the player, a node, the main job, the graph benchmarks
GRAPH = re.compile(r"pa10-dnbs\s+(launch|replay)\b|pa10_dnbs\.ros\.|run_main\.sh|soak_realtime|bench_graph|"
                   r"bench_observers|live_probe")
# commands that take --duration: a docs test gives them CAP_S when the block gives none
TAKES_DURATION = re.compile(r"(pa10-dnbs\s+(?:launch|simulate|study|tune)|scripts/run_main\.sh|"
                            r"scripts/equal_budget\.py)(?=\s|$)")


def _cap(value: str, cap: float) -> str:
    """min(value, cap) written as the value was: a float stays a float (a ROS parameter's type)."""
    out = f"{min(float(value), cap):g}"
    return out + ".0" if "." in value and "." not in out and "e" not in out else out


# (pattern, replacement): how a block is shortened; the leased domain is filled in by _as_run
DURATION_RULE = (re.compile(r"(--duration\s+)(\d+(?:\.\d+)?)"), lambda m: m[1] + _cap(m[2], CAP_S))
SHORTEN = [
    DURATION_RULE,
    (re.compile(r"(duration_s:=)(\d+(?:\.\d+)?)"), lambda m: m[1] + _cap(m[2], CAP_S)),
    (re.compile(r"(end_stamp_ns:=)(\d+)"), lambda m: m[1] + str(min(int(m[2]), int(CAP_S * 1e9)))),
    (re.compile(r"(--seeds\s+)\d+"), lambda m: m[1] + "1"),
    (re.compile(r"(--repeat\s+)\d+"), lambda m: m[1] + "1"),
    (re.compile(r"(--trials\s+)\d+"), lambda m: m[1] + "2"),
    (re.compile(r"(--held-out-seeds\s+)\d+"), lambda m: m[1] + "1"),
    (re.compile(r"(--minutes\s+)(\d+(?:\.\d+)?)"), lambda m: m[1] + _cap(m[2], CAP_S / 60)),
    (re.compile(r"--live(?:\s+\d+)?(?=\s|$)"), lambda m: "--live 0"),  # any free port, never one in use
]


def _logical_lines(src: str) -> list[str]:
    """The block's lines with backslash continuations joined (each command on one line)."""
    return re.sub(r"[ \t]*\\\n\s*", " ", src).splitlines()


def _with_duration(line: str) -> str:
    """``line`` with ``--duration CAP_S`` after a command that takes one when the line gives none."""
    code = line.split(" #", 1)[0]
    if "--duration" in code or not TAKES_DURATION.search(code):
        return line
    return TAKES_DURATION.sub(lambda m: f"{m[1]} --duration {CAP_S:g}", line, count=1)


TUNES = re.compile(r"(pa10-dnbs\s+tune|scripts/equal_budget\.py)(?=\s|$)")


def _with_held_out(line: str) -> str:
    """``line`` with ``--held-out-seeds 1`` after a tune that gives none (its default re-runs 3 seeds x 8
    scenarios twice)."""
    code = line.split(" #", 1)[0]
    if "--held-out-seeds" in code or not TUNES.search(code):
        return line
    return TUNES.sub(lambda m: f"{m[1]} --held-out-seeds 1", line, count=1)


# a graph started in the background, for a client of the block to find while it runs (docs/trajectories.md):
# its duration is the block's design, not a cost to cut (discovery alone can take seconds under load)
BACKGROUND_GRAPH = re.compile(r"pa10-dnbs\s+launch\b.*[^&]&$")


def as_run(src: str, domain_id: int) -> str:
    """The block as a docs test runs it: continuations joined, durations shortened (but a background graph's),
    the leased domain."""
    lines = []
    for line in _logical_lines(src):
        line = _with_held_out(_with_duration(line))
        keep = BACKGROUND_GRAPH.search(line.split(" #", 1)[0].rstrip())
        for pattern, repl in [r for r in SHORTEN if r is not DURATION_RULE] if keep else SHORTEN:
            line = pattern.sub(repl, line)
        lines.append(re.sub(r"ROS_DOMAIN_ID=\d+", f"ROS_DOMAIN_ID={domain_id}", line))
    return "\n".join(lines) + "\n"


def _markdown_files() -> list[Path]:
    try:
        names = subprocess.run(["git", "ls-files", "*.md"], cwd=ROOT, capture_output=True, text=True,
                               check=True).stdout.split()
        files = [ROOT / n for n in names]
    except (OSError, subprocess.CalledProcessError):  # not a git checkout
        files = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted(ROOT.glob("*/README.md"))]
    return [f for f in files if f.is_file() and f.relative_to(ROOT).parts[0] != "test"]


def _run_block(example) -> None:
    """Sybil's evaluator of a shell block: run it in the document's folder (``example.namespace['ctx']``).

    The block's shell holds the leased domain's occupancy lock (``domain_ids.occupy``), and so does every
    process it starts: a node the block leaves running keeps the domain from the next test's lease, and the
    ``domain`` fixture names it."""
    from pa10_dnbs.supervisor.domain_ids import occupy

    ctx = example.namespace["ctx"]
    example.namespace.setdefault("ran", set()).add(example.line)
    script = as_run(example.parsed, ctx["domain_id"])
    where = f"{Path(example.path).relative_to(ROOT)}:{example.line}"
    t0 = time.monotonic()
    started = time.time()
    log = Path(ctx["workdir"]) / f".block_{example.line}.log"  # a file, not a pipe: a node left running
    occupied = occupy(ctx["domain_id"])                          # in the background must not hold the test
    try:
        with open(log, "w") as out:
            proc = subprocess.Popen(["bash", "-euo", "pipefail", "-c", script], cwd=ctx["workdir"], env=ctx["env"],
                                    stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                    start_new_session=True, pass_fds=(occupied,))
    finally:
        os.close(occupied)
    try:
        proc.wait(timeout=BLOCK_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        pass
    finally:
        left = _stop_session(proc)
    ctx["times"][where] = time.monotonic() - t0
    report = (f"{where}, as run in {ctx['workdir']}:\n{script}--- output (end) ---\n"
              f"{log.read_text(errors='replace')[-6000:]}{_logs_written(Path(ctx['workdir']), started, log)}")
    assert proc.returncode == 0, f"exit code {proc.returncode}: {report}"
    assert not left, f"the block left processes running ({', '.join(left)}): {report}"


def _logs_written(workdir: Path, since: float, own: Path) -> str:
    """The ends of the ``*.log`` files the block wrote in its folder (a node started in the background logs
    there: ``> robot.log``), for the report of a failed block."""
    out = ""
    for f in sorted(workdir.glob("*.log")):
        try:
            if f != own and f.stat().st_mtime >= since:
                out += f"--- {f.name} (end) ---\n{f.read_text(errors='replace')[-3000:]}\n"
        except OSError:
            continue
    return out


def _stop_session(proc: subprocess.Popen) -> list[str]:
    """End the block's shell and whatever it started (SIGINT, then SIGKILL); the names of the processes that
    were still running after the shell had exited. By session, not process group: ``timeout`` puts its
    command in a group of its own, which a signal to the shell's group does not reach."""
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    left = _session_members(proc.pid)
    for sig, grace in ((signal.SIGINT, 10.0), (signal.SIGKILL, 5.0)):
        members = _session_members(proc.pid)
        if not members:
            break
        for pid in members:
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass
        end = time.monotonic() + grace
        while time.monotonic() < end and _session_members(proc.pid):
            time.sleep(0.1)
    return [left[pid] for pid in sorted(left)]


def _session_members(sid: int) -> dict[int, str]:
    """pid -> name of the live (not zombie) processes of session ``sid``."""
    members = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
            name, rest = text.split("(", 1)[1].rsplit(")", 1)
            fields = rest.split()
            if int(fields[3]) == sid and fields[0] != "Z":
                members[int(stat.parent.name)] = name
        except (OSError, IndexError, ValueError):
            continue
    return members


SYBIL = Sybil(parsers=[*(CodeBlockParser(language, _run_block) for language in SHELL_LANGUAGES), SkipParser()])


def _blocks():
    """(document, skip directive or None, shell block) in document order, for every Markdown file."""
    out = []
    for path in _markdown_files():
        doc = SYBIL.parse(path)
        doc.namespace["AS_ROOT"] = os.geteuid() == 0
        pending = None
        for ex in doc.examples():
            if isinstance(ex.parsed, tuple):  # a skip directive: (action, reason)
                pending = ex
                continue
            out.append((doc, pending, ex))
            pending = None
    return out


BLOCKS = _blocks()


def _param(doc, skip, ex):
    marks = [pytest.mark.docs] + ([pytest.mark.graph] if GRAPH.search(ex.parsed) else [])
    return pytest.param(doc, skip, ex, marks=marks, id=f"{Path(ex.path).relative_to(ROOT)}:{ex.line}")


def venv_is_current() -> bool:
    """True when .venv was installed from this checkout's requirements.txt, setup.py and setup.cfg, as
    scripts/bootstrap.sh checks: a docs block that sources it (scripts/run_main.sh) then installs nothing.
    Otherwise it would reinstall the package from the block's temporary folder, and the venv would point there."""
    import hashlib

    stamp = ROOT / ".venv" / ".pa10_dnbs-installed"
    want = hashlib.sha256(b"".join((ROOT / f).read_bytes() for f in ("requirements.txt", "setup.py", "setup.cfg")))
    return stamp.is_file() and stamp.read_text().strip() == want.hexdigest()


@pytest.fixture(scope="session")
def doc_folders(tmp_path_factory):
    """One folder per document, with links to the checkout's files; the commands run there."""
    if not venv_is_current():
        pytest.fail("the docs tests need an up-to-date .venv: run `bash scripts/bootstrap.sh` first "
                    "(scripts/run_tests.sh does)", pytrace=False)
    folders = {}

    def folder(doc) -> Path:
        if doc.path not in folders:
            d = tmp_path_factory.mktemp("doc_" + Path(doc.path).stem)
            for entry in ROOT.iterdir():
                if entry.name not in NOT_LINKED:
                    (d / entry.name).symlink_to(entry)
            folders[doc.path] = d
        return folders[doc.path]

    yield folder


@pytest.fixture(scope="session")
def block_times():
    """Wall time of each block [s]; printed at the end of the session (the docs tier's CI cost)."""
    times = {}
    yield times
    if times:
        print(f"\ndocs blocks: {len(times)} run, {sum(times.values()):.0f} s in all; slowest: "
              + ", ".join(f"{k} {v:.0f} s" for k, v in sorted(times.items(), key=lambda kv: -kv[1])[:5]))


@pytest.mark.parametrize("doc, skip, block", [_param(*b) for b in BLOCKS])
def test_doc_block_runs_as_written(doc, skip, block, doc_folders, domain, block_times):
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
           "PYTHONUNBUFFERED": "1"}
    env.pop("VIRTUAL_ENV", None)  # a newcomer's shell: the venv not activated, its tools called by path
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if "/.venv/" not in p + "/")
    env.pop("ROS_LOCALHOST_ONLY", None)
    doc.namespace["ctx"] = {"workdir": doc_folders(doc), "domain_id": domain, "env": env, "times": block_times}
    for earlier_skip, earlier in _not_yet_run_before(doc, block):
        # a later block may use an earlier one's runs/: the tier or the xdist worker may not have run it
        if earlier_skip is not None:
            earlier_skip.evaluate()
        try:
            earlier.evaluate()
        except unittest.SkipTest:
            continue
    if skip is not None:  # Sybil's skipper: the next block evaluated raises SkipTest with the reason, or runs
        skip.evaluate()
    block.evaluate()


def _not_yet_run_before(doc, block) -> list:
    """(skip directive or None, block) of ``doc``'s blocks before ``block`` that this process has not run: those
    a tier (``-m graph``) deselected or another xdist worker ran. A block that starts no ROS process never has a
    graph block run for it (the fast tier starts none)."""
    graph = bool(GRAPH.search(block.parsed))
    return [(sk, ex) for d, sk, ex in BLOCKS
            if d is doc and ex.line < block.line and ex.line not in doc.namespace.setdefault("ran", set())
            and (graph or not GRAPH.search(ex.parsed))]


def test_every_skip_gives_its_reason_and_precedes_a_shell_block():
    """A block left out of the docs tests says why: ``<!-- skip: next "reason" -->`` right before it."""
    for path in _markdown_files():
        doc = SYBIL.parse(path)
        examples = list(doc.examples())
        for i, ex in enumerate(examples):
            if not isinstance(ex.parsed, tuple):
                continue
            action, reason = ex.parsed
            where = f"{path.relative_to(ROOT)}:{ex.line}"
            assert action == "next", f"{where}: use 'skip: next' before one block"
            assert reason and (reason.strip().startswith(("'", '"', "if(")) and len(reason.strip()) > 10), \
                f"{where}: a skip needs its reason, e.g. <!-- skip: next \"needs a second machine\" -->"
            assert i + 1 < len(examples) and not isinstance(examples[i + 1].parsed, tuple), \
                f"{where}: the skip directive is not followed by a shell block"
            assert examples[i + 1].start - ex.end < 5, f"{where}: the skip directive must sit right before its block"


def test_as_run_shortens_durations_and_uses_the_leased_domain():
    src = ("export ROS_DOMAIN_ID=42\n"
           ".venv/bin/pa10-dnbs launch --duration 20 --out runs/r1 \\\n    --live 9000 --record bags/r1\n"
           ".venv/bin/pa10-dnbs simulate --controller all --out runs/compare   # in-process\n"
           ".venv/bin/pa10-dnbs study --scenarios nominal --seeds 10 --duration 0.5 --out runs/study\n"
           "python -m pa10_dnbs.ros.reference_node --ros-args -p duration_s:=5.0 &\n"
           "bash scripts/run_main.sh     # the main job\n"
           "python -m pa10_dnbs.ros.recorder_node --ros-args -p end_stamp_ns:=3000000000 -p live_hz:=50\n"
           ".venv/bin/pa10-dnbs tune --controller pid --trials 20 --out runs/tune_pid\n"
           ".venv/bin/pa10-dnbs launch --domain-id $ROS_DOMAIN_ID --duration 8 --out runs/t > launch.log &  # bg\n")
    assert as_run(src, 7).splitlines() == [
        "export ROS_DOMAIN_ID=7",
        ".venv/bin/pa10-dnbs launch --duration 1 --out runs/r1 --live 0 --record bags/r1",
        ".venv/bin/pa10-dnbs simulate --duration 1 --controller all --out runs/compare   # in-process",
        ".venv/bin/pa10-dnbs study --scenarios nominal --seeds 1 --duration 0.5 --out runs/study",
        "python -m pa10_dnbs.ros.reference_node --ros-args -p duration_s:=1.0 &",
        "bash scripts/run_main.sh --duration 1     # the main job",
        "python -m pa10_dnbs.ros.recorder_node --ros-args -p end_stamp_ns:=1000000000 -p live_hz:=50",
        ".venv/bin/pa10-dnbs tune --held-out-seeds 1 --duration 1 --controller pid --trials 2 --out runs/tune_pid",
        ".venv/bin/pa10-dnbs launch --domain-id $ROS_DOMAIN_ID --duration 8 --out runs/t > launch.log &  # bg"]


def test_the_venv_check_is_the_bootstrap_stamp():
    """The guard of doc_folders agrees with scripts/bootstrap.sh (which has just run under run_tests.sh)."""
    out = subprocess.run(["bash", "-c", "source scripts/bootstrap.sh >/dev/null 2>&1 && echo ok"], cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert out.stdout.strip() == "ok" and venv_is_current()


def test_the_docs_have_shell_blocks_to_run():
    """The harness finds the blocks (a parser change that found none would pass every docs test vacuously)."""
    files = {Path(d.path).relative_to(ROOT).as_posix() for d, _, _ in BLOCKS}
    assert {"README.md", "docs/graph.md", "docs/bags.md"} <= files
    assert len(BLOCKS) >= 10


def test_a_block_is_stopped_whole_even_what_timeout_put_in_a_group_of_its_own(tmp_path):
    """``timeout CMD &`` leaves the shell's process group; the block's end still stops it and names it."""
    script = "timeout 120 sleep 60 &\necho started\n"
    proc = subprocess.Popen(["bash", "-euo", "pipefail", "-c", script], cwd=tmp_path, stdout=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, start_new_session=True, text=True)
    assert proc.stdout.readline().strip() == "started"
    proc.wait(timeout=30)
    t0 = time.monotonic()  # until timeout's child has exec'd sleep (forked, it is named timeout for a moment)
    while sorted(_session_members(proc.pid).values()) != ["sleep", "timeout"] and time.monotonic() - t0 < 10:
        time.sleep(0.05)
    assert sorted(_session_members(proc.pid).values()) == ["sleep", "timeout"]
    assert sorted(_stop_session(proc)) == ["sleep", "timeout"]
    assert _session_members(proc.pid) == {}
