"""Joint reactions -> the columns of G (computed by the compiled core, `mbody.kernel`,
one constraint primitive per component), and what is built from them: the sparse G, a
dense block of it, the wrench of given reaction values, the joints a state breaks
(`joint_errors`).

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
from mbody.equations.workspace import workspace

if TYPE_CHECKING:
    import scipy.sparse as sp

    from mbody.model.model import Model, State


@dataclass(frozen=True)
class ReactionColumns:
    """Per reaction component (m of them) at one state, from the compiled core.

    W_e: (m, 3) its direction, world axes. W_P: (m, 3) joint point, world.
    child6, parent6: (m, 6) the column's entries in the child's and parent's six rows
    (parent entries are zero for ground). is_moment: (m,) bool. gamma: (m,) γ = −Ġᵀv
    (+ a driver's f″); phi: (m,) position errors (− a driver's f); gtv: (m,) Gᵀv (− a
    driver's f′): the relative velocity each joint forbids. joint_first: (J,) each joint's
    first component (for its point, `joint_W_P`).
    """

    W_e: np.ndarray
    W_P: np.ndarray
    child6: np.ndarray
    parent6: np.ndarray
    is_moment: np.ndarray
    gamma: np.ndarray
    phi: np.ndarray
    gtv: np.ndarray
    joint_first: np.ndarray

    @property
    def joint_W_P(self) -> np.ndarray:
        """(J, 3) each joint's point, world (its child's joint point)."""
        return self.W_P[self.joint_first] if len(self.W_P) else np.zeros((0, 3))

    def __repr__(self) -> str:  # the dataclass's would print every array
        m, moments = len(self.W_e), int(np.count_nonzero(self.is_moment))
        return (f"<ReactionColumns: {m} columns of G at one state ({m - moments} forces, "
                f"{moments} moments); .W_e (world), .child6, .parent6>")


def reaction_columns(model: Model, state: State, R: np.ndarray | None = None
                     ) -> ReactionColumns:
    """Every reaction component's column of G, direction, point, γ, φ and Gᵀv at `state`
    (the constraint primitives of the compiled core, `mbody.kernel`; `R` is not needed
    and kept for older callers)."""
    ws = workspace(model)
    m = len(model.reaction_table.joint)
    out = {"child6": np.empty((m, 6)), "parent6": np.empty((m, 6)),
           "W_e": np.empty((m, 3)), "W_P": np.empty((m, 3)), "gamma": np.empty(m),
           "phi": np.empty(m), "gtv": np.empty(m)}
    ws.core.columns(float(state.t), ws.pack_state(state), *out.values())
    return ReactionColumns(out["W_e"], out["W_P"], out["child6"], out["parent6"],
                           model.reaction_table.is_moment, out["gamma"], out["phi"],
                           out["gtv"], model.joint_table.first)


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
    """(m,) Gᵀ v: per component, the relative velocity its joint forbids (m/s or rad/s;
    a driven component's minus its law's rate), as the core computed it with `cols`."""
    return cols.gtv


JOINT_TOL = 1e-6
"""Relative size of φ (to the model's extent) and of Gᵀ v (to its largest speed) above
which a state is said to break a joint."""


def joint_errors(model: Model, state: State, cols: ReactionColumns | None = None,
                 enforced: np.ndarray | None = None, limit: int = 8,
                 gtv: np.ndarray | None = None) -> list[str]:
    """The enforced constraints (default: those of unknown reactions) that `state` breaks,
    as text: position errors φ ≠ 0 and relative velocities Gᵀ v ≠ 0 (the columns' `phi`
    and `gtv`, `mbody.equations.constraints`). At most
    `limit` are described; a last entry counts the rest."""
    rt = model.reaction_table
    if not len(rt.labels):
        return []
    if enforced is None:
        enforced = np.array([lab not in model.known_reactions for lab in rt.labels])

    v6 = np.concatenate((state.velocity, state.omega), axis=1)
    cols = reaction_columns(model, state) if cols is None else cols
    if gtv is None:  # (m,) Gᵀ v, unless the caller has it already
        gtv = cols.gtv
    ph = cols.phi
    size = float(np.ptp(state.position, axis=0).max()) if model.n > 1 else 0.0
    size = max(size, float(np.abs(model.joint_table.B_r_child).max()), 1e-3)
    speed = max(float(np.abs(v6).max()), 1e-3)
    out = []
    broken = (enforced & ((np.abs(ph) > JOINT_TOL * size)
                          | (np.abs(gtv) > JOINT_TOL * speed))).nonzero()[0]
    for k in broken[:limit]:
        unit = ("rad", "rad/s") if rt.is_moment[k] else ("m", "m/s")
        out.append(f"{rt.labels[k]} (phi {ph[k]:.3g} {unit[0]}, G^T v {gtv[k]:.3g} {unit[1]})")
    if len(broken) > limit:
        out.append(f"{len(broken) - limit} more")
    return out
