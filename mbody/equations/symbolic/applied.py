"""The applied-load symbols on one body: `LoadSymbol` and `load_symbols` (no sympy).

Each force or couple component the file sets (``F_push_x``, ``M_motor_1``) and each
spring's tension (``T_k1``) is one symbol, with what one unit of it puts into the body's
six rows and its value at a state. `mbody.answers` names a student's loads with them;
`mbody.equations.symbolic.build` writes them into the rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.equations.loads import spring_states
from mbody.equations.symbolic.printing import num
from mbody.equations.symbolic.terms import BODY_AXES, WORLD_AXES

if TYPE_CHECKING:
    from mbody.model.model import Model, State


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
        L, Ldot, T, u = spring_states(model, state)
        for s in range(len(sp.names)):
            for end, r, sign in ((sp.a[s], sp.r_a[s], 1.0), (sp.b[s], sp.r_b[s], -1.0)):
                if end != i:
                    continue
                f = sign * u[s]  # +T u pulls end a towards b, -T u end b towards a
                add(f"T_{sp.names[s]}", np.concatenate((f, np.cross(r, R.T @ f))),
                    float(T[s]),
                    f"k (L - L0) + c dL/dt = {num(sp.stiffness[s], 6)}*"
                    f"({num(L[s], 6)} - {num(sp.rest_length[s], 6)}) + "
                    f"{num(sp.damping[s], 6)}*({num(Ldot[s], 6)})")
    return list(out.values())
