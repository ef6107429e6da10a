"""Arm files for tests: a fixture URDF copied beside a small arm.yaml, and the settings of an arm built quietly."""
import contextlib
import io
import shutil
from pathlib import Path

import yaml

from pa10_dnbs.config import default_config_path
from pa10_dnbs.run_settings import build_settings


def arm_file(tmp_path: Path, urdf: Path, file_name: str, **fields) -> str:
    """The path of ``tmp_path/file_name``: an arm file for a copy of ``urdf`` (named after it), with the
    arm-file ``fields`` given (``settings``, ``rotor_inertia_kgm2``, ``sources`` ...) over a bare one."""
    shutil.copy(urdf, tmp_path / urdf.name)
    doc = {"name": urdf.stem, "urdf": urdf.name, "sources": {"urdf": "test fixture"}, **fields}
    path = tmp_path / file_name
    path.write_text(yaml.safe_dump(doc))
    return str(path)


def quiet_settings(arm):
    """The default config's settings for ``arm`` (a preset, an arm file or a URDF), the rules' table muted."""
    with contextlib.redirect_stderr(io.StringIO()):
        return build_settings(default_config_path(), arm=arm)
