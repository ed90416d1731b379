"""Free-body data and the Newton-Euler pair of one body, as plain data.

A `FreeBodyDiagram` lists every force and couple on one body: applied loads, gravity
and the reaction components of its joints, each with its point of application and its
moment about the mass centre. `BodyEquations` pairs it with the body's rows of
``M v̇ + b = Q + G λ`` written out as `Equation`s. Drawing lives in
`mbody.present.draw`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.conventions import APPLIED, GRAVITY, REACTION
from mbody.equations.fbd_text import body_text
from mbody.equations.joints import g_block
from mbody.equations.symbolic import body_symbolic
from mbody.util.formatting import num as _num
from mbody.util.formatting import quiet

if TYPE_CHECKING:
    from mbody.equations.assemble import Assembly
    from mbody.equations.symbolic import SymbolicBody



@dataclass(frozen=True)
class ForceOnBody:
    """One force or couple on a body.

    Parameters
    ----------
    name : str
        The load's name in the model file, ``gravity``, or the reaction's label.
    kind : str
        ``'applied'``, ``'gravity'`` or ``'reaction'``.
    couple : bool
        True for a pure moment.
    B_r : (3,) array
        Point of application from the mass centre, body axes (m).
    W_point : (3,) array
        The same point, world coordinates (m).
    W_vector : (3,) array
        The force (N) or couple (N m), world axes; for an unknown reaction, its value per
        unit of the unknown (the component's direction).
    B_moment : (3,) array
        Moment about the mass centre, body axes (N m); per unit for unknowns.
    label : str
        The reaction unknown (``A.Fx``); empty for applied loads and gravity.
    value : float or None
        The reaction's value when known (N; N m), else None.
    side : int
        +1 where the reaction acts as +R (on the joint's child), -1 as -R (on its
        parent, Newton's third law); +1 for applied loads and gravity.
    """

    name: str
    kind: str
    couple: bool
    B_r: np.ndarray
    W_point: np.ndarray
    W_vector: np.ndarray
    B_moment: np.ndarray
    label: str = ""
    value: float | None = None
    side: int = 1

    @property
    def unknown(self) -> bool:
        """Whether this is a reaction whose value is not known (solved for, or drawn as λ)."""
        return self.kind == REACTION and self.value is None

    @property
    def signed_label(self) -> str:
        """The reaction as it acts on this body: ``A.Fx`` on the child, ``−A.Fx`` on the
        parent (drawn along the joint axis, as the minus in the parent's equations says);
        the load's name for applied loads and gravity."""
        if self.kind != REACTION:
            return self.name
        return self.label if self.side > 0 else "−" + self.label

    @property
    def magnitude(self) -> float:
        """|vector| (for unknown reactions, of the unit direction: 1)."""
        return float(np.linalg.norm(self.W_vector))

    def __repr__(self) -> str:  # the dataclass's would print four arrays
        what = ("unknown" if self.value is None else f"= {_num(self.value)}"
                ) if self.kind == REACTION else f"|{_num(self.magnitude)}|"
        return (f"<ForceOnBody {self.name!r}: {self.kind}{' couple' if self.couple else ''} "
                f"{what} at {_vec(self.W_point)} m (world); .W_vector, .B_moment>")


@dataclass(frozen=True)
class FreeBodyDiagram:
    """Everything acting on one body. `forces` in order: applied, gravity, reactions.

    Parameters
    ----------
    body : str
        The body's name.
    dimension : int
        2 (planar) or 3 (spatial).
    mass : float
        The body's mass (kg).
    inertia : (3, 3) array
        Inertia tensor about the mass centre, body axes (kg m^2); zero for a particle.
    W_position : (3,) array
        The mass centre, world coordinates (m).
    W_R_B : (3, 3) array
        The body's orientation: body axes -> world axes.
    shape : dict or None
        The body's ``shape`` as in the model file (None when not given).
    forces : tuple of ForceOnBody
        Every force and couple on the body: applied, gravity, reactions.
    equations : tuple of Equation
        The body's Newton-Euler rows, shown under drawings (empty until assembled).
    """

    body: str
    dimension: int
    mass: float
    inertia: np.ndarray
    W_position: np.ndarray
    W_R_B: np.ndarray
    shape: dict | None
    forces: tuple[ForceOnBody, ...]
    equations: tuple[Equation, ...] = ()  # the body's Newton-Euler rows, shown under drawings

    @property
    def size(self) -> float:
        """The body's extent as its free body shows it (m): the farthest point a force
        acts at from the mass centre, or its radius of gyration when that is larger
        (0 for a particle with every force at its mass centre)."""
        arms = max((float(np.linalg.norm(fo.B_r)) for fo in self.forces), default=0.0)
        gyration = (float(np.sqrt(np.trace(self.inertia) / (2.0 * self.mass)))
                    if self.mass > 0 else 0.0)
        return max(arms, gyration)

    @property
    def applied(self) -> list[ForceOnBody]:
        """The applied loads and gravity on the body (every force but the reactions)."""
        return [f for f in self.forces if f.kind != REACTION]

    @property
    def reactions(self) -> list[ForceOnBody]:
        """The reaction components of the body's joints, known or not."""
        return [f for f in self.forces if f.kind == REACTION]

    def _repr_svg_(self) -> str:  # Jupyter shows a diagram as a picture
        from mbody.present.draw import draw_fbd, figure_svg  # a display hook

        return figure_svg(draw_fbd(self))

    def __repr__(self) -> str:  # the dataclass's would print every force's arrays
        unknown = sum(f.unknown for f in self.forces)
        return (f"<FreeBodyDiagram of {self.body!r}: {len(self.applied)} applied, "
                f"{len(self.reactions)} reaction ({unknown} unknown); .forces, mbody.draw_fbd(it)>")


@dataclass(frozen=True)
class Equation:
    """One row of ``M v̇ + b = Q + G λ``: Σ lhs[k]·k + gyro = rhs + Σ coeff·reaction.

    ``str(equation)`` writes it out in numbers, known reactions with their values.

    Parameters
    ----------
    row : str
        The row's coordinate label (``rod.x``, ``rod.w1``...).
    lhs : dict of str to float
        Acceleration name -> coefficient (a row of M: kg, or kg m^2 on Euler rows).
    gyro : float
        This row of b (N m; 0 on Newton rows).
    rhs : float
        This row of Q (N on Newton rows, N m on Euler rows).
    reactions : dict of str to float
        Reaction label -> coefficient (this row of G).
    known : dict of str to float
        Reaction label -> value, for the reactions of this row that are known.
    """

    row: str
    lhs: dict[str, float]
    gyro: float
    rhs: float
    reactions: dict[str, float]
    known: dict[str, float] = field(default_factory=dict)

    def __str__(self) -> str:
        left = _terms([(c, k) for k, c in self.lhs.items()]) or "0"
        if abs(self.gyro) > 0:
            left += f" {'-' if self.gyro < 0 else '+'} {_num(abs(self.gyro))}"
        right = _num(self.rhs) if self.rhs != 0 or not self.reactions else ""
        for label, coef in self.reactions.items():
            name = f"({label}={_num(self.known[label])})" if label in self.known else label
            term = _terms([(coef, name)])
            if not term:  # a coefficient that is rounding noise
                continue
            if right:
                term = f"+ {term}" if not term.startswith("-") else f"- {term[1:]}"
            right = f"{right} {term}".strip()
        return f"{left} = {right or '0'}"

    def __repr__(self) -> str:  # the row written out, cut short for a row of many terms
        text = str(self)
        return f"<Equation {self.row}: {text if len(text) < 240 else text[:236] + ' ...'}>"

    def _repr_latex_(self) -> str:  # notebook display as display math
        from mbody.present.rich import equation_latex  # a display hook (tools/check_imports.py)

        return equation_latex(self)


@dataclass(frozen=True)
class BodyEquations:
    """One body's free-body diagram and its Newton-Euler pair (rows in stacking order).

    Parameters
    ----------
    body : str
        The body's name.
    fbd : FreeBodyDiagram
        Every force and couple on the body.
    newton : tuple of Equation
        Newton's rows, m a_G = ΣF, in world axes.
    euler : tuple of Equation
        Euler's rows about the mass centre, in body axes (planar: one, about z); none for
        a particle.
    assembly : Assembly, optional
        The assembly these rows come from (what `symbolic` writes out again).
    """

    body: str
    fbd: FreeBodyDiagram
    newton: tuple[Equation, ...]
    euler: tuple[Equation, ...]
    assembly: Assembly | None = field(default=None, repr=False, compare=False)

    @property
    def equations(self) -> tuple[Equation, ...]:
        """Newton's rows then Euler's, in stacking order."""
        return self.newton + self.euler

    def symbolic(self) -> SymbolicBody:
        """These rows with symbols (m, I_1, w_2, loads by name, reaction labels) instead of
        numbers; needs sympy (see `mbody.equations.symbolic`).

        Returns
        -------
        SymbolicBody
            Its ``text()`` and ``latex()``; ``evaluate()`` gives back these numbers.
        """
        if self.assembly is None:
            raise ValueError("these equations were made without their assembly; use "
                             "mbody.assemble(model).bodies[name].symbolic()")
        return body_symbolic(self.assembly, self.body)

    def __repr__(self) -> str:  # the dataclass's would print the diagram's arrays (1-6 KB)
        unknown = sum(f.unknown for f in self.fbd.forces)
        return (f"<BodyEquations of {self.body!r}: {len(self.newton)} Newton and "
                f"{len(self.euler)} Euler rows, {unknown} reaction "
                f"unknown{'' if unknown == 1 else 's'}; print() it, .fbd, .equations>")

    def __str__(self) -> str:  # the block `mbody assemble` prints
        return body_text(self, self.fbd.dimension)

    def _repr_html_(self) -> str:  # notebook display: diagram, forces table, the pair
        from mbody.present.rich import body_html  # a display hook (tools/check_imports.py)

        return body_html(self)

    def _repr_latex_(self) -> str:  # the pair as display math
        from mbody.present.rich import body_latex  # a display hook (tools/check_imports.py)

        return body_latex(self)


def _vec(x: np.ndarray) -> str:
    return "(" + ", ".join(_num(v) for v in x) + ")"


def _terms(pairs: list[tuple[float, str]]) -> str:
    out = ""
    for coef, name in pairs:
        if quiet(coef) == 0.0:  # rounding noise from rotations, not a term
            continue
        mag = abs(coef)
        txt = name if _num(mag) == "1" else f"{_num(mag)} {name}"  # 0.9999999 is 1
        if not out:
            out = f"-{txt}" if coef < 0 else txt
        else:
            out += f" {'-' if coef < 0 else '+'} {txt}"
    return out


def body_equations(asm: Assembly, i: int) -> BodyEquations:
    model, state = asm.model, asm.state
    name = model.body_names[i]
    R = state.W_R_B[i]
    x = state.position[i]
    forces: list[ForceOnBody] = []

    con = asm.loads.contributions
    for k in np.flatnonzero(con.body == i):
        forces.append(ForceOnBody(con.names[k], APPLIED, bool(con.couple[k]), con.B_r[k],
                                  x + R @ con.B_r[k],
                                  (R @ con.B_m[k]) if con.couple[k] else con.W_f[k],
                                  con.B_m[k]))
    if np.any(model.gravity):
        forces.append(ForceOnBody("gravity", GRAVITY, False, np.zeros(3), x.copy(),
                                  model.mass[i] * model.gravity, np.zeros(3)))

    rt = model.reaction_table
    cols = asm.columns
    particle = bool(model.particle[i])
    known = model.known_reactions_at(asm.state.t)
    side: dict[str, float] = {}
    for c in np.flatnonzero((rt.child == i) | (rt.parent == i)):
        sign = 1.0 if rt.child[c] == i else -1.0
        six = cols.child6[c] if sign > 0 else cols.parent6[c]
        label = rt.labels[c]
        value = known.get(label)
        moment = bool(cols.is_moment[c])
        W_P = x.copy() if particle else cols.W_P[c].copy()  # forces act at a particle
        B_r = R.T @ (W_P - x)
        per_unit = sign * cols.W_e[c]
        scale = 1.0 if value is None else value
        forces.append(ForceOnBody(label, REACTION, moment, B_r, W_P,
                                  scale * per_unit, scale * six[3:], label, value,
                                  int(sign)))
        side[label] = sign

    J = np.zeros((3, 3)) if particle else model.J[i]  # a particle: no rotational inertia
    fbd = FreeBodyDiagram(name, model.dimension, float(model.mass[i]), J, x.copy(),
                          R.copy(), model.bodies[name].shape, tuple(forces))

    rpb = model.rows_per_body
    rows = cv.PLANAR_SELECT if model.dimension == cv.PLANAR else np.arange(6)
    suffixes = cv.PLANAR_ROWS if model.dimension == cv.PLANAR else cv.SPATIAL_ROWS
    nn = 2 if model.dimension == cv.PLANAR else 3
    shown = nn if particle else rpb  # a particle: Newton's rows only
    acc = [cv.ACCELERATION_NAMES[s] for s in suffixes]
    block = np.zeros((6, 6))
    block[:3, :3] = np.eye(3) * model.mass[i]
    block[3:, 3:] = model.J[i]
    block = block[np.ix_(rows, rows)]
    # this body's rows of G, dense and without scipy.sparse (`mbody assemble` prints them)
    Gi = g_block(model, cols, np.array([i]), np.arange(len(asm.reactions)))
    eqs = []
    b6, Q6 = asm._b6[i], asm._Q6[i]
    for r in range(shown):
        lhs = {acc[k]: float(block[r, k]) for k in range(shown) if block[r, k] != 0}
        reac = {asm.reactions[c]: float(Gi[r, c]) for c in np.flatnonzero(Gi[r])}
        eqs.append(Equation(f"{name}.{suffixes[r]}", lhs, float(b6[rows[r]]),
                            float(Q6[rows[r]]), reac,
                            {k: v for k, v in known.items() if k in reac}))
    fbd = replace(fbd, equations=tuple(eqs))
    return BodyEquations(name, fbd, tuple(eqs[:nn]), tuple(eqs[nn:]), asm)
