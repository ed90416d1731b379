"""Rows and terms written out for a student: ``0.167083 alpha = -0.433013 O.Fx - 0.25 O.Fy``.

The same style as `mbody assemble` prints (six significant figures, accelerations and
the gyroscopic term on the left, loads and reactions on the right, a known reaction with
its value), written here from the rows' numbers so that the checker's words do not
depend on another module's printing.
"""

from __future__ import annotations

from collections.abc import Mapping

from mbody.answers.compare import CONST, Row
from mbody.equations.fbd import Equation
from mbody.util import formatting


def num(x: float, ref: float = 1.0) -> str:
    """A number to six significant figures; rounding noise (below 1e-12 ref) is 0.

    Parameters
    ----------
    x : float
        The number.
    ref : float
        The magnitude it is noise against (default 1; the magnitude of a student's row
        written at a tiny scale, such as 1e-170 a_x = 5e-170, so that its numbers show).

    Returns
    -------
    str
    """
    return formatting.num(float(x), formatting.NOISE * ref)


def terms(coef: Mapping[str, float]) -> str:
    """``{O.Fx: -0.43, O.Fy: 1}`` -> ``-0.43 O.Fx + O.Fy`` ('0' when empty).

    Parameters
    ----------
    coef : mapping of str to float
        Name -> coefficient, in the order written.

    Returns
    -------
    str
    """
    out = ""
    for name, c in coef.items():
        if num(c) == "0":
            continue
        mag = abs(c)
        txt = name if num(mag) == "1" else f"{num(mag)} {name}"
        if not out:
            out = f"-{txt}" if c < 0 else txt
        else:
            out += f" {'-' if c < 0 else '+'} {txt}"
    return out or "0"


def _join(head: str, tail: str) -> str:
    if not head or head == "0":
        return tail
    if tail == "0":
        return head
    return f"{head} - {tail[1:]}" if tail.startswith("-") else f"{head} + {tail}"


def equation_text(eq: Equation) -> str:
    """One row of the assembly as `mbody assemble` writes it.

    Parameters
    ----------
    eq : Equation
        A row of a body's Newton-Euler pair.

    Returns
    -------
    str
    """
    left = terms(eq.lhs)
    if num(eq.gyro) != "0":
        left = _join(left, num(eq.gyro))
    right = num(eq.rhs) if num(eq.rhs) != "0" or not eq.reactions else "0"
    for label, c in eq.reactions.items():
        name = f"({label}={num(eq.known[label])})" if label in eq.known else label
        right = _join(right, terms({name: c}))
    return f"{left} = {right}"


def row_text(row: Row) -> str:
    """A row ``Σ c u + c0 = 0`` as an equation: accelerations left, the rest right.

    Parameters
    ----------
    row : Row
        The row.

    Returns
    -------
    str
    """
    left = terms({k: v for k, v in row.coef.items() if k != CONST and "." not in k})
    right = _join(num(-row.get(CONST)), terms({k: -v for k, v in row.coef.items()
                                                if "." in k}))
    return f"{left} = {right}"
