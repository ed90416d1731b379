"""The robust constrained solve: accelerations from the geometry of the constraints, for
the states where the Schur complement S = G_Uᵀ M⁻¹ G_U cannot be trusted.

The usual solve (`mbody.solve.kkt`) factorises S. S squares the conditioning of G_U and mixes
it with the mass ratios, so two kinds of state defeat it:

- positions close to a singular one (a four-bar chain passing its flat position), where
  a column of G_U is nearly a combination of the others: S's pivot there is the square
  of a small number, lost in rounding, and the constraint looks redundant;
- extreme mass ratios (a 1e12 kg body pinned to a 1e-12 kg one), where S's columns are
  nearly parallel whatever the geometry.

Here the decisions are taken on G_U alone, in units that make its entries comparable,
and the mass matrix enters only where it is well conditioned. With T = diag(1, 1/ℓ) per
body (ℓ the model's length scale) and C = diag of the columns' norms (both continuous
in the state, so that the least-squares answer of inconsistent constraints is too),
write Ĝ = T G_U C⁻¹, M̂ = T M T (mass, J/ℓ²), â = T⁻¹ v̇, λ̂ = C λ_U, r̂ = T r and
γ̂ = C⁻¹ γ_U. The system

    M̂ â − Ĝ λ̂ = r̂,    Ĝᵀ â = γ̂

is solved with the SVD Ĝ = [U₁ U₂] [Σ₁; 0] [V₁ V₂]ᵀ (rank from Σ with a relative
tolerance `RANK_RTOL`, which does not depend on units):

    â = U₁ c + U₂ z,   c = Σ₁⁻¹ V₁ᵀ γ̂,   (U₂ᵀ M̂ U₂) z = U₂ᵀ (r̂ − M̂ U₁ c),
    λ̂ = V₁ Σ₁⁻¹ U₁ᵀ (M̂ â − r̂).

U₂ spans the motions the joints allow, so U₂ᵀ M̂ U₂ is the mass matrix of the
mechanism's free coordinates: positive definite when every such motion carries mass or
inertia, whatever G_U's rank. Where G_U loses rank (exactly redundant joints, or a
singular position reached exactly) this is Gauss's principle: the accelerations are the
unique ones closest to the unconstrained ones in the kinetic metric, and λ is the
minimum-norm one, its components touched by G_U's null space named. Near a singular
position G_U keeps its rank and the solve resolves the small singular value; one or two
rounds of iterative refinement with residuals in extended precision
(`numpy.longdouble`) then give the accelerations of the data as given to near machine
precision, where the data (G_U, γ) are exact (a position 1e-9 rad from a singular one
then gives the accelerations to about 1e-12). `mbody.solve.compiled` has the same solve
(compensated dot products instead of long doubles).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

RANK_RTOL = 1e-12
"""Relative tolerance on Ĝ's singular values below which a constraint is redundant.
Redundancy computed from rounded geometry leaves singular values near 1e-16; a state
1e-9 rad from a singular position leaves about 1e-9."""
PIVOT_RTOL = 1e-6
"""The Schur complement's Cholesky factorisation is trusted when every pivot keeps this
fraction of its diagonal entry (a column of G_U at least 1e-3 rad from the span of the
ones before it, in the kinetic metric); below, this module's solve is used."""
SINGULAR_RTOL = 1e-14
"""A motion the joints allow whose Cholesky pivot in the reduced mass matrix keeps less
than this fraction of its diagonal entry carries no mass or inertia (an error)."""
STAB_RTOL = 1e-4
"""Baumgarte's stabilisation terms (a numerical correction of drift, not physics) are
solved through σ³ / (σ⁴ + (STAB_RTOL σ_max)⁴) instead of 1 / σ (the same to 1e-8
relative where σ > 1e-2 σ_max, where the Cholesky route serves): near a singular position
they would otherwise be amplified by 1/σ, stiffen the equations and throw a simulation
onto another branch of the mechanism."""
REFINE_STEPS = 2


_EXTENDED = np.finfo(np.longdouble).eps < 1e-17


class SingularMassError(ValueError):
    """A motion the joints allow carries no mass or inertia: accelerations not unique."""

    def __init__(self, body: int, row: int):
        self.body, self.row = body, row
        super().__init__(f"body {body}, row {row}")


class NullSpaceSolve:
    """The robust solve of one constrained system (module docstring).

    G: (6n, mu) dense G_U; mass (n,), J (n, 3, 3) body axes; length: the model's length
    scale (m); planar: keep only the in-plane rows (a_x, a_y, α_z) of each body, the others
    being free and unforced.
    """

    method = "null-space solve on the joints' geometry (SVD of the scaled G_U)"

    def __init__(self, G: np.ndarray, mass: np.ndarray, J: np.ndarray, length: float,
                 planar: bool = False):
        n = len(mass)
        self.n, self.mu = n, G.shape[1]
        inv_l = 1.0 / float(length)
        self.per = per = np.array([0, 1, 5]) if planar else np.arange(6)
        self.rows = (6 * np.arange(n)[:, None] + per).ravel()
        self.T = np.tile(np.r_[np.ones(3), np.full(3, inv_l)][per], n)
        Gh = G[self.rows] * self.T[:, None]
        norms = np.sqrt(np.einsum("ij,ij->j", Gh, Gh))
        self.C = np.where(norms > 0, norms, 1.0)
        A = Gh / self.C
        self.A = A
        U, s, Vt = np.linalg.svd(A, full_matrices=True)
        r = int(np.count_nonzero(s > RANK_RTOL * s[0])) if len(s) and s[0] > 0 else 0
        self.rank = r
        self.s1 = s[:r]
        self.U1, self.U2 = U[:, :r], U[:, r:]
        self.V1 = Vt[:r].T
        Mh = np.zeros((n, 6, 6))
        Mh[:, :3, :3] = mass[:, None, None] * np.eye(3)
        Mh[:, 3:, 3:] = J * inv_l * inv_l
        self.Mh_blocks = Mh[:, per[:, None], per]
        # the mass matrix of the motions the joints allow; a pivot that keeps less than
        # SINGULAR_RTOL of its diagonal entry is a motion without mass or inertia
        red = self.U2.T @ self._m(self.U2)
        red = 0.5 * (red + red.T)
        try:
            self.Lr = np.linalg.cholesky(red)
            if len(red) and not np.all(np.diag(self.Lr) ** 2 > SINGULAR_RTOL * np.diag(red)):
                raise np.linalg.LinAlgError
        except np.linalg.LinAlgError:
            w, V = np.linalg.eigh(red)
            motion = self.U2 @ V[:, 0]
            k = int(np.argmax(np.abs(motion)))
            raise SingularMassError(k // len(per), int(per[k % len(per)])) from None
        # G_U's null space in the model's λ (C⁻¹ V₂), orthonormal: the not-unique components
        if r < self.mu:
            q, _ = np.linalg.qr(Vt[r:].T / self.C[:, None])
            self.null: np.ndarray | None = q
            self.redundant = np.flatnonzero(np.linalg.norm(q, axis=1) > 1e-8).tolist()
        else:
            self.null = None
            self.redundant = []

    def _m(self, x: np.ndarray) -> np.ndarray:
        """M̂ x for x (rows,) or (rows, k)."""
        shape = x.shape
        xb = x.reshape(self.n, len(self.per), -1)
        return np.einsum("bij,bjk->bik", self.Mh_blocks, xb).reshape(shape)

    def _inner(self, rh: np.ndarray, gh: np.ndarray, sh: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
        s1 = self.s1
        c = (self.V1.T @ gh) / s1
        if sh is not None:
            reg = STAB_RTOL * s1[0] if len(s1) else 0.0
            c = c + (self.V1.T @ sh) * s1 ** 3 / (s1 ** 4 + reg ** 4)
        u1c = self.U1 @ c
        z = self.U2.T @ (rh - self._m(u1c))
        if len(z):
            z = np.linalg.solve(self.Lr.T, np.linalg.solve(self.Lr, z))
        ah = u1c + self.U2 @ z
        lamh = self.V1 @ ((self.U1.T @ (self._m(ah) - rh)) / self.s1)
        return ah, lamh

    @cached_property
    def _extended(self) -> tuple[np.ndarray, np.ndarray]:
        """Ĝ and M̂'s blocks in extended precision, for the refinement's residuals."""
        ld = np.longdouble if _EXTENDED else np.float64
        return self.A.astype(ld), self.Mh_blocks.astype(ld)

    def _residual(self, rh, gh, ah, lamh):
        """r̂ − M̂ â + Ĝ λ̂ and γ̂ − Ĝᵀ â, accumulated in extended precision."""
        A, Mb = self._extended
        a = ah.astype(A.dtype)
        Ma = np.einsum("bij,bj->bi", Mb, a.reshape(self.n, len(self.per))).ravel()
        r1 = rh.astype(A.dtype) - Ma + A @ lamh.astype(A.dtype)
        r2 = gh.astype(A.dtype) - A.T @ a
        return r1.astype(float), r2.astype(float)

    def solve(self, r6: np.ndarray, gamma_U: np.ndarray, refine: bool = True,
              stab: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(v̇ (n, 6), λ_U) for M v̇ − G_U λ_U = r6 (n, 6), G_Uᵀ v̇ = γ_U, where `stab`
        (mu,), when given, is the part of γ_U that is Baumgarte's stabilisation
        (`STAB_RTOL`)."""
        rh = self.T * np.ravel(r6)[self.rows]
        gh = np.asarray(gamma_U, float) / self.C
        if stab is None:
            ah, lamh = self._inner(rh, gh)
        else:
            ah, lamh = self._inner(rh, gh - stab / self.C, stab / self.C)
        for _ in range(REFINE_STEPS if refine else 0):
            r1, r2 = self._residual(rh, gh, ah, lamh)
            da, dl = self._inner(r1, r2)
            ah, lamh = ah + da, lamh + dl
        lam = lamh / self.C
        if self.null is not None:  # the minimum-norm λ in the model's units
            lam = lam - self.null @ (self.null.T @ lam)
        acc = np.zeros(6 * self.n)
        acc[self.rows] = ah * self.T
        return acc.reshape(self.n, 6), lam


def length_scale(child6: np.ndarray, parent6: np.ndarray, parent: np.ndarray) -> float:
    """The model's length scale (m) for weighing moment rows against force rows: the rms
    moment arm |r × e| / |e| over the sides (child; parent unless ground, `parent` < 0)
    of the unknown components that carry a force (1.0 when none has an arm)."""
    six = np.concatenate((child6, parent6[parent >= 0]))
    f = np.einsum("ij,ij->i", six[:, :3], six[:, :3])
    m = np.einsum("ij,ij->i", six[:, 3:], six[:, 3:])
    on = (f > 0) & (m > 0)
    if not on.any():
        return 1.0
    return float(np.sqrt(np.mean(m[on] / f[on])))
