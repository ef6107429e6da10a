"""--out never destroys what a run uses (report/outputs.py check_output_dir): not its inputs, not a folder of
unrelated files, not the current directory, its parents or the root; ``tune`` resumes only into its own folder.
Each refusal: exit 2, one line naming the flag, before any run (nothing printed to stdout), inputs byte-identical.
Tiny runs (0.2 s, pid unless a warm start needs dnbs, no figures)."""
import json
import subprocess
import sys
from pathlib import Path

import pytest
from cli_runner import run_cli
from test_bag_files import _write_run_bag

REPO = Path(__file__).resolve().parent.parent
TINY = ("--duration", "0.2", "--no-figures")
TUNE = ("tune", "--trials", "1", "--duration", "0.2", "--seeds", "1", "--scenarios", "nominal",
        "--held-out-seeds", "0", "--jobs", "1")


def _tree(path: Path) -> dict:
    """Every file under ``path`` (or the file itself) and its bytes."""
    path = Path(path)
    if path.is_file():
        return {path.name: path.read_bytes()}
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


def _refused(r, *words):
    """Exit 2, one line on stderr naming each of ``words``, before any run (nothing on stdout)."""
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1, (r.returncode, r.stdout, r.stderr)
    assert "Traceback" not in r.stderr and r.stdout == "", (r.stdout, r.stderr)
    for w in words:
        assert w in lines[0], lines[0]


def _simulate(out: Path, *extra, controller="pid"):
    r = run_cli("simulate", "--controller", controller, *TINY, "--out", out, *extra)
    assert r.returncode == 0, r.stderr
    return out


def test_analyse_force_into_its_own_bag_is_refused(tmp_path):
    bag = _write_run_bag(tmp_path / "bag", ns="/pa10")
    before = _tree(bag)
    _refused(run_cli("analyse", bag, "--out", bag, "--force", "--no-figures"), "--out", "BAG")
    _refused(run_cli("analyse", bag, "--out", bag / "analysis", "--force", "--no-figures"), "--out", "lies inside")
    assert _tree(bag) == before


def test_study_force_over_the_folder_of_its_config_is_refused(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "study.md").write_text("a previous study\n")
    cfg = out / "cfg.yaml"
    cfg.write_text((REPO / "config" / "default.yaml").read_text())
    before = _tree(out)
    r = run_cli("study", "--scenarios", "nominal", "--controllers", "pid", "--seeds", "1", "--duration", "0.2",
                "--jobs", "1", "--config", cfg, "--out", out, "--force")
    _refused(r, "--out", "--config", "holds")
    assert _tree(out) == before


def test_simulate_force_over_its_warm_start_is_refused(tmp_path):
    prev = _simulate(tmp_path / "prev", controller="dnbs")
    before = _tree(prev)
    for init, out in ((prev / "checkpoints", prev), (prev / "checkpoints", prev / "checkpoints"),
                      (prev / "checkpoints", prev / "checkpoints" / "new"), (prev, prev), (prev, prev / "new")):
        r = run_cli("simulate", "--controller", "dnbs", *TINY, "--init-from", init, "--out", out, "--force")
        _refused(r, "--out", "--init-from")
    assert _tree(prev) == before


def test_an_out_holding_an_extended_config_is_refused(tmp_path):
    """The config's ``extends`` files are inputs too: a folder holding one is not replaced."""
    out = _simulate(tmp_path / "out")
    (out / "base.yaml").write_text((REPO / "config" / "default.yaml").read_text())
    (tmp_path / "cfg.yaml").write_text(f"extends: {out / 'base.yaml'}\n")
    before = _tree(out)
    _refused(run_cli("simulate", "--controller", "pid", *TINY, "--config", tmp_path / "cfg.yaml", "--out", out,
                     "--force"), "--out", "--config")
    assert _tree(out) == before


def test_force_does_not_wipe_a_folder_of_other_files(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "keep").write_text("not a pa10-dnbs output\n")
    _refused(run_cli("simulate", "--controller", "pid", *TINY, "--out", out, "--force"),
             "--out", "not a pa10-dnbs output")
    assert (out / "keep").read_text() == "not a pa10-dnbs output\n" and len(list(out.iterdir())) == 1


@pytest.mark.parametrize("given", ["", ".", "..", "/"])
def test_the_current_directory_its_parents_and_the_root_are_refused_up_front(tmp_path, monkeypatch, given):
    here = tmp_path / "a" / "b"
    here.mkdir(parents=True)
    (here / "keep").write_text("x")
    monkeypatch.chdir(here)
    r = run_cli("simulate", "--controller", "pid", *TINY, "--out", given, "--force")
    _refused(r, "--out")
    assert _tree(tmp_path) == {"a/b/keep": b"x"}


@pytest.mark.parametrize("given", ["", ".", ".."])
def test_launch_record_is_never_the_current_directory_or_its_parents(tmp_path, monkeypatch, given):
    """``launch --record "" --force`` emptied the current directory and wrote the bag there: --record follows the
    rule of --out (refused before any node starts)."""
    here = tmp_path / "a" / "b"
    here.mkdir(parents=True)
    (here / "keep").write_text("x")
    monkeypatch.chdir(here)
    _refused(run_cli("launch", "--duration", "0.1", "--out", tmp_path / "o", "--record", given, "--force"),
             "--record")
    assert _tree(tmp_path) == {"a/b/keep": b"x"}


def test_launch_record_force_does_not_wipe_a_folder_of_other_files(tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "keep").write_text("not a bag\n")
    _refused(run_cli("launch", "--duration", "0.1", "--out", tmp_path / "o", "--record", mine, "--force"),
             "--record", "not a pa10-dnbs output")
    _refused(run_cli("launch", "--duration", "0.1", "--out", tmp_path / "o", "--record", mine), "--record", "--force")
    assert _tree(mine) == {"keep": b"not a bag\n"} and not (tmp_path / "o").exists()


@pytest.mark.parametrize("given", ["", ".", "mine"])
def test_equal_budget_out_is_never_the_current_directory_nor_a_folder_of_other_files(tmp_path, monkeypatch, given):
    """``scripts/equal_budget.py --out ""`` wrote pid/, dnbs/, ctc/ and comparison.md into the current directory:
    its --out follows the rule of every --out (a folder of its own tunes and comparison.md is resumed)."""
    here = tmp_path / "a"
    (here / "mine").mkdir(parents=True)
    (here / "mine" / "keep").write_text("x")
    monkeypatch.chdir(here)
    r = subprocess.run([sys.executable, str(REPO / "scripts" / "equal_budget.py"), "--out", given, "--duration",
                        "0.1", "--trials", "1", "--scenarios", "nominal"], capture_output=True, text=True, timeout=120)
    _refused(r, "--out")
    assert _tree(tmp_path) == {"a/mine/keep": b"x"}


def test_force_replaces_a_previous_output_and_an_empty_folder(tmp_path):
    out = _simulate(tmp_path / "out", controller="dnbs")
    assert (out / "checkpoints").is_dir()
    _simulate(out, "--force")   # a previous output: replaced by the pid run
    assert (out / "report.md").is_file() and not (out / "checkpoints").exists()
    empty = tmp_path / "empty"
    empty.mkdir()
    _simulate(empty, "--force")
    assert (empty / "report.md").is_file()


def test_tune_resumes_only_into_its_own_folder(tmp_path):
    sim = _simulate(tmp_path / "sim")
    before = _tree(sim)
    _refused(run_cli(*TUNE, "--controller", "pid", "--out", sim), "--out", "report.md")
    assert _tree(sim) == before

    tune = tmp_path / "tune"
    r = run_cli(*TUNE, "--controller", "pid", "--out", tune)
    assert r.returncode == 0, r.stderr
    before = _tree(tune)
    _refused(run_cli(*TUNE, "--controller", "dnbs", "--out", tune), "--out", "pa10-pid")   # another tune's folder
    _refused(run_cli(*TUNE, "--controller", "pid", "--seed", "1", "--out", tune), "--seed")  # other options
    _refused(run_cli(*TUNE, "--controller", "pid", "--config", tune / "tuned.yaml", "--out", tune),
             "--out", "--config")                                                # its own result as config
    assert _tree(tune) == before
    (tune / "tune.json").unlink()   # an interrupted tune: only its storage tells which it is
    _refused(run_cli(*TUNE, "--controller", "dnbs", "--out", tune), "--out", "pa10-pid")
    r = run_cli(*TUNE, "--controller", "pid", "--trials", "2", "--out", tune)   # the same tune: resumes
    assert r.returncode == 0 and "2 trials" in r.stdout, r.stderr


def test_a_tune_does_not_resume_through_a_symlinked_tune_db(tmp_path):
    """tune.db linked to another tune's database was resumed into (its trials added to the other folder's)."""
    first = tmp_path / "first"
    r = run_cli(*TUNE, "--controller", "pid", "--out", first)
    assert r.returncode == 0, r.stderr
    before = _tree(first)
    second = tmp_path / "second"
    second.mkdir()
    (second / "tune.db").symlink_to(first / "tune.db")
    _refused(run_cli(*TUNE, "--controller", "pid", "--trials", "2", "--out", second), "--out",
             f"{second}/tune.db is a symbolic link")
    assert _tree(first) == before and sorted(p.name for p in second.iterdir()) == ["tune.db"]
    (second / "tune.db").unlink()
    (second / "tune.db").symlink_to(tmp_path / "nowhere.db")   # dangling: would be created in another folder
    _refused(run_cli(*TUNE, "--controller", "pid", "--out", second), "--out", "tune.db is a symbolic link")
    assert not (tmp_path / "nowhere.db").exists()


def test_a_tune_with_its_storage_in_its_out_resumes(tmp_path):
    out = tmp_path / "t"
    out.mkdir()
    storage = f"sqlite:///{out / 'mine.db'}"
    for trials in ("1", "2"):
        r = run_cli(*TUNE, "--controller", "pid", "--trials", trials, "--storage", storage, "--out", out)
        assert r.returncode == 0 and f"{trials} trials" in r.stdout, r.stderr


def test_force_does_not_wipe_a_folder_that_only_has_an_output_like_file_name(tmp_path):
    """A report.md (or comparison.md, tuned.yaml) at a folder's top is no proof of a pa10-dnbs output: --force
    replaces only a folder holding the mark its commands write (report/outputs.py OUTPUT_MARK)."""
    thesis = tmp_path / "thesis"
    (thesis / "chapters").mkdir(parents=True)
    for name, text in (("report.md", "# my report\n"), ("chapters/ch1.tex", "\\chapter{One}\n"), ("data.csv", "1,2\n"),
                       ("comparison.md", "mine\n"), ("tuned.yaml", "a: 1\n")):
        (thesis / name).write_text(text)
    before = _tree(thesis)
    _refused(run_cli("simulate", "--controller", "pid", *TINY, "--out", thesis, "--force"),
             "--out", "not a pa10-dnbs output")
    assert _tree(thesis) == before
    out = _simulate(tmp_path / "out")
    assert (out / ".pa10-dnbs-output").read_text().startswith("Written by pa10-dnbs")


def test_an_out_holding_the_arm_files_urdf_is_refused(tmp_path):
    """The URDF an arm file names is an input too, even with --force into a previous output."""
    arm_dir = _simulate(tmp_path / "armout")
    (arm_dir / "arm.urdf").write_text((REPO / "urdf" / "pa10" / "pa10_7ce.urdf").read_text())
    arm = tmp_path / "arm.yaml"
    text = (REPO / "urdf" / "pa10" / "arm.yaml").read_text()
    arm.write_text(text.replace("urdf: pa10_7ce.urdf", f"urdf: {arm_dir / 'arm.urdf'}"))
    assert str(arm_dir / "arm.urdf") in arm.read_text()
    before = _tree(arm_dir)
    _refused(run_cli("simulate", "--controller", "pid", *TINY, "--arm", arm, "--out", arm_dir, "--force"),
             "--out", "arm URDF")
    assert _tree(arm_dir) == before


def test_an_input_given_as_a_link_inside_out_is_refused(tmp_path):
    """A --config or BAG given as a symbolic link that lies inside --out: the link is what the user named."""
    prev = _simulate(tmp_path / "prev")
    (tmp_path / "cfg.yaml").write_text((REPO / "config" / "default.yaml").read_text())
    (prev / "cfg.yaml").symlink_to(tmp_path / "cfg.yaml")
    before = _tree(prev)
    _refused(run_cli("simulate", "--controller", "pid", *TINY, "--config", prev / "cfg.yaml", "--out", prev,
                     "--force"), "--out", "--config")
    assert _tree(prev) == before and (prev / "cfg.yaml").is_symlink()
    bag = _write_run_bag(tmp_path / "bag", ns="/pa10")
    holder = tmp_path / "bagh2"
    holder.mkdir()
    (holder / "thebag").symlink_to(bag)
    bag_before = _tree(bag)
    _refused(run_cli("analyse", holder / "thebag", "--out", holder, "--force", "--no-figures"), "--out", "BAG")
    assert (holder / "thebag").is_symlink() and _tree(bag) == bag_before


def test_out_paths_atomic_output_dir_cannot_replace_are_refused_up_front(tmp_path, monkeypatch):
    """A symbolic link (dangling or not), a name too long for its temporary sibling, a component too long, and a
    last component '..' (of a folder or a link, naming a previous output): refused before the run (exit 2, one
    line naming --out), nothing changed or left behind."""
    monkeypatch.chdir(tmp_path)
    real = _simulate(tmp_path / "real")
    (real / "X").mkdir()
    (real / "lnk").symlink_to(real / "X")
    before = _tree(real)
    (tmp_path / "dang").symlink_to(tmp_path / "nowhere")
    (tmp_path / "link").symlink_to(real)
    for out, words, extra in (("dang", ("symbolic link",), ()), ("link", ("symbolic link",), ("--force",)),
                              ("a" * 250, ("too long",), ()), (f"real/{'b' * 300}/c", ("too long",), ()),
                              ("real/X/..", ("name the folder itself",), ("--force",)),
                              ("real/lnk/..", ("name the folder itself",), ("--force",))):
        _refused(run_cli("simulate", "--controller", "pid", *TINY, "--out", out, *extra), "--out", *words)
    assert (tmp_path / "link").is_symlink() and (tmp_path / "dang").is_symlink() and _tree(real) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dang", "link", "real"]
    assert sorted(p.name for p in real.iterdir()) == [".pa10-dnbs-output", "X", "lnk", "metrics.json", "report.md",
                                                     "timeseries.npz"]


def test_force_onto_a_tunes_folder_says_it_is_one(tmp_path):
    """A tune writes no output mark (its folder is its storage, resumed, never replaced); --force of another
    command said its files were "not a pa10-dnbs output"."""
    out = tmp_path / "t"
    r = run_cli("tune", "--controller", "pid", "--trials", 1, "--scenarios", "nominal", "--seeds", 1,
                "--held-out-seeds", 0, "--duration", 0.05, "--jobs", 1, "--no-progress", "--out", out)
    assert r.returncode == 0, r.stderr
    before = _tree(out)
    _refused(run_cli("simulate", "--controller", "pid", *TINY, "--out", out, "--force"),
             "--out", f"{out} is a tune's folder", "--force never replaces one")
    assert _tree(out) == before


@pytest.mark.parametrize("kind", ["other tables", "not sqlite"])
def test_a_tune_never_writes_into_a_tune_db_that_is_not_its_storage(tmp_path, kind):
    """A DIR/tune.db of the user's (an SQLite database of its own, or another file) was taken as the storage:
    Optuna's 13 tables were written into it, or the refusal named --storage, which was never given."""
    import sqlite3

    out = tmp_path / "t"
    out.mkdir()
    db = out / "tune.db"
    if kind == "other tables":
        with sqlite3.connect(db) as con:
            con.execute("CREATE TABLE mine (a)")
    else:
        db.write_text("my notes\n")
    before = db.read_bytes()
    r = run_cli("tune", "--controller", "pid", "--trials", 1, "--scenarios", "nominal", "--seeds", 1,
                "--held-out-seeds", 0, "--duration", 0.05, "--jobs", 1, "--no-progress", "--out", out)
    _refused(r, f"--out: {db} is not a tune's storage")
    assert db.read_bytes() == before and sorted(p.name for p in out.iterdir()) == ["tune.db"]
    r = run_cli("tune", "--controller", "pid", "--trials", 1, "--scenarios", "nominal", "--seeds", 1,
                "--held-out-seeds", 0, "--duration", 0.05, "--jobs", 1, "--no-progress", "--out", tmp_path / "t2",
                "--storage", f"sqlite:///{db}")   # the same file given as --storage: Optuna's tables were added
    _refused(r, f"--storage: {db} is not a tune's storage")
    assert db.read_bytes() == before and not (tmp_path / "t2").exists()


def test_an_output_given_up_removes_the_folders_above_it_that_it_made(tmp_path):
    """"Nothing written" left the missing folders above --out that the output's staging had made."""
    from pa10_dnbs.report.outputs import atomic_output_dir

    (tmp_path / "kept").mkdir()
    for out in (tmp_path / "deep" / "a" / "b", tmp_path / "kept" / "new" / "b"):
        with pytest.raises(KeyboardInterrupt):
            with atomic_output_dir(out, force=False) as tmp:
                (tmp / "half.txt").write_text("written before the Ctrl-C\n")
                raise KeyboardInterrupt
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept"] and not list((tmp_path / "kept").iterdir())
    with atomic_output_dir(tmp_path / "deep" / "a" / "b", force=False) as tmp:
        (tmp / "whole.txt").write_text("done\n")
    assert (tmp_path / "deep" / "a" / "b" / "whole.txt").is_file()


def test_a_folder_made_at_out_while_the_run_goes_on_is_left_as_it_was(tmp_path):
    """Something else makes --out (or swaps the folder --force was to replace) after the run's first look: the
    end of the run moved it aside and deleted it (a user's notes lost, exit 0). Now it is left as it was, and the
    finished outputs go to a visible sibling that the one-line error names."""
    import os

    from pa10_dnbs.report.outputs import OutputExistsError, atomic_output_dir, check_output_dir

    def notes(folder: Path) -> Path:
        folder.mkdir()
        (folder / "notes.txt").write_text("mine\n")
        return folder

    cases = {"made before the last look": "before", "made while the outputs are written": "inside",
             "a previous output swapped for a folder of the user's": "swapped"}
    for i, when in enumerate(cases.values()):
        out = tmp_path / f"out{i}"
        if when == "swapped":
            _simulate(out)
        check_output_dir(out, force=True)   # the command's first look (simulate: before its runs)
        if when == "swapped":
            out.rename(tmp_path / f"moved{i}")
        if when in ("before", "swapped"):
            notes(out)
        with pytest.raises(OutputExistsError, match="created by something else while this run went on") as err:
            with atomic_output_dir(out, force=True) as tmp:
                (tmp / "report.md").write_text("the run's\n")
                if when == "inside":
                    notes(out)
        kept = tmp_path / f"out{i}.finished-{os.getpid()}"
        assert str(kept) in str(err.value) and "\n" not in str(err.value)
        assert _tree(out) == {"notes.txt": b"mine\n"}, when
        assert (kept / "report.md").read_text() == "the run's\n", when
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]   # no hidden copy left


def test_an_out_the_system_cannot_look_at_is_one_line(tmp_path):
    """A path longer than the system takes, below a link to nothing, or through a loop of links: Errno lines
    (exit 1, a dangling parent only after the whole run) or a RuntimeError traceback; now refused up front."""
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere" / "dir")
    (tmp_path / "loop1").symlink_to(tmp_path / "loop2")
    (tmp_path / "loop2").symlink_to(tmp_path / "loop1")
    for out, words in ((tmp_path / "dangling" / "x", ("symbolic link to", "does not exist")),
                       (tmp_path / ("b/" * 3000), ("File name too long",)),
                       (tmp_path / "loop1" / "x", ("a loop of symbolic links",))):
        _refused(run_cli("simulate", "--controller", "pid", *TINY, "--out", out), "--out", *words)
    _refused(run_cli(*TUNE, "--controller", "pid", "--out", tmp_path / "loop1"), "--out", "a loop of symbolic links")
    r = run_cli(*TUNE, "--controller", "pid", "--out", tmp_path / "t", "--storage", f"sqlite:///{tmp_path}/loop1")
    assert r.returncode == 2 and "Traceback" not in r.stderr and "--storage" in r.stderr, r.stderr
    r = run_cli("analyse", tmp_path / "loop1", "--out", tmp_path / "a", "--no-figures")
    assert r.returncode == 2 and "no such bag (a symbolic link to nothing, or a loop of links)" in r.stderr, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dangling", "loop1", "loop2"]


def _as_a_user(*args) -> subprocess.CompletedProcess:
    """``pa10-dnbs ARGS`` in a process without root's power over file modes (setpriv drops it), as a user runs it."""
    import os
    import shutil

    drop = []
    if os.geteuid() == 0:
        if shutil.which("setpriv") is None:
            pytest.skip("root, and no setpriv to drop root's override of file modes")
        drop = ["setpriv", "--bounding-set=-dac_override,-dac_read_search",
                "--inh-caps=-dac_override,-dac_read_search"]
    return subprocess.run([*drop, sys.executable, "-m", "pa10_dnbs.cli", *map(str, args)], capture_output=True,
                          text=True, timeout=120, cwd=REPO)


def test_folders_a_user_cannot_search_or_write_are_handled(tmp_path):
    """An --out folder without permissions: "[Errno 13] Permission denied" (exit 1), now one line naming --out.
    A previous output made read-only, replaced with --force: the old copy was left as a hidden .NAME.old-PID."""
    shut = tmp_path / "shut"
    shut.mkdir(mode=0o000)
    try:
        for args in (("simulate", "--controller", "pid", *TINY, "--out", shut, "--force"),
                     ("simulate", "--controller", "pid", *TINY, "--out", shut / "sub"),
                     (*TUNE, "--controller", "pid", "--out", shut)):
            r = _as_a_user(*args)
            assert r.returncode == 2 and r.stderr.count("\n") == 1 and "--out" in r.stderr, r.stderr
            assert "Permission denied" in r.stderr and "Traceback" not in r.stderr, r.stderr
    finally:
        shut.chmod(0o755)
    previous = _simulate(tmp_path / "previous")
    previous.chmod(0o555)
    r = _as_a_user("simulate", "--controller", "pid", *TINY, "--out", previous, "--force")
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["previous", "shut"]


@pytest.mark.parametrize("mask", [0o022, 0o077])
def test_an_output_folder_gets_the_mode_mkdir_would_give(tmp_path, mask):
    """The output is written in a tempfile.mkdtemp folder (0700) and renamed into place: it used to stay 0700
    whatever the umask, so other users (a web server, a container's other user) could not read the results."""
    import os
    import stat

    from pa10_dnbs.report.outputs import atomic_output_dir

    old = os.umask(mask)
    try:
        with atomic_output_dir(tmp_path / "run", force=False) as tmp:
            (tmp / "report.md").write_text("x\n")
        (tmp_path / "plain").mkdir()
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "run").stat().st_mode) == stat.S_IMODE((tmp_path / "plain").stat().st_mode) \
        == 0o777 & ~mask


def test_an_output_folder_in_a_setgid_folder_keeps_the_bit_mkdir_gives(tmp_path):
    """A shared group's folder (g+s) passes its group and the bit down to a folder made in it: the output, made
    by mkdtemp and given mkdir's mode, must keep the bit (a chmod of 0777 less the umask alone cleared it)."""
    import os
    import stat

    from pa10_dnbs.report.outputs import atomic_output_dir

    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o2775)
    with atomic_output_dir(shared / "run", force=False) as tmp:
        (tmp / "report.md").write_text("x\n")
    (shared / "plain").mkdir()
    assert (shared / "run").stat().st_mode == (shared / "plain").stat().st_mode
    assert (shared / "run").stat().st_mode & stat.S_ISGID


@pytest.mark.parametrize("how", ["moved", "copied"])
def test_a_tune_folder_moved_or_copied_whole_resumes_where_it_is(tmp_path, how):
    """tune.json names the storage by its absolute path (sqlite:////old/place/tune.db): a tune folder renamed, or
    copied to another place, could never be resumed, each message pointing to the other (the review's rev_g
    finding 2). Given no --storage, the folder's own tune.db is its storage wherever the folder is."""
    import shutil

    first, there = tmp_path / "first", tmp_path / "there"
    r = run_cli(*TUNE, "--controller", "pid", "--trials", "1", "--out", first)
    assert r.returncode == 0, r.stderr
    (shutil.move if how == "moved" else shutil.copytree)(first, there)
    r = run_cli(*TUNE, "--controller", "pid", "--trials", "2", "--out", there)
    assert r.returncode == 0 and "2 trials" in r.stdout, r.stderr
    assert json.loads((there / "tune.json").read_text())["storage"] == f"sqlite:///{(there / 'tune.db').resolve()}"


def test_a_tune_whose_trials_are_lost_is_refused_not_started_over_its_reports(tmp_path):
    """The storage of reported trials deleted (DIR/tune.db, or a --storage file): the same command started a new
    study and wrote its reports over those of the lost trials, exit 0 (rev_g finding 3)."""
    out = tmp_path / "t"
    r = run_cli(*TUNE, "--controller", "pid", "--trials", "2", "--out", out)
    assert r.returncode == 0, r.stderr
    (out / "tune.db").unlink()
    before = _tree(out)
    _refused(run_cli(*TUNE, "--controller", "pid", "--trials", "3", "--out", out), "--out",
             f"{out}/tune.json reports 2 trials", "tune.db, which held them, is gone")
    assert _tree(out) == before

    elsewhere = tmp_path / "db"
    elsewhere.mkdir()
    storage = f"sqlite:///{elsewhere / 'trials.db'}"
    out2 = tmp_path / "t2"
    r = run_cli(*TUNE, "--controller", "pid", "--trials", "2", "--storage", storage, "--out", out2)
    assert r.returncode == 0, r.stderr
    (elsewhere / "trials.db").unlink()
    before = _tree(out2)
    _refused(run_cli(*TUNE, "--controller", "pid", "--trials", "3", "--storage", storage, "--out", out2), "--out",
             f"{out2}/tune.json reports 2 trials", f"but {elsewhere / 'trials.db'}, which held them, is gone")
    assert _tree(out2) == before and not (elsewhere / "trials.db").exists()   # nothing made again

    # a storage there that holds none of them (another database put in its place): refused before the study is
    # made in it
    import optuna

    optuna.create_study(storage=storage, study_name="unrelated")
    r = run_cli(*TUNE, "--controller", "pid", "--trials", "3", "--storage", storage, "--out", out2)
    _refused(r, "--out", f"{out2}/tune.json reports 2 trials", f"but {storage} holds 0")
    assert optuna.get_all_study_names(storage) == ["unrelated"]
