"""Jointed mechanisms in motion: accelerations with the unknown reactions solved at every
step, joint drift held down by Baumgarte stabilisation (used by the implicit integrators;
the explicit ones project the state instead, `mbody.simulate.projection`), reactions along a
trajectory.

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

from mbody.equations.assemble import assemble
from mbody.equations.constraints import phi
from mbody.equations.joints import constraint_velocity, reaction_columns
from mbody.model.model import Model, State

BAUMGARTE_RATE = 20.0
"""α = β in 1/s: joint errors decay with a time constant of 1/20 s."""


class ConstrainedDynamics:
    """f(model, state) -> (n, 6) accelerations with the unknown reactions solved each call
    (a `mbody.solve.dynamics.Dynamics`), stabilised with α = β = `rate` (1/s; 0 turns
    stabilisation off); `known`: given reaction values (label -> value)."""

    def __init__(self, known: Mapping[str, float] | None, rate: float):
        self.known, self.rate = known, rate
        self.stabilisation = f"Baumgarte, alpha = beta = {rate:g} 1/s" if rate else "none"
        """How the joints are held, in words (for a trajectory's info)."""

    def __call__(self, model: Model, state: State) -> np.ndarray:
        unknowns = model.plan.unknowns_at(state.t, self.known)
        return assemble(model, state).constrained(unknowns, rate=self.rate, refine=False)[0]


def constrained_dynamics(model: Model, known: Mapping[str, float] | None = None, *,
                         rate: float = BAUMGARTE_RATE) -> ConstrainedDynamics:
    """f(model, state) -> (n, 6) accelerations with the unknown reactions solved each call,
    stabilised with α = β = `rate` (1/s; 0 turns stabilisation off). The numpy path;
    `mbody.solve.dynamics.StateDerivative` takes the compiled one where it can."""
    return ConstrainedDynamics(known, rate)


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
    if not len(model.reactions):
        return {"joint_position_drift": 0.0, "joint_velocity_drift": 0.0}
    for s in states:
        cols = reaction_columns(model, s)
        pos = max(pos, float(np.max(np.abs(phi(model, s, cols=cols)))))
        vel = max(vel, float(np.max(np.abs(constraint_velocity(model, cols, s)))))
    return {"joint_position_drift": pos, "joint_velocity_drift": vel}
