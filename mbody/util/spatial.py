"""Rotations and frame helpers, vectorised over a leading body axis.

Names carry frames: ``W_R_B`` rotates body-axis components into world axes
(``W_v = W_R_B @ B_v``); quaternions are ``[w, x, y, z]`` (scalar first) of ``W_R_B``.
"""

from __future__ import annotations

import math

import numpy as np

# Euler angles and rotation matrices are converted here with numpy and the math module,
# not scipy.spatial.transform: importing that costs about 0.2 s (it pulls in scipy.spatial,
# scipy.sparse, scipy.linalg and scipy.special), which `mbody check` of any model with an
# `orientation: {euler: ...}` would pay. Both functions follow scipy's `Rotation`
# arithmetic step by step (`from_euler`, `from_matrix`) and give the same numbers to the
# last bit (tests/test_startup.py compares them).


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """(..., 4) unit quaternions [w, x, y, z] -> (..., 3, 3) rotation matrices W_R_B."""
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    R = np.empty((*np.shape(w), 3, 3))
    R[..., 0, 0] = 1 - 2 * (yy + zz)
    R[..., 0, 1] = 2 * (xy - wz)
    R[..., 0, 2] = 2 * (xz + wy)
    R[..., 1, 0] = 2 * (xy + wz)
    R[..., 1, 1] = 1 - 2 * (xx + zz)
    R[..., 1, 2] = 2 * (yz - wx)
    R[..., 2, 0] = 2 * (xz - wy)
    R[..., 2, 1] = 2 * (yz + wx)
    R[..., 2, 2] = 1 - 2 * (xx + yy)
    return R


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices -> (..., 4) quaternions [w, x, y, z] with w >= 0.

    As scipy's ``Rotation.from_matrix``: a matrix that is not orthogonal to 1e-12 is first
    replaced by the nearest rotation (U Vᵀ of its SVD); then the largest of the diagonal
    and the trace picks the best-conditioned formula, and the quaternion is normalised.
    """
    R = np.asarray(R, dtype=float)
    M = R.reshape(-1, 3, 3).copy()
    gram = M @ np.swapaxes(M, 1, 2)
    skew = ~np.all(np.isclose(gram, np.eye(3), rtol=1e-5, atol=1e-12), axis=(1, 2))
    if skew.any():
        U, _, Vt = np.linalg.svd(M[skew], full_matrices=False)
        M[skew] = U @ Vt
    trace = M[:, 0, 0] + M[:, 1, 1] + M[:, 2, 2]
    choice = np.argmax(np.stack((M[:, 0, 0], M[:, 1, 1], M[:, 2, 2], trace), axis=-1),
                       axis=-1)
    q = np.empty((len(M), 4))  # [x, y, z, w] here, as in scipy
    for c in range(3):  # a diagonal entry is largest: component c from it
        s = choice == c
        m, j, k = M[s], (c + 1) % 3, (c + 2) % 3
        q[s, c] = 1 - trace[s] + 2 * m[:, c, c]
        q[s, j] = m[:, j, c] + m[:, c, j]
        q[s, k] = m[:, k, c] + m[:, c, k]
        q[s, 3] = m[:, k, j] - m[:, j, k]
    s = choice == 3  # the trace is largest: w from it
    m = M[s]
    q[s] = np.stack((m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0],
                     m[:, 1, 0] - m[:, 0, 1], 1 + trace[s]), axis=-1)
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q = q[:, [3, 0, 1, 2]]
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(*R.shape[:-2], 4)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b of (..., 4) quaternions [w, x, y, z] (rotation b, then a)."""
    w1, x1, y1, z1 = np.moveaxis(np.asarray(a, dtype=float), -1, 0)
    w2, x2, y2, z2 = np.moveaxis(np.asarray(b, dtype=float), -1, 0)
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=-1)


def quat_conj(q: np.ndarray) -> np.ndarray:
    """(..., 4) conjugate quaternions: the inverse rotations of unit ones."""
    return np.asarray(q, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])


def axis_angle_quat(axis: np.ndarray, angle: float) -> np.ndarray:
    """(4,) the rotation by `angle` (rad) about the unit `axis`."""
    s = math.sin(angle / 2)
    return np.array([math.cos(angle / 2), axis[0] * s, axis[1] * s, axis[2] * s])


def planar_quat(theta: np.ndarray) -> np.ndarray:
    """(...,) angles about world z -> (..., 4) quaternions [cos θ/2, 0, 0, sin θ/2]."""
    theta = np.asarray(theta, dtype=float)
    q = np.zeros((*theta.shape, 4))
    q[..., 0] = np.cos(theta / 2)
    q[..., 3] = np.sin(theta / 2)
    return q


def quat_to_planar_angle(q: np.ndarray) -> np.ndarray:
    """(..., 4) quaternions of rotations about z -> (...,) angles θ in (-π, π]."""
    return 2.0 * np.arctan2(q[..., 3], q[..., 0])


def euler_to_quat(angles: np.ndarray, sequence: str) -> np.ndarray:
    """Euler angles (radians) -> quaternion [w, x, y, z] with w >= 0.

    `sequence` follows scipy: upper case (``ZYX``) is intrinsic (about the turning body
    axes, in order), lower case (``zyx``) is extrinsic (about the fixed world axes). The
    three elementary rotations are composed as scipy's ``Rotation.from_euler`` does.
    """
    intrinsic = sequence.isupper()
    q: list[float] = []  # [x, y, z, w], as in scipy
    for axis, angle in zip(sequence.lower(), np.asarray(angles, dtype=float).reshape(3),
                           strict=True):
        e = [0.0, 0.0, 0.0, math.cos(angle / 2.0)]
        e["xyz".index(axis)] = math.sin(angle / 2.0)
        if not q:
            q = e
            continue
        p, r = (q, e) if intrinsic else (e, q)  # q = p r
        q = [p[3] * r[0] + r[3] * p[0] + (p[1] * r[2] - p[2] * r[1]),
             p[3] * r[1] + r[3] * p[1] + (p[2] * r[0] - p[0] * r[2]),
             p[3] * r[2] + r[3] * p[2] + (p[0] * r[1] - p[1] * r[0]),
             p[3] * r[3] - p[0] * r[0] - p[1] * r[1] - p[2] * r[2]]
    out = np.array([q[3], q[0], q[1], q[2]])
    return out if out[0] >= 0 else -out


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (..., 3) arrays, written out (faster than np.cross)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0), axis=-1)


def matvec(A: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(..., 3, 3) @ (..., 3) -> (..., 3)."""
    return np.einsum("...ij,...j->...i", A, v)


def rmatvec(A: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(..., 3, 3)ᵀ @ (..., 3) -> (..., 3): world components into body axes for A = W_R_B."""
    return np.einsum("...ji,...j->...i", A, v)


FRAME_TIE = 1e-12
"""Direction components this close count as equal in the joint frame's rule."""


def joint_frame_spatial(axis: np.ndarray | None) -> np.ndarray:
    """Contract rule for a spatial joint frame; returns W_E, columns = joint x, y, z axes.

    z along `axis` (world z when None); x = the world axis least aligned with z (first on a
    tie) with its z component removed, normalised; y = z × x. Components within
    `FRAME_TIE` of each other tie: an axis read back from another program, (1.2e-16, 1,
    0) for (0, 1, 0), keeps the frame the exact axis has.
    """
    z = np.array([0.0, 0.0, 1.0]) if axis is None else np.asarray(axis, float)
    z = z / np.linalg.norm(z)
    i = int(least_aligned(z))
    x = np.eye(3)[i] - z[i] * z
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack((x, y, z))


def least_aligned(z: np.ndarray) -> np.ndarray:
    """(...,) the index of the world axis least aligned with each unit vector of (..., 3)
    `z`: the smallest |z_i|, the first of x, y, z within `FRAME_TIE` of it (the spatial
    frame rule's choice)."""
    a = np.abs(np.asarray(z, dtype=float))
    return np.argmax(a <= a.min(axis=-1, keepdims=True) + FRAME_TIE, axis=-1)


def joint_frames_spatial(z: np.ndarray, world_axis: np.ndarray) -> np.ndarray:
    """(k, 3, 3) the spatial rule's frames of the unit axes (k, 3) `z`, each with its x
    from the world axis `world_axis` (k,) (0-2) given rather than chosen: x = that axis
    with its component along z removed, normalised; y = z × x. Axes as columns."""
    z = np.asarray(z, dtype=float)
    k = np.arange(len(z))
    x = -z[k, world_axis][:, None] * z
    x[k, world_axis] += 1.0
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    return np.stack((x, np.cross(z, x), z), axis=2)


def joint_frame_planar(axis: np.ndarray | None) -> np.ndarray:
    """Contract rule for a planar joint frame (embedded in 3-D): x along `axis` (world x
    when None), y = x turned +90°, z = world z. Returns W_E with the axes as columns."""
    x2 = np.array([1.0, 0.0]) if axis is None else np.asarray(axis, float)[:2]
    x2 = x2 / np.linalg.norm(x2)
    x = np.array([x2[0], x2[1], 0.0])
    y = np.array([-x2[1], x2[0], 0.0])
    return np.column_stack((x, y, [0.0, 0.0, 1.0]))


def shape_inertia(shape: dict, mass: float, dimension: int) -> np.ndarray:
    """Inertia about the mass centre of a uniform solid `shape`, body axes.

    Spatial: returns the 3 principal moments. Planar: returns [I_G] (about the normal).
    Shapes: box [a, b, c] (planar [w, h]); cylinder {radius, length} (axis = body z;
    planar: a disc seen face-on); sphere {radius} (planar: a disc); ellipsoid [a, b, c]
    semi-axes (planar [a, b]); disc {radius} (planar).
    """
    m = mass
    kind, v = next(iter(shape.items()))
    if dimension == 2:
        if kind == "box":
            w, h = v[0], v[1]
            return np.array([m * (w * w + h * h) / 12.0])
        if kind == "ellipsoid":
            a, b = v[0], v[1]
            return np.array([m * (a * a + b * b) / 4.0])
        r = v["radius"]
        return np.array([0.5 * m * r * r])
    if kind == "box":
        a, b, c = v
        return m / 12.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    if kind == "sphere":
        r = v["radius"]
        return np.full(3, 0.4 * m * r * r)
    if kind == "cylinder":
        r, L = v["radius"], v["length"]
        side = m * (3 * r * r + L * L) / 12.0
        return np.array([side, side, 0.5 * m * r * r])
    if kind == "ellipsoid":
        a, b, c = v
        return m / 5.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    r = v["radius"]  # disc: thin, axis = body z
    return np.array([0.25 * m * r * r, 0.25 * m * r * r, 0.5 * m * r * r])


def box_equivalent(J_principal: np.ndarray, mass: float) -> np.ndarray:
    """Edge lengths of the uniform box with the given principal inertias (for drawing).

    From I1 = m(b²+c²)/12 etc.: a² = 6(I2 + I3 − I1)/m, and cyclic.
    """
    I1, I2, I3 = J_principal
    sq = 6.0 / mass * np.array([I2 + I3 - I1, I1 + I3 - I2, I1 + I2 - I3])
    return np.sqrt(np.maximum(sq, 1e-12))


def quaternion_rate(quaternion: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """q̇ = ½ q ⊗ (0, ω) for W_R_B quaternions (n, 4) [w, x, y, z] and ω (n, 3) body axes."""
    w, u = quaternion[:, :1], quaternion[:, 1:]
    out = np.empty_like(quaternion, dtype=float)
    out[:, :1] = -0.5 * np.einsum("ij,ij->i", u, omega)[:, None]
    out[:, 1:] = 0.5 * (w * omega + np.cross(u, omega))
    return out
