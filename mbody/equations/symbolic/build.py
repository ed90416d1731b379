"""Each body's symbolic rows built from an assembly: `assembly_symbolic`, `body_symbolic`.

The symbols are the body's mass and inertia, gravity, the angular velocity, the applied
loads by name (`mbody.equations.symbolic.applied`) and the reactions by label; lever
arms, directions and the rotation come from the assembly's state as numbers, and the
reactions' coefficients from its rows of G. sympy is imported when a body is built.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from mbody import conventions as cv
from mbody import joint_types
from mbody.equations.symbolic.applied import load_symbols
from mbody.equations.symbolic.rows import SymbolicBody, SymbolicEquations, SymbolicRow
from mbody.equations.symbolic.terms import (
    APPLIED,
    GRAVITY,
    GYROSCOPIC,
    INERTIA,
    REACTION,
    Term,
)

if TYPE_CHECKING:
    from mbody.equations.assemble import Assembly

NOISE = 1e-14
"""A coefficient below this fraction of its symbol's largest coefficient on the body's
rows of the same kind (force or moment), or of the largest coefficient of the same unit
in its row (in an Euler row the lever arms, m; else the direction cosines), is rounding
noise (cos 90° = 6e-17; a lever arm of 1.9e-18 m beside one of 0.25 m) and is left out."""
ARM = 1e-12
"""A reaction's coefficient (a direction cosine, or a lever arm in m) below this is left
out as well: the numeric `mbody assemble` prints it as 0 and `mbody verify`'s rows have
no such term (a UR5 link's 5.9e-13 m, a 4.9e-12 rad misalignment in the file times a
0.12 m arm), so a printed row copied into an answers file stays correct."""


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
    """One body's Newton-Euler pair with symbols (see `mbody.equations.symbolic`).

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
    # A coefficient that is itself its symbol's largest of its kind (a lever arm of
    # 1.9e-18 m, the only moment A.Fy has on the row) is judged against the row too: the
    # largest coefficient of the same unit in it.
    moment = {symbol: not np.any(W[:3]) for symbol, (W, _, _) in six.items()}
    rows: list[SymbolicRow] = []
    for r in range(shown):
        eq = eqs.equations[r]
        unit = row_units(((float(W[rows6[r]]), moment[symbol])
                          for symbol, (W, _, _) in six.items()),
                         ((c, is_moment(label)) for label, c in eq.reactions.items()))
        terms = list(left[r]) + gyro[rows6[r]]
        for symbol, (W, part, factors) in six.items():
            coef = float(W[rows6[r]])
            if abs(coef) > NOISE * max(_scale(W, rows6[r]), unit[moment[symbol]]):
                terms.append(Term(coef, factors, part, symbol))
        terms += [Term(c, (S(label),), REACTION, label) for label, c in eq.reactions.items()
                  if abs(c) >= ARM and abs(c) > NOISE * max(
                      reaction_scale[label, rows6[r] >= 3], unit[is_moment(label)])]
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


def is_moment(label: str) -> bool:
    """Whether a reaction label is a moment component (``A.Mz``, a universal joint's
    ``U.Mt``), not a force (``A.Fx``, a link's tension ``L.T``, a helical joint's axial
    wrench ``H.Wz``, whose value is its force): `mbody.joint_types.is_moment`."""
    return joint_types.is_moment(label)


def row_units(*coefficients: Any) -> dict[bool, float]:
    """The largest coefficient of each unit in one row: key True for the moment symbols'
    (couples, moment reactions), False for the force symbols' (loads, gravity, force
    reactions; in an Euler row their lever arms).

    Parameters
    ----------
    *coefficients : iterables of (float, bool)
        Each symbol's coefficient in the row, and whether the symbol is a moment.

    Returns
    -------
    dict of bool to float
    """
    unit = {False: 0.0, True: 0.0}
    for group in coefficients:
        for c, moment in group:
            unit[moment] = max(unit[moment], abs(c))
    return unit


def _scale(W: np.ndarray, row: int) -> float:
    """A symbol's largest coefficient among the rows of the same kind (force or moment)."""
    part = W[:3] if row < 3 else W[3:]
    return float(np.max(np.abs(part)))
