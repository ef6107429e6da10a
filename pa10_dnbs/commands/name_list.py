"""A comma-separated flag of names (``--scenarios a,b``), checked against the valid ones."""
from __future__ import annotations

from ..config import ConfigError


def name_list(flag: str, given: str, valid) -> list[str]:
    """The names in ``given``, in order and once each; ConfigError naming ``flag`` for an unknown or no name."""
    names = [n.strip() for n in given.split(",") if n.strip()]
    bad = [n for n in names if n not in valid]
    if bad or not names:
        raise ConfigError(f"{flag}: unknown {', '.join(bad) if bad else '(empty list)'}; valid: {', '.join(valid)}")
    return list(dict.fromkeys(names))
