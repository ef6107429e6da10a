"""``package://<package>/<path>`` URIs (ROS's convention) resolved to files, for an arm file's ``urdf`` or ``--arm``.

A package is looked for where packages put their share directory: ``<prefix>/share/<package>`` for every
prefix of ``$AMENT_PREFIX_PATH`` (a sourced ROS 2 workspace or distribution), then the running Python
environment's ``<purelib>/cmeel.prefix/share/<package>`` (a cmeel wheel from PyPI, e.g. example-robot-data).
The first directory that exists is the package's; a package found nowhere is a :class:`PackageNotFound` whose
one line names the package, the places looked in and how to install it.
"""
from __future__ import annotations

import os
import sysconfig
from pathlib import Path

SCHEME = "package://"
GENERIC_HINT = ("a ROS package: source its workspace's setup script (sets AMENT_PREFIX_PATH); "
                "a cmeel wheel: pip install it into this environment")


class PackageNotFound(ValueError):
    """The package a URI names is installed nowhere this module looks."""


def is_package_uri(text: str) -> bool:
    return isinstance(text, str) and text.startswith(SCHEME)


def share_dirs(package: str) -> list[Path]:
    """The candidate share directories of ``package``, in search order (existing or not)."""
    prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    out = [Path(p) / "share" / package for p in prefixes]
    out.append(Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / package)
    return out


def resolve_package_uri(uri: str, install_hint: str | None = None) -> Path:
    """The file ``package://<package>/<path>`` names (not checked to exist). Raises ValueError for a malformed
    URI and PackageNotFound (its message: the package, where it was looked for, ``install_hint`` or a generic
    one) when no share directory of the package exists."""
    rest = uri[len(SCHEME):] if is_package_uri(uri) else ""
    package, _, relative = rest.partition("/")
    if not package or not relative or package in (".", ".."):
        raise ValueError(f"{uri!r}: expected package://<package>/<path>")
    candidates = share_dirs(package)
    for share in candidates:
        if share.is_dir():
            return share / relative
    n = len(candidates) - 1
    looked = (f"$AMENT_PREFIX_PATH's share/ ({'unset' if n == 0 else f'{n} prefix' + ('es' if n > 1 else '')}) "
              f"and {candidates[-1].parent}")
    raise PackageNotFound(f"{uri}: package {package!r} is not installed (looked in {looked}); install it: "
                          f"{install_hint or GENERIC_HINT}")
