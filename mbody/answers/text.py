"""Rows and terms written out for a student: ``0.167083 alpha = -0.433013 O.Fx - 0.25 O.Fy``.

The same style as `mbody assemble` prints (six significant figures, accelerations and
the gyroscopic term on the left, loads and reactions on the right, a known reaction with
its value), written here from the rows' numbers so that the checker's words do not
depend on another module's printing.
"""

from __future__ import annotations

from collections.abc import Mapping

from mbody.answers.compare import CONST, Fit, Row
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


def differences(s: Row, t: Row, f: Fit, wrong: list[str], shown: int = 3) -> str:
    """The terms in which the student's row `s` differs from ``k·t`` (the fit `f`), at
    the student's scale: "the constant has -80 where -40 is expected; O.Fy is missing
    (expected 1.29904), and 2 more".

    Parameters
    ----------
    s, t : Row
        The student's row and the row it is compared with.
    f : Fit
        Their fit (`mbody.answers.compare.consensus`).
    wrong : list of str
        The keys that differ, worst first.
    shown : int
        How many are written out.

    Returns
    -------
    str
    """
    parts = []
    # numbers at the student's scale: noise only against the row's own magnitude
    ref = min(1.0, max((abs(v) for v in s.coef.values()), default=1.0))
    for key in wrong[:shown]:
        have, want = s.get(key), f.times(t.get(key))
        name = "the constant" if key == CONST else key
        if have == 0.0:
            parts.append(f"{name} is missing (expected {num(want, ref)})")
        elif want == 0.0:
            parts.append(f"{name} does not belong here (you have {num(have, ref)})")
        else:
            parts.append(f"{name} has {num(have, ref)} where {num(want, ref)} is expected")
    more = f", and {len(wrong) - shown} more" if len(wrong) > shown else ""
    return "; ".join(parts) + more


def percent(x: float) -> str:
    """0.00698 -> '0.7 %'."""
    return f"{100.0 * x:.2g} %"


def rounding(s: Row, t: Row, f: Fit, off: Mapping[str, float], tol: float) -> str:
    """"O.Fx has 0.43 where 0.433013 is expected (0.7 % off): a number rounded too
    coarsely? ..." for the keys of `off` (`mbody.answers.compare.rounded_off`)."""
    ref = min(1.0, max((abs(v) for v in s.coef.values()), default=1.0))
    parts = [f"{'the constant' if k == CONST else k} has {num(s.get(k), ref)} where "
             f"{num(f.times(t.get(k)), ref)} is expected ({percent(off[k])} off)"
             for k in sorted(off, key=lambda k: -off[k])[:3]]
    more = f", and {len(off) - 3} more" if len(off) > 3 else ""
    return ("; ".join(parts) + more + ": a number rounded too coarsely? Each coefficient "
            f"must match to {percent(tol)}; write numbers to about four significant "
            "figures, or use the model's names for them")
