"""The per-step path of a simulation: accelerations of every body at one state,

    v̇ = M⁻¹ (Q + G λ − b),   i.e.   a_G = W_F / m,   ω̇ = J⁻¹ (B_M + reactions − ω × J ω)

with M and J⁻¹ kept (constant in body axes) and no stacked matrices formed. Rows of the
result are per body ``[a_G (world axes, m/s²), ω̇ (body axes, rad/s²)]`` for planar and
spatial models alike (a planar body's rows 2-4 are 0). The numeric work is done by the
cache-blocked kernels in `mbody.kernels`; what depends only on the model (and on the
load values, while they do not change) is laid out once and cached on the model.

For integrators, `derivative` returns the time derivative of the packed state
``[position (3), quaternion (4), velocity (3), omega (3)]`` per body (see `pack`).
"""

from __future__ import annotations

import numpy as np

from . import kernels as k
from .errors import MbodyError
from .joints import reaction_columns
from .model import Model, State
from .spatial import quat_to_matrix


def _reaction_part(model: Model, state: State, reactions: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(body (2m,), wrench (2m, 6)): G λ split into the child and parent halves."""
    t = model.reaction_table
    lam = np.asarray(reactions, dtype=float).reshape(-1)
    if len(lam) != len(t.labels):
        raise MbodyError(f"expected {len(t.labels)} reaction values (one per label of "
                         f"model.reactions), got {len(lam)}")
    if not len(lam):
        return np.zeros(0, np.intp), np.zeros((0, 6))
    # Rotation matrices only for the bodies the joints touch (n may be large).
    involved = np.unique(np.concatenate((t.parent[t.parent >= 0], t.child, [0])))
    R = np.empty((model.n, 3, 3))
    R[involved] = quat_to_matrix(state.quaternion[involved])
    cols = reaction_columns(model, state, R)
    body = np.concatenate((t.child, t.parent))
    W = np.concatenate((cols.child6 * lam[:, None], cols.parent6 * lam[:, None]))
    return body, W


def accelerations(model: Model, state: State, reactions: np.ndarray | None = None, *,
                  out: np.ndarray | None = None) -> np.ndarray:
    """v̇ = M⁻¹ (Q + G λ − b) per body -> (n, 6) rows [a_G world, ω̇ body axes].

    `reactions`: (m,) values λ of the reaction components, in the order of
    ``model.reactions`` (None: no reaction forces). Load values are taken at
    ``state.t`` (``model.forces.vector_at``). `out`: an (n, 6) array to fill (any memory
    layout); by default a new one is returned whose columns are contiguous (it is the
    transpose of a (6, n) array), which is the fast layout to write.
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
