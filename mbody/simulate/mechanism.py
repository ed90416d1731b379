"""Jointed mechanisms in motion: accelerations with the unknown reactions solved at every
step; the joints held against drift, by Baumgarte stabilisation (scipy's integrators) or
by coordinate projection (the core's DOP853); and what a run reports at its output
samples: the reactions and the joints' drift, the energy and the linear and angular
momentum.

Integrating ``Gᵀ v̇ = γ`` alone lets the joints drift apart (rounding and truncation
errors in φ and φ̇ = Gᵀ v are never corrected). Baumgarte's method replaces it by

    Gᵀ v̇ = γ − 2 α Gᵀ v − β² φ,

so that the constraint error obeys φ̈ + 2 α φ̇ + β² φ = 0 and decays (critically damped
for α = β) instead of growing. The reactions stored with a trajectory are solved at each
output sample with the exact γ (no stabilisation terms), so they are the physical ones
for the sampled state.

Coordinate projection, the core DOP853's way, moves the state back onto the joints after
every integrator step instead (`mb_project`, mbody/kernel/src/project.c; `JointProjection`
for one state):

- positions by Gauss-Newton steps ``M Δ − G_U μ = 0, G_Uᵀ Δ = −φ_U`` (the smallest move
  in the kinetic metric that closes the joints; Δ = [Δx world, Δθ body axes]),
- then velocities by the mass-orthogonal projection ``M Δv − G_U μ = 0,
  G_Uᵀ Δv = −(G_Uᵀ v − f′)`` (the smallest change of kinetic energy that gives the
  joints' relative velocities their targets: 0, or a driven component's law f′(t)).

A driven component (a law f(t)) is held at φ − f(t) = 0 and Gᵀv − f′(t) = 0 by the same
steps: the core reports its φ and Gᵀv with the law subtracted (kernel.h), so neither the
projection nor the integrator needs anything else.

Both are the constrained solve with other right-hand sides, so near a singular position
they go through the same robust null-space solve.

Why projection rather than Baumgarte's terms: near a position where the constraint
Jacobian loses rank (a chain of parallelogram four-bars lying flat), the drift in the
direction that is about to lose its constraint is invisible in φ (φ is the product of
the small singular value and the drift) and the index-1 equations amplify it as 1/σ² on
the way in: the simulation leaves the mechanism's branch. The Gauss-Newton step divides
φ by the same small σ and so sees and removes that drift. Close to such a position
(the geometric ratio below `STAGE_PIVOT_RTOL`) the next step is *filtered*: its stage
states are projected as well (`STAGE_ITERATIONS` steps) before the accelerations are
evaluated, so that the stages never see the amplified drift, and its error estimate
counts only the part along the joints (the rest the projection removes whatever its
size: near a singular position it is rounding noise amplified by the small singular
values, and it would stall the integrator). Both are the core's too
(mbody/kernel/src/mechanism.c), bound to its DOP853 (`mbody.simulate.stepping`).

Every figure here comes from one call of the compiled core over all the samples
(`mbody.kernel`): no Python work per sample, body or component.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mbody.equations.workspace import Unknowns, workspace
from mbody.kernel import _core
from mbody.model.model import Model, State
from mbody.solve.dynamics import StateDerivative, status_error

BAUMGARTE_RATE = 20.0
"""α = β in 1/s: joint errors decay with a time constant of 1/20 s."""

ITERATIONS = 3
"""Gauss-Newton steps at most after a step; from a state an integrator step left (φ near
the tolerance) one step is enough to close the joints to rounding, the others stop early."""
STAGE_ITERATIONS = 2
"""Gauss-Newton steps of a filtered step's stage states."""
STAGE_PIVOT_RTOL = 1e-2
"""Filter the next step (project its stage states, count only the error along the joints)
when the geometric ratio at the accepted state is below this (the four-bar chain within
about 0.1 rad of flat; with 1e-4 it takes 11 % more steps than the exact ODE). The ratio
is the smallest squared Cholesky pivot of Ĝᵀ Ĝ over its diagonal entry, Ĝ = T G_U with
T = diag(1, 1/ℓ) per body: G_U's scaled geometry, not S = G_Uᵀ M⁻¹ G_U, which mixes in the
masses (a slender spatial four-bar's S has a ratio of 1e-3 at every position). Exactly
redundant columns (a pivot ratio below 1e-13: a spatial four-bar's; rounding leaves
~1e-16, a four-bar chain 3e-7 rad from flat 1e-13) are left out of it."""


class JointProjection:
    """`projection(y, t) -> (position step, velocity change, geometric ratio)`: moves the
    packed simulation state y (the core's layout) onto the joints enforced by the unknown
    reactions `unknowns` at time t, in place (the core's `mb_project`). The step is the
    largest Gauss-Newton correction (m or rad), the change the largest velocity correction
    (m/s or rad/s), the ratio the geometric ratio at the starting state (1: far from any
    singular position; see `STAGE_PIVOT_RTOL`)."""

    def __init__(self, model: Model, unknowns: Unknowns):
        self.model, self.unknowns = model, unknowns
        self.planar = model.dimension == 2
        self.solver = workspace(model).solver(unknowns)
        self._info = np.empty(_core.PROJECT_INFO)

    def __call__(self, y: np.ndarray, t: float, iterations: int = ITERATIONS
                 ) -> tuple[float, float, float]:
        info = self._info
        self.solver.project(float(t), y, iterations, STAGE_PIVOT_RTOL, False, info)
        if info[_core.PR_SINGULAR]:
            raise status_error(self.model, int(info[_core.PR_SINGULAR]))
        return (float(info[_core.PR_STEP]), float(info[_core.PR_VELOCITY]),
                float(info[_core.PR_RATIO]))


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
