"""The symbolic equations as data: `SymbolicRow` (one row), `SymbolicBody` (one body's
Newton-Euler pair and the values that make it numeric), `SymbolicEquations` (every
chosen body), and `RowValues` (a row's numbers after substitution).

Rows are written ``M v̇ = −b + Q + G λ``. How they are printed (text, LaTeX) is
`mbody.equations.symbolic.printing`'s job; how they are made from an assembly is
`mbody.equations.symbolic.build`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from mbody import conventions as cv
from mbody.equations.symbolic.printing import (
    gyro_text,
    inertia_words,
    join_terms,
    latex_number,
    latex_text,
    value_lines,
)
from mbody.equations.symbolic.terms import (
    APPLIED,
    GRAVITY,
    GYROSCOPIC,
    INERTIA,
    REACTION,
    Term,
)
from mbody.errors import not_found


@dataclass(frozen=True)
class RowValues:
    """One row's numbers after substitution: what the stacked system holds there.

    Parameters
    ----------
    label : str
        The row's coordinate label (``rod.theta``).
    inertia : dict of str to float
        Acceleration name -> coefficient (the row of M).
    gyroscopic : float
        The row of b (ω × Jω; 0 on Newton rows).
    applied : float
        The row of Q.
    reactions : dict of str to float
        Reaction label -> coefficient (the row of G).
    """

    label: str
    inertia: dict[str, float]
    gyroscopic: float
    applied: float
    reactions: dict[str, float]


@dataclass(frozen=True)
class SymbolicRow:
    """One row ``Σ inertia·acceleration = −b + Q + G λ`` with symbols.

    Parameters
    ----------
    label : str
        The row's coordinate label (``rod.x``, ``rotor.w1``...).
    terms : tuple of Term
        Left side (``inertia``) then right side: gyroscopic, applied, gravity, reactions.
    """

    label: str
    terms: tuple[Term, ...]

    @property
    def left(self) -> tuple[Term, ...]:
        """The terms of the left side (the row of M times the accelerations)."""
        return tuple(t for t in self.terms if t.part == INERTIA)

    @property
    def right(self) -> tuple[Term, ...]:
        """The terms of the right side, in the order printed."""
        return tuple(t for t in self.terms if t.part != INERTIA)

    @property
    def lhs(self) -> Any:
        """The left side as a sympy expression, e.g. ``I_1*alpha_1``."""
        return _sum(t.expr for t in self.left)

    @property
    def rhs(self) -> Any:
        """The right side as a sympy expression, e.g. ``(I_2 - I_3)*w_2*w_3``."""
        return _sum(t.expr for t in self.right)

    @property
    def equation(self) -> Any:
        """The row as ``sympy.Eq(lhs, rhs)``."""
        import sympy

        return sympy.Eq(self.lhs, self.rhs, evaluate=False)

    @property
    def inertia(self) -> dict[str, Any]:
        """Acceleration name -> its coefficient, symbolic (the row of M): ``{'a_x': m}``."""
        return {t.key: t.expr / _acceleration(t.key) for t in self.left}

    @property
    def gyroscopic(self) -> Any:
        """This row of b, ``(ω × Jω)_k``, symbolic (0 on Newton rows and in the plane)."""
        return -_sum(t.expr for t in self.terms if t.part == GYROSCOPIC)

    @property
    def applied(self) -> Any:
        """This row of Q, symbolic: loads by name, springs' tensions, gravity."""
        return _sum(t.expr for t in self.terms if t.part in (APPLIED, GRAVITY))

    @property
    def reactions(self) -> dict[str, float]:
        """Reaction label -> coefficient (this row of G; numbers: directions, lever arms)."""
        return {t.key: t.coefficient for t in self.terms if t.part == REACTION}

    def evaluate(self, values: dict[str, float]) -> RowValues:
        """The row's numbers with `values` substituted for its symbols.

        Parameters
        ----------
        values : dict of str to float
            Symbol name -> value (`SymbolicBody.values` holds the model's).

        Returns
        -------
        RowValues
            This row of M, b, Q and G.
        """
        sub = _substitution(values)
        return RowValues(self.label,
                         {k: float(c.xreplace(sub)) for k, c in self.inertia.items()},
                         float(self.gyroscopic.xreplace(sub)),
                         float(self.applied.xreplace(sub)), self.reactions)

    def text(self, digits: int = 6) -> str:
        """``lhs = rhs`` as plain text (sympy's syntax: a row can be pasted back).

        Parameters
        ----------
        digits : int
            Significant digits of the numbers (17 writes them exactly).

        Returns
        -------
        str
        """
        left, right = join_terms(self.left, digits, False), join_terms(self.right, digits, False)
        return f"{left or '0'} = {right or '0'}"

    def latex(self, digits: int = 6) -> str:
        """``lhs &= rhs`` for an ``aligned`` environment.

        Parameters
        ----------
        digits : int
            Significant digits of the numbers.

        Returns
        -------
        str
        """
        return (f"{join_terms(self.left, digits, True) or '0'} &= "
                f"{join_terms(self.right, digits, True) or '0'}")

    def __repr__(self) -> str:  # the dataclass's would print every Term
        return f"<SymbolicRow {self.label}: {self.text()}>"

    def __str__(self) -> str:
        return self.text()


@dataclass(frozen=True)
class SymbolicBody:
    """One body's Newton-Euler pair with symbols, and the values that make it numeric.

    Parameters
    ----------
    body : str
        The body's name.
    dimension : int
        2 (planar) or 3 (spatial).
    inertia_form : str
        ``planar`` (I_G), ``principal`` (I_1, I_2, I_3), ``tensor`` (entries I_11,
        I_12...) or ``particle`` (no rotation rows).
    rows : tuple of SymbolicRow
        Newton's rows (world axes) then Euler's (body axes), in stacking order.
    values : dict of str to float
        Symbol name -> value at the assembly's state (unknown reactions are absent).
    definitions : dict of str to str
        How a symbol's value is made, where it is more than a number: a load that varies
        in time (``50*sin(2*t)``), a spring's tension, a known reaction.
    t : float
        The time of the state (s).
    reactions : tuple of str
        The reaction labels acting on the body, in the order of the columns of G.
    """

    body: str
    dimension: int
    inertia_form: str
    rows: tuple[SymbolicRow, ...]
    values: dict[str, float]
    definitions: dict[str, str] = field(default_factory=dict)
    t: float = 0.0
    reactions: tuple[str, ...] = ()

    @property
    def newton(self) -> tuple[SymbolicRow, ...]:
        """Newton's rows, m a = ΣF, world axes."""
        n = 2 if self.dimension == cv.PLANAR else 3
        return self.rows[:n]

    @property
    def euler(self) -> tuple[SymbolicRow, ...]:
        """Euler's rows about the mass centre, body axes (planar: one; a particle: none)."""
        n = 2 if self.dimension == cv.PLANAR else 3
        return self.rows[n:]

    @property
    def unknowns(self) -> list[str]:
        """The reaction labels on this body whose values are not known (column order)."""
        return [k for k in self.reactions if k not in self.values]

    def evaluate(self, values: dict[str, float] | None = None) -> list[RowValues]:
        """Every row's numbers with `values` (default: the model's, `values`) substituted.

        Parameters
        ----------
        values : dict of str to float, optional
            Symbol name -> value; missing names are taken from `values`.

        Returns
        -------
        list of RowValues
            The body's rows of M, b, Q and G, in stacking order.
        """
        merged = {**self.values, **(values or {})}
        return [r.evaluate(merged) for r in self.rows]

    def text(self, digits: int = 6) -> str:
        """The body's section: its inertia, Newton's and Euler's rows, then the values.

        Parameters
        ----------
        digits : int
            Significant digits of the numbers (17 writes them exactly).

        Returns
        -------
        str
        """
        width = max(len(r.label) for r in self.rows) + 2
        out = [f"== {self.body} ==  {inertia_words(self.inertia_form)}",
               "Newton (world axes):"]
        out += [f"  {r.label:<{width}}{r.text(digits)}" for r in self.newton]
        if self.euler:
            if self.dimension == cv.PLANAR:
                out.append("Euler (about the mass centre, z):")
            else:
                out.append("Euler (about the mass centre, body axes): "
                           "J*alpha = -b + M_G, with b = w x (J*w):")
                b = [gyro_text(r, digits) for r in self.euler]
                if self.inertia_form == "principal":
                    out.append(f"  b = ({', '.join(b)})")
                else:
                    out += [f"  b_{k + 1} = {bk}" for k, bk in enumerate(b)]
            out += [f"  {r.label:<{width}}{r.text(digits)}" for r in self.euler]
        out += value_lines(self, digits)
        return "\n".join(out)

    def latex(self, digits: int = 6) -> str:
        """The body's rows as one ``aligned`` environment (amsmath).

        Parameters
        ----------
        digits : int
            Significant digits of the numbers.

        Returns
        -------
        str
        """
        return ("\\begin{aligned}\n" + " \\\\\n".join(r.latex(digits) for r in self.rows)
                + "\n\\end{aligned}")

    def _repr_latex_(self) -> str:  # Jupyter renders the equations
        return "$$" + self.latex() + "$$"

    def __repr__(self) -> str:  # the dataclass's would print every row's terms
        return (f"<SymbolicBody {self.body!r}: {len(self.rows)} rows; print() it, .rows, "
                ".evaluate(), .latex()>")

    def __str__(self) -> str:
        return self.text()


@dataclass(frozen=True)
class SymbolicEquations:
    """Every chosen body's `SymbolicBody`, in stacking order.

    Parameters
    ----------
    model : str
        The model's name.
    dimension : int
        2 (planar) or 3 (spatial).
    t : float
        The time of the state (s).
    bodies : tuple of SymbolicBody
        One per body, in stacking order.
    """

    model: str
    dimension: int
    t: float
    bodies: tuple[SymbolicBody, ...]

    def __getitem__(self, name: str) -> SymbolicBody:
        for b in self.bodies:
            if b.body == name:
                return b
        raise not_found("body named", name, [b.body for b in self.bodies], "bodies")

    def __repr__(self) -> str:  # the dataclass's would print every term
        return (f"<SymbolicEquations of {self.model!r} at t = {self.t:g} s: "
                f"{len(self.bodies)} bod{'y' if len(self.bodies) == 1 else 'ies'}, "
                f"{len(self.rows)} rows; print() it, .text(), .latex(), [body]>")

    @property
    def rows(self) -> list[SymbolicRow]:
        """Every row, body by body (Newton's then Euler's): the stacking order."""
        return [r for b in self.bodies for r in b.rows]

    def text(self, digits: int = 6) -> str:
        """A header with the symbols' meaning, then each body's section.

        Parameters
        ----------
        digits : int
            Significant digits of the numbers (17 writes them exactly).

        Returns
        -------
        str
        """
        planar = self.dimension == cv.PLANAR
        head = [f"model {self.model!r} at t = {self.t:g} s, symbolic: "
                f"M v_dot = {'' if planar else '-b + '}Q + G lambda per body",
                "a_x, a_y" + ("" if planar else ", a_z") + ": mass-centre acceleration "
                "(world axes); "
                + ("alpha, w: angular acceleration and velocity" if planar else
                   "alpha_k, w_k: angular acceleration and velocity (body axes)"),
                "loads by name (F_<load>_x world axes, F_<load>_1 body axes; M_ couples; "
                "T_ spring tensions); reactions by label; lever arms and directions are "
                "numbers at this state"]
        return "\n\n".join(["\n".join(head)] + [b.text(digits) for b in self.bodies])

    def latex(self, digits: int = 6) -> str:
        """Every body's rows in one ``aligned`` environment, a line naming each body.

        Parameters
        ----------
        digits : int
            Significant digits of the numbers.

        Returns
        -------
        str
        """
        parts = []
        for b in self.bodies:
            parts.append(f"&\\text{{{latex_text(b.body)}:}}")
            parts += [r.latex(digits) for r in b.rows]
        return "\\begin{aligned}\n" + " \\\\\n".join(parts) + "\n\\end{aligned}"

    def document(self, digits: int = 6) -> str:
        """A complete LaTeX article (amsmath) with each body's rows and values.

        Parameters
        ----------
        digits : int
            Significant digits of the numbers.

        Returns
        -------
        str
            The source, which pdflatex compiles.
        """
        planar = self.dimension == cv.PLANAR
        out = [r"\documentclass[11pt]{article}", r"\usepackage[margin=2cm]{geometry}",
               r"\usepackage{amsmath}",
               rf"\title{{Newton-Euler equations of {latex_text(self.model)}, with symbols}}",
               r"\author{}", r"\date{}", r"\begin{document}", r"\maketitle",
               (r"Rows are $M\dot{v} = " + ("" if planar else r"-\omega\times(J\omega) + ")
                + r"Q + G\lambda$ per body: Newton's in world axes, Euler's about the mass "
                + ("centre." if planar else "centre in body axes.")
                + " Lever arms and directions are numbers at "
                + rf"$t = {latex_number(self.t, 6)}$~s.")]
        for b in self.bodies:
            out += [rf"\section*{{Body {latex_text(b.body)}}}",
                    latex_text(inertia_words(b.inertia_form)) + ".",
                    "\\[\n" + b.latex(digits) + "\n\\]"]
            where = value_lines(b, digits)
            if where:
                out.append(r"\noindent " + r"\\ ".join(latex_text(w.strip())
                                                       for w in where))
        out += [r"\end{document}", ""]
        return "\n".join(out)

    def _repr_latex_(self) -> str:  # Jupyter renders the equations
        return "$$" + self.latex() + "$$"

    def __str__(self) -> str:
        return self.text()


def _acceleration(name: str) -> Any:
    import sympy

    return sympy.Symbol(name)


def _sum(exprs: Any) -> Any:
    import sympy

    return sympy.Add(*exprs)


def _substitution(values: dict[str, float]) -> dict[Any, Any]:
    import sympy

    return {sympy.Symbol(k): sympy.Float(v) for k, v in values.items()}
