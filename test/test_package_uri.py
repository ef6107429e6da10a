"""``package://<package>/<path>`` in an arm file's ``urdf`` and in ``--arm`` (pa10_dnbs/arm/package_uri.py): found
through $AMENT_PREFIX_PATH's share/<package> (a fixture package here) or the environment's cmeel.prefix/share;
a package installed nowhere is one line naming it and how to install it, exit 2, nothing written."""
import yaml

from cli_runner import run_cli
from pa10_dnbs.arm import load_arm
from pa10_dnbs.arm.package_uri import resolve_package_uri, share_dirs
from test_arms import three_link_urdf

import pytest


def _package(tmp_path, name="my_arm_description") -> str:
    """A prefix holding share/<name>/urdf/three.urdf, as a colcon install or a ROS distribution lays it out."""
    prefix = tmp_path / "prefix"
    (prefix / "share" / name / "urdf").mkdir(parents=True)
    (prefix / "share" / name / "urdf" / "three.urdf").write_text(three_link_urdf())
    return str(prefix)


def _arm_file(tmp_path, urdf: str, **extra) -> str:
    doc = {"name": "three", "urdf": urdf, "sources": {"urdf": "a fixture package"}, **extra}
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump(doc))
    return str(tmp_path / "arm.yaml")


def test_an_arm_file_finds_its_urdf_in_a_package_of_the_ament_prefix_path(tmp_path, monkeypatch):
    prefix = _package(tmp_path)
    monkeypatch.setenv("AMENT_PREFIX_PATH", f"{tmp_path / 'elsewhere'}:{prefix}")
    arm = load_arm(_arm_file(tmp_path, "package://my_arm_description/urdf/three.urdf"))
    assert arm.urdf == tmp_path / "prefix" / "share" / "my_arm_description" / "urdf" / "three.urdf"
    assert arm.joint_names == ("j1", "j2", "j3")
    assert share_dirs("x")[-1].parts[-3:] == ("cmeel.prefix", "share", "x")  # then the Python environment's


def test_arm_accepts_a_package_uri_of_a_bare_urdf(tmp_path, monkeypatch):
    monkeypatch.setenv("AMENT_PREFIX_PATH", _package(tmp_path))
    out = tmp_path / "out"
    r = run_cli("simulate", "--arm", "package://my_arm_description/urdf/three.urdf", "--controller", "pid",
                "--duration", "0.05", "--out", out, "--no-figures")
    assert r.returncode == 0, r.stderr
    assert (out / "metrics.json").is_file()


@pytest.mark.parametrize("hint, needle", [({"urdf_install": "pip install -r requirements-collection.txt"},
                                           "install it: pip install -r requirements-collection.txt"),
                                          ({}, "source its workspace's setup script")])
def test_a_package_installed_nowhere_is_one_line_naming_it_exit_2(tmp_path, monkeypatch, hint, needle):
    monkeypatch.setenv("AMENT_PREFIX_PATH", _package(tmp_path, "another_package"))
    arm = _arm_file(tmp_path, "package://missing_robot_data/robots/x.urdf", **hint)
    r = run_cli("simulate", "--arm", arm, "--duration", "0.05", "--out", tmp_path / "out")
    assert r.returncode == 2 and not (tmp_path / "out").exists()
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, r.stderr
    assert "urdf: package://missing_robot_data/robots/x.urdf: package 'missing_robot_data' is not installed" in lines[0]
    assert needle in lines[0] and "1 prefix)" in lines[0]


def test_a_malformed_uri_and_a_missing_file_in_a_found_package_are_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("AMENT_PREFIX_PATH", _package(tmp_path))
    with pytest.raises(ValueError, match="expected package://<package>/<path>"):
        resolve_package_uri("package://only_a_package")
    r = run_cli("simulate", "--arm", _arm_file(tmp_path, "package://my_arm_description/urdf/none.urdf"),
                "--duration", "0.05", "--out", tmp_path / "out")
    assert r.returncode == 2 and "urdf: file not found" in r.stderr and "none.urdf" in r.stderr
