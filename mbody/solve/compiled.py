"""The compiled small-model path: one call evaluates a whole mechanism at one state,

    M v̇ + b = Q + G λ,    Gᵀ v̇ = γ (− 2 α Gᵀ v − α² φ with Baumgarte's terms),

written as plain loops for numba (``njit(cache=True)``): rotations, applied loads and
springs, gyroscopic terms, reaction columns, γ, φ, Gᵀ v, the Schur complement
S = G_Uᵀ M⁻¹ G_U in banded storage, its Cholesky factorisation, one round of iterative
refinement and the backward error, with nothing allocated per body in Python.

The formulas are those of the numpy path (`mbody.equations.kernels`, `mbody.equations.joints`,
`mbody.equations.constraints`, `mbody.solve.kkt`), which stays the general path (large models, and
machines without numba); `tests/test_compiled.py` holds both equal on random mechanisms
of every joint type. Nothing here is imported by ``import mbody``: `mbody.equations.plan` loads
this module (and numba) only for models that are evaluated many times.

Packing (`pack_model`): numba's dispatcher costs about 0.1 µs per argument, so the model
is passed as one float and one int array. `F` holds gravity (3), then per body
[mass, J (9, row-major), J⁻¹ (9)], per point load `B_r` (3), per spring
[r_a (3), r_b (3), stiffness, rest length, damping], per joint
[B_r_child (3), B_r_parent (3), C_axis2 (3), P_E3 (9), C_E3 (9), link length]. `I` holds
the sizes [n, loads, springs, joints, components], then per load [body, in_body, couple],
per spring [a, b], per joint [parent, child, flags (1 particle link, 2 particle parent)],
per component [joint, axis, rot_kind]
(see `mbody.model.ReactionTable`). The unknown components' structure for one set of
unknowns is a third int array (`pack_unknowns`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

# Column offsets of the packed per-item rows (see the module docstring).
BODY_W, MASS, J0, JINV0 = 19, 0, 1, 10
SPRING_W, RA, RB, STIFF, REST, DAMP = 9, 0, 3, 6, 7, 8
JOINT_W, BRC, BRP, CAX2, PE3, CE3, LLEN = 28, 0, 3, 6, 9, 18, 27
LINK_AXIS, J_LINK, J_PARTICLE_PARENT = -1, 1, 2  # as mbody.conventions; joint flags
HEADER = 5
JOINT_TOL = 1e-6  # as mbody.equations.constraints.JOINT_TOL
# as mbody.solve.nullspace: the robust solve's tolerances
G_RANK_RTOL, PIVOT_RTOL, SINGULAR_RTOL, STAB_RTOL, REFINE_STEPS = 1e-12, 1e-6, 1e-14, 1e-4, 2
# exactly redundant columns: G_j − G_I x_j below this (relative, moment rows over the
# length scale), and a consistent answer (backward error below REDUNDANT_BERR)
DEPENDENT_RTOL, REDUNDANT_BERR = 1e-10, 1e-13
DROPPED_RTOL = 1e-13  # as mbody.simulate.projection: an exactly redundant constraint's pivot ratio
SPLIT = 134217729.0  # 2**27 + 1, Dekker's splitting constant

# info[] slots written by `solve`; ST_PATH: 0 Cholesky of S, 1 null-space solve;
# ST_SINGULAR: 0, or 1 + 6 body + row of a motion without mass or inertia
ST_RANK, ST_BERR, ST_BROKEN, ST_MU, ST_PATH, ST_SINGULAR = 0, 1, 2, 3, 4, 5
INFO = 6
# info[] slots written by `project`: largest position step, largest velocity change,
# `_geometric_ratio` at the starting positions, singular-mass code (0 when none)
PR_STEP, PR_VELOCITY, PR_RATIO, PR_SINGULAR = 0, 1, 2, 3
PROJECT_INFO = 4


def pack_model(model) -> tuple[np.ndarray, np.ndarray]:
    """(F, I): the model's constants as one float and one int array (module docstring)."""
    n = model.n
    ft, sp, rt, jt = model.forces, model.springs, model.reaction_table, model.joint_table
    k, s, nj, m = len(ft.names), len(sp.names), len(jt.parent), len(rt.labels)
    bodies = np.concatenate((np.asarray(model.mass, float)[:, None],
                             np.asarray(model.J).reshape(n, 9),
                             np.asarray(model.J_inv).reshape(n, 9)), axis=1)
    springs = np.concatenate((sp.r_a, sp.r_b, sp.stiffness[:, None],
                              sp.rest_length[:, None], sp.damping[:, None]), axis=1)
    joints = np.concatenate((jt.B_r_child, jt.B_r_parent, jt.C_axis2,
                             jt.P_E3.reshape(nj, 9), jt.C_E3.reshape(nj, 9),
                             jt.length[:, None]), axis=1)
    flags = J_LINK * jt.link.astype(np.int64) + J_PARTICLE_PARENT * jt.particle_parent
    F = np.concatenate((np.asarray(model.gravity, float), bodies.ravel(),
                        np.asarray(ft.B_r, float).ravel(), springs.ravel(), joints.ravel()))
    Ii = np.concatenate((
        [n, k, s, nj, m],
        np.stack((ft.body, ft.in_body, ft.couple), axis=1).ravel(),
        np.stack((sp.a, sp.b), axis=1).ravel(),
        np.stack((jt.parent, jt.child, flags), axis=1).ravel(),
        np.stack((rt.joint, rt.axis, rt.rot_kind), axis=1).ravel(),
    )).astype(np.int64)
    return np.ascontiguousarray(F), Ii


def pack_unknowns(model, U: np.ndarray) -> np.ndarray:
    """The int array describing the unknown components U (in their solve order).

    Layout: [mu, bw, nnz], U (mu), inc_ptr (n + 1), inc (nnz × [position in U, side]):
    for each body, the unknown components acting on it (side 0 child, 1 parent), so
    that S = G_Uᵀ M⁻¹ G_U is summed body by body; bw is S's half bandwidth in U's order.
    """
    rt = model.reaction_table
    n, mu = model.n, len(U)
    pos = np.arange(mu)
    body = np.concatenate((rt.child[U], rt.parent[U]))
    side = np.concatenate((np.zeros(mu, np.int64), np.ones(mu, np.int64)))
    where = np.concatenate((pos, pos))
    keep = body >= 0
    body, side, where = body[keep], side[keep], where[keep]
    order = np.lexsort((where, body))
    body, side, where = body[order], side[order], where[order]
    inc_ptr = np.searchsorted(body, np.arange(n + 1))
    bw = 0
    for b in range(n):  # per body, at plan time only
        w = where[inc_ptr[b]:inc_ptr[b + 1]]
        if len(w):
            bw = max(bw, int(w.max() - w.min()))
    inc = np.stack((where, side), axis=1).ravel()
    return np.concatenate(([mu, bw, len(where)], np.asarray(U), inc_ptr, inc)).astype(np.int64)


# -- small vector helpers ------------------------------------------------------------------
@njit(cache=True, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True)
def _rotations(q: np.ndarray) -> np.ndarray:
    """(n, 3, 3) W_R_B from (n, 4) quaternions [w, x, y, z], normalised first."""
    n = q.shape[0]
    R = np.empty((n, 3, 3))
    for i in range(n):
        s = 1.0 / np.sqrt(q[i, 0] ** 2 + q[i, 1] ** 2 + q[i, 2] ** 2 + q[i, 3] ** 2)
        w, x, y, z = q[i, 0] * s, q[i, 1] * s, q[i, 2] * s, q[i, 3] * s
        xx, yy, zz = x * x, y * y, z * z
        xy, xz, yz = x * y, x * z, y * z
        wx, wy, wz = w * x, w * y, w * z
        R[i, 0, 0] = 1 - 2 * (yy + zz)
        R[i, 0, 1] = 2 * (xy - wz)
        R[i, 0, 2] = 2 * (xz + wy)
        R[i, 1, 0] = 2 * (xy + wz)
        R[i, 1, 1] = 1 - 2 * (xx + zz)
        R[i, 1, 2] = 2 * (yz - wx)
        R[i, 2, 0] = 2 * (xz - wy)
        R[i, 2, 1] = 2 * (yz + wx)
        R[i, 2, 2] = 1 - 2 * (xx + yy)
    return R


class PackedModel(NamedTuple):
    """Views of `pack_model`'s (F, I) by item (numba builds and reads it as a plain tuple,
    with names): per-item rows at the column offsets above."""

    gravity: np.ndarray  # (3,)
    bodies: np.ndarray  # (n, BODY_W)
    B_r: np.ndarray  # (loads, 3) application points, body axes
    springs: np.ndarray  # (springs, SPRING_W)
    joints: np.ndarray  # (joints, JOINT_W)
    loads_i: np.ndarray  # (loads, 3) [body, in_body, couple]
    springs_i: np.ndarray  # (springs, 2) [a, b]
    joints_i: np.ndarray  # (joints, 3) [parent, child, flags]
    comps_i: np.ndarray  # (components, 3) [joint, axis, rot_kind]


class Evaluation(NamedTuple):
    """What `_evaluate` returns: accelerations (n, 6) [a_G world, ω̇ body axes], λ_U (mu,),
    φ and Gᵀ v (m,), rank of G_U, backward error, not-unique flags (mu,), the solve's path
    and the singular-mass code (see `_constrained`)."""

    acc: np.ndarray
    lamU: np.ndarray
    phi: np.ndarray
    gtv: np.ndarray
    rank: int
    berr: float
    nonunique: np.ndarray
    path: int
    singular: int


@njit(cache=True)
def _unpack(F, I):
    n, k, s, nj, m = I[0], I[1], I[2], I[3], I[4]
    o = 3
    bodies = F[o:o + n * BODY_W].reshape(n, BODY_W)
    o += n * BODY_W
    B_r = F[o:o + 3 * k].reshape(k, 3)
    o += 3 * k
    springs = F[o:o + s * SPRING_W].reshape(s, SPRING_W)
    o += s * SPRING_W
    joints = F[o:o + nj * JOINT_W].reshape(nj, JOINT_W)
    o = HEADER
    loads_i = I[o:o + 3 * k].reshape(k, 3)
    o += 3 * k
    springs_i = I[o:o + 2 * s].reshape(s, 2)
    o += 2 * s
    joints_i = I[o:o + 3 * nj].reshape(nj, 3)
    o += 3 * nj
    comps_i = I[o:o + 3 * m].reshape(m, 3)
    return PackedModel(F[0:3], bodies, B_r, springs, joints, loads_i, springs_i, joints_i,
                       comps_i)


# -- Q − b ----------------------------------------------------------------------------------
@njit(cache=True)
def _net_wrench(gravity, bodies, B_r, springs, loads_i, springs_i, x, R, v, w, fvec, out):
    """out (n, 6) = Q − b: [W_F (world); B_M − ω × J ω (body axes)] (module doc of kernels)."""
    n = x.shape[0]
    for i in range(n):
        m = bodies[i, MASS]
        for c in range(3):
            out[i, c] = m * gravity[c]
            out[i, 3 + c] = 0.0
    for j in range(loads_i.shape[0]):
        b, in_body, couple = loads_i[j, 0], loads_i[j, 1], loads_i[j, 2]
        f0, f1, f2 = fvec[j, 0], fvec[j, 1], fvec[j, 2]
        if in_body:  # body-axis components: the world force is R f
            W0 = R[b, 0, 0] * f0 + R[b, 0, 1] * f1 + R[b, 0, 2] * f2
            W1 = R[b, 1, 0] * f0 + R[b, 1, 1] * f1 + R[b, 1, 2] * f2
            W2 = R[b, 2, 0] * f0 + R[b, 2, 1] * f1 + R[b, 2, 2] * f2
            B0, B1, B2 = f0, f1, f2
        else:
            W0, W1, W2 = f0, f1, f2
            B0 = R[b, 0, 0] * f0 + R[b, 1, 0] * f1 + R[b, 2, 0] * f2
            B1 = R[b, 0, 1] * f0 + R[b, 1, 1] * f1 + R[b, 2, 1] * f2
            B2 = R[b, 0, 2] * f0 + R[b, 1, 2] * f1 + R[b, 2, 2] * f2
        if couple:
            out[b, 3] += B0
            out[b, 4] += B1
            out[b, 5] += B2
        else:
            out[b, 0] += W0
            out[b, 1] += W1
            out[b, 2] += W2
            m0, m1, m2 = _cross(B_r[j, 0], B_r[j, 1], B_r[j, 2], B0, B1, B2)
            out[b, 3] += m0
            out[b, 4] += m1
            out[b, 5] += m2
    for j in range(springs_i.shape[0]):
        _spring(springs[j], springs_i[j, 0], springs_i[j, 1], x, R, v, w, out)
    for i in range(n):  # − ω × (J ω)
        Jm = bodies[i, J0:J0 + 9]
        w0, w1, w2 = w[i, 0], w[i, 1], w[i, 2]
        h0 = Jm[0] * w0 + Jm[1] * w1 + Jm[2] * w2
        h1 = Jm[3] * w0 + Jm[4] * w1 + Jm[5] * w2
        h2 = Jm[6] * w0 + Jm[7] * w1 + Jm[8] * w2
        g0, g1, g2 = _cross(w0, w1, w2, h0, h1, h2)
        out[i, 3] -= g0
        out[i, 4] -= g1
        out[i, 5] -= g2


@njit(cache=True)
def _point(body, r, x, R, v, w):
    """World position and velocity of body point r (body axes); body −1: r is a world
    point at rest. P = x + R r, V = v + R (ω × r)."""
    if body < 0:
        return r[0], r[1], r[2], 0.0, 0.0, 0.0
    c0, c1, c2 = _cross(w[body, 0], w[body, 1], w[body, 2], r[0], r[1], r[2])
    P, V = np.empty(3), np.empty(3)
    for a in range(3):
        P[a] = x[body, a] + R[body, a, 0] * r[0] + R[body, a, 1] * r[1] + R[body, a, 2] * r[2]
        V[a] = v[body, a] + R[body, a, 0] * c0 + R[body, a, 1] * c1 + R[body, a, 2] * c2
    return P[0], P[1], P[2], V[0], V[1], V[2]


@njit(cache=True)
def _spring(row, a, b, x, R, v, w, out):
    """Spring-damper: T = k (L − L0) + c L̇ along u = (P_b − P_a) / L; +T u on end a,
    −T u on end b, each with its moment B_r × (W_R_Bᵀ f)."""
    ra, rb = row[RA:RA + 3], row[RB:RB + 3]
    pa0, pa1, pa2, va0, va1, va2 = _point(a, ra, x, R, v, w)
    pb0, pb1, pb2, vb0, vb1, vb2 = _point(b, rb, x, R, v, w)
    d0, d1, d2 = pb0 - pa0, pb1 - pa1, pb2 - pa2
    L = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    u0 = u1 = u2 = 0.0
    if L > 1e-12:
        u0, u1, u2 = d0 / L, d1 / L, d2 / L
    T = row[STIFF] * (L - row[REST]) + row[DAMP] * (
        u0 * (vb0 - va0) + u1 * (vb1 - va1) + u2 * (vb2 - va2))
    f = np.array((T * u0, T * u1, T * u2))
    for end, r, sign in ((a, ra, 1.0), (b, rb, -1.0)):
        if end >= 0:
            g0, g1, g2 = sign * f[0], sign * f[1], sign * f[2]
            out[end, 0] += g0
            out[end, 1] += g1
            out[end, 2] += g2
            B0 = R[end, 0, 0] * g0 + R[end, 1, 0] * g1 + R[end, 2, 0] * g2
            B1 = R[end, 0, 1] * g0 + R[end, 1, 1] * g1 + R[end, 2, 1] * g2
            B2 = R[end, 0, 2] * g0 + R[end, 1, 2] * g1 + R[end, 2, 2] * g2
            m0, m1, m2 = _cross(r[0], r[1], r[2], B0, B1, B2)
            out[end, 3] += m0
            out[end, 4] += m1
            out[end, 5] += m2


# -- reaction columns, γ, φ, Gᵀ v -------------------------------------------------------------
@njit(cache=True)
def _columns(joints, joints_i, comps_i, x, R, v, w, child6, parent6, gamma, phi, gtv):
    """Per component: its columns of G (child6, parent6 (m, 6)), γ = −Ġᵀ v, φ and Gᵀ v
    (formulas in `mbody.equations.joints` and `mbody.equations.constraints`)."""
    nj, m = joints_i.shape[0], comps_i.shape[0]
    W_E = np.empty((nj, 3, 3))
    Rrel = np.empty((nj, 3, 3))
    P = np.empty((nj, 3))
    Brp = np.empty((nj, 3))  # the parent's material point at P, parent axes
    d = np.empty((nj, 3))  # child's joint point − parent's
    T = np.empty((nj, 3))  # force components: γ = −e · T
    wc = np.empty((nj, 3))
    wp = np.empty((nj, 3))
    Rp = np.empty((3, 3))
    for j in range(nj):
        p, c = joints_i[j, 0], joints_i[j, 1]
        row = joints[j]
        if p >= 0:
            Rp[:, :] = R[p]
        else:
            Rp[:, :] = 0.0
            Rp[0, 0] = Rp[1, 1] = Rp[2, 2] = 1.0
        Rc = R[c]
        PE, CE = row[PE3:PE3 + 9], row[CE3:CE3 + 9]
        for a in range(3):
            for b in range(3):
                W_E[j, a, b] = Rp[a, 0] * PE[b] + Rp[a, 1] * PE[3 + b] + Rp[a, 2] * PE[6 + b]
        for a in range(3):
            P[j, a] = x[c, a] + Rc[a, 0] * row[BRC] + Rc[a, 1] * row[BRC + 1] \
                + Rc[a, 2] * row[BRC + 2]
        xp0 = xp1 = xp2 = 0.0
        vp0 = vp1 = vp2 = 0.0
        if p >= 0:
            xp0, xp1, xp2 = x[p, 0], x[p, 1], x[p, 2]
            vp0, vp1, vp2 = v[p, 0], v[p, 1], v[p, 2]
        s0, s1, s2 = P[j, 0] - xp0, P[j, 1] - xp1, P[j, 2] - xp2
        for a in range(3):
            Brp[j, a] = Rp[0, a] * s0 + Rp[1, a] * s1 + Rp[2, a] * s2
            d[j, a] = P[j, a] - (
                (xp0, xp1, xp2)[a] + Rp[a, 0] * row[BRP] + Rp[a, 1] * row[BRP + 1]
                + Rp[a, 2] * row[BRP + 2])
            wc[j, a] = Rc[a, 0] * w[c, 0] + Rc[a, 1] * w[c, 1] + Rc[a, 2] * w[c, 2]
            wp[j, a] = 0.0
            if p >= 0:
                wp[j, a] = Rp[a, 0] * w[p, 0] + Rp[a, 1] * w[p, 1] + Rp[a, 2] * w[p, 2]
        rho0, rho1, rho2 = P[j, 0] - x[c, 0], P[j, 1] - x[c, 1], P[j, 2] - x[c, 2]
        c0, c1, c2 = _cross(wc[j, 0], wc[j, 1], wc[j, 2], rho0, rho1, rho2)
        Vc0, Vc1, Vc2 = v[c, 0] + c0, v[c, 1] + c1, v[c, 2] + c2
        e0, e1, e2 = _cross(wp[j, 0], wp[j, 1], wp[j, 2], s0, s1, s2)
        D0, D1, D2 = Vc0 - vp0 - e0, Vc1 - vp1 - e1, Vc2 - vp2 - e2
        t0, t1, t2 = _cross(D0, D1, D2, wp[j, 0], wp[j, 1], wp[j, 2])
        a0, a1, a2 = _cross(wc[j, 0], wc[j, 1], wc[j, 2], c0, c1, c2)
        b0, b1, b2 = _cross(wp[j, 0], wp[j, 1], wp[j, 2], Vc0 - vp0, Vc1 - vp1, Vc2 - vp2)
        T[j, 0], T[j, 1], T[j, 2] = t0 + a0 - b0, t1 + a1 - b1, t2 + a2 - b2
        # R_rel = (Rp P_E3)ᵀ (Rc C_E3), for the moment components' φ
        for a in range(3):
            for b in range(3):
                acc = 0.0
                for k in range(3):
                    ck = Rc[k, 0] * CE[b] + Rc[k, 1] * CE[3 + b] + Rc[k, 2] * CE[6 + b]
                    acc += W_E[j, k, a] * ck
                Rrel[j, a, b] = acc
    for i in range(m):
        j, axis, rot = comps_i[i, 0], comps_i[i, 1], comps_i[i, 2]
        p, c = joints_i[j, 0], joints_i[j, 1]
        kk = axis % 3
        e0, e1, e2 = W_E[j, 0, kk], W_E[j, 1, kk], W_E[j, 2, kk]
        row = joints[j]
        PE = row[PE3:PE3 + 9]
        Bp0, Bp1, Bp2 = PE[kk], PE[3 + kk], PE[6 + kk]  # axis fixed in the parent
        if axis == 6:  # universal: e = a × b / |a × b|, a on the parent, b on the child
            A0, A1, A2 = W_E[j, 0, 2], W_E[j, 1, 2], W_E[j, 2, 2]
            cx = row[CAX2:CAX2 + 3]
            b0 = R[c, 0, 0] * cx[0] + R[c, 0, 1] * cx[1] + R[c, 0, 2] * cx[2]
            b1 = R[c, 1, 0] * cx[0] + R[c, 1, 1] * cx[1] + R[c, 1, 2] * cx[2]
            b2 = R[c, 2, 0] * cx[0] + R[c, 2, 1] * cx[1] + R[c, 2, 2] * cx[2]
            e0, e1, e2 = _cross(A0, A1, A2, b0, b1, b2)
            nrm = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
            e0, e1, e2 = e0 / nrm, e1 / nrm, e2 / nrm
            if p >= 0:
                Bp0 = R[p, 0, 0] * e0 + R[p, 1, 0] * e1 + R[p, 2, 0] * e2
                Bp1 = R[p, 0, 1] * e0 + R[p, 1, 1] * e1 + R[p, 2, 1] * e2
                Bp2 = R[p, 0, 2] * e0 + R[p, 1, 2] * e1 + R[p, 2, 2] * e2
            else:
                Bp0, Bp1, Bp2 = e0, e1, e2
            pa0, pa1, pa2 = _cross(wp[j, 0], wp[j, 1], wp[j, 2], A0, A1, A2)
            q0, q1, q2 = _cross(pa0, pa1, pa2, b0, b1, b2)
            cb0, cb1, cb2 = _cross(wc[j, 0], wc[j, 1], wc[j, 2], b0, b1, b2)
            r0, r1, r2 = _cross(A0, A1, A2, cb0, cb1, cb2)
            gamma[i] = -((q0 + r0) * (wc[j, 0] - wp[j, 0]) + (q1 + r1) * (wc[j, 1] - wp[j, 1])
                         + (q2 + r2) * (wc[j, 2] - wp[j, 2]))
            phi[i] = -(A0 * b0 + A1 * b1 + A2 * b2)
        Rc = R[c]
        Bc0 = Rc[0, 0] * e0 + Rc[1, 0] * e1 + Rc[2, 0] * e2
        Bc1 = Rc[0, 1] * e0 + Rc[1, 1] * e1 + Rc[2, 1] * e2
        Bc2 = Rc[0, 2] * e0 + Rc[1, 2] * e1 + Rc[2, 2] * e2
        if axis >= 3:
            child6[i, 0] = child6[i, 1] = child6[i, 2] = 0.0
            child6[i, 3], child6[i, 4], child6[i, 5] = Bc0, Bc1, Bc2
            parent6[i, 3], parent6[i, 4], parent6[i, 5] = -Bp0, -Bp1, -Bp2
            if axis != 6:
                k0, k1, k2 = _cross(wc[j, 0], wc[j, 1], wc[j, 2], wp[j, 0], wp[j, 1], wp[j, 2])
                gamma[i] = -(e0 * k0 + e1 * k1 + e2 * k2)
                A = Rrel[j]
                kq = axis - 3
                if rot == 1:  # tilt of the child's joint z axis in the parent's frame
                    phi[i] = -A[1, 2] if kq == 0 else A[0, 2]
                else:  # small-rotation vector ½ vee(R_rel − R_relᵀ)
                    if kq == 0:
                        phi[i] = 0.5 * (A[2, 1] - A[1, 2])
                    elif kq == 1:
                        phi[i] = 0.5 * (A[0, 2] - A[2, 0])
                    else:
                        phi[i] = 0.5 * (A[1, 0] - A[0, 1])
        elif axis == LINK_AXIS:  # a particle link's tension T (mbody.equations.joints, constraints)
            _link(row, p, c, x, R, v, w, d[j], wc[j], wp[j], child6[i], parent6[i], gamma, phi,
                  i)
        else:
            child6[i, 0], child6[i, 1], child6[i, 2] = e0, e1, e2
            child6[i, 3], child6[i, 4], child6[i, 5] = _cross(
                row[BRC], row[BRC + 1], row[BRC + 2], Bc0, Bc1, Bc2)
            m0, m1, m2 = _cross(Brp[j, 0], Brp[j, 1], Brp[j, 2], Bp0, Bp1, Bp2)
            parent6[i, 3], parent6[i, 4], parent6[i, 5] = -m0, -m1, -m2
            gamma[i] = -(e0 * T[j, 0] + e1 * T[j, 1] + e2 * T[j, 2])
            phi[i] = e0 * d[j, 0] + e1 * d[j, 1] + e2 * d[j, 2]
        parent6[i, 0], parent6[i, 1], parent6[i, 2] = -child6[i, 0], -child6[i, 1], -child6[i, 2]
        if joints_i[j, 2] & J_PARTICLE_PARENT:  # forces act at the particle: no moment
            parent6[i, 3] = parent6[i, 4] = parent6[i, 5] = 0.0
        s = 0.0
        for a in range(3):
            s += child6[i, a] * v[c, a] + child6[i, 3 + a] * w[c, a]
        if p >= 0:
            for a in range(3):
                s += parent6[i, a] * v[p, a] + parent6[i, 3 + a] * w[p, a]
        else:
            for a in range(6):
                parent6[i, a] = 0.0
        gtv[i] = s


@njit(cache=True)
def _link(row, p, c, x, R, v, w, dj, wcj, wpj, child6, parent6, gamma, phi, i):
    """A particle link's column, γ and φ: d = P_c − P_p, u = d / |d|, e = −u (on the
    child), φ = L − |d|, γ = u · (ω_c×(ω_c×ρ_c) − ω_p×(ω_p×ρ_p)) + (|ḋ|² − (u·ḋ)²) / |d|."""
    dist = np.sqrt(dj[0] ** 2 + dj[1] ** 2 + dj[2] ** 2)
    u0, u1, u2 = dj[0] / dist, dj[1] / dist, dj[2] / dist
    e0, e1, e2 = -u0, -u1, -u2
    Rc = R[c]
    Bc0 = Rc[0, 0] * e0 + Rc[1, 0] * e1 + Rc[2, 0] * e2
    Bc1 = Rc[0, 1] * e0 + Rc[1, 1] * e1 + Rc[2, 1] * e2
    Bc2 = Rc[0, 2] * e0 + Rc[1, 2] * e1 + Rc[2, 2] * e2
    child6[0], child6[1], child6[2] = e0, e1, e2
    child6[3], child6[4], child6[5] = _cross(row[BRC], row[BRC + 1], row[BRC + 2],
                                             Bc0, Bc1, Bc2)
    rc0 = Rc[0, 0] * row[BRC] + Rc[0, 1] * row[BRC + 1] + Rc[0, 2] * row[BRC + 2]
    rc1 = Rc[1, 0] * row[BRC] + Rc[1, 1] * row[BRC + 1] + Rc[1, 2] * row[BRC + 2]
    rc2 = Rc[2, 0] * row[BRC] + Rc[2, 1] * row[BRC + 1] + Rc[2, 2] * row[BRC + 2]
    rp0, rp1, rp2 = row[BRP], row[BRP + 1], row[BRP + 2]
    vp0 = vp1 = vp2 = 0.0
    if p >= 0:
        Rp = R[p]
        Bp0 = Rp[0, 0] * e0 + Rp[1, 0] * e1 + Rp[2, 0] * e2
        Bp1 = Rp[0, 1] * e0 + Rp[1, 1] * e1 + Rp[2, 1] * e2
        Bp2 = Rp[0, 2] * e0 + Rp[1, 2] * e1 + Rp[2, 2] * e2
        m0, m1, m2 = _cross(row[BRP], row[BRP + 1], row[BRP + 2], Bp0, Bp1, Bp2)
        parent6[3], parent6[4], parent6[5] = -m0, -m1, -m2
        rp0 = Rp[0, 0] * row[BRP] + Rp[0, 1] * row[BRP + 1] + Rp[0, 2] * row[BRP + 2]
        rp1 = Rp[1, 0] * row[BRP] + Rp[1, 1] * row[BRP + 1] + Rp[1, 2] * row[BRP + 2]
        rp2 = Rp[2, 0] * row[BRP] + Rp[2, 1] * row[BRP + 1] + Rp[2, 2] * row[BRP + 2]
        vp0, vp1, vp2 = v[p, 0], v[p, 1], v[p, 2]
    else:
        parent6[3] = parent6[4] = parent6[5] = 0.0
        rp0 = rp1 = rp2 = 0.0  # ground: P_p is a world point at rest, ω_p = 0
    k0, k1, k2 = _cross(wcj[0], wcj[1], wcj[2], rc0, rc1, rc2)
    f0, f1, f2 = _cross(wpj[0], wpj[1], wpj[2], rp0, rp1, rp2)
    dd0 = v[c, 0] + k0 - vp0 - f0
    dd1 = v[c, 1] + k1 - vp1 - f1
    dd2 = v[c, 2] + k2 - vp2 - f2
    a0, a1, a2 = _cross(wcj[0], wcj[1], wcj[2], k0, k1, k2)
    b0, b1, b2 = _cross(wpj[0], wpj[1], wpj[2], f0, f1, f2)
    ud = u0 * dd0 + u1 * dd1 + u2 * dd2
    gamma[i] = (u0 * (a0 - b0) + u1 * (a1 - b1) + u2 * (a2 - b2)
                + (dd0 * dd0 + dd1 * dd1 + dd2 * dd2 - ud * ud) / dist)
    phi[i] = row[LLEN] - dist


# -- the constrained solve ---------------------------------------------------------------------
@njit(cache=True)
def _minv(bodies, i, g, out):
    """out (6,) = M_i⁻¹ g (6,): [g_N / m, J⁻¹ g_E]."""
    m = bodies[i, MASS]
    Ji = bodies[i, JINV0:JINV0 + 9]
    out[0], out[1], out[2] = g[0] / m, g[1] / m, g[2] / m
    for a in range(3):
        out[3 + a] = Ji[3 * a] * g[3] + Ji[3 * a + 1] * g[4] + Ji[3 * a + 2] * g[5]


@njit(cache=True)
def _side(child6, parent6, comp, side):
    return child6[comp] if side == 0 else parent6[comp]


@njit(cache=True)
def _gt(U, comps_i, joints_i, child6, parent6, a6, out):
    """out (mu,) = G_Uᵀ a for per-body rows a6 (n, 6)."""
    for k in range(U.shape[0]):
        i = U[k]
        j = comps_i[i, 0]
        p, c = joints_i[j, 0], joints_i[j, 1]
        s = 0.0
        for r in range(6):
            s += child6[i, r] * a6[c, r]
        if p >= 0:
            for r in range(6):
                s += parent6[i, r] * a6[p, r]
        out[k] = s


@njit(cache=True)
def _add_g(U, comps_i, joints_i, child6, parent6, lam, out, sign):
    """out (n, 6) += sign · G_U λ."""
    for k in range(U.shape[0]):
        i = U[k]
        j = comps_i[i, 0]
        p, c = joints_i[j, 0], joints_i[j, 1]
        f = sign * lam[k]
        for r in range(6):
            out[c, r] += child6[i, r] * f
        if p >= 0:
            for r in range(6):
                out[p, r] += parent6[i, r] * f


@njit(cache=True)
def _band_cholesky(Sb, bw, rtol, stop):
    """In place: lower banded S (Sb[i, i − j] = S_ij) -> its Cholesky factor L. A squared
    pivot that keeps no more than `rtol` of its diagonal entry stops the factorisation
    (`stop`: returns −1) or leaves its column out (L's column 0, as a pivoted Cholesky
    would). Returns the smallest ratio of a kept squared pivot to its diagonal entry."""
    mu = Sb.shape[0]
    worst = 1.0
    for i in range(mu):
        for j in range(max(0, i - bw), i + 1):
            s = Sb[i, i - j]
            for k in range(max(0, i - bw), j):
                s -= Sb[i, i - k] * Sb[j, j - k]
            if i == j:
                if not s > rtol * Sb[i, 0]:
                    if stop:
                        return -1.0
                    Sb[i, 0] = 0.0
                else:
                    worst = min(worst, s / Sb[i, 0])
                    Sb[i, 0] = np.sqrt(s)
            else:
                Sb[i, i - j] = s / Sb[j, 0] if Sb[j, 0] > 0.0 else 0.0
    return worst


@njit(cache=True)
def _cholesky_band(Sb, bw):
    """In place: lower banded S -> its Cholesky factor L. Returns False when a squared
    pivot keeps no more than PIVOT_RTOL of its diagonal entry (redundant constraints, a
    position near a singular one, extreme mass ratios: the null-space solve takes over),
    as `mbody.solve.kkt`."""
    return _band_cholesky(Sb, bw, PIVOT_RTOL, True) >= 0.0


@njit(cache=True)
def _cho_solve_band(Lb, bw, r):
    """r (mu,) <- S⁻¹ r for S = L Lᵀ in lower banded storage."""
    mu = Lb.shape[0]
    for i in range(mu):
        s = r[i]
        for k in range(max(0, i - bw), i):
            s -= Lb[i, i - k] * r[k]
        r[i] = s / Lb[i, 0]
    for i in range(mu - 1, -1, -1):
        s = r[i]
        for k in range(i + 1, min(mu, i + bw + 1)):
            s -= Lb[k, k - i] * r[k]
        r[i] = s / Lb[i, 0]


@njit(cache=True)
def _schur(bodies, child6, parent6, U, inc_ptr, inc, S, banded):
    """S = G_Uᵀ M⁻¹ G_U summed body by body over the components acting on it: the lower
    triangle in banded storage (S[i, i − j]) or, with `banded` False, all of it."""
    h = np.empty(6)
    for b in range(inc_ptr.shape[0] - 1):
        for x in range(inc_ptr[b], inc_ptr[b + 1]):
            kx, sx = inc[x, 0], inc[x, 1]
            _minv(bodies, b, _side(child6, parent6, U[kx], sx), h)
            for y in range(inc_ptr[b], inc_ptr[b + 1]):
                ky, sy = inc[y, 0], inc[y, 1]
                if ky <= kx:
                    iy = U[ky]  # indexed, not a view: this is the innermost loop
                    s = 0.0
                    if sy == 0:
                        for r in range(6):
                            s += child6[iy, r] * h[r]
                    else:
                        for r in range(6):
                            s += parent6[iy, r] * h[r]
                    if banded:
                        S[kx, kx - ky] += s
                    else:
                        S[kx, ky] += s
                        if ky != kx:
                            S[ky, kx] += s


@njit(cache=True)
def _constrained(bodies, joints_i, comps_i, Iu, child6, parent6, r6, gam, stab, planar,
                 refine, acc, lamU, nonunique):
    """Solve M v̇ − G_U λ = r6, G_Uᵀ v̇ = γ_U through S = G_Uᵀ M⁻¹ G_U: banded Cholesky
    (one round of iterative refinement when the backward error exceeds 1e-15 and
    `refine`), or, when its pivots are not trusted, the null-space solve
    (`_null_space`): minimum-norm λ with `nonunique` (mu,) marking the components that
    redundant constraints leave undetermined. Returns (rank of G_U, backward error,
    path: 0 Cholesky / 1 null space / 2 pivoted Cholesky (redundant), singular-mass
    code)."""
    n = r6.shape[0]
    mu, bw, nnz = Iu[0], Iu[1], Iu[2]
    U = Iu[3:3 + mu]
    inc_ptr = Iu[3 + mu:4 + mu + n]
    inc = Iu[4 + mu + n:4 + mu + n + 2 * nnz].reshape(nnz, 2)
    for i in range(n):
        _minv(bodies, i, r6[i], acc[i])
    nonunique[:] = False
    if mu == 0:
        return 0, 0.0, 0, 0
    Sb = np.zeros((mu, bw + 1))
    _schur(bodies, child6, parent6, U, inc_ptr, inc, Sb, True)
    # λ = S⁻¹ (γ − G_Uᵀ M⁻¹ r), v̇ = M⁻¹ (r + G_U λ)
    _gt(U, comps_i, joints_i, child6, parent6, acc, lamU)
    for k in range(mu):
        lamU[k] = gam[k] - lamU[k]
    # ‖K‖_F² = ‖M‖_F² + 2 ‖G_U‖_F², for the backward error
    nk = 0.0
    for i in range(n):
        nk += 3.0 * bodies[i, MASS] ** 2
        for a in range(9):
            nk += bodies[i, J0 + a] ** 2
    for k in range(mu):
        i = U[k]
        for r in range(6):
            nk += 2.0 * child6[i, r] ** 2
            if joints_i[comps_i[i, 0], 0] >= 0:
                nk += 2.0 * parent6[i, r] ** 2
    normK = np.sqrt(nk)
    rank, path, singular = mu, 0, 0
    S0 = Sb.copy()  # for the pivoted route when the band has no Cholesky factor
    if _cholesky_band(Sb, bw):
        _cho_solve_band(Sb, bw, lamU)
        rhs = r6.copy()
        _add_g(U, comps_i, joints_i, child6, parent6, lamU, rhs, 1.0)
        for i in range(n):
            _minv(bodies, i, rhs[i], acc[i])
    else:
        # exactly redundant joints (the usual reason) are solved on S with pivoting;
        # anything else, or an inconsistent answer, goes to the null-space solve
        # (spatial models only: a planar one's robust solve keeps the in-plane rows, and
        # the pivoted route would answer its out-of-plane rows too, differently)
        path = 2
        rank = -1 if planar else _redundant(bodies, joints_i, comps_i, U, S0, bw, child6,
                                            parent6, r6, acc, lamU, nonunique)
        if rank >= 0:
            r1 = np.empty((n, 6))
            r2 = np.empty(mu)
            berr = _residual(bodies, joints_i, comps_i, U, child6, parent6, r6, gam, acc,
                             lamU, normK, r1, r2)
            if berr > REDUNDANT_BERR:
                rank = -1
            else:
                return rank, berr, path, 0
        if rank < 0:
            path = 1
            rank, singular = _null_space(bodies, joints_i, comps_i, U, child6, parent6, r6,
                                         gam, stab, planar, refine, acc, lamU, nonunique)
            if singular:
                return rank, 0.0, path, singular
    r1 = np.empty((n, 6))
    r2 = np.empty(mu)
    berr = _residual(bodies, joints_i, comps_i, U, child6, parent6, r6, gam, acc, lamU,
                     normK, r1, r2)
    if refine and path == 0 and berr > 1e-15:
        dacc = np.empty((n, 6))
        dlam = np.empty(mu)
        _solve_again(bodies, joints_i, comps_i, U, child6, parent6, Sb, bw, r1, r2, dacc,
                     dlam)
        for i in range(n):
            for r in range(6):
                acc[i, r] += dacc[i, r]
        for k in range(mu):
            lamU[k] += dlam[k]
        berr = _residual(bodies, joints_i, comps_i, U, child6, parent6, r6, gam, acc, lamU,
                         normK, r1, r2)
    return rank, berr, path, 0


@njit(cache=True)
def _cho_solve_dense(L, r, x):
    """x (r,) <- (L Lᵀ)⁻¹ x with L the lower triangle of L[:r, :r]."""
    for i in range(r):
        xi = x[i]
        for k in range(i):
            xi -= L[i, k] * x[k]
        x[i] = xi / L[i, i]
    for i in range(r - 1, -1, -1):
        xi = x[i]
        for k in range(i + 1, r):
            xi -= L[k, i] * x[k]
        x[i] = xi / L[i, i]


@njit(cache=True)
def _inv_length(U, comps_i, joints_i, child6, parent6):
    """1 / the model's length scale: the rms moment arm |r × e| / |e| of the unknown
    components' force columns, both sides (as `mbody.solve.nullspace.length_scale`)."""
    num, cnt = 0.0, 0
    for k in range(U.shape[0]):
        i = U[k]
        for side in range(2 if joints_i[comps_i[i, 0], 0] >= 0 else 1):
            g = child6[i] if side == 0 else parent6[i]
            f = g[0] ** 2 + g[1] ** 2 + g[2] ** 2
            m = g[3] ** 2 + g[4] ** 2 + g[5] ** 2
            if f > 0.0 and m > 0.0:
                num += m / f
                cnt += 1
    return 1.0 / np.sqrt(num / cnt) if cnt else 1.0


@njit(cache=True)
def _orthonormal(A):
    """An orthonormal basis (columns) of A's column space, A of full column rank with few
    columns (a null space [−X; I]): modified Gram-Schmidt, each column orthogonalised
    twice ("twice is enough": orthogonal to rounding, as a Householder QR)."""
    m, k = A.shape
    Q = A.copy()
    for a in range(k):
        for _ in range(2):
            for b in range(a):
                d = 0.0
                for i in range(m):
                    d += Q[i, b] * Q[i, a]
                for i in range(m):
                    Q[i, a] -= d * Q[i, b]
        norm = 0.0
        for i in range(m):
            norm += Q[i, a] * Q[i, a]
        norm = np.sqrt(norm)
        for i in range(m):
            Q[i, a] /= norm
    return Q


@njit(cache=True)
def _redundant(bodies, joints_i, comps_i, U, Sb, bw, child6, parent6, r6, acc, lamU,
               nonunique):
    """Exactly redundant joints, fast: S = G_Uᵀ M⁻¹ G_U factorised with pivoting on the
    pivot's share of its diagonal entry; the columns left with less than PIVOT_RTOL are
    redundant if G_U's columns themselves (not only M⁻¹-weighted: extreme mass ratios
    look alike) are combinations x_j of the kept ones. Then λ on the kept columns, the
    minimum-norm λ through the null space [−X; I], and `nonunique`. lamU holds
    γ − G_Uᵀ M⁻¹ r on entry, λ on return. Returns the rank, or −1 when the columns are
    not exactly dependent (the null-space solve takes over). Sb: S's lower band (`_schur`,
    band width bw)."""
    n, mu = r6.shape[0], U.shape[0]
    S = np.zeros((mu, mu))
    for i in range(mu):
        for j in range(max(0, i - bw), i + 1):
            S[i, j] = Sb[i, i - j]
            S[j, i] = Sb[i, i - j]
    diag = np.empty(mu)
    for k in range(mu):
        diag[k] = S[k, k]
    perm = np.arange(mu)
    r = 0
    for k in range(mu):  # outer-product Cholesky, lower triangle, symmetric pivoting
        jb, best = -1, PIVOT_RTOL
        for j in range(k, mu):
            if diag[perm[j]] > 0.0 and S[j, j] > best * diag[perm[j]]:
                jb, best = j, S[j, j] / diag[perm[j]]
        if jb < 0:
            break
        if jb != k:
            for c in range(mu):
                S[k, c], S[jb, c] = S[jb, c], S[k, c]
            for c in range(mu):
                S[c, k], S[c, jb] = S[c, jb], S[c, k]
            perm[k], perm[jb] = perm[jb], perm[k]
        d = np.sqrt(S[k, k])
        S[k, k] = d
        for i in range(k + 1, mu):
            S[i, k] /= d
        for i in range(k + 1, mu):
            S[k, i] = S[i, k]
        for j in range(k + 1, mu):  # the whole trailing block: pivoting swaps both halves
            for i in range(k + 1, mu):
                S[i, j] -= S[i, k] * S[j, k]
        r += 1
    if r == mu or r == 0:
        return -1
    nd = mu - r
    # X (r × nd): L₁₁ᵀ X = L₂₁ᵀ, the kept columns' combinations for the dropped ones
    X = np.empty((r, nd))
    for a in range(nd):
        for i in range(r):
            X[i, a] = S[r + a, i]
        for i in range(r - 1, -1, -1):
            xia = X[i, a]
            for k in range(i + 1, r):
                xia -= S[k, i] * X[k, a]
            X[i, a] = xia / S[i, i]
    inv_l = _inv_length(U, comps_i, joints_i, child6, parent6)
    res = np.empty((n, 6))
    coef = np.zeros(mu)
    for a in range(nd):  # G_j − G_I x_j = 0 for every dropped column j?
        coef[:] = 0.0
        coef[perm[r + a]] = 1.0
        for i in range(r):
            coef[perm[i]] = -X[i, a]
        res[:, :] = 0.0
        _add_g(U, comps_i, joints_i, child6, parent6, coef, res, 1.0)
        big, small = 0.0, 0.0
        for k in range(mu):
            if coef[k] != 0.0:
                i = U[k]
                g2 = 0.0
                for c in range(6):
                    w = 1.0 if c < 3 else inv_l
                    g2 += (child6[i, c] * w) ** 2
                    if joints_i[comps_i[i, 0], 0] >= 0:
                        g2 += (parent6[i, c] * w) ** 2
                big += abs(coef[k]) * np.sqrt(g2)
        for b in range(n):
            for c in range(6):
                small += (res[b, c] * (1.0 if c < 3 else inv_l)) ** 2
        if not np.sqrt(small) <= DEPENDENT_RTOL * big:
            return -1
    # λ on the kept columns (the dropped ones 0), then the minimum-norm λ
    rhs = np.empty(r)
    for i in range(r):
        rhs[i] = lamU[perm[i]]
    _cho_solve_dense(S, r, rhs)
    lamU[:] = 0.0
    for i in range(r):
        lamU[perm[i]] = rhs[i]
    Nn = np.zeros((mu, nd))
    for a in range(nd):
        Nn[perm[r + a], a] = 1.0
        for i in range(r):
            Nn[perm[i], a] = -X[i, a]
    Q = _orthonormal(Nn)
    for a in range(nd):  # λ minus its part in the null space
        s2 = 0.0
        for k in range(mu):
            s2 += Q[k, a] * lamU[k]
        for k in range(mu):
            lamU[k] -= s2 * Q[k, a]
    for k in range(mu):
        s2 = 0.0
        for a in range(nd):
            s2 += Q[k, a] ** 2
        nonunique[k] = np.sqrt(s2) > 1e-8
    rhs6 = r6.copy()
    _add_g(U, comps_i, joints_i, child6, parent6, lamU, rhs6, 1.0)
    for i in range(n):
        _minv(bodies, i, rhs6[i], acc[i])
    return r


@njit(cache=True, inline="always")
def _dot_add(s, c, a, b):
    """(s, c) += a b, compensated (TwoProduct by Dekker's split, TwoSum): Ogita, Rump
    and Oishi's Dot2, for residuals as if computed in twice the working precision."""
    p = a * b
    f = SPLIT * a
    ah = f - (f - a)
    al = a - ah
    f = SPLIT * b
    bh = f - (f - b)
    bl = b - bh
    ep = al * bl - (((p - ah * bh) - al * bh) - ah * bl)
    total = s + p
    z = total - s
    es = (s - (total - z)) + (p - z)
    return total, c + ep + es


@njit(cache=True)
def _null_space(bodies, joints_i, comps_i, U, child6, parent6, r6, gam, stab, planar,
                refine, acc, lamU, nonunique):
    """The robust solve on G_U's geometry, as `mbody.solve.nullspace.NullSpaceSolve` (read its
    docstring): Ĝ = T G_U C⁻¹, its SVD, the reduced mass
    matrix of the allowed motions, REFINE_STEPS rounds of refinement with compensated
    residuals (when `refine`), the minimum-norm λ and the not-unique flags. Writes acc
    (n, 6) and lamU (mu,); returns (rank, singular-mass code or 0)."""
    n, mu = r6.shape[0], U.shape[0]
    nonunique[:] = False
    per = np.array([0, 1, 5]) if planar else np.arange(6)
    npr = per.shape[0]
    nr = n * npr
    inv_l = _inv_length(U, comps_i, joints_i, child6, parent6)
    T = np.empty(nr)
    for b in range(n):
        for a in range(npr):
            T[b * npr + a] = 1.0 if per[a] < 3 else inv_l
    A = np.zeros((nr, mu))
    C = np.ones(mu)
    for k in range(mu):
        i = U[k]
        j = comps_i[i, 0]
        p, c = joints_i[j, 0], joints_i[j, 1]
        for a in range(npr):
            A[c * npr + a, k] += child6[i, per[a]] * T[c * npr + a]
            if p >= 0:
                A[p * npr + a, k] += parent6[i, per[a]] * T[p * npr + a]
        s2 = 0.0
        for r in range(nr):
            s2 += A[r, k] ** 2
        if s2 > 0.0:
            C[k] = np.sqrt(s2)
            for r in range(nr):
                A[r, k] /= C[k]
    Uf, sv, Vt = np.linalg.svd(A)
    rank = 0
    for a in range(sv.shape[0]):
        if sv[a] > G_RANK_RTOL * sv[0]:
            rank += 1
    dof = nr - rank
    U1 = np.ascontiguousarray(Uf[:, :rank])
    U2 = np.ascontiguousarray(Uf[:, rank:])
    V1 = np.ascontiguousarray(Vt[:rank].T)
    s1 = sv[:rank]
    # M̂ = T M T per body (npr × npr blocks)
    Mb = np.zeros((n, npr, npr))
    for b in range(n):
        for a in range(npr):
            for e in range(npr):
                ra, re = per[a], per[e]
                if ra < 3 and re < 3:
                    Mb[b, a, e] = bodies[b, MASS] if ra == re else 0.0
                elif ra >= 3 and re >= 3:
                    Mb[b, a, e] = bodies[b, J0 + 3 * (ra - 3) + (re - 3)] * inv_l * inv_l
    MU2 = np.zeros((nr, dof))
    for b in range(n):
        for a in range(npr):
            for e in range(npr):
                mbe = Mb[b, a, e]
                if mbe != 0.0:
                    for d in range(dof):
                        MU2[b * npr + a, d] += mbe * U2[b * npr + e, d]
    red = U2.T @ MU2
    Lr = np.zeros((dof, dof))
    for i in range(dof):  # Cholesky, pivots checked against their diagonal entries
        for j in range(i + 1):
            sij = 0.5 * (red[i, j] + red[j, i])
            for k in range(j):
                sij -= Lr[i, k] * Lr[j, k]
            if i == j:
                if not sij > SINGULAR_RTOL * red[i, i]:
                    w, V = np.linalg.eigh(0.5 * (red + red.T))
                    motion = U2 @ np.ascontiguousarray(V[:, 0])
                    kmax = 0
                    for r in range(nr):
                        if abs(motion[r]) > abs(motion[kmax]):
                            kmax = r
                    return rank, 1 + 6 * (kmax // npr) + per[kmax % npr]
                Lr[i, i] = np.sqrt(sij)
            else:
                Lr[i, j] = sij / Lr[j, j]
    rh = np.empty(nr)
    for b in range(n):
        for a in range(npr):
            rh[b * npr + a] = r6[b, per[a]] * T[b * npr + a]
    gh = np.empty(mu)
    sh = np.empty(mu)
    for k in range(mu):  # γ's physical part exactly, Baumgarte's part regularised
        gh[k] = (gam[k] - stab[k]) / C[k]
        sh[k] = stab[k] / C[k]
    ah = np.empty(nr)
    lamh = np.empty(mu)
    reg = STAB_RTOL * sv[0] if sv.shape[0] else 0.0
    _ns_inner(U1, U2, V1, s1, Mb, Lr, rh, gh, sh, reg, ah, lamh)
    if refine:
        r1 = np.empty(nr)
        r2 = np.empty(mu)
        da = np.empty(nr)
        dl = np.empty(mu)
        for _ in range(REFINE_STEPS):
            for b in range(n):  # r̂ − M̂ â + Ĝ λ̂, compensated
                for a in range(npr):
                    row = b * npr + a
                    sm, cm = rh[row], 0.0
                    for e in range(npr):
                        sm, cm = _dot_add(sm, cm, -Mb[b, a, e], ah[b * npr + e])
                    for k in range(mu):
                        if A[row, k] != 0.0:
                            sm, cm = _dot_add(sm, cm, A[row, k], lamh[k])
                    r1[row] = sm + cm
            for k in range(mu):  # γ̂ − Ĝᵀ â
                sm, cm = gh[k], 0.0
                for row in range(nr):
                    if A[row, k] != 0.0:
                        sm, cm = _dot_add(sm, cm, -A[row, k], ah[row])
                r2[k] = sm + cm
            sh[:] = 0.0
            _ns_inner(U1, U2, V1, s1, Mb, Lr, r1, r2, sh, 0.0, da, dl)
            for row in range(nr):
                ah[row] += da[row]
            for k in range(mu):
                lamh[k] += dl[k]
    for k in range(mu):
        lamU[k] = lamh[k] / C[k]
    if rank < mu:  # minimum-norm λ in the model's units; name what the null space touches
        Nn = np.empty((mu, mu - rank))
        for k in range(mu):
            for a in range(mu - rank):
                Nn[k, a] = Vt[rank + a, k] / C[k]
        Q = np.ascontiguousarray(np.linalg.qr(Nn)[0])
        proj = Q.T @ lamU
        lamU -= Q @ proj
        for k in range(mu):
            s2 = 0.0
            for a in range(Q.shape[1]):
                s2 += Q[k, a] ** 2
            nonunique[k] = np.sqrt(s2) > 1e-8
    acc[:, :] = 0.0
    for b in range(n):
        for a in range(npr):
            acc[b, per[a]] = ah[b * npr + a] * T[b * npr + a]
    return rank, 0


@njit(cache=True)
def _ns_inner(U1, U2, V1, s1, Mb, Lr, rh, gh, sh, reg, ah, lamh):
    """One solve of M̂ â − Ĝ λ̂ = r̂, Ĝᵀ â = γ̂ + ŝ with the SVD in hand (`_null_space`);
    the stabilisation ŝ through σ³ / (σ⁴ + reg⁴) instead of 1 / σ."""
    n, npr = Mb.shape[0], Mb.shape[1]
    rank, dof = s1.shape[0], U2.shape[1]
    s3 = s1 * s1 * s1
    c = (V1.T @ gh) / s1 + (V1.T @ sh) * s3 / (s3 * s1 + reg ** 4)
    u1c = U1 @ c
    rest = rh.copy()  # r̂ − M̂ U₁ c
    for b in range(n):
        for a in range(npr):
            for e in range(npr):
                rest[b * npr + a] -= Mb[b, a, e] * u1c[b * npr + e]
    z = U2.T @ rest
    _cho_solve_dense(Lr, dof, z)  # Lr Lrᵀ z = U₂ᵀ rest
    ah[:] = u1c + U2 @ z
    t2 = np.empty(ah.shape[0])
    for b in range(n):
        for a in range(npr):
            s = -rh[b * npr + a]
            for e in range(npr):
                s += Mb[b, a, e] * ah[b * npr + e]
            t2[b * npr + a] = s
    if rank:
        lamh[:] = V1 @ ((U1.T @ t2) / s1)
    else:
        lamh[:] = 0.0


@njit(cache=True)
def _solve_again(bodies, joints_i, comps_i, U, child6, parent6, Lb, bw, r6, gam, acc, lamU):
    """The same solve with the factor already in hand (for refinement)."""
    n, mu = r6.shape[0], U.shape[0]
    for i in range(n):
        _minv(bodies, i, r6[i], acc[i])
    _gt(U, comps_i, joints_i, child6, parent6, acc, lamU)
    for k in range(mu):
        lamU[k] = gam[k] - lamU[k]
    _cho_solve_band(Lb, bw, lamU)
    rhs = r6.copy()
    _add_g(U, comps_i, joints_i, child6, parent6, lamU, rhs, 1.0)
    for i in range(n):
        _minv(bodies, i, rhs[i], acc[i])


@njit(cache=True)
def _residual(bodies, joints_i, comps_i, U, child6, parent6, r6, gam, acc, lamU, normK,
              r1, r2):
    """r1 = r6 − (M v̇ − G_U λ), r2 = γ − G_Uᵀ v̇; returns the backward error."""
    n, mu = r6.shape[0], U.shape[0]
    for i in range(n):
        m = bodies[i, MASS]
        Jm = bodies[i, J0:J0 + 9]
        for a in range(3):
            r1[i, a] = r6[i, a] - m * acc[i, a]
            r1[i, 3 + a] = r6[i, 3 + a] - (Jm[3 * a] * acc[i, 3] + Jm[3 * a + 1] * acc[i, 4]
                                           + Jm[3 * a + 2] * acc[i, 5])
    _add_g(U, comps_i, joints_i, child6, parent6, lamU, r1, 1.0)
    _gt(U, comps_i, joints_i, child6, parent6, acc, r2)
    res = normx = normf = 0.0
    for k in range(mu):
        r2[k] = gam[k] - r2[k]
        res += r2[k] ** 2
        normx += lamU[k] ** 2
        normf += gam[k] ** 2
    for i in range(n):
        for r in range(6):
            res += r1[i, r] ** 2
            normx += acc[i, r] ** 2
            normf += r6[i, r] ** 2
    denom = normK * np.sqrt(normx) + np.sqrt(normf)
    return np.sqrt(res) / denom if denom > 0 else np.sqrt(res)


# -- the two entry points ----------------------------------------------------------------------
@njit(cache=True)
def _state(y, n):
    """Views (x, q, v, ω) of the packed state [x (n, 3) | q (n, 4) | v (n, 3) | ω (n, 3) | …]."""
    return (y[0:3 * n].reshape(n, 3), y[3 * n:7 * n].reshape(n, 4),
            y[7 * n:10 * n].reshape(n, 3), y[10 * n:13 * n].reshape(n, 3))


@njit(cache=True)
def _evaluate(F, I, Iu, x, q, v, w, fvec, lam, rate, refine, planar):
    """The shared body of `solve` and `derivative` (see there) -> `Evaluation`."""
    pm = _unpack(F, I)
    bodies, joints_i, comps_i = pm.bodies, pm.joints_i, pm.comps_i
    n, m = x.shape[0], comps_i.shape[0]
    mu = Iu[0]
    U = Iu[3:3 + mu]
    R = _rotations(q)
    r6 = np.empty((n, 6))
    _net_wrench(pm.gravity, bodies, pm.B_r, pm.springs, pm.loads_i, pm.springs_i, x, R, v,
                w, fvec, r6)
    child6 = np.empty((m, 6))
    parent6 = np.empty((m, 6))
    gamma, phi, gtv = np.empty(m), np.empty(m), np.empty(m)
    _columns(pm.joints, joints_i, comps_i, x, R, v, w, child6, parent6, gamma, phi, gtv)
    # known reactions: r6 += G_K λ_K (λ holds 0 on the unknown components)
    for i in range(m):
        if lam[i] != 0.0:
            j = comps_i[i, 0]
            p, c = joints_i[j, 0], joints_i[j, 1]
            for r in range(6):
                r6[c, r] += child6[i, r] * lam[i]
            if p >= 0:
                for r in range(6):
                    r6[p, r] += parent6[i, r] * lam[i]
    gam = np.empty(mu)
    stab = np.empty(mu)
    for k in range(mu):
        i = U[k]
        stab[k] = -2.0 * rate * gtv[i] - rate * rate * phi[i]
        gam[k] = gamma[i] + stab[k]
    acc = np.empty((n, 6))
    lamU = np.empty(mu)
    nonunique = np.empty(mu, dtype=np.bool_)
    rank, berr, path, singular = _constrained(bodies, joints_i, comps_i, Iu, child6, parent6,
                                              r6, gam, stab, planar, refine, acc, lamU,
                                              nonunique)
    return Evaluation(acc, lamU, phi, gtv, rank, berr, nonunique, path, singular)


def solve_layout(n: int, m: int, planar: bool) -> tuple[int, int, int]:
    """Where `solve` writes into `out`: (N, offset of λ, offset of info); Gᵀ v (m) and
    the not-unique flags (m) follow λ; info holds `INFO` entries."""
    N = (3 if planar else 6) * n
    return N, N, N + 3 * m


@njit(cache=True)
def solve(F, I, Iu, y, fvec, lam, planar, out):
    """Accelerations and reactions at one state (what `Assembly.solve` returns).

    y: the state packed as [x (n, 3) world | q (n, 4) W_R_B [w, x, y, z] | v (n, 3) world
    | ω (n, 3) body axes]; fvec: (k, 3) load values; lam: (m,) known reaction values, 0
    on the unknown components. Writes `out` (`solve_layout`): the accelerations in the
    model's coordinates (planar [a_x, a_y, α], spatial [a_G world, ω̇ body axes] per
    body), λ (m,) (the known values, and the solved ones in place), Gᵀ v (m,), 1.0 for
    each component that redundant constraints leave not unique (m,), and info [rank of
    S, backward error, number of broken enforced joints, mu].
    """
    n = I[0]
    m = I[4]
    x, q, v, w = _state(y, n)
    ev = _evaluate(F, I, Iu, x, q, v, w, fvec, lam, 0.0, True, planar)
    acc, lamU, phi, gtv = ev.acc, ev.lamU, ev.phi, ev.gtv
    mu = Iu[0]
    N = (3 if planar else 6) * n
    for i in range(n):
        if planar:
            out[3 * i], out[3 * i + 1], out[3 * i + 2] = acc[i, 0], acc[i, 1], acc[i, 5]
        else:
            for r in range(6):
                out[6 * i + r] = acc[i, r]
    for i in range(m):
        out[N + i] = lam[i]
        out[N + m + i] = gtv[i]
        out[N + 2 * m + i] = 0.0
    for k in range(mu):
        out[N + Iu[3 + k]] = lamU[k]
        out[N + 2 * m + Iu[3 + k]] = 1.0 if ev.nonunique[k] else 0.0
    # broken-joint check on the enforced (unknown) components
    # (mbody.equations.constraints.joint_errors)
    size = 0.0
    if n > 1:
        for a in range(3):
            lo, hi = x[0, a], x[0, a]
            for i in range(n):
                lo, hi = min(lo, x[i, a]), max(hi, x[i, a])
            size = max(size, hi - lo)
    pm = _unpack(F, I)
    joints, comps_i = pm.joints, pm.comps_i
    for i in range(m):
        row = joints[comps_i[i, 0]]
        for a in range(3):
            size = max(size, abs(row[BRC + a]))
    size = max(size, 1e-3)
    speed = 1e-3
    for i in range(n):
        for a in range(3):
            speed = max(speed, abs(v[i, a]), abs(w[i, a]))
    broken = 0
    for k in range(mu):
        i = Iu[3 + k]
        if abs(phi[i]) > JOINT_TOL * size or abs(gtv[i]) > JOINT_TOL * speed:
            broken += 1
    o = N + 3 * m
    out[o + ST_RANK] = ev.rank
    out[o + ST_BERR] = ev.berr
    out[o + ST_BROKEN] = broken
    out[o + ST_MU] = mu
    out[o + ST_PATH] = ev.path
    out[o + ST_SINGULAR] = ev.singular


@njit(cache=True)
def derivative(F, I, Iu, y, fvec, lam, rate, planar, out):
    """out = ẏ for the packed state y = [x (3n) | q (4n) | v (3n) | ω (3n) | θ (n, planar)]
    (see `mbody.simulate`), with the unknown reactions solved and Baumgarte's terms
    (α = β = `rate`); redundant constraints get the minimum-norm reactions. Returns 0, or
    the singular-mass code (info slot ST_SINGULAR of `solve`) when a motion the joints
    allow carries no mass or inertia (then `out` is not written)."""
    n = I[0]
    x, q, v, w = _state(y, n)
    ev = _evaluate(F, I, Iu, x, q, v, w, fvec, lam, rate, False, planar)
    if ev.singular:
        return ev.singular
    acc = ev.acc
    for i in range(n):
        for a in range(3):
            out[3 * i + a] = v[i, a]
            out[7 * n + 3 * i + a] = acc[i, a]
            out[10 * n + 3 * i + a] = acc[i, 3 + a]
        # q̇ = ½ q ⊗ (0, ω)
        qw, qx, qy, qz = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        p, r, s = w[i, 0], w[i, 1], w[i, 2]
        o = 3 * n + 4 * i
        out[o] = 0.5 * (-qx * p - qy * r - qz * s)
        out[o + 1] = 0.5 * (qw * p + qy * s - qz * r)
        out[o + 2] = 0.5 * (qw * r + qz * p - qx * s)
        out[o + 3] = 0.5 * (qw * s + qx * r - qy * p)
    if planar:  # out-of-plane rows are identically zero; θ̇ = ω_z
        for i in range(n):
            out[7 * n + 3 * i + 2] = 0.0
            out[10 * n + 3 * i] = 0.0
            out[10 * n + 3 * i + 1] = 0.0
            out[13 * n + i] = w[i, 2]
    return 0


# -- coordinate projection (mbody.simulate.projection) -----------------------------------------
@njit(cache=True)
def _pivot_ratio(Sb, bw):
    """The smallest ratio of a squared Cholesky pivot of the banded S to its diagonal
    entry (1 for well separated constraints, ~σ_min² near a singular position). A column
    whose ratio is below `DROPPED_RTOL` is an exactly redundant constraint (a spatial
    four-bar's): it is left out, as a pivoted Cholesky would. Sb is overwritten."""
    return _band_cholesky(Sb, bw, DROPPED_RTOL, False)


@njit(cache=True)
def _geometric_ratio(bodies, joints_i, comps_i, U, inc_ptr, inc, child6, parent6, bw):
    """`_pivot_ratio` of Ĝᵀ Ĝ, Ĝ = T G_U with T = diag(1, 1/ℓ) per body (as
    `mbody.simulate.projection.geometric_ratio`): how close the joints are to a singular position,
    whatever the masses (S = G_Uᵀ M⁻¹ G_U of a slender spatial four-bar has a ratio of
    1e-3 at every position)."""
    n = bodies.shape[0]
    il = _inv_length(U, comps_i, joints_i, child6, parent6)
    unit = np.zeros((n, bodies.shape[1]))
    for i in range(n):
        unit[i, MASS] = 1.0
        for a in range(3):
            unit[i, JINV0 + 4 * a] = il * il
    Sb = np.zeros((U.shape[0], bw + 1))
    _schur(unit, child6, parent6, U, inc_ptr, inc, Sb, True)
    return _pivot_ratio(Sb, bw)


@njit(cache=True)
def _project_solve(bodies, joints_i, comps_i, Iu, child6, parent6, r6, gam, stab, planar,
                   robust, d, lamU, nonunique):
    """The constrained solve of a projection: the null-space solve when `robust` (near a
    singular position, where S's Cholesky route loses 1/σ² of the accuracy that the
    projection of the nearly lost direction needs), else `_constrained`. Returns the
    singular-mass code."""
    if robust:
        mu = Iu[0]
        _, singular = _null_space(bodies, joints_i, comps_i, Iu[3:3 + mu], child6, parent6,
                                  r6, gam, stab, planar, True, d, lamU, nonunique)
        return singular
    _, _, _, singular = _constrained(bodies, joints_i, comps_i, Iu, child6, parent6, r6, gam,
                                     stab, planar, True, d, lamU, nonunique)
    return singular


@njit(cache=True)
def project(F, I, Iu, y, planar, iters, robust_below, info):
    """Move the packed state y (in place, layout of `derivative`) onto the enforced
    joints: positions by Gauss-Newton steps M Δ − G_U μ = 0, G_Uᵀ Δ = −φ_U (the smallest
    move in the kinetic metric; Δ = [Δx world, Δθ body axes], at most `iters` steps, until
    a step changes nothing), then velocities by the mass-orthogonal projection
    M Δv − G_U μ = 0, G_Uᵀ Δv = −G_Uᵀ v. info (PROJECT_INFO,) <- slots PR_STEP (largest
    position step, m or rad), PR_VELOCITY (largest velocity change, m/s or rad/s),
    PR_RATIO (`_geometric_ratio` at the starting positions), PR_SINGULAR (singular-mass
    code, 0 when none). Below a pivot ratio of `robust_below` the solves are the
    null-space solve (`_project_solve`)."""
    pm = _unpack(F, I)
    bodies, joints, joints_i, comps_i = pm.bodies, pm.joints, pm.joints_i, pm.comps_i
    n, m = I[0], comps_i.shape[0]
    mu, bw, nnz = Iu[0], Iu[1], Iu[2]
    U = Iu[3:3 + mu]
    x, q, v, w = _state(y, n)
    info[PR_STEP], info[PR_VELOCITY], info[PR_RATIO], info[PR_SINGULAR] = 0.0, 0.0, 1.0, 0.0
    if mu == 0:
        return
    child6, parent6 = np.empty((m, 6)), np.empty((m, 6))
    gamma, phi, gtv = np.empty(m), np.empty(m), np.empty(m)
    r6 = np.zeros((n, 6))
    gam, stab = np.empty(mu), np.zeros(mu)
    d = np.empty((n, 6))
    lamU = np.empty(mu)
    nonunique = np.empty(mu, dtype=np.bool_)
    inc_ptr = Iu[3 + mu:4 + mu + n]
    inc = Iu[4 + mu + n:4 + mu + n + 2 * nnz].reshape(nnz, 2)
    robust = False
    for it in range(iters + 1):
        R = _rotations(q)
        _columns(joints, joints_i, comps_i, x, R, v, w, child6, parent6, gamma, phi, gtv)
        if it == 0:
            info[PR_RATIO] = _geometric_ratio(bodies, joints_i, comps_i, U, inc_ptr, inc,
                                              child6, parent6, bw)
            robust = info[PR_RATIO] < robust_below
        if it == iters:
            break
        for k in range(mu):
            gam[k] = -phi[U[k]]
        singular = _project_solve(bodies, joints_i, comps_i, Iu, child6, parent6, r6, gam,
                                  stab, planar, robust, d, lamU, nonunique)
        if singular:
            info[PR_SINGULAR] = singular
            return
        step = 0.0
        for i in range(n):
            for a in range(6):
                step = max(step, abs(d[i, a]))
        if step == 0.0:
            break
        info[PR_STEP] = max(info[PR_STEP], step)
        if planar:  # the in-plane rows only (the others are 0 up to rounding)
            for i in range(n):
                d[i, 2], d[i, 3], d[i, 4] = 0.0, 0.0, 0.0
        for i in range(n):
            for a in range(3):
                x[i, a] += d[i, a]
            # q <- q ⊗ (1, Δθ/2), renormalised (Δθ in body axes, as ω)
            p0, p1, p2 = 0.5 * d[i, 3], 0.5 * d[i, 4], 0.5 * d[i, 5]
            qw, qx, qy, qz = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
            nw = qw - qx * p0 - qy * p1 - qz * p2
            nx = qx + qw * p0 + qy * p2 - qz * p1
            ny = qy + qw * p1 + qz * p0 - qx * p2
            nz = qz + qw * p2 + qx * p1 - qy * p0
            s = 1.0 / np.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
            q[i, 0], q[i, 1], q[i, 2], q[i, 3] = nw * s, nx * s, ny * s, nz * s
            if planar:
                y[13 * n + i] += d[i, 5]
        if step < 1e-15:
            break
    for k in range(mu):
        gam[k] = -gtv[U[k]]
    singular = _project_solve(bodies, joints_i, comps_i, Iu, child6, parent6, r6, gam, stab,
                              planar, robust, d, lamU, nonunique)
    if singular:
        info[PR_SINGULAR] = singular
        return
    for i in range(n):
        for a in range(3):
            v[i, a] += d[i, a]
            w[i, a] += d[i, 3 + a]
            info[PR_VELOCITY] = max(info[PR_VELOCITY], abs(d[i, a]), abs(d[i, 3 + a]))
        if planar:
            v[i, 2] = 0.0
            w[i, 0] = 0.0
            w[i, 1] = 0.0


# -- loads given as expressions of time (mbody.model.expressions) ------------------------------
@njit(cache=True, error_model="numpy")
def _evaluate_program(codes, numbers, start, end, t, stack):
    """The value at time t of one expression's postfix program (`mbody.model.expressions.Expression.
    program`, codes `PROGRAM_CODES`); out of a function's domain, inf or nan as numpy
    gives them."""
    top = 0
    for p in range(start, end):
        c = codes[p]
        if c == 0:
            stack[top] = numbers[p]
            top += 1
        elif c == 1:
            stack[top] = t
            top += 1
        elif c == 2:
            stack[top - 1] = -stack[top - 1]
        elif c <= 7:
            a, b = stack[top - 2], stack[top - 1]
            top -= 1
            if c == 3:
                stack[top - 1] = a + b
            elif c == 4:
                stack[top - 1] = a - b
            elif c == 5:
                stack[top - 1] = a * b
            elif c == 6:
                stack[top - 1] = a / b
            else:
                stack[top - 1] = a ** b
        else:
            a = stack[top - 1]
            if c == 8:
                stack[top - 1] = np.sin(a)
            elif c == 9:
                stack[top - 1] = np.cos(a)
            elif c == 10:
                stack[top - 1] = np.tan(a)
            elif c == 11:
                stack[top - 1] = np.exp(a)
            elif c == 12:
                stack[top - 1] = np.log(a) if a >= 0.0 else np.nan
            elif c == 13:
                stack[top - 1] = np.sqrt(a) if a >= 0.0 else np.nan
            else:
                stack[top - 1] = abs(a)
    return stack[0]


@njit(cache=True)
def set_loads(base, rows, cols, which, starts, codes, numbers, t, out):
    """out (k, 3) <- base with the entries given as expressions (`mbody.model.expressions.
    ExpressionTable.program`) set to their values at time t (s)."""
    for i in range(base.shape[0]):
        for a in range(base.shape[1]):
            out[i, a] = base[i, a]
    u = starts.shape[0] - 1
    if u == 0:
        return
    values = np.empty(u)
    stack = np.empty(codes.shape[0])
    for e in range(u):
        values[e] = _evaluate_program(codes, numbers, starts[e], starts[e + 1], t, stack)
    for k in range(rows.shape[0]):
        out[rows[k], cols[k]] = values[which[k]]


# -- one explicit Runge-Kutta step (mbody.simulate.stepping) -----------------------------------
@njit(cache=True)
def rk_attempt(F, I, Iu, y, f, t, h, base, rows, cols, which, starts, codes, numbers, lam,
               rate, planar, A, B, C, E3, E5, rtol, atol, K, y_new):
    """One attempted step of an explicit embedded Runge-Kutta pair with `derivative` as
    the right-hand side, as scipy's `rk_step` and DOP853's error norm compute it: K
    (stages + 1, size) <- the stages with K[-1] = ẏ(t + h, y_new); y_new <- the solution
    at t + h. The loads at each stage's time: base (k, 3) with the entries that are
    expressions of time set (`set_loads`). Returns (error norm, singular-mass code); the
    code stops the step."""
    size = y.shape[0]
    stages = A.shape[0]
    for i in range(size):
        K[0, i] = f[i]
    z = np.empty(size)
    loads = np.empty(base.shape)
    for s in range(1, stages):
        for i in range(size):
            acc = 0.0
            for j in range(s):
                acc += K[j, i] * A[s, j]
            z[i] = y[i] + acc * h
        set_loads(base, rows, cols, which, starts, codes, numbers, t + C[s] * h, loads)
        code = derivative(F, I, Iu, z, loads, lam, rate, planar, K[s])
        if code:
            return 0.0, code
    for i in range(size):
        acc = 0.0
        for j in range(stages):
            acc += K[j, i] * B[j]
        y_new[i] = y[i] + h * acc
    set_loads(base, rows, cols, which, starts, codes, numbers, t + h, loads)
    code = derivative(F, I, Iu, y_new, loads, lam, rate, planar, K[stages])
    if code:
        return 0.0, code
    n5, n3 = 0.0, 0.0
    for i in range(size):
        scale = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        e5, e3 = 0.0, 0.0
        for j in range(stages + 1):
            e5 += K[j, i] * E5[j]
            e3 += K[j, i] * E3[j]
        e5 /= scale
        e3 /= scale
        n5 += e5 * e5
        n3 += e3 * e3
    if n5 == 0.0 and n3 == 0.0:
        return 0.0, 0
    return abs(h) * n5 / np.sqrt((n5 + 0.01 * n3) * size), 0


RUN_T, RUN_H, RUN_T_OLD, RUN_H_OLD, RUN_STEPS, RUN_NFEV, RUN_STATUS, RUN_RATIO, \
    RUN_REFRESHED = range(9)
RUN_SIZE = 9
"""Slots of `rk_run`'s `run` array (RUN_SIZE of them). Status: 0 running (stopped at
t_stop, max_steps or near a singular position), 1 step too small, 2 singular mass (code
in RUN_RATIO)."""


@njit(cache=True)
def rk_run(F, I, Iu, base, rows, cols, which, starts, codes, numbers, lam, rate, planar, A,
           B, C, E3, E5, rtol, atol, max_step, t_bound, t_stop, max_steps, project_too,
           robust_below, refresh_tol, y, f, K, y_old, run):
    """Steps of scipy's embedded Runge-Kutta control (`mbody.simulate.stepping`) with `rk_attempt`,
    each followed, when `project_too`, by the coordinate projection (`project`) and, when
    it moved the state by more than `refresh_tol`, a fresh ẏ at the projected state. Stops
    after the first step that reaches t_stop, after `max_steps` steps, or after a step
    whose `_geometric_ratio` is below `robust_below` (the next steps need the stage
    projection of the Python path). y, f (ẏ at y), K (last accepted step's stages) and
    y_old (its starting state) are updated in place; run holds t, h_abs, the last step's
    start and size, and counters (slots RUN_*)."""
    stages = A.shape[0]
    size = y.shape[0]
    y_new = np.empty(size)
    pinfo = np.empty(PROJECT_INFO)
    loads = np.empty(base.shape)
    exponent = -1.0 / 8.0  # DOP853's error estimator is of order 7
    t, h_abs = run[RUN_T], run[RUN_H]
    direction = 1.0 if t_bound >= t else -1.0
    run[RUN_STATUS] = 0.0
    for _ in range(max_steps):
        min_step = 10.0 * abs(np.nextafter(t, direction * np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step
        rejected = False
        while True:
            if h_abs < min_step:
                run[RUN_T], run[RUN_H], run[RUN_STATUS] = t, h_abs, 1.0
                return
            h = h_abs * direction
            t_new = t + h
            if direction * (t_new - t_bound) > 0:
                t_new = t_bound
            h = t_new - t
            h_abs = abs(h)
            error, code = rk_attempt(F, I, Iu, y, f, t, h, base, rows, cols, which, starts,
                                     codes, numbers, lam, rate, planar, A, B, C, E3, E5,
                                     rtol, atol, K, y_new)
            run[RUN_NFEV] += stages
            if code:
                run[RUN_T], run[RUN_H] = t, h_abs
                run[RUN_STATUS], run[RUN_RATIO] = 2.0, code
                return
            if error < 1.0:
                factor = 10.0 if error == 0.0 else min(10.0, 0.9 * error ** exponent)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            shrink = 0.9 * error ** exponent
            h_abs *= shrink if shrink > 0.2 else 0.2  # nan -> 0.2, as scipy (max(0.2, nan))
            rejected = True
        for i in range(size):
            y_old[i] = y[i]
            y[i] = y_new[i]
            f[i] = K[stages, i]
        run[RUN_T_OLD], run[RUN_H_OLD] = t, h
        t = t_new
        run[RUN_STEPS] += 1.0
        run[RUN_RATIO] = 1.0
        if project_too:
            project(F, I, Iu, y, planar, 3, robust_below, pinfo)
            if pinfo[PR_SINGULAR]:
                run[RUN_T], run[RUN_H] = t, h_abs
                run[RUN_STATUS], run[RUN_RATIO] = 2.0, pinfo[PR_SINGULAR]
                return
            run[RUN_RATIO] = pinfo[PR_RATIO]
            if max(pinfo[PR_STEP], pinfo[PR_VELOCITY]) > refresh_tol:
                set_loads(base, rows, cols, which, starts, codes, numbers, t, loads)
                code = derivative(F, I, Iu, y, loads, lam, rate, planar, f)
                run[RUN_NFEV] += 1.0
                run[RUN_REFRESHED] += 1.0
                if code:
                    run[RUN_T], run[RUN_H] = t, h_abs
                    run[RUN_STATUS], run[RUN_RATIO] = 2.0, code
                    return
            if pinfo[PR_RATIO] < robust_below:
                break
        if direction * (t - t_stop) >= 0.0 or t == t_bound:
            break
    run[RUN_T], run[RUN_H] = t, h_abs
