"""Rotations and frame helpers, vectorised over a leading body axis.

Names carry frames: ``W_R_B`` rotates body-axis components into world axes
(``W_v = W_R_B @ B_v``); quaternions are ``[w, x, y, z]`` (scalar first) of ``W_R_B``.
"""

from __future__ import annotations

import numpy as np

# scipy.spatial.transform is imported inside the two functions using it: it costs about
# 0.2 s (it pulls in scipy.spatial, scipy.sparse and scipy.special), which every command
# would pay at start-up otherwise.


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
    """(..., 3, 3) rotation matrices -> (..., 4) quaternions [w, x, y, z] with w >= 0."""
    from scipy.spatial.transform import Rotation

    R = np.asarray(R, dtype=float)
    q = Rotation.from_matrix(R.reshape(-1, 3, 3)).as_quat(scalar_first=True)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(*R.shape[:-2], 4)


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
    """Euler angles (radians) -> quaternion [w, x, y, z].

    `sequence` follows scipy: upper case (``ZYX``) is intrinsic (about the turning body
    axes, in order), lower case (``zyx``) is extrinsic (about the fixed world axes).
    """
    from scipy.spatial.transform import Rotation

    q = Rotation.from_euler(sequence, angles).as_quat(scalar_first=True)
    return q if q[0] >= 0 else -q


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


def joint_frame_spatial(axis: np.ndarray | None) -> np.ndarray:
    """Contract rule for a spatial joint frame; returns W_E, columns = joint x, y, z axes.

    z along `axis` (world z when None); x = the world axis least aligned with z (first on a
    tie) with its z component removed, normalised; y = z × x.
    """
    z = np.array([0.0, 0.0, 1.0]) if axis is None else np.asarray(axis, float)
    z = z / np.linalg.norm(z)
    i = int(np.argmin(np.abs(z)))  # argmin returns the first index on a tie
    x = np.eye(3)[i] - z[i] * z
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack((x, y, z))


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
