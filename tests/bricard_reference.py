"""An independent reference motion of Bricard's mechanism (IFToMM multibody benchmark A04).

Written from the benchmark's published definition and the mechanics alone: numpy and
scipy, no code of mbody's. Five rods of 1 m and 1 kg with a 0.1 m square section lie
along six edges of a unit cube; the sixth edge, from E (0, 0, 1) to O (0, 0, 0), is the
ground. Six revolute joints close the loop (in loop order, point and axis in the released
pose):

    O (0, 0, 0) y    A (1, 0, 0) z    B (1, -1, 0) x    C (1, -1, 1) y
    D (0, -1, 1) z   E (0, 0, 1) x

rod k joining the joint before it to the joint after it (rod1 O-A, ..., rod5 D-E).
Gravity is 9.81 m/s² along -y; the mechanism is released at rest; the benchmark reports
the point P3, the joint B between rod2 and rod3, at (1, -1, 0) in that pose.

Formulation: the loop as an open chain in relative joint angles q1..q6 (the product of
exponentials: rod k moves with g1(q1) ... gk(qk), gj the rotation by qj about joint j's
axis in the released pose), closed by g1 ... g6 = I. Those are six equations with rank 5
on the mechanism's configurations (its one self-stress): given s = q1, Gauss-Newton (least
squares) finds q2..q6; velocities are q̇ = n(q) ṡ with n spanning the null space of the
closure's twist Jacobian (n1 = 1). The kinetic energy is T = ½ m(s) ṡ² with m summed
from the rods' own velocities (mass centre and angular velocity, box inertia), the
potential V(s) = Σ m g y_G, and the motion is the one-degree-of-freedom Lagrange equation

    m(s) s̈ + ½ m'(s) ṡ² + V'(s) = 0,

integrated by scipy's solve_ivp (DOP853, rtol 1e-13, atol 1e-14). V' = Σ m g (dy_G/ds)
is exact from n; m' is the complex step Im m(s + ih)/h (h = 1e-30: no subtractive
cancellation, exact to rounding). The closure continues to complex s as
q(s + ih) = q + ih n up to h² (1e-60, below rounding), and its null vector there comes
from a square solve on the five equations spanning the real Jacobian's range at s (the
continued null vector satisfies all six, being the analytic continuation of an
identity): every operation holomorphic (no |z|, no conjugate). `check_m_prime` compares
m' with a sixth-order central difference (truncation estimated from the fourth-order
one). Accelerations at a moving state (`kinematics`) take u' (u = dv_G/dṡ) the same way.

Its own accuracy (tests/test_bricard.py): over 10 s the energy T + V (-29.43 J) drifts by
4e-12 J; P3 moves by 5e-12 m between rtol 1e-12 and 1e-13; m' agrees with the finite
difference to 1e-12.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

G = 9.81  # m/s², along -y
MASS = 1.0  # kg per rod
LENGTH = 1.0  # m
SECTION = 0.1  # m, side of the square section
AXIAL = MASS * (SECTION ** 2 + SECTION ** 2) / 12.0  # kg m², about the rod's own axis
TRANSVERSE = MASS * (LENGTH ** 2 + SECTION ** 2) / 12.0  # kg m², across it

POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1], [0, 0, 1]],
                  dtype=float)
"""Joints O, A, B, C, D, E in loop order: their points in the released pose (m)."""
AXES = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]],
                dtype=float)
"""Their axes (unit) in the released pose."""
RODS = 5
CENTRES = 0.5 * (POINTS[:RODS] + POINTS[1:RODS + 1])
"""Rod k's mass centre in the released pose: midway between its two joints."""
_DIRS = POINTS[1:RODS + 1] - POINTS[:RODS]
INERTIA0 = np.array([TRANSVERSE * np.eye(3) + (AXIAL - TRANSVERSE) * np.outer(d, d)
                     for d in _DIRS])
"""Rod k's inertia about its mass centre in world axes, released pose (kg m²)."""
P3_ROD, P3_POINT = 1, POINTS[2]
"""The benchmark's P3 is joint B: carried by rod2 (index 1), at POINTS[2] when released."""

H = 1e-30  # complex step


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b, row by row (k, 3) (numpy's cross is slow on small arrays)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape), dtype=np.result_type(a, b))
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def _skew(a: np.ndarray) -> np.ndarray:
    """â (3, 3) with â x = a × x."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


_K = np.array([_skew(a) for a in AXES])
_K2 = _K @ _K


def _chain(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poses of g1 ... gj for j = 0 .. 6: R (7, 3, 3), t (7, 3), the pose x ↦ R x + t.
    Each gj is Rodrigues' rotation by qj (real or complex) about joint j's axis through
    its point."""
    dtype = np.result_type(q.dtype, float)
    Rj = (np.eye(3) + np.sin(q)[:, None, None] * _K + (1.0 - np.cos(q))[:, None, None] * _K2)
    tj = POINTS - np.einsum("jab,jb->ja", Rj, POINTS)
    R = np.empty((7, 3, 3), dtype=dtype)
    t = np.empty((7, 3), dtype=dtype)
    R[0], t[0] = np.eye(3), 0.0
    for j in range(6):
        R[j + 1] = R[j] @ Rj[j]
        t[j + 1] = R[j] @ tj[j] + t[j]
    return R, t


def _twists(R: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The joints' unit twists in world axes at the configuration of `_chain`'s poses:
    (w, v) (6, 3) each, v = -w × p (the spatial velocity of the body carried, per unit
    joint rate; p the joint's point now)."""
    w = np.einsum("jab,jb->ja", R[:6], AXES)
    p = np.einsum("jab,jb->ja", R[:6], POINTS) + t[:6]
    return w, -_cross(w, p)


def _closure(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The closure g1 ... g6 = I as six residuals (the translation t, the axial vector of
    the rotation R's skew part) and their exact Jacobian (6, 6): d(g1..g6) = ξ̂ (g1..g6)
    for each joint's world twist ξ = (w, v), so dt = w × t + v, and dR = ŵ R whose skew
    part's axial vector is ½ (tr R I − R) w (the identity ŵ A + Aᵀ ŵ = ((tr A) I − A) w^)."""
    R, t = _chain(q)
    w, v = _twists(R, t)
    R6, t6 = R[6], t[6]
    r = np.concatenate((t6, 0.5 * np.array([R6[2, 1] - R6[1, 2], R6[0, 2] - R6[2, 0],
                                            R6[1, 0] - R6[0, 1]])))
    J = np.empty((6, 6), dtype=r.dtype)
    J[:3] = (_cross(w, t6[None, :]) + v).T
    J[3:] = 0.5 * (np.trace(R6) * np.eye(3) - R6) @ w.T
    return r, J


def close_loop(s: float, guess: np.ndarray, tol: float = 1e-13
               ) -> tuple[np.ndarray, np.ndarray]:
    """q (6,) with q1 = s on the loop, by Gauss-Newton (least squares: the six equations
    have rank 5) from `guess`; and the closure's Jacobian there (6, 6) (evaluated before
    the last correction, below `tol`: its error is of that order)."""
    q = np.array(guess, dtype=float)
    q[0] = s
    for _ in range(50):
        r, J = _closure(q)
        dq = np.linalg.lstsq(J[:, 1:], -r, rcond=None)[0]
        q[1:] += dq
        if np.max(np.abs(dq)) < tol:  # quadratic: the next would be at rounding level
            return q, J
    raise RuntimeError(f"the loop does not close at q1 = {s!r}")


def loop_at(s: float, stride: float = 0.05) -> np.ndarray:
    """q (6,) with q1 = s on the released pose's branch: continued from s = 0."""
    q = np.zeros(6)
    for x in np.linspace(0.0, s, int(np.ceil(abs(s) / stride)) + 1)[1:]:
        q = close_loop(float(x), q)[0]
    return q


def _range_basis(J: np.ndarray) -> np.ndarray:
    """(6, 5) orthonormal basis of the closure Jacobian's range at a real solution."""
    U, sv, _ = np.linalg.svd(J)
    if sv[4] < 1e-8 * sv[0] or sv[5] > 1e-10 * sv[0]:
        raise RuntimeError(f"the loop's Jacobian has singular values {sv}: not rank 5")
    return U[:, :5]


def null_vector(J: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """n (6,) with J n = 0 and n1 = 1 (q̇ = n ṡ), from the square system basisᵀ J."""
    Jb = basis.T @ J
    n = np.empty(6, dtype=Jb.dtype)
    n[0] = 1.0
    n[1:] = np.linalg.solve(Jb[:, 1:], -Jb[:, 0])
    return n


def _rods(q: np.ndarray, n: np.ndarray):
    """Per rod: mass centre (5, 3), its velocity per unit ṡ (5, 3), angular velocity per
    unit ṡ (5, 3), rotation (5, 3, 3); all world axes. Rod k turns with joints 1..k."""
    R, t = _chain(q)
    w, v = _twists(R, t)
    W = np.cumsum(w * n[:, None], axis=0)[:RODS]
    Vs = np.cumsum(v * n[:, None], axis=0)[:RODS]
    c = np.einsum("kab,kb->ka", R[1:RODS + 1], CENTRES) + t[1:RODS + 1]
    return c, Vs + _cross(W, c), W, R[1:RODS + 1]


def mass_and_potential(q: np.ndarray, n: np.ndarray):
    """m (T = ½ m ṡ²), V = Σ m g y_G and V' = Σ m g dy_G/ds; written without conjugates
    or absolute values (holomorphic, for the complex step)."""
    c, vc, W, R = _rods(q, n)
    Iw = R @ INERTIA0 @ np.swapaxes(R, 1, 2)
    m = MASS * np.einsum("ka,ka->", vc, vc) + np.einsum("ka,kab,kb->", W, Iw, W)
    return m, MASS * G * np.sum(c[:, 1]), MASS * G * np.sum(vc[:, 1])


@dataclass
class Point:
    """The reference at one s: the closed loop q, the null vector n, m, m', V, V'."""

    s: float
    q: np.ndarray
    n: np.ndarray
    m: float
    dm: float
    V: float
    dV: float


def evaluate(s: float, guess: np.ndarray) -> Point:
    """m, m', V and V' at s, the loop closed from `guess`."""
    q, J = close_loop(s, guess)
    basis = _range_basis(J)
    n = null_vector(J, basis)
    m, V, dV = mass_and_potential(q, n)
    # complex step: q(s + ih) = q + ih n up to h² (1e-60); n(s + ih) from its Jacobian
    qc = q + 1j * H * n
    mc, _, _ = mass_and_potential(qc, null_vector(_closure(qc)[1], basis))
    return Point(s, q, n, float(m), float(mc.imag / H), float(V), float(dV))


class Bricard:
    """The one-degree-of-freedom motion. Each loop is closed from the last one, moved
    along its null vector (a first-order predictor: Newton then needs two or three
    iterations)."""

    def __init__(self):
        self.s, self.q, self.n = 0.0, np.zeros(6), np.zeros(6)
        self.evaluations = 0

    def guess(self, s: float) -> np.ndarray:
        return self.q + self.n * (s - self.s)

    def at(self, s: float) -> Point:
        p = evaluate(s, self.guess(s))
        self.s, self.q, self.n = s, p.q, p.n
        self.evaluations += 1
        return p

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        p = self.at(y[0])
        return np.array([y[1], -(0.5 * p.dm * y[1] ** 2 + p.dV) / p.m])

    def pose(self, s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, n, the closure's range basis) at s, without the complex step."""
        q, J = close_loop(s, self.guess(s))
        basis = _range_basis(J)
        n = null_vector(J, basis)
        self.s, self.q, self.n = s, q, n
        return q, n, basis


@dataclass
class Motion:
    """The reference sampled at `t` (K,): s = q1 (rad), ṡ, the rods' mass centres (K, 5,
    3) and rotations (K, 5, 3, 3) in world axes, P3 (K, 3), and the energy (K,) (J)."""

    t: np.ndarray
    s: np.ndarray
    sdot: np.ndarray
    centres: np.ndarray
    rotations: np.ndarray
    p3: np.ndarray
    energy: np.ndarray
    evaluations: int


def motion(t: np.ndarray, rtol: float = 1e-13, atol: float = 1e-14, s0: float = 0.0,
           sdot0: float = 0.0) -> Motion:
    """Integrate from (s0, ṡ0) (default: at rest in the released pose) over [0, t[-1]]
    and sample at t (increasing, from 0)."""
    from scipy.integrate import solve_ivp

    t = np.asarray(t, dtype=float)
    b = Bricard()
    b.s, b.q = s0, loop_at(s0)
    sol = solve_ivp(b.rhs, (0.0, float(t[-1])), [s0, sdot0], method="DOP853", rtol=rtol,
                    atol=atol, t_eval=t)
    if sol.status != 0:
        raise RuntimeError(sol.message)
    evaluations = b.evaluations
    K = len(t)
    centres, rotations = np.empty((K, RODS, 3)), np.empty((K, RODS, 3, 3))
    p3, energy = np.empty((K, 3)), np.empty(K)
    b = Bricard()
    b.s, b.q = s0, loop_at(s0)
    for i in range(K):  # samples in time order: each loop closed from the one before
        q, n, _ = b.pose(sol.y[0, i])
        c, _, _, R = _rods(q, n)
        centres[i], rotations[i] = c, R
        p3[i] = R[P3_ROD] @ P3_POINT + (c[P3_ROD] - R[P3_ROD] @ CENTRES[P3_ROD])
        m, V, _ = mass_and_potential(q, n)
        energy[i] = 0.5 * m * sol.y[1, i] ** 2 + V
    return Motion(t, sol.y[0], sol.y[1], centres, rotations, p3, energy, evaluations)


@dataclass
class Kinematics:
    """The rods at one state (s, ṡ): mass centres (5, 3), rotations from the released pose
    (5, 3, 3), velocities of the mass centres (5, 3), angular velocities (5, 3), and their
    accelerations a_G (5, 3) and ω̇ (5, 3); world axes."""

    centres: np.ndarray
    rotations: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    acceleration: np.ndarray
    alpha: np.ndarray


def kinematics(s: float, sdot: float) -> Kinematics:
    """Positions, velocities and accelerations at (s, ṡ) on the released pose's branch,
    s̈ from the Lagrange equation: v_G = u(s) ṡ, so a_G = u s̈ + u' ṡ² (u' by the complex
    step, u(s + ih) from q + ih n and its own null vector); the same for ω."""
    p = evaluate(s, loop_at(s))
    sddot = -(0.5 * p.dm * sdot ** 2 + p.dV) / p.m
    c, vc, W, R = _rods(p.q, p.n)
    J = _closure(p.q)[1]
    basis = _range_basis(J)
    qc = p.q + 1j * H * p.n
    _, vcc, Wc, _ = _rods(qc, null_vector(_closure(qc)[1], basis))
    acc = vc * sddot + vcc.imag / H * sdot ** 2
    alpha = W * sddot + Wc.imag / H * sdot ** 2
    return Kinematics(c, R, vc * sdot, W * sdot, acc, alpha)


def initial_accelerations() -> tuple[np.ndarray, np.ndarray]:
    """Released at rest: each rod's mass-centre acceleration (5, 3) and angular
    acceleration (5, 3), both world axes."""
    k = kinematics(0.0, 0.0)
    return k.acceleration, k.alpha


def check_m_prime(s: float, step: float = 1e-3) -> tuple[float, float, float]:
    """(complex-step m', sixth-order central difference, that difference's truncation
    estimate: its gap to the fourth-order one)."""
    guess = loop_at(s)

    def m(x: float) -> float:
        return evaluate(x, guess).m

    h = step
    f = {k: m(s + k * h) for k in (-3, -2, -1, 1, 2, 3)}
    d6 = (f[3] - 9 * f[2] + 45 * f[1] - 45 * f[-1] + 9 * f[-2] - f[-3]) / (60 * h)
    d4 = (-f[2] + 8 * f[1] - 8 * f[-1] + f[-2]) / (12 * h)
    return evaluate(s, guess).dm, d6, abs(d6 - d4)
