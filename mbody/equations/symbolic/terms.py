"""The vocabulary of a symbolic row: what a term is part of, the axis suffixes, `Term`.

A `Term` is ``coefficient · Π factors``: the coefficient a number (geometry at the
assembly's state, or ±1), the factors sympy symbols. sympy is imported only when a
term's expression is asked for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

INERTIA, GYROSCOPIC, APPLIED, GRAVITY, REACTION = (
    "inertia", "gyroscopic", "applied", "gravity", "reaction")
"""What a `Term` is: a row of M (left side), −b, Q (applied loads, springs, gravity), G."""

WORLD_AXES, BODY_AXES = ("x", "y", "z"), ("1", "2", "3")
"""Component suffixes: letters for world axes, numbers for body axes (as a_x and w_1)."""


@dataclass(frozen=True)
class Term:
    """``coefficient · Π factors``, one term of a row.

    Parameters
    ----------
    coefficient : float
        The number in front: geometry (a lever arm, a direction cosine) or ±1, exact.
    factors : tuple of sympy.Expr
        The symbols multiplied, in the order they are printed (may hold an unevaluated
        sum, such as ``I_2 - I_3``).
    part : str
        ``inertia`` (left side, a row of M), ``gyroscopic`` (−b), ``applied`` (loads and
        springs, Q), ``gravity`` (Q) or ``reaction`` (G).
    key : str
        The acceleration (inertia terms), reaction label (reaction terms) or load symbol
        the term is about.
    """

    coefficient: float
    factors: tuple[Any, ...]
    part: str
    key: str

    @property
    def shown(self) -> Any:
        """The factors as one unevaluated product (printed in their order)."""
        import sympy

        if len(self.factors) == 1:
            return self.factors[0]
        return sympy.Mul(*self.factors, evaluate=False)

    @property
    def expr(self) -> Any:
        """The term as an ordinary sympy expression (evaluated, exact coefficient)."""
        import sympy

        return _sympy_number(self.coefficient) * sympy.Mul(*(f.doit() for f in self.factors))


def _sympy_number(x: float) -> Any:
    """An integral float as a sympy Integer (prints ``2``, not ``2.0``), else an exact Float."""
    import sympy

    if x.is_integer() and abs(x) < 2**53:
        return sympy.Integer(int(x))
    return sympy.Float(x)
