"""Coordinate projection: a mechanism's integrated state moved back onto its joints.

A simulation integrates ``Gᵀ v̇ = γ``, which holds the joints at acceleration level only;
integration errors make them drift at position (φ) and velocity (Gᵀ v) level. After
every integrator step the compiled core (`mb_project`, mbody/kernel/src/project.c) moves
the state back:

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
"""

from __future__ import annotations

import numpy as np

from mbody.equations.workspace import Unknowns, workspace
from mbody.kernel import _core
from mbody.model.model import Model
from mbody.solve.dynamics import status_error

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
