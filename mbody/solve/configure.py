"""The state at given values of the generalized coordinates and their rates.

    state = configure(model, {"O.angle": 0.3, "A.angle": -0.2}, {"O.angle": 1.0})

Newton's method on the coordinates: from a start (the model's initial state), each step
moves the bodies along v = T Δq (Δq what the coordinates still lack; T of the generalized
equations, `mbody.equations.generalized`), each body by its exponential map, then back
onto the held joints by the compiled core's projection (the least move in the kinetic
metric). Near the solution the error falls quadratically. The rates then give the
velocities v = T q' + v_e. A quasi-velocity (a ball joint's or a free body's angular
velocity components) has no value: its orientation is the start's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from mbody.equations.coordinates import CoordinateSet, columns, coordinate_set
from mbody.equations.generalized import evaluate, state_with_velocities
from mbody.equations.workspace import workspace
from mbody.errors import MbodyError
from mbody.kernel import _core
from mbody.model.arguments import checked_state
from mbody.model.model import Model, State
from mbody.util.spatial import quat_mul

STEPS = 40
"""Newton steps at most (a few from a nearby start)."""
TOL = 1e-13
"""The coordinates are reached when every one is within this (rad; m over the model's
size)."""


def move(model: Model, state: State, d: np.ndarray) -> State:
    """`state` moved along the stacked velocity `d` (rows as `Model.coordinates`) for a
    unit time: mass centres by d's translation, orientations by the rotation whose vector
    is d's angular part (body axes)."""
    full = np.zeros(6 * model.n)
    full[columns(model)] = d
    six = full.reshape(model.n, 6)
    w = six[:, 3:]
    th = np.linalg.norm(w, axis=1)
    half = 0.5 * th
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(th > 0, np.sin(half) / np.where(th > 0, th, 1.0), 0.5)
    dq = np.concatenate((np.cos(half)[:, None], s[:, None] * w), axis=1)
    q = quat_mul(state.quaternion, dq)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return state.replace(position=state.position + six[:, :3], quaternion=q)


def project(model: Model, cs: CoordinateSet, state: State) -> State:
    """`state`'s positions moved back onto the held joints (the core's projection)."""
    if not len(cs.held.U):
        return state
    ws = workspace(model)
    solver = ws.solver(cs.held)
    y = ws.state_vector(state)
    info = np.empty(_core.PROJECT_INFO)
    solver.project(float(state.t), y, 8, 1e-2, 0, info)
    n = model.n
    q = y[3 * n:7 * n].reshape(n, 4)
    return state.replace(position=y[:3 * n].reshape(n, 3).copy(),
                         quaternion=q / np.linalg.norm(q, axis=1, keepdims=True))


def configure(model: Model, q: Mapping[str, float] | Sequence[float],
              qdot: Mapping[str, float] | Sequence[float] | None = None, *,
              coordinates: Sequence[str] | None = None, start: State | None = None,
              t: float | None = None) -> State:
    """The state where the generalized coordinates take the values `q` and rates `qdot`.

    Parameters
    ----------
    model : Model
        The model.
    q : mapping or sequence of float
        Values (rad, m) by label, or in the order of the coordinates (a quasi-velocity's
        entry is then ignored); a coordinate not named keeps the start's value.
    qdot : mapping or sequence of float, optional
        Rates (rad/s, m/s); default 0 (the drivers' rates, if held, still apply).
    coordinates : sequence of str, optional
        The coordinate set (default: `Assembly.generalized`'s).
    start : State, optional
        Where Newton's method starts, which decides the branch of a closed loop
        (default: the model's initial state).
    t : float, optional
        Time (s) for the drivers' laws (default: the start's).

    Returns
    -------
    State

    Raises
    ------
    MbodyError
        An unknown label, a value for a quasi-velocity, or a loop that does not close.
    """
    start = model.initial if start is None else checked_state(model, start, "start")
    if t is not None:
        start = start.replace(t=float(t))
    cs = coordinate_set(model, coordinates)
    labels = cs.labels
    state = start
    g = evaluate(model, state, cs, np.zeros(len(cs)))
    target = _values(q, labels, g.q, "q")
    if isinstance(q, Mapping):
        for k in np.flatnonzero(cs.quasi):
            if labels[k] in q:
                raise MbodyError(f"{labels[k]} is a quasi-velocity: it has no value to set "
                                 "(set the orientation in the start state)")
    target[cs.quasi] = 0.0
    angle = np.array([c.unit == "rad" for c in cs.items])
    size = float(np.ptp(model.initial.position, axis=0).max()) if model.n > 1 else 1.0
    scale = np.where(angle, 1.0, max(size, 1e-3))
    for _ in range(STEPS):
        dq = np.where(cs.quasi, 0.0, target - np.nan_to_num(g.q))
        dq[angle] = (dq[angle] + np.pi) % (2 * np.pi) - np.pi
        if np.all(np.abs(dq) <= TOL * scale):
            break
        state = project(model, cs, move(model, state, g.T @ dq))
        g = evaluate(model, state, cs, np.zeros(len(cs)))
    else:
        raise MbodyError(f"the coordinates of '{model.name}' cannot all take the values "
                         f"asked (left: {np.abs(dq).max():.3g}); the loops may not close there")
    rates = _values(qdot, labels, np.zeros(len(cs)), "qdot") if qdot is not None \
        else np.zeros(len(cs))
    g = evaluate(model, state, cs, rates)
    return state_with_velocities(model, state, g.velocities(rates))


def _values(given, labels: list[str], default: np.ndarray, what: str) -> np.ndarray:
    out = np.array(default, dtype=float)
    if isinstance(given, Mapping):
        for label, v in given.items():
            if label not in labels:
                raise MbodyError(f"{what}: no coordinate {label!r} (the coordinates: "
                                 f"{', '.join(labels)})")
            out[labels.index(label)] = float(v)
        return out
    arr = np.asarray(given, dtype=float).ravel()
    if arr.shape != out.shape:
        raise MbodyError(f"{what}: expected {len(labels)} values ({', '.join(labels)}), got "
                         f"{arr.size}")
    return arr
