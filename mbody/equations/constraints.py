"""Joint constraints at position and acceleration level, one per reaction component.

Gᵀ is the velocity-level constraint Jacobian: ``Gᵀ v = φ̇`` (see `joints`). Here are the
other two levels, vectorised over the m components:

- ``phi(model, state)``: position errors φ (0 when the joint holds).
  force along e (parent-fixed joint axis): φ = e · (P_c − P_p), P_c and P_p the joint
  point carried by the child and by the parent;
  moment, revolute/cylindrical (Mx, My): the tilt of the child's joint z axis seen in
  the parent's joint frame, φ_x = −z_rel,y, φ_y = z_rel,x;
  moment, fixed/prismatic: the small-rotation vector of R_rel = E_pᵀ E_c,
  φ = ½ vee(R_rel − R_relᵀ); universal Mt: φ = −a · b (a on the parent, b on the child).
- ``gamma(model, state)``: γ = −Ġᵀ v, the velocity-product terms, so that the joints
  hold at acceleration level when ``Gᵀ v̇ = γ``. With w = e · (V_c(P) − V_p(P)):
  force:  γ = −[(ω_p × e) · (V_c(P) − V_p(P)) + e · (ω_c × (ω_c × ρ_c) − ω_p × ṡ)],
          ρ_c = P − x_c, s = P − x_p, ṡ = v_c + ω_c × ρ_c − v_p;
  moment: γ = −(ω_p × e) · (ω_c − ω_p);
  universal: γ = −ė · (ω_c − ω_p), ė = (ω_p × a) × b + a × (ω_c × b).
  All vectors in world axes; ω_p, v_p are 0 for ground.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mbody.equations.joints import ReactionColumns, constraint_velocity, reaction_columns
from mbody.equations.spatial import cross, matvec
from mbody.model.model import Model, State

if TYPE_CHECKING:
    import scipy.sparse as sp


def phi(model: Model, state: State, R: np.ndarray | None = None,
        cols: ReactionColumns | None = None) -> np.ndarray:
    """(m,) position errors of every reaction component's constraint (see module doc).

    Worked out per joint (the joint frames of `cols`, computed when not given), then
    picked per component.
    """
    rt = model.reaction_table
    jt = model.joint_table
    m = len(rt.labels)
    if m == 0:
        return np.zeros(0)
    if cols is None:

        cols = reaction_columns(model, state, R)
    Rp, Rc = cols.joint_Rp, cols.joint_Rc
    on_p = jt.parent >= 0
    x_p = state.position[np.where(on_p, jt.parent, 0)]
    x_p[~on_p] = 0.0
    d = cols.joint_W_P - (x_p + matvec(Rp, jt.B_r_parent))  # child's point − parent's
    j = rt.joint
    out = np.einsum("ij,ij->i", cols.W_e, d[j])  # forces: e · (P_c − P_p)
    if rt.link.any():  # a particle link's T: L − |P_c − P_p| (W_e = −(P_c − P_p) / |…|)
        out = out + rt.length
    mom = rt.rot_kind > 0
    if mom.any():
        jm = np.unique(j[mom])  # joints with moment components
        R_rel = np.zeros((len(jt.parent), 3, 3))
        R_rel[jm] = np.swapaxes(Rp[jm] @ jt.P_E3[jm], 1, 2) @ (Rc[jm] @ jt.C_E3[jm])
        A = R_rel[j]
        k = rt.axis - 3
        tilt = np.where(k == 0, -A[:, 1, 2], A[:, 0, 2])  # child's z axis in parent frame
        vee = 0.5 * np.stack((A[:, 2, 1] - A[:, 1, 2], A[:, 0, 2] - A[:, 2, 0],
                              A[:, 1, 0] - A[:, 0, 1]), axis=1)
        lock = vee[np.arange(m), np.clip(k, 0, 2)]
        out = np.where(rt.rot_kind == 1, tilt, np.where(rt.rot_kind == 2, lock, out))
        uni = rt.rot_kind == 3
        if uni.any():
            ju = j[uni]
            a = matvec(Rp[ju], jt.P_E3[ju, :, 2])
            b = matvec(Rc[ju], jt.C_axis2[ju])
            out[uni] = -np.einsum("ij,ij->i", a, b)
    return out


def gamma(model: Model, state: State, cols: ReactionColumns,
          R: np.ndarray | None = None) -> np.ndarray:
    """(m,) γ = −Ġᵀ v: the right-hand side of Gᵀ v̇ = γ (see module doc).

    Per joint, with D = V_c(P) − V_p(P): force components γ = −e · (D × ω_p + A),
    A = ω_c × (ω_c × ρ_c) − ω_p × ṡ; moment components γ = −e · (ω_c × ω_p).
    """
    rt = model.reaction_table
    jt = model.joint_table
    m = len(rt.labels)
    if m == 0:
        return np.zeros(0)
    on_p = jt.parent >= 0
    p = np.where(on_p, jt.parent, 0)
    Rp, Rc = cols.joint_Rp, cols.joint_Rc
    c = jt.child
    w_c = matvec(Rc, state.omega[c])
    w_p = matvec(Rp, state.omega[p])
    v_p = state.velocity[p]
    x_p = state.position[p]
    w_p[~on_p] = 0.0
    v_p[~on_p] = 0.0
    x_p[~on_p] = 0.0
    P = cols.joint_W_P
    rho = P - state.position[c]
    V_c = state.velocity[c] + cross(w_c, rho)
    D = V_c - v_p - cross(w_p, P - x_p)
    T = cross(D, w_p) + cross(w_c, cross(w_c, rho)) - cross(w_p, V_c - v_p)
    j = rt.joint
    moment = (rt.axis >= 3)[:, None]
    TU = np.where(moment, cross(w_c, w_p)[j], T[j]) if moment.any() else T[j]
    out = -np.einsum("ij,ij->i", cols.W_e, TU)
    if rt.link.any():  # particle links: γ = u · (ω_c×(ω_c×ρ_c) − ω_p×(ω_p×ρ_p)) + |ḋ⊥|² / |d|
        li = np.flatnonzero(rt.link)
        jl = j[li]
        rho_p = matvec(Rp[jl], jt.B_r_parent[jl])
        u = -cols.W_e[li]
        dd = V_c[jl] - v_p[jl] - cross(w_p[jl], rho_p)
        acc = (cross(w_c[jl], cross(w_c[jl], rho[jl]))
               - cross(w_p[jl], cross(w_p[jl], rho_p)))
        dist = np.linalg.norm(P[jl] - x_p[jl] - rho_p, axis=1)
        ud = np.einsum("ij,ij->i", u, dd)
        out[li] = (np.einsum("ij,ij->i", u, acc)
                   + (np.einsum("ij,ij->i", dd, dd) - ud * ud) / dist)
    uni = rt.axis == 6
    if uni.any():
        ju = j[uni]
        a = matvec(Rp[ju], jt.P_E3[ju, :, 2])
        b = matvec(Rc[ju], jt.C_axis2[ju])
        e_dot = cross(cross(w_p[ju], a), b) + cross(a, cross(w_c[ju], b))
        out[uni] = -np.einsum("ij,ij->i", e_dot, w_c[ju] - w_p[ju])
    return out


@dataclass(frozen=True)
class ConstraintJacobian:
    """The velocity-level constraint Jacobian of the joints, Φ_v = Gᵀ, with labels.

    matrix: (m, N) sparse; row k is the constraint that reaction component `rows[k]`
    enforces, column i the coordinate `columns[i]` (rows of the stacked equations:
    Newton in world axes, Euler in body axes). ``matrix @ v`` is the relative velocity
    each joint forbids; ``matrix @ v̇ = gamma`` holds for motions that keep the joints;
    `phi` are the position errors (0 when the joints are assembled).
    """

    matrix: sp.csr_matrix
    rows: list[str]
    columns: list[str]
    gamma: np.ndarray
    phi: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        return self.matrix.shape

    def toarray(self) -> np.ndarray:
        return self.matrix.toarray()

    def row(self, label: str) -> dict[str, float]:
        """The nonzero entries of one constraint row, by coordinate label."""
        r = self.matrix.getrow(self.rows.index(label)).tocoo()
        return {self.columns[j]: float(v) for j, v in zip(r.col, r.data, strict=True)}

    def __repr__(self) -> str:  # the dataclass's would print every label and the matrix
        m, n = self.matrix.shape
        worst = float(np.abs(self.phi).max()) if self.phi.size else 0.0
        return (f"<ConstraintJacobian G^T: {m} constraints x {n} coordinates, "
                f"{self.matrix.nnz} nonzero, max |phi| {worst:.3g}; .row(label), "
                f".toarray(), .rows, .columns>")


JOINT_TOL = 1e-6
"""Relative size of φ (to the model's extent) and of Gᵀ v (to its largest speed) above
which a state is said to break a joint."""


def joint_errors(model: Model, state: State, cols: ReactionColumns | None = None,
                 enforced: np.ndarray | None = None, limit: int = 8,
                 gtv: np.ndarray | None = None) -> list[str]:
    """The enforced constraints (default: those of unknown reactions) that `state` breaks,
    as text: position errors φ ≠ 0 and relative velocities Gᵀ v ≠ 0 (see `phi`). At most
    `limit` are described; a last entry counts the rest."""
    rt = model.reaction_table
    if not len(rt.labels):
        return []
    if enforced is None:
        enforced = np.array([lab not in model.known_reactions for lab in rt.labels])

    v6 = np.concatenate((state.velocity, state.omega), axis=1)
    cols = reaction_columns(model, state) if cols is None else cols
    if gtv is None:  # (m,) Gᵀ v, unless the caller has it already
        gtv = constraint_velocity(model, cols, state)
    ph = phi(model, state, cols=cols)
    size = float(np.ptp(state.position, axis=0).max()) if model.n > 1 else 0.0
    size = max(size, float(np.abs(model.joint_table.B_r_child).max()), 1e-3)
    speed = max(float(np.abs(v6).max()), 1e-3)
    out = []
    broken = np.flatnonzero(enforced & ((np.abs(ph) > JOINT_TOL * size)
                                        | (np.abs(gtv) > JOINT_TOL * speed)))
    for k in broken[:limit]:
        unit = ("rad", "rad/s") if rt.axis[k] >= 3 else ("m", "m/s")
        out.append(f"{rt.labels[k]} (phi {ph[k]:.3g} {unit[0]}, G^T v {gtv[k]:.3g} {unit[1]})")
    if len(broken) > limit:
        out.append(f"{len(broken) - limit} more")
    return out
