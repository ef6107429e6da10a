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
    """The run folder (.partial) of a failed launch is removed; its logs move to <out>.failed/logs and the
    failure message names them there. An interrupted run (Ctrl-C) keeps nothing."""
    from pa10_dnbs.commands.launch import _keep_logs
    from pa10_dnbs.supervisor.graph_options import GraphFailure

    out = tmp_path / "run"
    tmp = tmp_path / ".run.partial-x"
    (tmp / "logs").mkdir(parents=True)
    (tmp / "logs" / "plant.log").write_text("graph incomplete\n")
    exc = _keep_logs(GraphFailure(f"plant exited early with code 1\n--- last lines of {tmp}/logs/plant.log ---"),
                     tmp, out)
    kept = tmp_path / "run.failed" / "logs"
    assert (kept / "plant.log").read_text() == "graph incomplete\n"
    assert f"--- last lines of {kept}/plant.log ---" in str(exc) and str(tmp) not in str(exc)
    assert not exc.interrupted
    (tmp / "logs").mkdir()
    stopped = GraphFailure("interrupted (SIGINT)", interrupted=True)
    assert _keep_logs(stopped, tmp, tmp_path / "other") is stopped and not (tmp_path / "other.failed").exists()
