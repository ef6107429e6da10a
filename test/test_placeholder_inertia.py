"""A link whose inertia no real link has (a placeholder: 1 kg m^2 on 10 mg) is named at intake, once, on stderr
(arm/placeholder_inertia.py): the PhantomX Pincher's URDF gives three gripper links these values, and its pan
joint then feels 3 kg m^2. The presets and the collection's arms print no such line (their widest link: 0.42 m)."""
from __future__ import annotations

import pytest

from chain_urdf import chain_urdf
from pa10_dnbs.arm import load_arm
from pa10_dnbs.arm.placeholder_inertia import GYRATION_MAX_M

PLACEHOLDER = '<inertial><mass value="0.00001"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>'


def _with(tmp_path, where: str, inertial: str):
    text = chain_urdf(3)
    if where == "flange":   # a fixed link the arm moves
        text = text.replace('<link name="flange"/>', f'<link name="flange">{inertial}</link>')
    else:                   # the fixed base, which never moves
        text = text.replace('<link name="l0"><inertial>', '<link name="l0"><inertial_old>', 1)
        text = text.replace('</inertial></link>', '</inertial_old>' + inertial + '</link>', 1)
    (tmp_path / f"{where}.urdf").write_text(text)
    return tmp_path / f"{where}.urdf"


def test_a_placeholder_inertia_on_a_moving_link_is_named_once(tmp_path, capsys):
    urdf = _with(tmp_path, "flange", PLACEHOLDER)
    load_arm(urdf)
    load_arm(urdf)   # read once per process
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert err == (f"warning: {urdf}: link 'flange': inertia 1 kg m^2 on a mass of 1e-05 kg is a radius of gyration "
                   "of 316 m, wider than any arm's link (a placeholder?); the plant moves it as written\n")


@pytest.mark.parametrize("where, inertial", [
    ("base", PLACEHOLDER),   # the base never moves
    ("flange", f'<inertial><mass value="1"/><inertia ixx="{0.99 * GYRATION_MAX_M ** 2}" ixy="0" ixz="0" '
               f'iyy="0.1" iyz="0" izz="0.1"/></inertial>')])   # just within the bound
def test_no_line_where_the_inertia_is_possible_or_never_moves(tmp_path, capsys, where, inertial):
    load_arm(_with(tmp_path, where, inertial))
    assert "radius of gyration" not in capsys.readouterr().err
