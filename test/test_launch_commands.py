"""The launcher writes each child's command line into the run's logs/commands.sh (supervisor/processes.py)."""
import shlex
import subprocess
import sys

from pa10_dnbs.supervisor.processes import COMMANDS_FILE, ManagedProcess, command_line, stop_all


def test_command_line_quotes_and_places_the_child_on_its_domain():
    line = command_line([sys.executable, "-m", "x", "--ros-args", "-p", "topics:=['a', 'b']"],
                        {"ROS_DOMAIN_ID": "7", "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "HOME": "/root"})
    words = shlex.split(line)
    assert words[:2] == ["ROS_DOMAIN_ID=7", "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST"]
    assert words[2:] == [sys.executable, "-m", "x", "--ros-args", "-p", "topics:=['a', 'b']"]  # HOME left out


def test_each_child_appends_its_command_and_the_file_runs_it_again(tmp_path):
    """Two children, one line each (in start order); the file, run by bash, starts them again as started."""
    logs = tmp_path / "logs"
    logs.mkdir()
    env = {"ROS_DOMAIN_ID": "9", "PATH": "/usr/bin:/bin"}
    procs = [ManagedProcess(name, [sys.executable, "-c", f"import os; open({str(tmp_path / name)!r}, 'w')"
                                   f".write(os.environ['ROS_DOMAIN_ID'])"], env, logs / f"{name}.log")
             for name in ("first", "second")]
    for p in procs:
        p.proc.wait(timeout=60)
    assert stop_all(procs) == {"first": 0, "second": 0}
    text = (logs / COMMANDS_FILE).read_text()
    assert text.index("# first (log: first.log)") < text.index("# second (log: second.log)")
    for name in ("first", "second"):
        (tmp_path / name).unlink()
    subprocess.run(["bash", "-c", f"source {logs / COMMANDS_FILE}; wait"], check=True, timeout=60)
    assert (tmp_path / "first").read_text() == "9" and (tmp_path / "second").read_text() == "9"


def test_a_failed_runs_logs_are_kept_where_its_message_points(tmp_path):
    """The run folder (.partial) of a failed launch is removed; its logs move to <out>.failed/logs, the params
    their command lines read beside them, and the failure message names them there. An interrupted run (Ctrl-C)
    keeps nothing."""
    from pa10_dnbs.commands.launch import _keep_logs
    from pa10_dnbs.supervisor.graph_options import GraphFailure

    out = tmp_path / "run"
    tmp = tmp_path / ".run.partial-x"
    (tmp / "logs").mkdir(parents=True)
    (tmp / "logs" / "plant.log").write_text("graph incomplete\n")
    (tmp / "ros_params.yaml").write_text("/pa10/plant: {}\n")
    (tmp / "checkpoints").mkdir()   # where a controller's line writes (its folder is checked at the start)
    (tmp / "logs" / COMMANDS_FILE).write_text(f"x --params-file {tmp}/ros_params.yaml &\n")
    exc = _keep_logs(GraphFailure(f"plant exited early with code 1\n--- last lines of {tmp}/logs/plant.log ---"),
                     tmp, out)
    kept = tmp_path / "run.failed" / "logs"
    assert (kept / "plant.log").read_text() == "graph incomplete\n"
    # its command lines read the params beside them there (they pointed into the removed run folder)
    assert (kept.parent / "ros_params.yaml").read_text() == "/pa10/plant: {}\n"
    assert (kept.parent / "checkpoints").is_dir()
    assert (kept / COMMANDS_FILE).read_text() == f"x --params-file {kept.parent}/ros_params.yaml &\n"
    assert f"--- last lines of {kept}/plant.log ---" in str(exc) and str(tmp) not in str(exc)
    assert not exc.interrupted
    (tmp / "logs").mkdir()
    stopped = GraphFailure("interrupted (SIGINT)", interrupted=True)
    assert _keep_logs(stopped, tmp, tmp_path / "other") is stopped and not (tmp_path / "other.failed").exists()


def test_a_failed_runs_logs_never_replace_a_users_folder_or_file(tmp_path):
    """<out>.failed was removed unchecked (a user's folder of that name lost); a file there turned the failure
    into [Errno 17]. Only an earlier failure's kept logs (its mark) are replaced; else a fresh folder."""
    from pa10_dnbs.commands.launch import _keep_logs
    from pa10_dnbs.supervisor.graph_options import GraphFailure

    def fail(name):
        tmp = tmp_path / f".{name}.partial-x"
        (tmp / "logs").mkdir(parents=True)
        (tmp / "logs" / "plant.log").write_text("graph incomplete\n")
        return _keep_logs(GraphFailure(f"plant exited early with code 1 ({tmp}/logs/plant.log)"), tmp,
                          tmp_path / name)

    (tmp_path / "thesis.failed").mkdir()
    (tmp_path / "thesis.failed" / "precious.txt").write_text("my data\n")
    (tmp_path / "notes.failed").write_text("a file\n")
    for name in ("thesis", "notes"):
        exc = fail(name)
        fresh = [p for p in tmp_path.glob(f"{name}.failed-*") if p.is_dir()]
        assert len(fresh) == 1 and (fresh[0] / "logs" / "plant.log").is_file(), list(tmp_path.iterdir())
        assert str(exc).startswith("plant exited early") and f"kept in {fresh[0] / 'logs'}" in str(exc)
    assert (tmp_path / "thesis.failed" / "precious.txt").read_text() == "my data\n"
    assert (tmp_path / "notes.failed").read_text() == "a file\n"
    fail("run")
    fail("run")   # a second failure replaces the first's kept logs (its mark), no fresh folder
    assert (tmp_path / "run.failed" / "logs" / "plant.log").is_file() and not list(tmp_path.glob("run.failed-*"))


def test_the_command_lines_name_the_folder_where_the_run_ends_up(tmp_path):
    """They named the run's temporary folder (.NAME.partial-XXXX), renamed when the run ends: a line copied from a
    finished run's commands.sh failed ("Couldn't parse params file")."""
    from pa10_dnbs.supervisor.processes import move_commands

    logs = tmp_path / ".run.partial-x" / "logs"
    logs.mkdir(parents=True)
    staged = logs.parent
    (logs / COMMANDS_FILE).write_text(f"a --params-file {staged}/ros_params.yaml -p 'f:=\"{staged}/w.npz\"' &\n")
    move_commands(logs, logs.parent, tmp_path / "run")
    assert (logs / COMMANDS_FILE).read_text() == (f"a --params-file {tmp_path}/run/ros_params.yaml "
                                                  f"-p 'f:=\"{tmp_path}/run/w.npz\"' &\n")
