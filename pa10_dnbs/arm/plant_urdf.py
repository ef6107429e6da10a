"""The copy of a URDF that PyBullet loads, where the URDF as written would make PyBullet change its physics.

PyBullet's importer departs from the URDF spec in five ways the plant must not inherit:

- a link without ``<inertial>`` gets mass 1 kg and inertia diag(1, 1, 1) kg m^2 (the spec: massless);
- an inertia tensor whose principal moments break the triangle inequality (one larger than the sum of the
  other two, which no mass distribution has) is set to zero ("Bad inertia tensor properties");
- a mesh it cannot find (a ``package://`` URI outside a ROS workspace) stops the load;
- a line longer than LINE_MAX bytes is read in pieces joined by a newline, which breaks (or silently changes)
  the tag it falls in (a URDF written on one line: "PyBullet cannot load this URDF");
- a ``<robot>`` without a name is refused ("Expected a name for robot"): the copy is named after the file.

:func:`plant_urdf` returns None when a URDF has none of these (it is loaded exactly as written: the presets),
else the path of a cleaned copy, written once to a cache directory named by the copy's content hash, in which
every link without ``<inertial>`` gets an explicit zero mass and inertia, every tensor breaking the triangle
inequality is repaired, every ``<visual>`` or ``<collision>`` holding a mesh is dropped (the plant takes its
inertias from the file and needs no geometry), and a line too long is broken, one tag a line. Repair of a tensor
with principal moments I1 <= I2 < I3, I3 > I1 + I2: the least thin rod along the I3 axis that makes it
consistent, i.e. d = (I3 (1 + 1e-6) - I1 - I2) / 2 added to I1 and I2 (nothing removed, the centre of mass and
I3 kept). A tensor with a negative or non-finite principal moment cannot be repaired: ValueError naming the
link.

A cached copy is read back before use (a damaged one is written anew, atomically); a cache that cannot be used
(a file, read-only, another user's unreadable copy) gives way to a temporary directory of the process.
"""
from __future__ import annotations

import atexit
import contextlib
import hashlib
import os
import shutil
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..kinematics.urdf_xml import urdf_root

CACHE_DIR_NAME = "pa10_dnbs_urdf"  # under the system's temporary directory
MARGIN = 1e-6                      # relative margin a repaired tensor keeps from the triangle inequality's edge
EDGE = 1e-9                        # off-diagonal tensors: I1 + I2 - I3 down to -EDGE I3 counts as on the edge
LINE_MAX = 8191   # PyBullet reads a URDF with fgets into 8192 bytes and joins the pieces with a newline
_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def cache_dir() -> Path:
    """Where cleaned copies are written: ``$PA10_DNBS_URDF_CACHE`` or <tmp>/pa10_dnbs_urdf."""
    return Path(os.environ.get("PA10_DNBS_URDF_CACHE") or Path(tempfile.gettempdir()) / CACHE_DIR_NAME)


def plant_urdf(urdf: Path) -> tuple[Path | None, list[str]]:
    """(the cleaned copy's path, or None when ``urdf`` needs no change; one line per repaired link).

    Raises ValueError naming the link for an inertia that cannot be repaired, ET.ParseError for bad XML.
    """
    written = urdf.read_bytes()
    root = urdf_root(written)
    root_link = _root_link(root)
    changed, notes = False, []
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            _add_zero_inertial(link)
            changed = changed or link.get("name") != root_link  # a fixed base's own mass never matters
            continue
        note = _repair_inertia(urdf, link.get("name"), inertial)
        if note:
            notes.append(note)
            changed = True
    if _has_unusable_mesh(root, urdf.parent) or _longest_line(written) > LINE_MAX:
        changed = True
    if not root.get("name", "").strip():   # PyBullet: "Expected a name for robot" (xacro output without one)
        root.set("name", urdf.stem)
        changed = True
    if not changed:
        return None, []
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                if el.find("geometry/mesh") is not None:
                    link.remove(el)
    data = _broken_into_lines(root)
    name = f"{urdf.stem}-{hashlib.sha256(data).hexdigest()[:16]}.urdf"
    try:
        return _cached(cache_dir(), name, data), notes
    except OSError:   # the cache is a file, read-only, or holds another user's unreadable copy
        return _cached(_private_dir(), name, data), notes


def _cached(folder: Path, name: str, data: bytes) -> Path:
    """``folder/name`` holding ``data``: the copy there when it holds exactly that (read back: a truncated or
    damaged copy is not trusted by its name), else written anew. OSError when the folder cannot be used."""
    path = folder / name
    try:
        if path.read_bytes() == data:
            return path
    except FileNotFoundError:
        pass
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", dir=folder)
    try:
        os.fchmod(fd, 0o644)   # other users sharing the cache read it (mkstemp makes it 0600)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)  # atomic: concurrent runs write the same bytes
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


_private: list[Path] = []   # this process's own cache, made when the shared one cannot be used


def _private_dir() -> Path:
    """A temporary directory of this process alone, removed at its exit."""
    if not _private:
        _private.append(Path(tempfile.mkdtemp(prefix=f"{CACHE_DIR_NAME}-")))
        atexit.register(shutil.rmtree, _private[0], ignore_errors=True)
    return _private[0]


def _longest_line(data: bytes) -> int:
    return max(len(line) for line in data.split(b"\n"))


def _broken_into_lines(root: ET.Element) -> bytes:
    """The URDF ``root`` as UTF-8, as written, or indented one tag a line where a line would be longer than
    LINE_MAX bytes (PyBullet would split it inside a tag); ValueError when a single tag is that long."""
    data = ET.tostring(root, encoding="unicode").encode()
    if _longest_line(data) <= LINE_MAX:
        return data
    ET.indent(root)
    data = ET.tostring(root, encoding="unicode").encode()
    if _longest_line(data) > LINE_MAX:
        raise ValueError(f"a tag longer than {LINE_MAX} bytes (PyBullet reads a URDF in lines of at most "
                         f"{LINE_MAX} bytes and splits a longer one)")
    return data


def principal_moments(inertial: ET.Element) -> tuple[np.ndarray, np.ndarray]:
    """(principal moments ascending (3,) kg m^2, their axes as columns (3, 3)) of an ``<inertial>``."""
    return np.linalg.eigh(_tensor(inertial))


def _tensor(inertial: ET.Element) -> np.ndarray:
    el = inertial.find("inertia")
    i = {k: float(el.get(k, 0.0)) if el is not None else 0.0 for k in _KEYS}
    return np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]], [i["ixz"], i["iyz"], i["izz"]]])


def _repair_inertia(urdf: Path, name: str, inertial: ET.Element) -> str | None:
    """Repair ``inertial`` in place if it breaks the triangle inequality; the one line saying so, else None."""
    try:
        tensor = _tensor(inertial)
    except ValueError:
        raise ValueError(f"link {name!r}: <inertia> values must be numbers") from None
    if not np.all(np.isfinite(tensor)):
        raise ValueError(f"link {name!r}: <inertia> values must be finite")
    moments, axes = np.linalg.eigh(tensor)
    if moments[0] < -1e-12 * max(1.0, abs(moments[2])):
        raise ValueError(f"link {name!r}: inertia has a negative principal moment ({moments[0]:.3g} kg m^2): "
                         f"fix its <inertia> in the URDF")
    off_diagonal = np.any(tensor[np.triu_indices(3, 1)] != 0.0)
    slack = moments[0] + moments[1] - moments[2]
    # PyBullet tests its own principal moments (the diagonal itself, else a Jacobi sweep): a planar body sits
    # on the edge (I3 = I1 + I2) and passes there; off the axes, the last digits of an eigen-solver decide
    if slack >= (-EDGE * moments[2] if off_diagonal else 0.0):
        return None
    d = 0.5 * (moments[2] * (1.0 + MARGIN) - moments[0] - moments[1])
    fixed = tensor + d * (np.outer(axes[:, 0], axes[:, 0]) + np.outer(axes[:, 1], axes[:, 1]))
    el = inertial.find("inertia")
    for key, value in zip(_KEYS, (fixed[0, 0], fixed[0, 1], fixed[0, 2], fixed[1, 1], fixed[1, 2], fixed[2, 2])):
        el.set(key, repr(float(value)))
    return (f"{urdf}: link {name!r}: inertia breaks the triangle inequality (principal moments "
            f"{moments[0]:.4g} + {moments[1]:.4g} < {moments[2]:.4g} kg m^2; PyBullet would zero it): repaired, "
            f"{d:.3g} kg m^2 added to the two smaller moments (docs/arms.md)")


def _add_zero_inertial(link: ET.Element) -> None:
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "mass", value="0")
    ET.SubElement(inertial, "inertia", **{k: "0" for k in _KEYS})


def _root_link(root: ET.Element) -> str:
    children = {j.find("child").get("link") for j in root.findall("joint") if j.find("child") is not None}
    return next((link.get("name") for link in root.findall("link") if link.get("name") not in children), "")


def _has_unusable_mesh(root: ET.Element, base: Path) -> bool:
    """A mesh given by a package:// (or other URI) or by a path that does not exist."""
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        if "://" in name or not (base / name).is_file():
            return True
    return False
