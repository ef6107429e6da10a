"""An RMW_IMPLEMENTATION this environment does not hold: one line naming it, exit 2, before any ROS process
starts. Before, replay and robot ended with rcl's 'Expected RMW implementation identifier ... exiting with 102'
(exit 102), and launch started its ten processes to fail one by one and wrote OUT.failed (review rev_g, 5)."""
import pytest
from cli_runner import run_cli

from pa10_dnbs.supervisor.rmw_check import installed_rmws


def test_the_installed_rmw_is_the_wheels_fast_dds():
    assert "rmw_fastrtps_cpp" in installed_rmws()


@pytest.mark.parametrize("command", [["replay", "BAG"], ["robot", "--duration", "0.1"],
                                     ["launch", "--duration", "0.2", "--out", "OUT"]])
def test_an_rmw_not_installed_is_refused_before_ros(tmp_path, monkeypatch, command):
    monkeypatch.setenv("RMW_IMPLEMENTATION", "rmw_cyclonedds_cpp")
    bag = tmp_path / "bag"
    bag.mkdir()
    words = [str(bag) if w == "BAG" else str(tmp_path / "out") if w == "OUT" else w for w in command]
    r = run_cli(*words)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert "RMW_IMPLEMENTATION: 'rmw_cyclonedds_cpp' is not installed here" in lines[0]
    assert "rmw_fastrtps_cpp" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]


def test_the_installed_rmw_or_none_passes(monkeypatch):
    from pa10_dnbs.supervisor.rmw_check import check_rmw
    for value in ("rmw_fastrtps_cpp", "", " "):
        monkeypatch.setenv("RMW_IMPLEMENTATION", value)
        check_rmw()
    monkeypatch.delenv("RMW_IMPLEMENTATION")
    check_rmw()
