"""Joint reactions -> the columns of G, vectorised over reaction components.

Column c holds what a unit value of reaction component c puts into the bodies' rows.
With e the component's joint axis in world axes (the joint frame is fixed to the parent)
and P the joint point (the child's attachment point, in world coordinates):

- force component:  child  Newton +e,  Euler +B_r_c × (W_R_cᵀ e)
                    parent Newton −e,  Euler −B_r_p × (W_R_pᵀ e)
- moment component: child  Euler +W_R_cᵀ e;  parent Euler −W_R_pᵀ e

where B_r_c, B_r_p locate P from each mass centre in that body's axes. Both halves act
at the same world point P, so Newton's third law holds for forces and moments, and
``Gᵀ v = e · (V_child(P) − V_parent(P))`` (or ``e · (ω_child − ω_parent)``): the relative
velocity the joint forbids.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.equations.spatial import cross, matvec, rmatvec

if TYPE_CHECKING:
    import scipy.sparse as sp

    from mbody.model.model import Model, State


@dataclass(frozen=True)
class ReactionColumns:
    """Per reaction component (m of them) at one state.

    W_e: (m, 3) its direction, world axes. W_P: (m, 3) joint point, world.
    child6, parent6: (m, 6) the column's entries in the child's and parent's six rows
    (parent entries are zero for ground). is_moment: (m,) bool.
    Per joint (J): joint_W_P (J, 3) joint points; joint_Rp, joint_Rc (J, 3, 3) the
    parent's (identity for ground) and child's W_R_B.
    """

    W_e: np.ndarray
    W_P: np.ndarray
    child6: np.ndarray
    parent6: np.ndarray
    is_moment: np.ndarray
    joint_W_P: np.ndarray
    joint_Rp: np.ndarray
    joint_Rc: np.ndarray

    def __repr__(self) -> str:  # the dataclass's would print every array
        m, moments = len(self.W_e), int(np.count_nonzero(self.is_moment))
        return (f"<ReactionColumns: {m} columns of G at one state ({m - moments} forces, "
                f"{moments} moments); .W_e (world), .child6, .parent6>")


def joint_parents(model: Model, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per joint: (has a body parent (J,), parent index with ground -> 0, W_R_B of the
    parent with the identity for ground (J, 3, 3))."""
    jt = model.joint_table
    on_p = jt.parent >= 0
    p = np.where(on_p, jt.parent, 0)
    Rp = R[p]
    if not on_p.all():
        Rp[~on_p] = np.eye(3)
    return on_p, p, Rp


@dataclass(frozen=True)
class ReactionConstants:
    """Per component, what its column needs of the model only (kept by `model.plan`)."""

    k: np.ndarray  # joint-frame axis index 0-2
    is_moment: np.ndarray  # (m, 1) bool
    any_moment: bool
    B_r_child: np.ndarray  # (m, 3) joint point on the child, child axes
    B_e_p: np.ndarray  # (m, 3) the axis fixed in the parent, parent axes
    ground: np.ndarray  # (m,) bool: parent is ground


def reaction_constants(model: Model) -> ReactionConstants:
    """The `ReactionConstants` of `model` (use ``model.plan.reaction_constants``)."""
    rt, jt = model.reaction_table, model.joint_table
    j, k = rt.joint, rt.axis % 3
    is_moment = (rt.axis >= 3)[:, None]
    return ReactionConstants(k, is_moment, bool(is_moment.any()), jt.B_r_child[j],
                             jt.P_E3[j, :, k], rt.parent < 0)


def reaction_columns(model: Model, state: State, R: np.ndarray | None = None) -> ReactionColumns:
    R = state.W_R_B if R is None else R
    rt = model.reaction_table
    jt = model.joint_table
    m = len(rt.labels)
    if m == 0:
        z, z3 = np.zeros((0, 3)), np.zeros((0, 3, 3))
        return ReactionColumns(z, z, np.zeros((0, 6)), np.zeros((0, 6)), np.zeros(0, bool),
                               z, z3, z3)
    # Per joint: its frame in world axes and in the child's axes, and the joint point.
    on_p, p, Rp = joint_parents(model, R)
    Rc = R[jt.child]
    W_E = Rp @ jt.P_E3
    B_E_c = np.swapaxes(Rc, 1, 2) @ W_E
    P = state.position[jt.child] + matvec(Rc, jt.B_r_child)
    x_p = state.position[p]
    x_p[~on_p] = 0.0
    B_r_p = rmatvec(Rp, P - x_p)  # the parent's material point at P, parent axes

    # Per component: pick its axis of the joint frame.
    const = model.plan.reaction_constants
    j, k = rt.joint, const.k
    W_e = W_E[j, :, k]
    B_e_c = B_E_c[j, :, k]
    B_e_p = const.B_e_p
    universal = rt.axis == 6
    if universal.any():
        ju = j[universal]
        a = W_E[ju, :, 2]
        b = matvec(Rc[ju], jt.C_axis2[ju])
        e = cross(a, b)
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        W_e[universal] = e
        B_e_c[universal] = rmatvec(Rc[ju], e)
        B_e_p = B_e_p.copy()
        B_e_p[universal] = rmatvec(Rp[ju], e)
    is_moment = const.is_moment
    child6 = np.empty((m, 6))
    parent6 = np.empty((m, 6))
    if const.any_moment:
        child6[:, :3] = np.where(is_moment, 0.0, W_e)
        child6[:, 3:] = np.where(is_moment, B_e_c, cross(const.B_r_child, B_e_c))
        parent6[:, 3:] = np.where(is_moment, B_e_p, cross(B_r_p[j], B_e_p))
    else:  # forces only (spherical joints): no selection needed
        child6[:, :3] = W_e
        child6[:, 3:] = cross(const.B_r_child, B_e_c)
        parent6[:, 3:] = cross(B_r_p[j], B_e_p)
    np.negative(child6[:, :3], out=parent6[:, :3])
    np.negative(parent6[:, 3:], out=parent6[:, 3:])
    if rt.link.any():  # particle links: T along the line from P_c to P_p
        li = np.flatnonzero(rt.link)
        jl = j[li]
        P_p = x_p[jl] + matvec(Rp[jl], jt.B_r_parent[jl])
        d = P[jl] - P_p
        e = -d / np.linalg.norm(d, axis=1, keepdims=True)
        W_e[li] = e
        child6[li, :3] = e
        child6[li, 3:] = cross(jt.B_r_child[jl], rmatvec(Rc[jl], e))
        parent6[li, :3] = -e
        parent6[li, 3:] = -cross(jt.B_r_parent[jl], rmatvec(Rp[jl], e))
    if rt.particle_parent.any():  # a particle turns with nothing: forces act at it
        parent6[rt.particle_parent, 3:] = 0.0
    if const.ground.any():
        parent6[const.ground] = 0.0
    return ReactionColumns(W_e, P[j], child6, parent6, is_moment[:, 0], P, Rp, Rc)


def g_matrix(model: Model, cols: ReactionColumns) -> sp.csc_matrix:
    """The sparse G (rows = stacked coordinates, columns = reaction unknowns)."""
    import scipy.sparse as sp

    rt = model.reaction_table
    m = len(rt.labels)
    rpb = model.rows_per_body
    N = model.n * rpb
    if m == 0:
        return sp.csc_matrix((N, 0))
    keep = np.arange(6) if model.dimension == cv.SPATIAL else cv.PLANAR_SELECT
    k = len(keep)
    col = np.repeat(np.arange(m), k)
    rows_c = (rt.child[:, None] * rpb + np.arange(k)).ravel()
    data_c = cols.child6[:, keep].ravel()
    on_p = rt.parent >= 0
    rows_p = (rt.parent[on_p, None] * rpb + np.arange(k)).ravel()
    data_p = cols.parent6[on_p][:, keep].ravel()
    col_p = np.repeat(np.arange(m)[on_p], k)
    rows = np.concatenate((rows_c, rows_p))
    cols_ = np.concatenate((col, col_p))
    data = np.concatenate((data_c, data_p))
    nz = data != 0.0
    G = sp.csc_matrix((data[nz], (rows[nz], cols_[nz])), shape=(N, m))
    G.sum_duplicates()
    return G


def g_block(model: Model, cols: ReactionColumns, bodies: np.ndarray,
            components: np.ndarray) -> np.ndarray:
    """Dense G[rows of `bodies`, `components`]: the same numbers as
    ``g_matrix(model, cols)[rows][:, components].toarray()`` without scipy.sparse (for a
    body's equations and the rank test). `bodies`: body indices, whose rows are stacked in
    that order; `components`: reaction component indices (the columns, in that order)."""
    rt = model.reaction_table
    rpb = model.rows_per_body
    keep = np.arange(6) if model.dimension == cv.SPATIAL else cv.PLANAR_SELECT
    bodies, components = np.asarray(bodies, dtype=int), np.asarray(components, dtype=int)
    local = np.full(model.n + 1, -1)  # body index -> its place in `bodies`; ground (-1) -> -1
    local[bodies] = np.arange(len(bodies))
    A = np.zeros((len(bodies), len(components), rpb))
    for owner, six in ((rt.child, cols.child6), (rt.parent, cols.parent6)):
        at = local[owner[components]]
        on = np.flatnonzero(at >= 0)
        # 0.0 + x: +0.0 where x is -0.0, as a sparse G (which drops zeros) gives
        A[at[on], on] += six[components[on]][:, keep]
    return A.transpose(0, 2, 1).reshape(len(bodies) * rpb, len(components))


def reaction_wrench(model: Model, cols: ReactionColumns, lam: np.ndarray) -> np.ndarray:
    """(n, 6) what reactions with values `lam` (m,) put into every body's six rows."""
    rt = model.reaction_table
    out = np.zeros((model.n, 6))
    nz = np.flatnonzero(lam)
    if len(nz) == 0:
        return out
    for body, six in ((rt.child[nz], cols.child6[nz]), (rt.parent[nz], cols.parent6[nz])):
        keep = body >= 0
        w = six[keep] * lam[nz][keep, None]
        for r in range(6):  # six rows, not a loop over bodies
            out[:, r] += np.bincount(body[keep], w[:, r], minlength=model.n)
    return out


def constraint_velocity(model: Model, cols: ReactionColumns, state: State) -> np.ndarray:
    """(m,) Gᵀ v: per component, the relative velocity its joint forbids (m/s or rad/s),
    from the columns at `state` and the bodies' [v (world), ω (body axes)]."""
    rt = model.reaction_table
    v6 = np.concatenate((state.velocity, state.omega), axis=1)
    out = np.einsum("ij,ij->i", cols.child6, v6[rt.child])
    on = rt.parent >= 0
    out[on] += np.einsum("ij,ij->i", cols.parent6[on], v6[rt.parent[on]])
    return out
