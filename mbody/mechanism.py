"""Jointed mechanisms in motion: accelerations with the unknown reactions solved at every
step, joint drift held down by Baumgarte stabilisation, reactions along a trajectory.

Integrating ``Gᵀ v̇ = γ`` alone lets the joints drift apart (rounding and truncation
errors in φ and φ̇ = Gᵀ v are never corrected). Baumgarte's method replaces it by

    Gᵀ v̇ = γ − 2 α Gᵀ v − β² φ,

so that the constraint error obeys φ̈ + 2 α φ̇ + β² φ = 0 and decays (critically damped
for α = β) instead of growing. The reactions stored with a trajectory are solved at each
output sample with the exact γ (no stabilisation terms), so they are the physical ones
for the sampled state.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .assemble import assemble
from .constraints import gamma, phi
from .joints import reaction_columns, reaction_wrench
from .kkt import ConstrainedSystem, split_reactions
from .loads import applied_loads, gyroscopic
from .model import Model, State

BAUMGARTE_RATE = 20.0
"""α = β in 1/s: joint errors decay with a time constant of 1/20 s."""


def constrained_dynamics(model: Model, known: Mapping[str, float] | None = None, *,
                         rate: float = BAUMGARTE_RATE):
    """f(model, state) -> (n, 6) accelerations with the unknown reactions solved each call,
    stabilised with α = β = `rate` (1/s; 0 turns stabilisation off)."""

    def f(model: Model, state: State) -> np.ndarray:
        R = state.W_R_B
        cols = reaction_columns(model, state, R)
        unknown, lam = split_reactions(model, {**model.known_reactions_at(state.t),
                                               **(known or {})})
        loads = applied_loads(model, state, R)
        r6 = np.concatenate((loads.W_F, loads.B_M), axis=1)
        if model.dimension == 3:
            r6[:, 3:] -= gyroscopic(model.J, state.omega)
        if (~unknown).any():
            r6 += reaction_wrench(model, cols, lam)
        system = ConstrainedSystem(model, cols, unknown)
        g = gamma(model, state, cols, R)[unknown]
        if rate:
            v6 = np.concatenate((state.velocity, state.omega), axis=1).ravel()
            g = g - 2 * rate * system.gt(v6) - rate**2 * phi(model, state, R, cols)[unknown]
        acc, _ = system.solve(r6, g)
        return acc

    f.stabilisation = (f"Baumgarte, alpha = beta = {rate:g} 1/s" if rate  # type: ignore[attr-defined]
                       else "none")
    return f


def reactions_along(model: Model, states: list[State],
                    known: Mapping[str, float] | None = None) -> np.ndarray:
    """(K, m) every reaction value at each sampled state (exact γ, no stabilisation).

    One constrained solve per sample: a loop over time samples, each vectorised over bodies.
    """
    out = np.empty((len(states), len(model.reactions)))
    for k, s in enumerate(states):
        sol = assemble(model, s).solve(known=known)
        arr = getattr(sol.reactions, "array", None)
        out[k] = arr if arr is not None else [sol.reactions[r] for r in model.reactions]
    return out


def constraint_drift(model: Model, states: list[State]) -> dict[str, float]:
    """Largest joint position error |φ| (m for forces, rad for moments) and velocity error
    |Gᵀ v| over the samples."""
    pos = vel = 0.0
    m = len(model.reactions)
    if m == 0:
        return {"joint_position_drift": 0.0, "joint_velocity_drift": 0.0}
    for s in states:
        pos = max(pos, float(np.max(np.abs(phi(model, s)))))
        cols = reaction_columns(model, s)
        v6 = np.concatenate((s.velocity, s.omega), axis=1)
        rel = np.einsum("ij,ij->i", cols.child6, v6[model.reaction_table.child])
        on = model.reaction_table.parent >= 0
        rel[on] += np.einsum("ij,ij->i", cols.parent6[on],
                             v6[model.reaction_table.parent[on]])
        vel = max(vel, float(np.max(np.abs(rel))))
    return {"joint_position_drift": pos, "joint_velocity_drift": vel}
