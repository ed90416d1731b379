"""A static equilibrium in generalized coordinates: a configuration where, at rest, every
generalized force vanishes (``f(q, 0) = 0``).

    state = static_equilibrium(model)           # nearest the model's initial pose

Newton's method on f(q, 0) = 0: the stiffness K = −∂f/∂q comes from the linearisation's
differences (`mbody.solve.linearize`), the step δq = K⁻¹ f moves the bodies along
v = T δq and back onto their joints (`mbody.solve.configure.move`, ``project``). Newton's
method finds the equilibrium nearest the start, stable or not (`linearize` says which).
The drivers are held as at time t.

This is the small finder the linearisation's tests and ``mbody modes --equilibrium``
need; ``mbody.equilibrium`` (issue 25, built alongside) is the model-level one.
"""

from __future__ import annotations

import numpy as np

from mbody.equations.coordinates import CoordinateSet
from mbody.equations.generalized import evaluate, state_with_velocities
from mbody.errors import MbodyError
from mbody.model.model import Model, State
from mbody.solve.configure import move, project
from mbody.solve.linearize import STEADY_RTOL, free_coordinates, linearize

NEWTON_STEPS = 50
"""Newton steps at most (a few from a nearby start)."""


class NoEquilibriumError(MbodyError):
    """Newton's method did not find a static equilibrium from the start."""


def static_equilibrium(model: Model, *, start: State | None = None, t: float | None = None
                       ) -> State:
    """The static equilibrium nearest `start` (default: the model's initial state).

    Parameters
    ----------
    model : Model
        The model (its drivers held as at time t).
    start : State, optional
        Where Newton's method starts (its velocities are dropped).
    t : float, optional
        Time (s) of the drivers' laws and the loads (default: the start's).

    Returns
    -------
    State
        At rest, with every generalized force below 1e-8 of the terms that make it.

    Raises
    ------
    NoEquilibriumError
        Newton's method did not converge from the start (no equilibrium near it, or a
        load that never balances: a constant torque on a free wheel).
    """
    start = model.initial if start is None else start
    if t is not None:
        start = start.replace(t=float(t))
    cs = free_coordinates(model)
    zero = np.zeros(len(cs))
    state = _at_rest(model, cs, start)
    best = np.inf
    for _ in range(NEWTON_STEPS):
        g = evaluate(model, state, cs, zero)
        if np.all(np.abs(g.f) <= STEADY_RTOL * g.f_scale):
            return _at_rest(model, cs, state)
        lin = linearize(model, state, coordinates=cs.labels)
        try:
            dq = np.linalg.lstsq(lin.K, g.f, rcond=1e-12)[0]
        except np.linalg.LinAlgError:
            break
        size = float(np.max(np.abs(dq) / cs.scales)) if len(dq) else 0.0
        if size > 0.5:  # at most half a radian (or half the model's size) a step
            dq *= 0.5 / size
        state = project(model, cs, move(model, state, g.T @ dq))
        best = min(best, float(np.max(np.abs(g.f) / np.maximum(g.f_scale, 1e-300))))
    raise NoEquilibriumError(f"no static equilibrium of '{model.name}' found near the start "
                             f"in {NEWTON_STEPS} Newton steps (the generalized forces fell "
                             f"to {best:.2g} of their terms at best): the loads may never "
                             "balance (a constant torque on a free wheel), or start nearer one")


def _at_rest(model: Model, cs: CoordinateSet, state: State) -> State:
    """`state` with the velocities of q' = 0 (the held drivers' own rates kept)."""
    g = evaluate(model, state, cs, np.zeros(len(cs)))
    return state_with_velocities(model, state, g.v_e)
