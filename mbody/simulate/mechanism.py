"""Jointed mechanisms in motion: accelerations with the unknown reactions solved at every
step, joint drift held down by Baumgarte stabilisation (used by scipy's integrators; the
core's DOP853 projects the state instead, `mbody.simulate.projection`), and what a run
reports at its output samples: the reactions and the joints' drift, the energy and the
linear and angular momentum.

Integrating ``Gᵀ v̇ = γ`` alone lets the joints drift apart (rounding and truncation
errors in φ and φ̇ = Gᵀ v are never corrected). Baumgarte's method replaces it by

    Gᵀ v̇ = γ − 2 α Gᵀ v − β² φ,

so that the constraint error obeys φ̈ + 2 α φ̇ + β² φ = 0 and decays (critically damped
for α = β) instead of growing. The reactions stored with a trajectory are solved at each
output sample with the exact γ (no stabilisation terms), so they are the physical ones
for the sampled state.

Every figure here comes from one call of the compiled core over all the samples
(`mbody.kernel`): no Python work per sample, body or component.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mbody.equations.workspace import Unknowns, workspace
from mbody.kernel import _core
from mbody.model.model import Model, State
from mbody.solve.dynamics import StateDerivative

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
        ws = workspace(model)
        f = StateDerivative(model, unknowns=ws.unknowns_at(state.t, self.known),
                            rate=self.rate)
        n = model.n
        y = np.zeros(ws.state_size)
        y[:13 * n] = ws.pack_state(state)
        acc = f(state.t, y)[7 * n:13 * n].reshape(2, n, 3)
        return np.concatenate((acc[0], acc[1]), axis=1)


def constrained_dynamics(model: Model, known: Mapping[str, float] | None = None, *,
                         rate: float = BAUMGARTE_RATE) -> ConstrainedDynamics:
    """f(model, state) -> (n, 6) accelerations with the unknown reactions solved each call,
    stabilised with α = β = `rate` (1/s; 0 turns stabilisation off)."""
    return ConstrainedDynamics(known, rate)


class SampleFigures:
    """A run's figures at its K output samples (`sample_figures`). A plain class, as
    `ConservedFigures`."""

    __slots__ = ("reactions", "lengths", "position_drift", "velocity_drift")

    def __init__(self, reactions: np.ndarray | None, lengths: np.ndarray | None,
                 position_drift: float, velocity_drift: float):
        self.reactions, self.lengths = reactions, lengths
        self.position_drift, self.velocity_drift = position_drift, velocity_drift

    reactions: np.ndarray | None
    """(K, m) every reaction value (N; N m), or None when not asked for."""
    lengths: np.ndarray | None
    """(K, s) each spring's length (m), or None when not asked for."""
    position_drift: float
    """Largest |φ| (m for forces, rad for moments; a driven component: φ − f)."""
    velocity_drift: float
    """Largest |Gᵀ v| (a driven component: Gᵀ v − f′)."""


def sample_figures(model: Model, unknowns: Unknowns, t: np.ndarray, Y: np.ndarray, *,
                   reactions: bool = True, lengths: bool = False) -> SampleFigures:
    """The figures of the sampled states Y (K, state size: the core's layout) at the times
    t (K,), in one call of the compiled core: every reaction value (the components of
    `unknowns` solved with the exact γ, the others at their given values, those varying
    in t at t), the springs' lengths, and the joints' largest drift over every reaction
    component."""
    ws = workspace(model)
    core = ws.core
    K = len(t)
    Y = np.ascontiguousarray(Y, dtype=float)
    lam_out = np.empty((K, int(core.m))) if reactions else None
    len_out = np.empty((K, int(core.s))) if lengths else None
    drift = np.zeros(2)
    _core.samples(ws.solver(unknowns), np.ascontiguousarray(unknowns.lam, dtype=float),
                  np.ascontiguousarray(t, dtype=float), Y, lam_out, len_out, drift)
    return SampleFigures(lam_out, len_out, float(drift[0]), float(drift[1]))


ANGULAR_MOMENTUM_ABOUT = {"world origin": 0, "spins": 1, "mass centre": 2}
"""The core's codes of the point angular momentum is taken about (`conserved_figures`)."""


class ConservedFigures:
    """What a run conserves, at its K samples (`conserved_figures`). A plain class, not a
    NamedTuple: it is made at every simulate's import, where a NamedTuple costs 0.1 ms."""

    __slots__ = ("kinetic_energy", "potential_energy", "angular_momentum", "energy_drift",
                 "momentum_drift", "angular_momentum_drift", "momentum_initial", "spin_peak")

    def __init__(self, kinetic_energy: np.ndarray, potential_energy: np.ndarray,
                 angular_momentum: np.ndarray, energy_drift: float, momentum_drift: float,
                 angular_momentum_drift: float, momentum_initial: np.ndarray,
                 spin_peak: np.ndarray):
        self.kinetic_energy, self.potential_energy = kinetic_energy, potential_energy
        self.angular_momentum, self.energy_drift = angular_momentum, energy_drift
        self.momentum_drift, self.angular_momentum_drift = momentum_drift, angular_momentum_drift
        self.momentum_initial, self.spin_peak = momentum_initial, spin_peak

    kinetic_energy: np.ndarray
    """(K,) T = Σ ½ m vᵀv + ½ ωᵀ J ω (J)."""
    potential_energy: np.ndarray
    """(K,) V = −Σ m g·x + Σ ½ k (L − L0)² (J)."""
    angular_momentum: np.ndarray
    """(K, 3) H, world axes (kg m²/s), about the point asked for."""
    energy_drift: float
    """max |E − E(0)| / max(|E(0)|, max T), E = T + V (0 when that scale is 0)."""
    momentum_drift: float
    """max |p − p(0)| over the largest Σ |m v| (0 when that is)."""
    angular_momentum_drift: float
    """max |H − H(0)| over the largest sum of its terms' magnitudes (0 when that is)."""
    momentum_initial: np.ndarray
    """(3,) p = Σ m v at the first sample (kg m/s)."""
    spin_peak: np.ndarray
    """(n,) each body's largest |ω| over the samples (rad/s; planar: |ω_z|)."""


def conserved_figures(model: Model, Y: np.ndarray, about: str,
                      lengths: np.ndarray | None = None) -> ConservedFigures:
    """Energy, linear and angular momentum at the sampled states Y (K, state size: the
    core's layout, unit quaternions; a planar model's carried angles) in one call of the
    compiled core (`_core.conservation`), with their largest relative changes. `about`:
    a key of `ANGULAR_MOMENTUM_ABOUT` (the spins alone, or with the orbital terms about
    the world origin or the system's mass centre); `lengths` (K, s): the springs' lengths
    at the samples (needed when the model has springs)."""
    K = len(Y)
    sp = model.springs
    T, V, H, figures = np.empty(K), np.empty(K), np.empty((K, 3)), np.empty(6)
    spin = np.empty(model.n)
    _core.conservation(np.ascontiguousarray(model.mass, dtype=float),
                       np.ascontiguousarray(model.J, dtype=float),
                       np.ascontiguousarray(model.gravity, dtype=float),
                       np.ascontiguousarray(sp.stiffness, dtype=float),
                       np.ascontiguousarray(sp.rest_length, dtype=float),
                       None if lengths is None else np.ascontiguousarray(lengths, dtype=float),
                       np.ascontiguousarray(Y, dtype=float), model.dimension == 2,
                       ANGULAR_MOMENTUM_ABOUT[about], T, V, H, figures, spin)
    return ConservedFigures(T, V, H, float(figures[0]), float(figures[1]),
                            float(figures[2]), figures[3:6].copy(), spin)


def reactions_at(model: Model, unknowns: Unknowns, t: np.ndarray, Y: np.ndarray
                 ) -> np.ndarray:
    """(K, m) every reaction value at the sampled states (`sample_figures`)."""
    out = sample_figures(model, unknowns, t, Y).reactions
    assert out is not None
    return out


def drift_at(model: Model, t: np.ndarray, Y: np.ndarray) -> dict[str, float]:
    """Largest joint position error |φ| (m for forces, rad for moments) and velocity error
    |Gᵀ v| (a driven component: φ − f and Gᵀ v − f′) over the sampled states Y (K, state
    size) at the times t, every reaction component counted."""
    f = sample_figures(model, workspace(model).file_unknowns, t, Y, reactions=False)
    return {"joint_position_drift": f.position_drift,
            "joint_velocity_drift": f.velocity_drift}


def pack_states(model: Model, states: list[State]) -> tuple[np.ndarray, np.ndarray]:
    """(t (K,), Y (K, state size)): states in the core's layout (planar angles 0: the
    evaluations do not read them)."""
    ws = workspace(model)
    Y = np.zeros((len(states), ws.state_size))
    for k, s in enumerate(states):
        Y[k, :13 * model.n] = ws.pack_state(s)
    return np.array([s.t for s in states], dtype=float), Y


def reactions_along(model: Model, states: list[State],
                    known: Mapping[str, float] | None = None) -> np.ndarray:
    """(K, m) every reaction value at each sampled state (exact γ, no stabilisation); the
    components not in the file's or `known`'s values solved."""
    t, Y = pack_states(model, states)
    if not len(states):
        return np.zeros((0, len(model.reactions)))
    return reactions_at(model, workspace(model).unknowns_at(float(t[0]), known), t, Y)


def constraint_drift(model: Model, states: list[State]) -> dict[str, float]:
    """Largest joint position error |φ| (m for forces, rad for moments) and velocity error
    |Gᵀ v| over the samples."""
    t, Y = pack_states(model, states)
    return drift_at(model, t, Y)
