"""Error bounds on the eigenvalues of ``M δq'' + D δq' + K δq = 0`` from the modes of the
symmetric part: much tighter than the first-order system's own (`Linearization`'s
κ_i ‖δA‖, with ‖δA‖ = ‖M⁻¹‖ (‖δK‖ + ‖δD‖)) when M is ill conditioned, as a long chain's
is in its joints' angles, and K's symmetric part is positive definite relative to M.

Derivation. The true matrices are M = M̂ + E_M, D = D̂ + E_D, K = K̂ + E_K, with the
computed M̂, D̂, K̂ and entrywise bounds |E_K| ≤ K_err, |E_D| ≤ D_err (the differences'
bounds) and |E_M| ≤ m_rel √(M̂_ii M̂_jj) (M's assembly rounding: the dot products
M_ij = t_iᵀ M_b t_j of T's columns, whose terms a diagonal body mass bounds by
Cauchy–Schwarz, the same rounding model as f's, `ROUNDING` over the projection's pivot
ratio; a model, not a bound: T's own errors make M's measured ones 1.8 to 4.2 times it on
chains of 20 to 80 rods, docs/modes.md). Write K = K_s + E with K_s = (K̂ + K̂ᵀ)/2,
so |E| ≤ K_err + |K̂ − K̂ᵀ|/2 whatever the true K's symmetry. Let (Λ̂, X̂) be the
computed eigenpairs of K_s x = λ M̂ x
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

A disc apart. The row sums count every mode's coupling to mode i at first order, though
its effect on ω̂_i is of second order. The same theorem holds for S⁻¹ (μ² P + μ G + Q) S
with S diagonal: at s_i = 1/t, row i's off-diagonal bounds are multiplied by t and column
i's by 1/t. When disc i at that scaling lies apart from every other row's disc (their
discs at the same scaling, (2) holding for each), it holds exactly one eigenvalue (the
discs shrink with τ as before), and its radius bounds that eigenvalue: the smallest such
radius over t in `SCALINGS` is kept where it is below the union's.

Measured on the hanging chains of `tests/test_lagrange_large.py` (rods in their joints'
angles), the largest bound over its eigenvalue: 1.4e-7 at 40 rods, 1.1e-5 at 100, 1.2e-4
at 150 (the first-order system's: 0.03, 2.8 and 23); up to 180 rods every mode is decided
an oscillation. Past that the highest modes' discs (mostly M's rounding) overlap even
scaled, a bound spans the whole overlap and those modes read neutral again; (2) fails
between 250 and 300 rods, where the first-order system's bounds are all there is
(docs/modes.md).
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
    K_off = K_err + 0.5 * np.abs(K - K.T) + gamma * np.abs(Ks)
    r = np.abs(R).sum(axis=1) + sandwich(K_off)
    n = np.abs(N).sum(axis=1) + sandwich(gamma * np.abs(M)) + m_rel * (aX.T @ s) * (s @ ones)
    g = sandwich(np.abs(D) + D_err)
    safety = 1.0 + 8 * k * EPS  # the rounding of these sums of non-negative terms
    d = _radius(n * safety, g * safety, r * safety, lam, omega)
    if not np.all(np.isfinite(d)):  # (2) fails for a mode
        return None
    reach = _union_reach(omega, d * safety + EPS * omega)
    # a disc apart at a scaling (module doc): the full bounds, entry by entry
    a = aX.T @ s
    Nb = (np.abs(N) + aX.T @ (gamma * np.abs(M)) @ aX + m_rel * np.outer(a, a)) * safety
    Rb = (np.abs(R) + aX.T @ K_off @ aX) * safety
    Gb = (aX.T @ (np.abs(D) + D_err) @ aX) * safety
    apart = _apart(Nb, Gb, Rb, lam, omega)
    reach = np.minimum(reach, apart * safety + EPS * omega)
    # each eigenvalue's nearest centre iω_i (a conjugate's: the mirror's), among the two
    # whose ω bracket its imaginary part (ω ascending)
    up = eigenvalues.real + 1j * np.abs(eigenvalues.imag)
    above = np.clip(np.searchsorted(omega, up.imag), 0, k - 1)
    below = np.clip(above - 1, 0, k - 1)
    far_above, far_below = np.abs(up - 1j * omega[above]), np.abs(up - 1j * omega[below])
    return np.where(far_above <= far_below, far_above + reach[above],
                    far_below + reach[below])


def _radius(n: np.ndarray, g: np.ndarray, r: np.ndarray, lam: np.ndarray,
            omega: np.ndarray) -> np.ndarray:
    """d: the smaller root of φ(d) = −(1 + n) d² + b d − c, b = 2ω (1 − n) − g, c = n ω² +
    g ω + r (module doc), where (2) holds; inf where it does not."""
    ok = (1.0 - 4.0 * n) * lam - 2.0 * g * omega - r > 0.0
    b = 2.0 * omega * (1.0 - n) - g
    c = n * lam + g * omega + r
    with np.errstate(invalid="ignore", divide="ignore"):
        d = 2.0 * c / (b + np.sqrt(np.maximum(b * b - 4.0 * (1.0 + n) * c, 0.0)))
    return np.where(ok, d, np.inf)


SCALINGS = (0.3, 0.1, 0.03, 0.01, 3e-3, 1e-3, 3e-4, 1e-4)
"""The factors t tried on a disc's row (module doc: a disc apart)."""


def _apart(Nb: np.ndarray, Gb: np.ndarray, Rb: np.ndarray, lam: np.ndarray,
           omega: np.ndarray) -> np.ndarray:
    """Each disc's smallest radius at a scaling that sets it apart from every other row's
    disc (module doc), or inf: the row's off-diagonal bounds times t, the column's over
    t, for each t of `SCALINGS`."""
    n, g, r = Nb.sum(axis=1), Gb.sum(axis=1), Rb.sum(axis=1)
    dn, dg, dr = np.diagonal(Nb), np.diagonal(Gb), np.diagonal(Rb)
    k = len(omega)
    best = np.full(k, np.inf)
    for start in range(0, k, BLOCK):  # discs start.. at a time: (BLOCK, k) arrays
        i = np.arange(start, min(k, start + BLOCK))
        gap = np.abs(omega[i, None] - omega[None, :])
        gap[np.arange(len(i)), i] = np.inf  # not apart from itself
        for t in SCALINGS:
            own = _radius(dn[i] + t * (n[i] - dn[i]), dg[i] + t * (g[i] - dg[i]),
                          dr[i] + t * (r[i] - dr[i]), lam[i], omega[i])
            more = 1.0 / t - 1.0  # row j for disc i: + (1/t − 1) times its entry (j, i)
            others = _radius(n[None, :] + more * Nb[:, i].T, g[None, :] + more * Gb[:, i].T,
                             r[None, :] + more * Rb[:, i].T, lam[None, :], omega[None, :])
            alone = np.all(gap > own[:, None] + others, axis=1) & np.isfinite(own)
            best[i] = np.where(alone, np.minimum(best[i], own), best[i])
    return best


BLOCK = 256
"""Discs whose scalings `_apart` tries at once (memory: a few (BLOCK, k) arrays)."""


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
