"""Each body's Newton-Euler pair written with symbols, as a student derives it:

    m a_x = Σ F_x                                   (Newton, world axes)
    I_1 α_1 = (I_2 − I_3) ω_2 ω_3 + Σ M_1          (Euler, body axes: J α = −ω × Jω + M_G)

The symbols are the physics: the body's mass ``m`` and inertia (``I_G``; ``I_1, I_2,
I_3`` when the tensor is diagonal in body axes; its entries ``I_11, I_12, ...``
otherwise), ``g``, the angular velocity ``w`` / ``w_1, w_2, w_3``, each applied load by
name (``F_push_x``, ``M_motor_1``, a spring's tension ``T_k1``) and each reaction by its
label (``O.Fx``). Geometry stays numbers: lever arms, directions and the rotation from
body to world axes are taken at the assembly's state, so substituting the model's values
gives back that assembly's M, b, Q and G rows (`SymbolicBody.evaluate`).

Rows are written ``M v̇ = −b + Q + G λ``: the stacked contract's ``M v̇ + b = Q + G λ``
with the gyroscopic term moved to the right, first, where the course writes it.

sympy is imported only when equations are made (it takes a few hundred ms to load), so
this module costs `import mbody` and the numeric commands nothing.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody import conventions as cv
from mbody.equations import kernels

if TYPE_CHECKING:
    from mbody.equations.assemble import Assembly
    from mbody.model.model import Model, State

INERTIA, GYROSCOPIC, APPLIED, GRAVITY, REACTION = (
    "inertia", "gyroscopic", "applied", "gravity", "reaction")
"""What a `Term` is: a row of M (left side), −b, Q (applied loads, springs, gravity), G."""

NOISE = 1e-14
"""A coefficient below this fraction of its symbol's largest coefficient on the body is
rounding noise (cos 90° = 6e-17) and is left out."""

WORLD_AXES, BODY_AXES = ("x", "y", "z"), ("1", "2", "3")
"""Component suffixes: letters for world axes, numbers for body axes (as a_x and w_1)."""

_UNITS = {"m": "kg", "I": "kg m^2", "g": "m/s^2", "w": "rad/s", "F": "N", "M": "N m",
          "T": "N"}
_LATEX_TEXT = {"\\": r"\textbackslash{}", "{": r"\{", "}": r"\}", "$": r"\$", "&": r"\&",
               "#": r"\#", "^": r"\textasciicircum{}", "_": r"\_", "%": r"\%",
               "~": r"\textasciitilde{}", "<": r"\textless{}", ">": r"\textgreater{}",
               "|": r"\textbar{}", '"': "{''}"}


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
        left, right = _join(self.left, digits, False), _join(self.right, digits, False)
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
        return (f"{_join(self.left, digits, True) or '0'} &= "
                f"{_join(self.right, digits, True) or '0'}")

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
        out = [f"== {self.body} ==  {_inertia_words(self.inertia_form)}",
               "Newton (world axes):"]
        out += [f"  {r.label:<{width}}{r.text(digits)}" for r in self.newton]
        if self.euler:
            if self.dimension == cv.PLANAR:
                out.append("Euler (about the mass centre, z):")
            else:
                out.append("Euler (about the mass centre, body axes): "
                           "J*alpha = -b + M_G, with b = w x (J*w):")
                b = [_gyro_text(r, digits) for r in self.euler]
                if self.inertia_form == "principal":
                    out.append(f"  b = ({', '.join(b)})")
                else:
                    out += [f"  b_{k + 1} = {bk}" for k, bk in enumerate(b)]
            out += [f"  {r.label:<{width}}{r.text(digits)}" for r in self.euler]
        out += _where(self, digits)
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
        raise KeyError(f"no body named {name!r}")

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
                + rf"$t = {_latex_number(self.t, 6)}$~s.")]
        for b in self.bodies:
            out += [rf"\section*{{Body {latex_text(b.body)}}}",
                    latex_text(_inertia_words(b.inertia_form)) + ".",
                    "\\[\n" + b.latex(digits) + "\n\\]"]
            where = _where(b, digits)
            if where:
                out.append(r"\noindent " + r"\\ ".join(latex_text(w.strip())
                                                       for w in where))
        out += [r"\end{document}", ""]
        return "\n".join(out)

    def _repr_latex_(self) -> str:  # Jupyter renders the equations
        return "$$" + self.latex() + "$$"

    def __str__(self) -> str:
        return self.text()


# -- building the rows -------------------------------------------------------------------
def assembly_symbolic(asm: Assembly, bodies: list[str] | None = None) -> SymbolicEquations:
    """The symbolic Newton-Euler pair of every body (or of `bodies`) of an assembly.

    Parameters
    ----------
    asm : Assembly
        The numeric equations; their state gives the geometry (lever arms, directions).
    bodies : list of str, optional
        Body names (default: every body, in stacking order).

    Returns
    -------
    SymbolicEquations
    """
    model = asm.model
    names = list(model.body_names) if bodies is None else bodies
    return SymbolicEquations(model.name, model.dimension, float(asm.state.t),
                             tuple(body_symbolic(asm, name) for name in names))


def body_symbolic(asm: Assembly, name: str) -> SymbolicBody:
    """One body's Newton-Euler pair with symbols (see the module's docstring).

    Parameters
    ----------
    asm : Assembly
        The numeric equations; their state gives the geometry.
    name : str
        The body's name.

    Returns
    -------
    SymbolicBody

    Raises
    ------
    KeyError
        No body of that name (with a did-you-mean).
    """
    import sympy

    eqs = asm.bodies[name]  # KeyError with a did-you-mean for a wrong name
    model, state = asm.model, asm.state
    i = model.index[name]
    planar = model.dimension == cv.PLANAR
    particle = bool(model.particle[i])
    values: dict[str, float] = {"m": float(model.mass[i])}
    definitions: dict[str, str] = {}
    S = sympy.Symbol

    # Each symbol's contribution to the body's six rows [F (world); M about G (body)].
    six: dict[str, tuple[np.ndarray, str, tuple[Any, ...]]] = {}
    for load in load_symbols(model, state, name):
        six[load.name] = (load.wrench, APPLIED, (S(load.name),))
        values[load.name] = load.value
        if load.definition is not None:
            definitions[load.name] = load.definition

    g = float(np.linalg.norm(model.gravity))
    if g > 0:
        values["g"] = g
        six["m*g"] = (np.concatenate((model.gravity / g, np.zeros(3))), GRAVITY,
                      (S("m"), S("g")))

    # -- inertia and the gyroscopic term (body axes) -----------------------------------
    J = model.J[i]
    rows6 = cv.PLANAR_SELECT if planar else np.arange(6)
    suffixes = cv.PLANAR_ROWS if planar else cv.SPATIAL_ROWS
    shown = (2 if planar else 3) if particle else len(rows6)
    acc = [cv.ACCELERATION_NAMES[s] for s in suffixes]
    left: list[list[Term]] = [[Term(1.0, (S("m"), S(acc[r])), INERTIA, acc[r])]
                              for r in range(2 if planar else 3)]
    gyro: list[list[Term]] = [[] for _ in range(6)]
    if particle:
        form = "particle"
    elif planar:
        form = "planar"
        values["I_G"] = float(J[2, 2])
        left.append([Term(1.0, (S("I_G"), S("alpha")), INERTIA, "alpha")])
    else:
        w = [S(f"w_{k + 1}") for k in range(3)]
        values.update({f"w_{k + 1}": float(state.omega[i, k]) for k in range(3)})
        principal = not np.any(J - np.diag(np.diag(J)))
        form = "principal" if principal else "tensor"
        I = _inertia_symbols(J, principal, values)
        for j in range(3):
            left.append([Term(1.0, (I[j][k], S(acc[3 + k])), INERTIA, acc[3 + k])
                         for k in range(3) if I[j][k] is not None])
        gyro[3:] = _minus_gyroscopic(I, w, principal)

    # -- the rows: left side, then −b, loads and springs, gravity, reactions ------------
    # A reaction's noise is judged against its largest coefficient among the body's rows
    # of the same kind (forces or moments), as a load's: a lever arm of 1e-17 m on a
    # row where it has no real moment (the heavy top's pivot.Fx about axis 3) is
    # rounding, not a term; the row's other reactions may all be such noise.
    reaction_scale: dict[tuple[str, bool], float] = {}
    for r in range(shown):
        for label, c in eqs.equations[r].reactions.items():
            key = (label, rows6[r] >= 3)
            reaction_scale[key] = max(reaction_scale.get(key, 0.0), abs(c))
    rows: list[SymbolicRow] = []
    for r in range(shown):
        terms = list(left[r]) + gyro[rows6[r]]
        for symbol, (W, part, factors) in six.items():
            coef = float(W[rows6[r]])
            if abs(coef) > NOISE * _scale(W, rows6[r]):
                terms.append(Term(coef, factors, part, symbol))
        eq = eqs.equations[r]
        terms += [Term(c, (S(label),), REACTION, label) for label, c in eq.reactions.items()
                  if abs(c) > NOISE * reaction_scale[label, rows6[r] >= 3]]
        rows.append(SymbolicRow(eq.row, tuple(terms)))

    known = model.known_reactions_at(state.t)
    on = {t.key for row in rows for t in row.terms if t.part == REACTION}
    labels = tuple(label for label in asm.reactions if label in on)
    for label in labels:
        if label in known:
            values[label] = known[label]
            if label in model.known_expressions:
                definitions[label] = str(model.known_expressions[label])
    return SymbolicBody(name, model.dimension, form, tuple(rows), values, definitions,
                        float(state.t), labels)


@dataclass(frozen=True)
class LoadSymbol:
    """One symbol of an applied load on one body (no sympy needed).

    Parameters
    ----------
    name : str
        ``F_<load>_x`` (a force component, world axes), ``F_<load>_1`` (body axes),
        ``M_<load>_...`` (a couple; planar: ``M_<load>``), ``T_<spring>`` (a tension).
    wrench : (6,) array
        What one unit of it puts into the body's rows: force (world axes), then moment
        about the mass centre (body axes), at the state it was made at.
    value : float
        Its value at that state (N; N m).
    definition : str or None
        How the value is made, where it varies: the load's expression of t, or the
        spring's law with its numbers.
    """

    name: str
    wrench: np.ndarray
    value: float
    definition: str | None = None


def load_symbols(model: Model, state: State, body: str) -> list[LoadSymbol]:
    """The applied-load symbols acting on `body`, with their values at `state`.

    A force's or couple's component the file leaves at 0 (and not an expression of t) is
    no symbol. A spring with both ends on the body gives one symbol.

    Parameters
    ----------
    model : Model
        The model.
    state : State
        Positions, orientations, velocities and time the values are taken at.
    body : str
        A body of the model.

    Returns
    -------
    list of LoadSymbol
        In the file's order of loads; springs last.
    """
    i = model.index[body]
    planar = model.dimension == cv.PLANAR
    R = state.W_R_B[i]
    out: dict[str, LoadSymbol] = {}

    def add(symbol: str, wrench: np.ndarray, value: float, definition: str | None) -> None:
        if symbol in out:  # the other end of a spring on the same body
            wrench = wrench + out[symbol].wrench
        out[symbol] = LoadSymbol(symbol, wrench, value, definition)

    ft = model.forces
    vec = ft.vector_at(state.t)
    loads = {load.name: load for load in model.loads}
    for k in np.flatnonzero(ft.body == i):
        load = loads[ft.names[k]]
        couple, in_body = bool(ft.couple[k]), bool(ft.in_body[k])
        for c in [2] if planar and couple else [0, 1] if planar else [0, 1, 2]:
            if load.vector is not None and load.vector[c] == 0 and c not in load.expressions:
                continue
            e = np.zeros(3)
            e[c] = 1.0
            suffix = "" if planar and couple else (BODY_AXES if in_body else WORLD_AXES)[c]
            W = np.zeros(6)
            if couple:
                W[3:] = e if in_body else R.T @ e
            else:
                W[:3] = R @ e if in_body else e
                W[3:] = np.cross(ft.B_r[k], e if in_body else R.T @ e)
            add(f"{'M' if couple else 'F'}_{load.name}" + (f"_{suffix}" if suffix else ""),
                W, float(vec[k, c]),
                str(load.expressions[c]) if c in load.expressions else None)

    sp = model.springs
    if np.any(sp.a == i) or np.any(sp.b == i):
        Pa, Pb, Va, Vb = kernels.spring_ends(model, state.position, state.quaternion,
                                             state.velocity, state.omega)
        L, u, T = kernels.spring_tension(model, Pa, Pb, Va, Vb)
        Ldot = np.einsum("si,si->s", u, Vb - Va)
        for s in range(len(sp.names)):
            for end, r, sign in ((sp.a[s], sp.r_a[s], 1.0), (sp.b[s], sp.r_b[s], -1.0)):
                if end != i:
                    continue
                f = sign * u[s]  # +T u pulls end a towards b, -T u end b towards a
                add(f"T_{sp.names[s]}", np.concatenate((f, np.cross(r, R.T @ f))),
                    float(T[s]),
                    f"k (L - L0) + c dL/dt = {_num(sp.stiffness[s], 6)}*"
                    f"({_num(L[s], 6)} - {_num(sp.rest_length[s], 6)}) + "
                    f"{_num(sp.damping[s], 6)}*({_num(Ldot[s], 6)})")
    return list(out.values())


def _inertia_symbols(J: np.ndarray, principal: bool,
                     values: dict[str, float]) -> list[list[Any]]:
    """3x3 grid of the inertia symbols (None where the entry is 0); fills `values`."""
    import sympy

    grid: list[list[Any]] = [[None] * 3 for _ in range(3)]
    for j in range(3):
        for k in range(3):
            if principal and j != k or J[j, k] == 0:
                continue
            # symmetric: I_21 is I_12
            name = f"I_{j + 1}" if principal else f"I_{min(j, k) + 1}{max(j, k) + 1}"
            grid[j][k] = sympy.Symbol(name)
            values[name] = float(J[j, k])
    return grid


def _minus_gyroscopic(I: list[list[Any]], w: list[Any], principal: bool) -> list[list[Term]]:
    """−(ω × Jω) on the three Euler rows, as the course writes it: row j (j, k, l
    cyclic) gets (I_k − I_l) ω_k ω_l for principal axes, else h_k ω_l − h_l ω_k with
    h = Jω written out (the cross product's two terms, h_k in brackets)."""
    import sympy

    out: list[list[Term]] = []
    for j in range(3):
        k, m = (j + 1) % 3, (j + 2) % 3
        if principal:
            diff = sympy.Add(I[k][k], -I[m][m], evaluate=False)
            out.append([Term(1.0, (diff, w[k], w[m]), GYROSCOPIC, "w x (J*w)")])
            continue
        h = [sympy.Add(*(I[a][b] * w[b] for b in range(3) if I[a][b] is not None),
                       evaluate=False) for a in range(3)]
        out.append([Term(1.0, (w[m], h[k]), GYROSCOPIC, "w x (J*w)"),
                    Term(-1.0, (w[k], h[m]), GYROSCOPIC, "w x (J*w)")])
    return out


def _scale(W: np.ndarray, row: int) -> float:
    """A symbol's largest coefficient among the rows of the same kind (force or moment)."""
    part = W[:3] if row < 3 else W[3:]
    return float(np.max(np.abs(part)))


def _acceleration(name: str) -> Any:
    import sympy

    return sympy.Symbol(name)


def _sum(exprs: Any) -> Any:
    import sympy

    return sympy.Add(*exprs)


def _sympy_number(x: float) -> Any:
    """An integral float as a sympy Integer (prints ``2``, not ``2.0``), else an exact Float."""
    import sympy

    if x.is_integer() and abs(x) < 2**53:
        return sympy.Integer(int(x))
    return sympy.Float(x)


def _substitution(values: dict[str, float]) -> dict[Any, Any]:
    import sympy

    return {sympy.Symbol(k): sympy.Float(v) for k, v in values.items()}


# -- printing ----------------------------------------------------------------------------
def _num(x: float, digits: int) -> str:
    x = float(x)
    if x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x) if digits >= 17 else f"{x:.{digits}g}"


def _latex_number(x: float, digits: int) -> str:
    s = _num(x, digits)
    if "e" in s:
        mant, _, exp = s.partition("e")
        return rf"{mant}\times10^{{{int(exp)}}}"
    return s


def latex_text(text: str) -> str:
    """`text` safe inside LaTeX text mode (``\\text{}``): specials escaped.

    Parameters
    ----------
    text : str
        A model, body or load name.

    Returns
    -------
    str
    """
    return "".join(_LATEX_TEXT.get(ch, ch) if ord(ch) < 128 or ch.isalpha() else
                   f"[U+{ord(ch):04X}]" for ch in str(text))


def latex_symbol(name: str) -> str:
    """The LaTeX of a symbol name: ``alpha_1`` -> ``\\dot{\\omega}_{1}``, ``O.Fx`` ->
    ``F^{\\text{O}}_{x}``, ``F_push_x`` -> ``F^{\\text{push}}_{x}``, ``I_12`` -> ``I_{12}``.

    Parameters
    ----------
    name : str
        A symbol of the vocabulary (see the module's docstring).

    Returns
    -------
    str
    """
    fixed = {"alpha": r"\alpha", "w": r"\omega", "I_G": "I_G", "m": "m", "g": "g"}
    if name in fixed:
        return fixed[name]
    if "." in name:  # a reaction label
        joint, _, comp = name.rpartition(".")
        return f"{comp[0]}^{{\\text{{{latex_text(joint)}}}}}_{{{latex_text(comp[1:])}}}"
    head, _, rest = name.partition("_")
    if head in ("alpha", "w", "a", "I") and rest:
        base = {"alpha": r"\dot{\omega}", "w": r"\omega", "a": "a", "I": "I"}[head]
        return f"{base}_{{{rest}}}"
    load, _, comp = rest.rpartition("_")
    if head in ("F", "M") and comp in WORLD_AXES + BODY_AXES and load:
        return f"{head}^{{\\text{{{latex_text(load)}}}}}_{{{comp}}}"
    return f"{head}^{{\\text{{{latex_text(rest)}}}}}"  # M_<couple> (planar), T_<spring>


def _factor_text(term: Term, latex: bool) -> str:
    import sympy

    if latex:
        names = {s: latex_symbol(s.name) for s in term.shown.free_symbols}
        return sympy.latex(term.shown, order="none", symbol_names=names)
    return sympy.sstr(term.shown, order="none")


def _join(terms: tuple[Term, ...], digits: int, latex: bool) -> str:
    out = ""
    for term in terms:
        factor = _factor_text(term, latex)
        if len(term.factors) == 1 and isinstance(term.factors[0], _add_type()):
            factor = rf"\left({factor}\right)" if latex else f"({factor})"
        mag = abs(term.coefficient)
        number = _latex_number(mag, digits) if latex else _num(mag, digits)
        body = factor if number == "1" else (f"{number}\\,{factor}" if latex else
                                             f"{number}*{factor}")
        negative = term.coefficient < 0
        if not out:
            out = f"-{body}" if negative else body
        else:
            out += f" {'-' if negative else '+'} {body}"
    return out


def _add_type() -> type:
    import sympy

    return sympy.Add


def _gyro_text(row: SymbolicRow, digits: int) -> str:
    """This row of b = ω × Jω, written the way round a textbook writes it: the row's
    gyroscopic terms with their signs turned: (I_3 - I_2)*w_2*w_3, w_2*h_3 - w_3*h_2."""
    import sympy

    terms = []
    for t in row.right:
        if t.part != GYROSCOPIC:
            continue
        first, *rest = t.factors
        if len(rest) == 2:  # principal: -(I_k - I_l) w_k w_l = (I_l - I_k) w_k w_l
            a, b = first.args
            terms.append(Term(t.coefficient, (sympy.Add(-b, -a, evaluate=False), *rest),
                              t.part, t.key))
        else:  # w_l h_k - w_k h_l  ->  w_k h_l - w_l h_k
            terms.append(Term(-t.coefficient, t.factors, t.part, t.key))
    terms.sort(key=lambda t: t.coefficient < 0)
    return _join(tuple(terms), digits, False) or "0"


def _inertia_words(form: str) -> str:
    return {"planar": "mass m, moment of inertia I_G about the mass centre",
            "principal": "mass m, principal moments I_1, I_2, I_3 (body axes)",
            "tensor": "mass m, inertia tensor entries I_jk (body axes, I_jk = I_kj; "
                      "zero entries left out)",
            "particle": "mass m (a particle: Newton's rows only)"}[form]


def _unit(name: str) -> str:
    if "." in name:  # a reaction label: a force component or a moment
        return "N m" if name.rpartition(".")[2].startswith("M") else "N"
    return _UNITS.get(name.partition("_")[0], "")


def _family(name: str) -> str:
    """Which line of the values a symbol goes on: the body, its spin, a load, a reaction."""
    if "." in name:
        return "reactions"
    head, _, rest = name.partition("_")
    if head in ("m", "g", "I"):
        return "body"
    if head == "w":
        return "spin"
    return rest.rpartition("_")[0] if head in ("F", "M") and rest.count("_") else rest


def _where(body: SymbolicBody, digits: int) -> list[str]:
    """The values of the body's symbols at this state (how they are made, where they vary
    or come from a spring), then the unknown reactions: a few lines under the rows."""
    lines: dict[str, list[tuple[str, str]]] = {}
    for name, v in body.values.items():
        unit, how = _unit(name), body.definitions.get(name)
        if how is not None:
            at = "" if name.startswith("T_") else f" at t = {body.t:g} s"
            item = f"{name} = {how} = {_num(v, digits)}"
            lines.setdefault(name, []).append((item, f"{unit}{at}"))
        else:
            known = " (known)" if "." in name else ""
            lines.setdefault(_family(name), []).append(
                (f"{name} = {_num(v, digits)}", f"{unit}{known}"))
    order = {"body": 0, "spin": 1, "reactions": 3}
    out = []
    for _, items in sorted(lines.items(), key=lambda kv: order.get(kv[0], 2)):
        text = ""  # a run of values with one unit writes the unit once, at its end
        for k, (item, unit) in enumerate(items):
            last = k + 1 == len(items) or items[k + 1][1] != unit
            text += item + (f" {unit}".rstrip() + ("; " if not last or k + 1 < len(items)
                                                   else "") if last else ", ")
        out.append("  " + text.rstrip("; "))
    if body.unknowns:
        out.append("  unknown: " + ", ".join(body.unknowns))
    return (["values:"] + out) if out else []
