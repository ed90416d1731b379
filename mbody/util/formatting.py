"""Numbers, vectors and tables as the text outputs print them: 6 significant digits,
rounding noise as 0.

One rule for the noise (`quiet`): a value smaller than the tolerance of the computation
that gave it prints as 0. The data (JSON, npz, the Python objects) keep every value as
computed; only the text rounds. The tolerance is the caller's, in the value's units:
`NOISE` for a number with no scale of its own, `LENGTH_RTOL` times the body's (or the
model's) size for a length, a solver's own tolerance for what it solved for.
"""

from __future__ import annotations

import math

import numpy as np

from mbody.errors import g_text

NOISE = 1e-12
"""A magnitude below which a number with no scale of its own is rounding (a rotation's
-2.4e-17), not data."""
LENGTH_RTOL = 1e-9
"""A length below this fraction of its body's or model's size is not a dimension: mbody
takes a joint to hold when its points are that close (`mbody.solve.kinematics`, 1000
``CLOSE_RTOL`` of the model's size), so a coordinate that small comes from the file's
rounding (a position written to 10 digits puts a pin 4e-12 m off a 0.5 m rod's axis)."""


def quiet(x: float, tol: float = NOISE) -> float:
    """`x`, or 0 when |x| is below `tol` (the module's rule)."""
    return 0.0 if abs(x) < tol else x


def num(x: float, tol: float = NOISE) -> str:
    """6 significant digits; |x| below `tol` as 0 (`quiet`), never -0."""
    s = f"{quiet(x, tol):.6g}"
    return "0" if s in ("-0", "0") else s


def number(x: float) -> str:
    """`x` as a message states a bound or a count: as %g writes it, with exponents as
    people write them (1e9, 2.5e-13); an int below 10^12 in full, its thousands apart
    (10 000 000)."""
    if isinstance(x, int) and abs(x) < 10**12:
        return f"{x:,}".replace(",", " ")
    if isinstance(x, int) and abs(x) >= 10**300:
        # past a float's range (and past what str() of an int converts in linear time):
        # its power of ten (math.log10 takes an int of any size)
        return f"{'-' if x < 0 else ''}about 1e{math.floor(math.log10(abs(x)))}"
    return g_text(float(x))


_BINARY_UNITS = ("KiB", "MiB", "GiB", "TiB", "PiB", "EiB")


def size_text(n: int) -> str:
    """A count of `n` bytes as a message gives it to people: the one wording of a size
    (a model file's, a run's, an export's, a budget).

    Below 1 KiB the count itself, singular for one: '1 byte', '1,023 bytes'. From 1 KiB,
    3 significant digits in the largest binary unit (1024) whose figure is at least 1,
    and the next unit once the figure rounds to 1000, so that a size never prints with an
    exponent: 1,024,000 bytes (1000 KiB) is '0.977 MiB (1,024,000 bytes)', 1,048,575
    bytes (1023.999 KiB) '1 MiB (1,048,575 bytes)'. Under 1 MiB the exact count follows
    in brackets, where the rounded figure says little: '1 KiB (1,024 bytes)', '1.5 KiB
    (1,536 bytes)'; from 1 MiB the figure alone: '1 MiB', '2 GiB', '7.11 PiB' (two sizes
    compared: `sizes_apart`).
    """
    if n < 1024:
        return "1 byte" if n == 1 else f"{n:,} bytes"
    value, unit = n / 1024, 0
    while float(f"{value:.3g}") >= 1000 and unit < len(_BINARY_UNITS) - 1:
        value, unit = value / 1024, unit + 1
    figure = f"{value:.3g}" if value < 999.5 else f"{value:,.0f}"  # beyond EiB: whole
    text = f"{figure} {_BINARY_UNITS[unit]}"
    return f"{text} ({n:,} bytes)" if n < 2**20 else text


def sizes_apart(a: int, b: int) -> tuple[str, str]:
    """Two sizes as `size_text` gives them, or as exact byte counts when they round
    alike ('1 GiB' against '1 GiB' would not say which is more)."""
    ta, tb = size_text(a), size_text(b)
    return (ta, tb) if ta != tb or a == b else (f"{a:,} bytes", f"{b:,} bytes")


def vec(x: np.ndarray, dim: int, tol: float = NOISE) -> str:
    """``(x, y)`` of a planar model's vector (its first two components), ``(x, y, z)``;
    each component below `tol` as 0."""
    x = np.asarray(x)[:2] if dim == 2 else np.asarray(x)  # a planar model's
    return "(" + ", ".join(num(v, tol) for v in x) + ")"


def table(header: list[str], rows: list[list[str]], indent: str = "  ") -> list[str]:
    """Left-aligned columns, each as wide as its longest cell plus two spaces."""
    widths = [max(len(r[c]) for r in [header, *rows]) for c in range(len(header))]
    fmt = indent + "  ".join(f"{{:<{w}}}" for w in widths)
    return [fmt.format(*r).rstrip() for r in [header, *rows]]


def clean(x: np.ndarray, rel: float = 1e-10) -> np.ndarray:
    """Values below `rel` times the largest one as 0: rounding noise, not data."""
    x = np.asarray(x, dtype=float)
    top = float(np.max(np.abs(x), initial=0.0))
    return np.where(np.abs(x) <= rel * top, 0.0, x)


def rounded_to(x: np.ndarray, scale: float, rel: float = NOISE) -> np.ndarray:
    """`x` rounded to the decimal place of `rel` times `scale` (the column's largest
    magnitude, or more): a label computed through a conversion (a law's radians in
    degrees, 29.999999999999996) written as the value it stands for (30.0)."""
    x = np.asarray(x, dtype=float)
    if not (scale > 0 and math.isfinite(scale)):
        return x
    return np.round(x, -math.floor(math.log10(rel * scale)))


FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r", "\0")
"""The first characters that make a spreadsheet (Excel, LibreOffice, Google Sheets) read a
CSV cell as a formula (OWASP's CSV injection list, with ASVS's NUL)."""
_SEPARATORS = (";", "\t")
"""Characters some spreadsheets split a CSV line at (a ';' locale, tab-separated)."""


def spreadsheet_text(cell: str) -> str:
    """A CSV text cell that a spreadsheet shows as text, never runs as a formula.

    A cell that starts with one of `FORMULA_STARTS` gets a ``'`` in front (the
    spreadsheets' "this is text" mark, as OWASP advises); so does one of ``= + - @``
    right after a ``;`` or a tab inside the cell, where a spreadsheet that splits lines
    at those would start a cell. Only text cells are given to it: a number column's -1
    stays a number.

    Parameters
    ----------
    cell : str
        Free text (a student's name, a file name, an error message).

    Returns
    -------
    str
        `cell`, unchanged unless it holds such a start.
    """
    if cell.startswith(FORMULA_STARTS):
        cell = "'" + cell
    if any(s in cell for s in _SEPARATORS):
        out = [cell[0]] if cell else []
        for prev, ch in zip(cell, cell[1:], strict=False):
            if prev in _SEPARATORS and ch in "=+-@":
                out.append("'")
            out.append(ch)
        cell = "".join(out)
    return cell
