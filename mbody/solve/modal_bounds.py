"""Error bounds on the eigenvalues of ``M δq'' + D δq' + K δq = 0`` from the modes of the
symmetric part: much tighter than the first-order system's own (`Linearization`'s
κ_i ‖δA‖, with ‖δA‖ = ‖M⁻¹‖ (‖δK‖ + ‖δD‖)) when M is ill conditioned, as a long chain's
is in its joints' angles, and K's symmetric part is positive definite relative to M.

Derivation. The true matrices are M = M̂ + E_M, D = D̂ + E_D, K = K̂ + E_K, with the
computed M̂, D̂, K̂ and entrywise bounds |E_K| ≤ K_err, |E_D| ≤ D_err (the differences'
bounds) and |E_M| ≤ m_rel √(M̂_ii M̂_jj) (M's assembly rounding: the dot products
M_ij = t_iᵀ M_b t_j of T's columns, whose terms a diagonal body mass bounds by
Cauchy–Schwarz, the same rounding model as f's, `ROUNDING` over the projection's pivot
ratio). Write K = K_s + E with K_s = (K̂ + K̂ᵀ)/2, so |E| ≤ K_err + |K̂ − K̂ᵀ|/2 whatever
the true K's symmetry. Let (Λ̂, X̂) be the computed eigenpairs of K_s x = λ M̂ x
(Cholesky, then a symmetric eigensolver: X̂ᵀ M̂ X̂ ≈ I, X̂ᵀ K_s X̂ ≈ Λ̂ = diag(ω̂_i²)). In
the basis q = X̂ η the system's eigenvalues μ (those of A) make

    μ² (I + N) + μ G + (Λ̂ + R)

singular, with N = X̂ᵀ M X̂ − I, G = X̂ᵀ D X̂, R = X̂ᵀ K X̂ − Λ̂. Each is bounded entrywise:
the computed residuals N̂ = fl(X̂ᵀ M̂ X̂) − I and R̂ = fl(X̂ᵀ K_s X̂) − Λ̂, their rounding
γ_{2k+1} |X̂|ᵀ |·| |X̂| (γ_m = m ε / (1 − m ε)), and |X̂|ᵀ |E_·| |X̂|. A singular matrix is
not strictly diagonally dominant (Levy–Desplanques), so for some i, with n_i, g_i, r_i the
row sums of those bounds,

    |μ² + ω̂_i²| ≤ n_i |μ|² + g_i |μ| + r_i.                                   (1)

For Im μ ≥ 0 and d = |μ − iω̂_i|: |μ| ≤ ω̂_i + d and |μ + iω̂_i| ≥ max(2ω̂_i − d, d).
When d ≥ ω̂_i, (1) gives d² (1 − 4n_i) ≤ 2 g_i d + r_i, impossible when

    (1 − 4 n_i) ω̂_i² − 2 g_i ω̂_i − r_i > 0;                                    (2)

when d ≤ ω̂_i it gives φ(d) = d (2ω̂_i − d) − n_i (ω̂_i + d)² − g_i (ω̂_i + d) − r_i ≤ 0,
with φ(0) < 0 < φ(ω̂_i) by (2) and φ concave: so d ≤ d_i, φ's smaller root (about
(n_i ω̂_i² + g_i ω̂_i + r_i) / (2ω̂_i): on one degree of freedom, k's error over 2 m ω, the
first-order change of ω itself). Under (2) for every i,
every eigenvalue with Im μ ≥ 0 lies in a disc of centre iω̂_i and radius d_i (none is
real: d_i < ω̂_i), the conjugates in the mirror discs. The discs grow with N, G and R
scaled by τ from 0 (μ = ±iω̂_i exactly) to 1, so a connected union of m discs holds m
eigenvalues: a computed eigenvalue λ̂ whose nearest centre is iω̂_i is within
|λ̂ − iω̂_i| plus the farthest point of iω̂_i's union of a true eigenvalue.

Measured on the hanging chains of `tests/test_lagrange_large.py` (rods in their joints'
angles): the bounds are below 1e-6 of each frequency up to 100 rods and below 1e-2 at 200,
where the first-order system's exceed the eigenvalues (all modes then read neutral);
(2) fails past about 250 rods, where N's rounding model reaches a quarter (the bounds are
then the first-order system's).
"""

from __future__ import annotations

import numpy as np

EPS = float(np.finfo(float).eps)


def modal_bounds(M: np.ndarray, K: np.ndarray, K_err: np.ndarray, D: np.ndarray,
                 D_err: np.ndarray, m_rel: float, eigenvalues: np.ndarray
                 ) -> np.ndarray | None:
    """A bound on each of `eigenvalues`' errors (1/s; the first-order system's, any order)
    from the modes of K's symmetric part (module doc), or None where the derivation does
    not hold: M̂ not positive definite, K's symmetric part not positive definite relative
    to M̂, or (2) failing for a mode.

    Parameters
    ----------
    M, K, K_err, D, D_err : (k, k) arrays
        The generalized mass, stiffness and damping, and the entrywise bounds on K's and
        D's errors.
    m_rel : float
        M's entries are off by at most ``m_rel √(M_ii M_jj)``.
    eigenvalues : (2k,) complex array
        The first-order system's computed eigenvalues (every coordinate kept).

    Returns
    -------
    (2k,) array or None
    """
    k = len(M)
    if k == 0 or len(eigenvalues) != 2 * k:
        return None
    Ks = 0.5 * (K + K.T)
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        return None
    Li = np.linalg.inv(L)  # X = L⁻ᵀ U: any X̂ will do, its residuals are measured below
    C = Li @ Ks @ Li.T
    lam, U = np.linalg.eigh(0.5 * (C + C.T))
    if not (np.all(np.isfinite(lam)) and lam[0] > 0.0):
        return None
    X = Li.T @ U
    omega = np.sqrt(lam)
    gamma = (2 * k + 1) * EPS / (1.0 - (2 * k + 1) * EPS)
    aX = np.abs(X)
    ones = aX.sum(axis=1)  # |X̂| 1

    def sandwich(B: np.ndarray) -> np.ndarray:
        """The row sums of |X̂|ᵀ B |X̂| (B ≥ 0), by two matrix-vector products."""
        return aX.T @ (B @ ones)

    s = np.sqrt(np.diag(M))
    R = X.T @ (Ks @ X)
    R[np.diag_indices(k)] -= lam
    N = X.T @ (M @ X)
    N[np.diag_indices(k)] -= 1.0
    r = np.abs(R).sum(axis=1) + sandwich(K_err + 0.5 * np.abs(K - K.T) + gamma * np.abs(Ks))
    n = np.abs(N).sum(axis=1) + sandwich(gamma * np.abs(M)) + m_rel * (aX.T @ s) * (s @ ones)
    g = sandwich(np.abs(D) + D_err)
    safety = 1.0 + 8 * k * EPS  # the rounding of these sums of non-negative terms
    r, n, g = r * safety, n * safety, g * safety
    if not np.all((1.0 - 4.0 * n) * lam - 2.0 * g * omega - r > 0.0):  # (2)
        return None
    b = 2.0 * omega * (1.0 - n) - g  # φ(d) = −(1 + n) d² + b d − c
    c = n * lam + g * omega + r
    d = 2.0 * c / (b + np.sqrt(np.maximum(b * b - 4.0 * (1.0 + n) * c, 0.0)))  # smaller root
    d *= safety
    reach = _union_reach(omega, d)
    # each eigenvalue's nearest centre iω_i (a conjugate's: the mirror's), among the two
    # whose ω bracket its imaginary part (ω ascending)
    up = eigenvalues.real + 1j * np.abs(eigenvalues.imag)
    above = np.clip(np.searchsorted(omega, up.imag), 0, k - 1)
    below = np.clip(above - 1, 0, k - 1)
    far_above, far_below = np.abs(up - 1j * omega[above]), np.abs(up - 1j * omega[below])
    return np.where(far_above <= far_below, far_above + reach[above],
                    far_below + reach[below])


def _union_reach(omega: np.ndarray, d: np.ndarray) -> np.ndarray:
    """For each disc (centre iω_i, radius d_i), the farthest distance from its centre to a
    point of the connected union of discs it belongs to: their intervals [ω − d, ω + d]
    on the imaginary axis merged, in the order of their lower ends."""
    order = np.argsort(omega - d, kind="stable")
    reach = np.empty(len(omega))
    group: list[int] = []
    low = top = 0.0
    for i in [*order.tolist(), -1]:
        if i >= 0 and group and omega[i] - d[i] <= top:
            group.append(i)
            top = max(top, omega[i] + d[i])
            continue
        if group:
            at = np.array(group)
            reach[at] = np.maximum(top - omega[at], omega[at] - low)
        if i >= 0:
            group, low, top = [i], omega[i] - d[i], omega[i] + d[i]
    return reach
