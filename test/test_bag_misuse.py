"""Bags other programs wrote, or a hand-damaged run description: one line on stderr naming the topic, key or
flag, exit 2, nothing written, never a traceback."""
from test_bag_files import _assert_clear_error, _write_run_bag

from cli_runner import run_cli


def test_a_reference_point_without_a_position_is_named(tmp_path):
    """Reference points with empty positions (another program's bag) gave an IndexError traceback."""
    bag = _write_run_bag(tmp_path / "b", n=20, ref_positions=())
    r = run_cli("analyse", bag, "--out", tmp_path / "out")
    _assert_clear_error(r, f"{bag}: /pa10/s1/reference: a reference point holds no position")
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists(), r.stderr
