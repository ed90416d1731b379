"""Coordinate projection: a mechanism's integrated state moved back onto its joints.

A simulation integrates ``Gᵀ v̇ = γ``, which holds the joints at acceleration level only;
integration errors make them drift at position (φ) and velocity (Gᵀ v) level. After
every integrator step the state is moved back:

- positions by Gauss-Newton steps ``M Δ − G_U μ = 0, G_Uᵀ Δ = −φ_U`` (the smallest move
  in the kinetic metric that closes the joints; Δ = [Δx world, Δθ body axes]),
- then velocities by the mass-orthogonal projection ``M Δv − G_U μ = 0,
  G_Uᵀ Δv = −G_Uᵀ v`` (the smallest change of kinetic energy that makes the joints'
  relative velocities vanish).

Both are the constrained solve of `mbody.solve.kkt` / `mbody.solve.compiled` with other right-hand
sides, so near a singular position they go through the same robust null-space solve.

Why projection rather than Baumgarte's terms: near a position where the constraint
Jacobian loses rank (a chain of parallelogram four-bars lying flat), the drift in the
direction that is about to lose its constraint is invisible in φ (φ is the product of
the small singular value and the drift) and the index-1 equations amplify it as 1/σ² on
the way in: the simulation leaves the mechanism's branch. The Gauss-Newton step divides
φ by the same small σ and so sees and removes that drift. Close to such a position
(`geometric_ratio` below `STAGE_PIVOT_RTOL`) the integrator's stage states are projected
as well before the accelerations are evaluated, so that the stages never see the
amplified drift (`mbody.solve.dynamics.StateDerivative.project_stages`).
"""

from __future__ import annotations

import numpy as np

from mbody.equations.constraints import phi
from mbody.equations.joints import ReactionColumns, constraint_velocity, reaction_columns
from mbody.equations.plan import Unknowns
from mbody.equations.plan import compiled as compiled_module
from mbody.model.model import Model, State
from mbody.solve.dynamics import quaternion_rate
from mbody.solve.kkt import ConstrainedSystem, singular_mass_error
from mbody.solve.nullspace import length_scale

ITERATIONS = 3
"""Gauss-Newton steps at most; from a state an integrator step left (φ near the
tolerance) one step is enough to close the joints to rounding, the others stop early."""
STAGE_PIVOT_RTOL = 1e-2
"""Project the stage states of the next step, and count only the error along the joints,
when `geometric_ratio` at the accepted state is below this (the four-bar chain within
about 0.1 rad of flat; with 1e-4 it takes 11 % more steps than the exact ODE). The ratio
is taken on G_U's scaled geometry, not on S = G_Uᵀ M⁻¹ G_U: S mixes in the masses, and a
slender spatial four-bar's S has a ratio of 1e-3 at every position."""


DROPPED_RTOL = 1e-13
"""A pivot ratio below this is an exactly redundant constraint (a spatial
four-bar's), not a position near a singular one: rounding leaves ~1e-16, a four-bar
chain 3e-7 rad from flat 1e-13. Such columns are left out of the ratio."""


class JointProjection:
    """`projection(y, t) -> (position step, velocity change, pivot ratio)`: moves the
    packed simulation state y (`mbody.solve.dynamics.StateDerivative` layout) onto the joints
    enforced by the unknown reactions `unknowns`, in place. The step is the largest
    Gauss-Newton correction (m or rad), the change the largest velocity correction (m/s or
    rad/s), the ratio `geometric_ratio` at the starting state (1: far from any
    singular position)."""

    def __init__(self, model: Model, unknowns: Unknowns, *, compiled: bool):
        self.model, self.unknowns = model, unknowns
        self.planar = model.dimension == 2
        self._kernel = None
        if compiled:
            plan = model.plan
            self._compiled = compiled_module()
            self._kernel = self._compiled.project
            self._F, self._I = plan.packed
            self._Iu = plan.packed_unknowns(unknowns)
            self._info = np.empty(self._compiled.PROJECT_INFO)

    def __call__(self, y: np.ndarray, t: float, iterations: int = ITERATIONS
                 ) -> tuple[float, float, float]:
        if self._kernel is not None:
            info, c = self._info, self._compiled
            self._kernel(self._F, self._I, self._Iu, y, self.planar, iterations,
                         STAGE_PIVOT_RTOL, info)
            if info[c.PR_SINGULAR]:
                code = int(info[c.PR_SINGULAR])
                raise singular_mass_error(self.model, (code - 1) // 6, (code - 1) % 6)
            return float(info[c.PR_STEP]), float(info[c.PR_VELOCITY]), float(info[c.PR_RATIO])
        return self._numpy(y, t, iterations)

    def _numpy(self, y: np.ndarray, t: float, iterations: int) -> tuple[float, float, float]:
        model, unknowns, n = self.model, self.unknowns, self.model.n
        U = unknowns.U
        x = y[:3 * n].reshape(n, 3)
        q = y[3 * n:7 * n].reshape(n, 4)
        v = y[7 * n:10 * n].reshape(n, 3)
        w = y[10 * n:13 * n].reshape(n, 3)
        zero = np.zeros((n, 6))
        moved = 0.0

        robust = False

        def system_at() -> tuple[State, ReactionColumns, ConstrainedSystem]:
            qn = q / np.linalg.norm(q, axis=1)[:, None]
            state = State(x, qn, v, w, t)
            cols = reaction_columns(model, state)
            system = ConstrainedSystem(model, cols, unknowns)
            if robust and system.robust is None:  # as the compiled `_project_solve`
                system.fact = system._null_space(system.fact.matrix())
            return state, cols, system

        state, cols, system = system_at()
        ratio = geometric_ratio(system)
        if ratio < STAGE_PIVOT_RTOL:
            robust = True
            state, cols, system = system_at()
        for _ in range(iterations):
            d, _, _ = system.solve_refined(zero, -phi(model, state, cols=cols)[U])
            if self.planar:
                d[:, 2:5] = 0.0
            step = float(np.max(np.abs(d))) if d.size else 0.0
            if step == 0.0:
                break
            moved = max(moved, step)
            x += d[:, :3]
            q += quaternion_rate(q, d[:, 3:])  # q ⊗ (1, Δθ/2): Δθ in body axes, as ω
            q /= np.linalg.norm(q, axis=1)[:, None]
            if self.planar:
                y[13 * n:] += d[:, 5]
            state, cols, system = system_at()
            if step < 1e-15:
                break
        d, _, _ = system.solve_refined(zero, -constraint_velocity(model, cols, state)[U])
        if self.planar:
            d[:, 2:5] = 0.0
        v += d[:, :3]
        w += d[:, 3:]
        change = float(np.max(np.abs(d))) if d.size else 0.0
        return moved, change, ratio


def geometric_ratio(system: ConstrainedSystem) -> float:
    """How close the joints are to a singular position, whatever the masses: the smallest
    squared Cholesky pivot of Ĝᵀ Ĝ over its diagonal entry, Ĝ = T G_U with
    T = diag(1, 1/ℓ) per body (`mbody.solve.nullspace`'s scaling), exactly redundant columns
    left out (as `mbody.solve.compiled._geometric_ratio`, whose `DROPPED_RTOL` it uses)."""
    G = getattr(system, "G", None)
    if G is None or system.blocks is not None or hasattr(G, "tocsr"):
        return 1.0  # the large models' sparse factorisations: no cheap figure
    parent, child6, parent6 = system._arms
    G = np.array(G, dtype=float).reshape(-1, 6, G.shape[1])
    G[:, 3:] /= length_scale(child6, parent6, parent)
    G = G.reshape(-1, G.shape[2])
    A = G.T @ G
    mu, worst = len(A), 1.0
    L = np.zeros_like(A)
    for i in range(mu):  # a few dozen columns at most on this path
        s = A[i, i] - L[i, :i] @ L[i, :i]
        if not s > DROPPED_RTOL * A[i, i]:
            continue  # an exactly redundant column: L[i] stays 0
        worst = min(worst, s / A[i, i])
        L[i, i] = np.sqrt(s)
        L[i + 1:, i] = (A[i + 1:, i] - L[i + 1:, :i] @ L[i, :i]) / L[i, i]
    return worst


def tangent_error(projection: JointProjection, y: np.ndarray, e: np.ndarray) -> np.ndarray:
    """The part of an integrator's error estimate e (layout of y) that moves along the
    joints at the state y: its velocity block and its position block (Δx, and the body
    rotation 2 vec(q̄ ⊗ Δq) of the quaternion block) each projected mass-orthogonally onto
    the motions the joints allow (the quaternion's radial part, its norm, is kept).

    The rest is removed by the projection after the step whatever its size, so it should
    not shrink the step: near a singular position it is rounding noise amplified by the
    small singular values (`STAGE_PIVOT_RTOL`), and it would stall the integrator."""
    n = projection.model.n
    out = e.copy()
    z = y.copy()
    z[7 * n:13 * n] = e[7 * n:13 * n]
    projection(z, 0.0, iterations=0)
    out[7 * n:13 * n] = z[7 * n:13 * n]
    q = y[3 * n:7 * n].reshape(n, 4)
    dq = e[3 * n:7 * n].reshape(n, 4)
    norm2 = np.einsum("ij,ij->i", q, q)
    radial = np.einsum("ij,ij->i", q, dq) / norm2
    # Δq = q ⊗ (0, Δφ) / 2 + radial q  ->  Δφ = 2 vec(q̄ ⊗ (Δq − radial q)) / |q|²
    rest = dq - radial[:, None] * q
    w, u = q[:, :1], q[:, 1:]
    dphi = 2.0 * (w * rest[:, 1:] - rest[:, :1] * u - np.cross(u, rest[:, 1:])) \
        / norm2[:, None]
    z = y.copy()
    z[7 * n:10 * n] = e[:3 * n]
    z[10 * n:13 * n] = dphi.ravel()
    projection(z, 0.0, iterations=0)
    out[:3 * n] = z[7 * n:10 * n]
    dphi = z[10 * n:13 * n].reshape(n, 3)
    out[3 * n:7 * n] = (quaternion_rate(q, dphi) + radial[:, None] * q).ravel()
    if projection.planar:
        out[13 * n:] = dphi[:, 2]
    return out
