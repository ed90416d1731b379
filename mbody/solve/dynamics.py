"""The per-step path of a simulation: accelerations of every body at one state,

    v̇ = M⁻¹ (Q + G λ − b),   i.e.   a_G = W_F / m,   ω̇ = J⁻¹ (B_M + reactions − ω × J ω)

with M and J⁻¹ kept (constant in body axes) and no stacked matrices formed. Rows of the
result are per body ``[a_G (world axes, m/s²), ω̇ (body axes, rad/s²)]`` for planar and
spatial models alike (a planar body's rows 2-4 are 0). The numeric work is done by the
cache-blocked kernels in `mbody.equations.kernels`; what depends only on the model (and on the
load values, while they do not change) is laid out once and cached on the model.

For integrators, `derivative` returns the time derivative of the packed state
``[position (3), quaternion (4), velocity (3), omega (3)]`` per body (see `pack`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from mbody.equations import kernels as k
from mbody.equations.joints import reaction_columns
from mbody.equations.plan import JIT_AFTER
from mbody.equations.plan import compiled as compiled_module
from mbody.equations.spatial import quat_to_matrix
from mbody.errors import MbodyError
from mbody.model.model import Model, State
from mbody.solve.kkt import singular_mass_error

if TYPE_CHECKING:
    from mbody.equations.plan import Unknowns
    from mbody.simulate.projection import JointProjection


def _reaction_part(model: Model, state: State, reactions: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(body (2m,), wrench (2m, 6)): G λ split into the child and parent halves."""
    rt = model.reaction_table
    lam = np.asarray(reactions, dtype=float).reshape(-1)
    if len(lam) != len(rt.labels):
        raise MbodyError(f"expected {len(rt.labels)} reaction values (one per label of "
                         f"model.reactions), got {len(lam)}")
    if not len(lam):
        return np.zeros(0, np.intp), np.zeros((0, 6))
    # Rotation matrices only for the bodies the joints touch (n may be large).
    involved = np.unique(np.concatenate((rt.parent[rt.parent >= 0], rt.child, [0])))
    R = np.empty((model.n, 3, 3))
    R[involved] = quat_to_matrix(state.quaternion[involved])
    cols = reaction_columns(model, state, R)
    body = np.concatenate((rt.child, rt.parent))
    W = np.concatenate((cols.child6 * lam[:, None], cols.parent6 * lam[:, None]))
    return body, W


def accelerations(model: Model, state: State, reactions: np.ndarray | None = None, *,
                  out: np.ndarray | None = None) -> np.ndarray:
    """v̇ = M⁻¹ (Q + G λ − b) per body -> (n, 6) rows [a_G world, ω̇ body axes].

    Every reaction value is given: nothing is solved for (`Assembly.solve` solves for
    the unknown ones). Load values are taken at ``state.t`` (``model.forces.vector_at``).

    Parameters
    ----------
    model : Model
        The model, from `load` or `loads`.
    state : State
        Positions (world, m), orientations, velocities (world, m/s), angular velocities
        (body axes, rad/s) and time (s).
    reactions : (m,) array, optional
        Values λ of the reaction components (N; N m), in the order of
        ``model.reactions`` (None: no reaction forces).
    out : (n, 6) array, optional
        An array to fill (any memory layout); by default a new one is returned whose
        columns are contiguous (it is the transpose of a (6, n) array), which is the fast
        layout to write.

    Returns
    -------
    (n, 6) array
        Per body, in file order: a_G, mass-centre acceleration in world axes (m/s²), then
        ω̇, angular acceleration in body axes (rad/s²); a planar body's rows 2-4 are 0.
        `out` when given.

    Raises
    ------
    MbodyError
        `reactions` does not have one value per reaction component.
    """
    plan = k.plan_for(model)
    frame = k.frame_at(model, state.t)
    parts = [k.load_wrenches(model, plan, frame, state), k.spring_wrenches(model, state)]
    if reactions is not None:
        parts.append(_reaction_part(model, state, reactions))
    sparse = k.sparse_wrench(plan, parts)
    if out is None:
        out = np.empty((6, model.n)).T
    k.accelerations(plan, frame, state, sparse, out.T)
    return out


def quaternion_rate(quaternion: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """q̇ = ½ q ⊗ (0, ω) for W_R_B quaternions (n, 4) [w, x, y, z] and ω (n, 3) body axes."""
    w, u = quaternion[:, :1], quaternion[:, 1:]
    out = np.empty_like(quaternion, dtype=float)
    out[:, :1] = -0.5 * np.einsum("ij,ij->i", u, omega)[:, None]
    out[:, 1:] = 0.5 * (w * omega + np.cross(u, omega))
    return out


Dynamics = Callable[[Model, State], np.ndarray]
"""f(model, state) -> (n, 6) accelerations [a_G (world, m/s²), ω̇ (body axes, rad/s²)]."""


class StateDerivative:
    """ẏ = f(t, y) for the packed state a simulation integrates,

        y = [x (n, 3) | q (n, 4) | v (n, 3) | ω (n, 3) | θ (n,), planar only]   (flat),
        ẏ = [v | ½ q ⊗ (0, ω) | a_G | ω̇ | ω_z],

    with the accelerations from `dynamics` (numpy path, a `Dynamics` callable) or, for
    models `mbody.equations.plan` compiles, from one call of
    `mbody.solve.compiled.derivative` with the unknown reactions solved and Baumgarte's
    terms (α = β = `rate`). The rotation is
    built from q/‖q‖; q itself is integrated as it is. Planar models' out-of-plane rows
    are set to exactly 0 (rounding would otherwise creep in).
    """

    def __init__(self, model: Model, dynamics: Dynamics, *, unknowns: Unknowns | None = None,
                 rate: float = 0.0, known_at: Callable[[float], np.ndarray] | None = None,
                 compiled: bool = False):
        self.model, self.dynamics, self.rate = model, dynamics, rate
        self.unknowns, self.known_at = unknowns, known_at
        self.projection: JointProjection | None = None
        """A `mbody.simulate.projection.JointProjection`, set by `simulate` for mechanisms."""
        self.project_stages = False
        """Evaluate at the projected copy of y (near singular positions, see
        `mbody.simulate.projection`)."""
        self.planar = model.dimension == 2
        n = model.n
        self.size = 13 * n + (n if self.planar else 0)
        self._kernel = None
        # a simulation makes thousands of evaluations: worth the compiled path at once
        if compiled and unknowns is not None and model.plan.use_compiled(calls=JIT_AFTER):
            plan = model.plan
            self._kernel = compiled_module().derivative
            self._F, self._I = plan.packed
            self._Iu = plan.packed_unknowns(unknowns)
            self._lam = unknowns.lam  # the given reaction values, 0 on the unknown ones
            # loads given as expressions of t: evaluated by the compiled path as well
            # a plain tuple: CPython passes `*t` of an exact tuple without copying it
            self._program = tuple(plan.load_program)
            self._varying = model.forces.varying is not None
            self._loads = plan.constant_loads.copy() if self._varying else plan.constant_loads
            self._set_loads = compiled_module().set_loads

    @property
    def compiled(self) -> bool:
        """Whether evaluations go through the compiled path."""
        return self._kernel is not None

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        if self.project_stages and self.projection is not None:
            y = y.copy()
            self.projection(y, t, iterations=2)
        if self._kernel is not None:
            out = np.empty(self.size)
            lam = self._lam if self.known_at is None else self.known_at(t)
            loads = self._loads
            if self._varying:
                self._set_loads(*self._program, t, loads)
            code = self._kernel(self._F, self._I, self._Iu, y, loads, lam, self.rate,
                                self.planar, out)
            if code:
                raise singular_mass_error(self.model, (code - 1) // 6, (code - 1) % 6)
            return out
        return self._numpy(t, y)

    def _numpy(self, t: float, y: np.ndarray) -> np.ndarray:
        n = self.model.n
        x = y[:3 * n].reshape(n, 3)
        q = y[3 * n:7 * n].reshape(n, 4)
        v = y[7 * n:10 * n].reshape(n, 3)
        w = y[10 * n:13 * n].reshape(n, 3)
        qn = q / np.sqrt(np.einsum("ij,ij->i", q, q))[:, None]
        acc = self.dynamics(self.model, State(x, qn, v, w, t))
        d = np.empty(self.size)
        d[:3 * n] = y[7 * n:10 * n]
        d[3 * n:7 * n] = quaternion_rate(q, w).ravel()
        d[7 * n:10 * n].reshape(n, 3)[:] = acc[:, :3]
        d[10 * n:13 * n].reshape(n, 3)[:] = acc[:, 3:]
        if self.planar:
            d[7 * n + 2:10 * n:3] = 0.0
            d[10 * n:13 * n].reshape(n, 3)[:, :2] = 0.0
            d[13 * n:] = w[:, 2]
        return d


def pack(state: State) -> np.ndarray:
    """State -> flat (13 n,) vector, per body [position, quaternion, velocity, omega]."""
    return np.concatenate((state.position, state.quaternion, state.velocity, state.omega),
                          axis=1).reshape(-1)


def unpack(y: np.ndarray, t: float = 0.0) -> State:
    """Inverse of `pack` (the quaternion is used as given; renormalise in the integrator)."""
    Y = np.asarray(y, dtype=float).reshape(-1, 13)
    return State(Y[:, 0:3], Y[:, 3:7], Y[:, 7:10], Y[:, 10:13], t)


def derivative(model: Model, state: State, reactions: np.ndarray | None = None) -> np.ndarray:
    """ẏ for y = `pack(state)`: per body [v, q̇ = ½ q ⊗ (0, ω), a_G, ω̇], flat (13 n,)."""
    acc = accelerations(model, state, reactions)
    return np.concatenate((state.velocity, quaternion_rate(state.quaternion, state.omega),
                           acc), axis=1).reshape(-1)
