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

import numpy as np
import scipy.sparse as sp

from . import conventions as cv
from .model import Model, State
from .spatial import cross, matvec, rmatvec


@dataclass(frozen=True)
class ReactionColumns:
    """Per reaction component (m of them) at one state.

    W_e: (m, 3) its direction, world axes. W_P: (m, 3) joint point, world.
    child6, parent6: (m, 6) the column's entries in the child's and parent's six rows
    (parent entries are zero for ground). is_moment: (m,) bool.
    """

    W_e: np.ndarray
    W_P: np.ndarray
    child6: np.ndarray
    parent6: np.ndarray
    is_moment: np.ndarray


def reaction_columns(model: Model, state: State, R: np.ndarray | None = None) -> ReactionColumns:
    R = state.W_R_B if R is None else R
    t = model.reaction_table
    m = len(t.labels)
    if m == 0:
        z = np.zeros((0, 3))
        return ReactionColumns(z, z, np.zeros((0, 6)), np.zeros((0, 6)), np.zeros(0, bool))
    on_p = t.parent >= 0
    p = np.where(on_p, t.parent, 0)
    c = t.child
    Rp = np.where(on_p[:, None, None], R[p], np.eye(3))
    Rc = R[c]
    W_e = matvec(Rp, t.P_E)
    universal = t.axis == 6
    if universal.any():
        W_a2 = matvec(Rc[universal], t.C_axis2[universal])
        e = cross(W_e[universal], W_a2)
        W_e[universal] = e / np.linalg.norm(e, axis=1, keepdims=True)
    W_P = state.position[c] + matvec(Rc, t.B_r_child)
    is_moment = t.axis >= 3

    B_e_c = rmatvec(Rc, W_e)
    B_e_p = rmatvec(Rp, W_e)
    B_r_p = rmatvec(Rp, W_P - np.where(on_p[:, None], state.position[p], 0.0))
    child6 = np.zeros((m, 6))
    parent6 = np.zeros((m, 6))
    f = ~is_moment
    child6[f, :3] = W_e[f]
    child6[f, 3:] = cross(t.B_r_child[f], B_e_c[f])
    child6[is_moment, 3:] = B_e_c[is_moment]
    parent6[f, :3] = -W_e[f]
    parent6[f, 3:] = -cross(B_r_p[f], B_e_p[f])
    parent6[is_moment, 3:] = -B_e_p[is_moment]
    parent6[~on_p] = 0.0
    return ReactionColumns(W_e, W_P, child6, parent6, is_moment)


def g_matrix(model: Model, cols: ReactionColumns) -> sp.csc_matrix:
    """The sparse G (rows = stacked coordinates, columns = reaction unknowns)."""
    t = model.reaction_table
    m = len(t.labels)
    rpb = model.rows_per_body
    N = model.n * rpb
    if m == 0:
        return sp.csc_matrix((N, 0))
    keep = np.arange(6) if model.dimension == cv.SPATIAL else cv.PLANAR_SELECT
    k = len(keep)
    col = np.repeat(np.arange(m), k)
    rows_c = (t.child[:, None] * rpb + np.arange(k)).ravel()
    data_c = cols.child6[:, keep].ravel()
    on_p = t.parent >= 0
    rows_p = (t.parent[on_p, None] * rpb + np.arange(k)).ravel()
    data_p = cols.parent6[on_p][:, keep].ravel()
    col_p = np.repeat(np.arange(m)[on_p], k)
    rows = np.concatenate((rows_c, rows_p))
    cols_ = np.concatenate((col, col_p))
    data = np.concatenate((data_c, data_p))
    nz = data != 0.0
    G = sp.csc_matrix((data[nz], (rows[nz], cols_[nz])), shape=(N, m))
    G.sum_duplicates()
    return G


def reaction_wrench(model: Model, cols: ReactionColumns, lam: np.ndarray) -> np.ndarray:
    """(n, 6) what reactions with values `lam` (m,) put into every body's six rows."""
    t = model.reaction_table
    out = np.zeros((model.n, 6))
    if len(lam) == 0:
        return out
    np.add.at(out, t.child, cols.child6 * lam[:, None])
    on_p = t.parent >= 0
    np.add.at(out, t.parent[on_p], cols.parent6[on_p] * lam[on_p, None])
    return out
