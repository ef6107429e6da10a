"""Numbers as people write them: ``0.829`` not ``0.8290000000000001``, ``1e9`` not ``1e+09``."""
from __future__ import annotations


def num(x, digits: int = 6) -> str:
    """``x`` in at most ``digits`` significant digits, without a float's binary tail or an exponent's padding."""
    text = f"{float(f'{float(x):.{digits}g}'):g}"  # rounded to ``digits``, then without an exponent below 1e6
    if "e" in text:
        mantissa, exp = text.split("e")
        text = f"{mantissa}e{int(exp)}"
    return text


def interval(pair) -> str:
    """A window ``(a, b)`` as ``[a, b]`` with :func:`num`."""
    a, b = pair
    return f"[{num(a)}, {num(b)}]"


def fixed(x: float, spec: str) -> str:
    """``x`` in the fixed-point format ``spec`` (``'+.2f'``, ``'>9.1f'``), or in 3 significant digits from 1e7 on,
    where fixed point would print every digit (a limit of 1e300: 300 of them)."""
    return format(x, spec) if not abs(x) >= 1e7 else format(x, spec.rsplit(".", 1)[0] + ".3g")
