"""Which file an arm value names (``--arm``, a config's ``arm:``) and what kind of file it is.

The value is a preset's name (``urdf/<name>/arm.yaml``), a ``package://`` URI, an arm folder (its ``arm.yaml``),
an arm file (YAML) or a URDF. A URDF is known by its XML root ``<robot>``, whatever its name ends in (``.urdf``,
``.xml``, ``.URDF``). A path the OS refuses (a name too long for it, a loop of symbolic links, a NUL byte) is an
:class:`ArmError` naming it, as a missing file is: one line, exit 2.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from ..config_error import ConfigError
from ..file_path import PathProblem, file_or_folder, shown
from ..paths import share_path
from .package_uri import is_package_uri, resolve_package_uri

ARM_YAML = "arm.yaml"      # the arm file of an arm folder


class ArmError(ConfigError):
    """An arm file or URDF is unusable; the message names the file and what is wrong."""


def preset_names() -> list[str]:
    """The arms shipped in ``urdf/`` (folders with an arm.yaml)."""
    root = share_path("urdf")
    return sorted(p.parent.name for p in root.glob(f"*/{ARM_YAML}"))


def existing(path, who: str) -> tuple[Path, bool]:
    """(``path`` resolved, whether it is a folder), when it is a file or a folder; else ArmError ``"<who>: ..."``
    (file_path.file_or_folder: not found, the OS's reason, not a regular file)."""
    try:
        return file_or_folder(path)
    except PathProblem as exc:
        raise ArmError(f"{who}: {exc}") from None


def existing_file(path, who: str) -> Path:
    """``path`` resolved, when it is an existing file (not a folder); else ArmError ``"<who>: ..."``
    (:func:`existing`)."""
    resolved, is_dir = existing(path, who)
    if is_dir:
        raise ArmError(f"{who}: {shown(resolved)} is a folder, not a file")
    return resolved


def arm_file_path(spec: str | Path) -> Path:
    """The file ``spec`` names, resolved: a preset's ``urdf/<name>/arm.yaml``, a ``package://`` URI's file, a
    folder's ``arm.yaml``, or the path itself (an arm file or a URDF)."""
    text = "" if spec is None else str(spec)
    if not text.strip():
        raise ArmError("arm: empty (a preset name or the path of an arm file or URDF)")
    if is_package_uri(text):
        try:
            path = resolve_package_uri(text)
        except ValueError as exc:  # PackageNotFound too
            raise ArmError(f"arm: {exc}") from None
        return existing_file(path, f"arm: {text}")
    if "/" not in text and not text.endswith((".yaml", ".yml", ".urdf")):
        preset = share_path("urdf", text, ARM_YAML)
        if _is_file(preset):
            return preset.resolve()
        if not _exists(Path(text).expanduser()):
            raise ArmError(f"arm: no arm called {shown(text)!r} (presets: {', '.join(preset_names())}; or give the "
                           f"path of an arm file, URDF or arm folder)")
    path, is_dir = existing(Path(text).expanduser(), "arm")
    if not is_dir:
        return path
    inside = path / ARM_YAML
    if not _is_file(inside):
        raise ArmError(f"arm: {shown(path)} is a folder without an {ARM_YAML} (give an arm folder, an arm file or "
                       f"a URDF)")
    return inside


def is_urdf(path: Path) -> bool:
    """Whether the file ``path`` is to be read as a URDF: its name ends in ``.urdf`` (any case), or it is an XML
    document whose root is ``<robot>``. ArmError for another XML document or a xacro file (not an arm file)."""
    if path.suffix.lower() == ".urdf":
        return True
    if path.suffix.lower() == ".xacro":
        raise ArmError(f"{path}: not an arm file: a xacro file (URDF macros): expand it to a URDF first "
                       f"(xacro {path.name} > {path.stem}.urdf)")
    try:
        with open(path, "rb") as f:
            head = f.read(64).lstrip(b"\xef\xbb\xbf \t\r\n")
    except OSError as exc:
        raise ArmError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if not head.startswith(b"<"):
        return False   # YAML (an arm file); read_yaml names what is wrong with it
    try:
        with open(path, "rb") as f:
            tag = next(ET.iterparse(f, events=("start",)))[1].tag
    except (ET.ParseError, OSError, StopIteration):
        return True    # XML that does not parse: read as the URDF it was meant to be (the line says where it fails)
    if tag != "robot":
        raise ArmError(f"{path}: not an arm file: an XML document whose root is <{tag}> (a URDF's root is <robot>)")
    return True


def _is_file(path: Path) -> bool:
    try:
        return path.is_file()
    except (OSError, ValueError):   # a name too long, a NUL byte: not a preset
        return False


def _exists(path: Path) -> bool:
    try:
        return path.exists() or path.is_symlink()
    except (OSError, ValueError):   # a name too long: exists as far as the message goes (existing() says why)
        return True
