"""Locate the package's data files (config/, urdf/): a source tree, a colcon install, or a pip install."""
from __future__ import annotations

import sys
from pathlib import Path

PACKAGE = "pa10_dnbs"
_SOURCE_ROOT = Path(__file__).resolve().parent.parent


def share_dir() -> Path:
    """The directory holding config/ and urdf/.

    The source tree when the package is imported from one (``config/`` beside it); else the package's share
    directory in the ament index (a colcon install: ``AMENT_PREFIX_PATH`` set by its setup script); else
    ``<prefix>/share/pa10_dnbs`` (a wheel installed into an environment).
    """
    if (_SOURCE_ROOT / "config").is_dir() and (_SOURCE_ROOT / "package.xml").is_file():
        return _SOURCE_ROOT
    try:
        from ament_index_python.packages import PackageNotFoundError, get_package_share_directory

        try:
            return Path(get_package_share_directory(PACKAGE))
        except (PackageNotFoundError, LookupError, ValueError):
            pass
    except ImportError:
        pass
    return Path(sys.prefix, "share", PACKAGE)


def share_path(*parts: str) -> Path:
    """Path of a data file under :func:`share_dir`."""
    return share_dir().joinpath(*parts)
