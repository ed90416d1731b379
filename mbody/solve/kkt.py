"""Accelerations and unknown reactions together: the constrained Newton-Euler system

    M v̇ − G_U λ_U = Q − b + G_K λ_K        (per-body Newton-Euler pairs)
    G_Uᵀ v̇        = γ_U                    (the joints hold at acceleration level)

with U the unknown reaction components and K the known ones (whose joints are then not
enforced: their forces are given instead). M is block diagonal, so the Schur complement

    S = G_Uᵀ M⁻¹ G_U,     S λ_U = γ_U − G_Uᵀ M⁻¹ (Q − b + G_K λ_K),     v̇ = M⁻¹(… + G_U λ_U)

is small, sparse and symmetric positive semi-definite; for chains and trees its
nonzeros lie in a narrow band around the diagonal (a joint couples only with the joints
sharing one of its bodies), so a banded Cholesky factorisation solves it in time linear
in the number of links. Redundant constraints make S singular; then the minimum-norm
reactions are returned and the components that are not unique are named.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeGuard

import numpy as np

from mbody.equations.joints import ReactionColumns
from mbody.equations.plan import Unknowns
from mbody.equations.spatial import matvec
from mbody.errors import MbodyError
from mbody.model.model import Model
from mbody.solve.nullspace import PIVOT_RTOL, NullSpaceSolve, SingularMassError, length_scale

if TYPE_CHECKING:
    import scipy.sparse as sp

    from mbody.solve.blockplan import BlockOperators

# scipy.sparse and scipy.linalg are imported where a large system needs them: a small
# mechanism is solved with numpy alone, so `mbody solve` starts without them.


def _issparse(a: object) -> TypeGuard[sp.spmatrix]:
    return type(a).__module__.startswith("scipy.sparse")


Solver = Callable[[np.ndarray], np.ndarray]
"""r -> S⁻¹ r (or a generalised inverse's product)."""
SchurMatrix = Any
"""S as a dense array or a scipy.sparse matrix (scipy has no type information here)."""

SMALL_BODIES = 60
"""Up to this many bodies (and DENSE_LIMIT unknowns) G is held as a dense array."""
DENSE_LIMIT = 48
"""Up to this many unknown components, S is factorised densely (and checked for rank);
above, S is banded (a joint couples only with the joints sharing one of its bodies) and
a dense factorisation would waste time on zeros."""
EIGEN_LIMIT = 1200
"""Up to this many unknowns, a singular S (redundant constraints) is handled by an
eigen-decomposition that names the components left undetermined; above, by LSQR."""
RANK_RTOL = 1e-10
"""Relative tolerance on S's eigenvalues below which a constraint is redundant (only for
systems too large for the null-space solve, `ROBUST_MAX_ROWS`)."""
ROBUST_MAX_ROWS = 1200
"""Up to this many rows (6 per body), a Schur complement whose Cholesky pivots are not
trusted (`mbody.solve.nullspace.PIVOT_RTOL`) hands the system to the null-space solve
(`mbody.solve.nullspace`); above, to the eigen-decomposition or LSQR of S."""


def _trusted(d: np.ndarray, diag: np.ndarray) -> bool:
    """Every squared Cholesky pivot keeps `PIVOT_RTOL` of its diagonal entry of S (a ratio
    that does not depend on the units of the columns)."""
    return bool(np.all(d > PIVOT_RTOL * diag))


def block_solve(model: Model, body: np.ndarray, g6: np.ndarray) -> np.ndarray:
    """M_b⁻¹ g for rows g6 (k, 6) acting on bodies `body` (k,): [g_N / m, J⁻¹ g_E]."""
    d = model.minv6
    if d is not None:  # principal axes: M_b⁻¹ is diagonal
        return g6 * d[body]
    out = np.empty_like(g6)
    out[:, :3] = g6[:, :3] / model.mass[body, None]
    out[:, 3:] = matvec(model.J_inv[body], g6[:, 3:])
    return out


def _g_and_minv_g_dense(model: Model, parent: np.ndarray, child: np.ndarray,
                        child6: np.ndarray, parent6: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """G_U and M⁻¹ G_U as dense (6n x mu) arrays (for small mechanisms)."""
    mu = len(child)
    G = np.zeros((6 * model.n, mu))
    H = np.zeros((6 * model.n, mu))
    k = np.arange(6)
    u = np.arange(mu)[:, None]
    G[child[:, None] * 6 + k, u] = child6
    H[child[:, None] * 6 + k, u] = block_solve(model, child, child6)
    on = parent >= 0
    if on.any():
        rows = parent[on, None] * 6 + k
        G[rows, u[on]] = parent6[on]
        H[rows, u[on]] = block_solve(model, parent[on], parent6[on])
    return G, H


def _g_and_minv_g(model: Model, parent: np.ndarray, child: np.ndarray, child6: np.ndarray,
                  parent6: np.ndarray) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """G_U and M⁻¹ G_U (6n x mu) built straight in CSC form, 12 entries a column: the
    child's 6 rows, then the parent's (for ground, zeros placed on the child's rows
    again: duplicates that add nothing, and no masking or sorting of the arrays)."""
    import scipy.sparse as sp

    mu = len(child)
    k = np.arange(6)
    p = np.where(parent >= 0, parent, child)
    rows = np.empty((mu, 12), dtype=np.int64)
    rows[:, :6] = child[:, None] * 6 + k
    rows[:, 6:] = p[:, None] * 6 + k
    g = np.empty((mu, 12))
    g[:, :6] = child6
    g[:, 6:] = parent6  # zero for ground
    h = np.empty((mu, 12))
    h[:, :6] = block_solve(model, child, child6)
    h[:, 6:] = block_solve(model, p, parent6)
    indptr = np.arange(0, 12 * mu + 1, 12, dtype=np.int64)
    shape = (6 * model.n, mu)
    idx = rows.ravel()
    G = sp.csc_matrix((g.ravel(), idx, indptr), shape=shape)
    H = sp.csc_matrix((h.ravel(), idx, indptr), shape=shape)
    return G, H


def _banded(ab: np.ndarray, perm: np.ndarray | None, mu: int) -> Factorisation | None:
    """Banded Cholesky of S in upper banded storage; None when S is not positive definite
    (redundant constraints: the general path then finds the minimum-norm reactions)."""
    import scipy.linalg as sla
    import scipy.sparse as sp

    bw = ab.shape[0] - 1
    try:
        cb = sla.cholesky_banded(ab, lower=False, check_finite=False)
    except np.linalg.LinAlgError:
        return None
    if not _trusted(cb[bw] ** 2, ab[bw]):
        return None

    def solve(r, cb=cb, perm=perm):
        if perm is None:
            return sla.cho_solve_banded((cb, False), r, check_finite=False)
        x = np.empty_like(r)
        x[perm] = sla.cho_solve_banded((cb, False), r[perm], check_finite=False)
        return x

    def S_matrix() -> sp.csr_matrix:  # S itself, for the condition estimate only
        upper = sp.dia_matrix((ab, np.arange(bw, -1, -1)), shape=(mu, mu)).tocsr()
        S = upper + sp.triu(upper, 1).T
        if perm is None:
            return S.tocsr()
        inv = np.empty(mu, dtype=np.intp)
        inv[perm] = np.arange(mu)
        return S.tocsr()[inv][:, inv]

    return Factorisation("banded Cholesky of the Schur complement (per-body blocks)", mu,
                         rank=mu, _solve=solve, _S=S_matrix)


@dataclass
class Factorisation:
    """S = G_Uᵀ M⁻¹ G_U factorised once; `solve(rhs)` applies (a generalised) S⁻¹."""

    method: str
    size: int
    redundant: list[int] = field(default_factory=list)
    rank: int = 0
    _solve: Solver | None = None  # None: the null-space solve answers (`ConstrainedSystem`)
    _S: SchurMatrix | Callable[[], SchurMatrix] | None = None  # S, or how to build it

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        if self._solve is None:
            raise TypeError(f"{self.method}: solved by the null-space solve, not by S")
        return self._solve(rhs)

    def matrix(self) -> SchurMatrix:
        """S itself (built on request when only a function that builds it was kept)."""
        S = self._S() if callable(self._S) else self._S
        if S is None:
            raise ValueError(f"{self.method}: S was not kept")
        return S

    def condition(self) -> float:
        """1-norm condition estimate of S (inf when singular)."""
        if self.size == 0:
            return 1.0
        if self.redundant:
            return float("inf")
        S = self.matrix()
        if not _issparse(S):
            return float(np.linalg.cond(S, 1))
        import scipy.sparse.linalg as spla

        inv = spla.LinearOperator(S.shape, matvec=self.solve, rmatvec=self.solve,
                                  dtype=float)
        return float(spla.onenormest(S) * spla.onenormest(inv))


def singular_mass_error(model, body: int, row: int) -> MbodyError:
    """The error for a motion the joints allow that carries no mass or inertia."""
    names = getattr(model, "body_names", None)
    name = names[body] if names is not None else f"#{body}"
    what = (f"translation along world {'xyz'[row]}" if row < 3
            else f"rotation about its body {'xyz'[row - 3]} axis")
    return MbodyError(f"the accelerations are not unique: body {name!r} has no mass or "
                      f"inertia for the {what}, and no joint constrains that motion; give "
                      "it mass or inertia there, or a joint that holds it")


def _cholesky_solver(L: np.ndarray) -> Solver:
    """r -> S⁻¹ r for S = L Lᵀ (dense, small: two triangular solves with numpy)."""
    def solve(r: np.ndarray) -> np.ndarray:
        return np.linalg.solve(L.T, np.linalg.solve(L, r))

    return solve


class ConstrainedSystem:
    """The constrained system of a model at one state, for a set of unknown components.

    cols: the reaction columns at the state; unknowns: which components are unknown
    (`mbody.equations.plan.Unknowns`).
    """

    def __init__(self, model: Model, cols: ReactionColumns, unknowns: Unknowns):
        self.model = model
        self.cols = cols
        rt = model.reaction_table
        self.unknown = unknowns.mask
        U = unknowns.U
        self.U = U
        if unknowns.every:  # every component unknown: no copies
            args = (model, rt.parent, rt.child, cols.child6, cols.parent6)
        else:
            args = (model, rt.parent[U], rt.child[U], cols.child6[U], cols.parent6[U])
        self.G: np.ndarray | sp.csc_matrix
        self.H: np.ndarray | sp.csc_matrix
        self.blocks: BlockOperators | None = None
        self.robust: NullSpaceSolve | None = None
        self._arms = args[1], args[3], args[4]  # parent, child6, parent6 of U
        if len(U) <= DENSE_LIMIT and model.n <= SMALL_BODIES:
            # Small mechanisms: dense arrays beat sparse-matrix bookkeeping by far.
            self.G, self.H = _g_and_minv_g_dense(*args)
            self.fact = self._dense(self.G.T @ self.H)
            return
        if len(U) > DENSE_LIMIT:  # large: per-body blocks and a banded S (mbody.solve.blockplan)
            from mbody.solve.blockplan import BlockOperators

            plan = model.plan.block_plan(unknowns) if model.plan is not None else None
            if plan is not None:
                blocks = BlockOperators(model, plan, args[3], args[4])
                fact = _banded(blocks.band(), plan.perm, len(U))
                if fact is not None:
                    self.blocks, self.fact = blocks, fact
                    return
        self.G, self.H = _g_and_minv_g(*args)
        self.fact = self._factorise((self.G.T @ self.H).tocsr())

    # -- the products a solve needs, whichever form G_U is held in --------------------------
    def g(self, lam: np.ndarray) -> np.ndarray:
        """(6n,) G_U λ."""
        return self.blocks.G(lam) if self.blocks is not None else self.G @ lam

    def gt(self, x: np.ndarray) -> np.ndarray:
        """(mu,) G_Uᵀ x for x (6n,) or (n, 6)."""
        x = np.ravel(x)
        return self.blocks.GT(x) if self.blocks is not None else self.G.T @ x

    def h(self, lam: np.ndarray) -> np.ndarray:
        """(6n,) M⁻¹ G_U λ."""
        return self.blocks.H(lam) if self.blocks is not None else self.H @ lam

    def g_sparse(self) -> sp.csc_matrix:
        """G_U as a sparse matrix (built on request from the blocks)."""
        import scipy.sparse as sp

        if self.blocks is None:
            return sp.csc_matrix(self.G)
        b = self.blocks
        p = b.plan
        six = b.Gb[p.inc_body, p.inc_slot]
        rows = (p.inc_body[:, None] * 6 + np.arange(6)).ravel()
        return sp.csc_matrix((six.ravel(), (rows, np.repeat(p.inc_u, 6))),
                             shape=(b.Gb.shape[0] * 6, p.mu))

    # -- factorisation -------------------------------------------------------------------
    def _factorise(self, S: sp.csr_matrix) -> Factorisation:
        import scipy.linalg as sla
        import scipy.sparse.linalg as spla
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        mu = S.shape[0]
        if mu == 0:
            return Factorisation("none", 0, _solve=lambda r: r, _S=S)
        if mu <= DENSE_LIMIT:
            return self._dense(S)
        coo = S.tocoo()
        bw = int(np.max(np.abs(coo.row - coo.col)))
        perm = None
        if bw > 64:
            perm = reverse_cuthill_mckee(S, symmetric_mode=True)
            Sp = S[perm][:, perm].tocoo()
            bw_p = int(np.max(np.abs(Sp.row - Sp.col)))
            if bw_p < bw:
                coo, bw = Sp, bw_p
            else:
                perm = None
        if (bw + 1) * mu <= 5e7:
            up = coo.row <= coo.col
            ab = np.zeros((bw + 1, mu))
            ab[bw + coo.row[up] - coo.col[up], coo.col[up]] = coo.data[up]
            try:
                cb = sla.cholesky_banded(ab, lower=False, check_finite=False)
                if _trusted(cb[bw] ** 2, ab[bw]):
                    def banded_solve(r: np.ndarray, cb: np.ndarray = cb,
                                     perm: np.ndarray | None = perm) -> np.ndarray:
                        if perm is None:
                            return sla.cho_solve_banded((cb, False), r, check_finite=False)
                        x = np.empty_like(r)
                        x[perm] = sla.cho_solve_banded((cb, False), r[perm],
                                                       check_finite=False)
                        return x

                    return Factorisation("banded Cholesky of the Schur complement", mu,
                                         rank=mu, _solve=banded_solve, _S=S)
            except np.linalg.LinAlgError:
                pass
        if mu <= EIGEN_LIMIT:
            return self._dense(S)
        try:
            lu = spla.splu(S.tocsc())
            return Factorisation("sparse LU of the Schur complement", mu, rank=mu,
                                 _solve=lu.solve, _S=S)
        except RuntimeError:  # exactly singular: minimum-norm by LSQR
            def lsqr_solve(r: np.ndarray, S: SchurMatrix = S) -> np.ndarray:
                return spla.lsqr(S, r, atol=1e-15, btol=1e-15, iter_lim=20 * mu)[0]

            return Factorisation("LSQR (rank-deficient, redundant constraints)", mu,
                                 redundant=[-1], _solve=lsqr_solve, _S=S)

    def _dense(self, S) -> Factorisation:
        A = S.toarray() if _issparse(S) else np.asarray(S)
        A = 0.5 * (A + A.T)
        try:  # the usual case: independent constraints, S positive definite
            L = np.linalg.cholesky(A)
            if _trusted(np.diag(L) ** 2, np.diag(A)):
                return Factorisation("dense Cholesky of the Schur complement", len(A),
                                     rank=len(A), _S=A, _solve=_cholesky_solver(L))
        except np.linalg.LinAlgError:
            pass
        if 6 * self.model.n <= ROBUST_MAX_ROWS:
            return self._null_space(A)
        w, V = np.linalg.eigh(A)
        tol = RANK_RTOL * max(w[-1], 0.0)
        good = w > tol
        rank = int(good.sum())
        if rank == len(w):
            return Factorisation("dense Cholesky of the Schur complement", len(w), rank=rank,
                                 _solve=_cholesky_solver(np.linalg.cholesky(A)), _S=A)
        # Minimum-norm solution through the pseudo-inverse; the null space of S (= that of
        # G_U) tells which components are not unique.
        Vg, wg = V[:, good], w[good]
        null = V[:, ~good]
        not_unique = np.flatnonzero(np.linalg.norm(null, axis=1) > 1e-8).tolist()
        return Factorisation("dense pseudo-inverse of the Schur complement (redundant "
                             "constraints)", len(w), redundant=not_unique, rank=rank,
                             _solve=lambda r: Vg @ ((Vg.T @ r) / wg), _S=A)

    def _null_space(self, S: SchurMatrix) -> Factorisation:
        """Hand the system to the robust solve on G_U's geometry (`mbody.solve.nullspace`)."""
        model = self.model
        if self.blocks is not None:
            G = self.g_sparse().toarray()
        else:
            G = self.G.toarray() if _issparse(self.G) else np.asarray(self.G)
        try:
            self.robust = NullSpaceSolve(G, np.asarray(model.mass, float),
                                         np.asarray(model.J, float),
                                         length_scale(*self._arms[1:], self._arms[0]),
                                         planar=getattr(model, "dimension", 3) == 2)
        except SingularMassError as e:
            raise singular_mass_error(model, e.body, e.row) from None
        rs = self.robust
        return Factorisation(rs.method, self.robust.mu, redundant=rs.redundant, rank=rs.rank,
                             _S=S)

    # -- solving -------------------------------------------------------------------------
    def solve(self, r6: np.ndarray, gamma_U: np.ndarray, stab: np.ndarray | None = None
              ) -> tuple[np.ndarray, np.ndarray]:
        """Solve M v̇ − G_U λ = r (n, 6 rows), G_Uᵀ v̇ = γ_U; returns (v̇ (n, 6), λ_U).
        `stab`: the part of γ_U that is Baumgarte's stabilisation, which the null-space
        solve damps near singular positions (`mbody.solve.nullspace.STAB_RTOL`)."""
        if self.robust is not None:
            return self.robust.solve(r6, gamma_U, refine=False, stab=stab)
        model = self.model
        a0 = block_solve(model, np.arange(model.n), r6).ravel()
        lam = self.fact.solve(gamma_U - self.gt(a0))
        acc = a0 + self.h(lam)
        return acc.reshape(-1, 6), lam

    def residual(self, r6: np.ndarray, gamma_U: np.ndarray, acc6: np.ndarray,
                 lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residuals (r1 (n, 6), r2 (mu,)) of the two block rows for a candidate solution."""
        model = self.model
        Ma = np.empty_like(acc6)
        Ma[:, :3] = acc6[:, :3] * model.mass[:, None]
        Ma[:, 3:] = matvec(model.J, acc6[:, 3:])
        r1 = r6.ravel() - (Ma.ravel() - self.g(lam))
        r2 = gamma_U - self.gt(acc6)
        return r1.reshape(-1, 6), r2

    def _norm_K(self) -> float:
        """‖K‖_F of the KKT matrix [[M, −G_U], [G_Uᵀ, 0]]: √(‖M‖_F² + 2 ‖G_U‖_F²), a bound
        on its 2-norm that costs one dot product per array."""
        model = self.model
        if self.blocks is not None:
            g = self.blocks.Gb.ravel()
        elif _issparse(self.G):
            g = self.G.data
        else:
            g = np.ravel(self.G)
        m2 = 3.0 * float(model.mass @ model.mass) + float(np.vdot(model.J, model.J))
        return float(np.sqrt(m2 + 2.0 * float(g @ g)))

    @staticmethod
    def _backward(r6, gamma_U, acc6, lam, r1, r2, normK: float) -> float:
        """‖r‖₂ / (‖K‖_F ‖x‖₂ + ‖f‖₂): the norm-wise relative backward error."""
        def norm2(*arrays) -> float:
            return float(np.sqrt(sum(float(np.vdot(a, a)) for a in arrays)))

        res, normx, normf = norm2(r1, r2), norm2(acc6, lam), norm2(r6, gamma_U)
        denom = normK * normx + normf
        return res / denom if denom > 0 else res

    def backward_error(self, r6, gamma_U, acc6, lam) -> float:
        """Norm-wise relative backward error ‖r‖₂ / (‖K‖_F ‖x‖₂ + ‖f‖₂) of the KKT system."""
        r1, r2 = self.residual(r6, gamma_U, acc6, lam)
        return self._backward(r6, gamma_U, acc6, lam, r1, r2, self._norm_K())

    def solve_refined(self, r6: np.ndarray, gamma_U: np.ndarray, target: float = 1e-15):
        """`solve`, then one round of iterative refinement (same factorisation) when the
        backward error is above `target` (the null-space solve refines its own answer, with
        residuals in extended precision). Returns (v̇ (n, 6), λ_U, backward error)."""
        if self.robust is not None:
            acc, lam = self.robust.solve(r6, gamma_U, refine=True)
            return acc, lam, self.backward_error(r6, gamma_U, acc, lam)
        acc, lam = self.solve(r6, gamma_U)
        normK = self._norm_K()
        r1, r2 = self.residual(r6, gamma_U, acc, lam)
        err = self._backward(r6, gamma_U, acc, lam, r1, r2, normK)
        if err > target and not self.fact.redundant:
            da, dl = self.solve(r1, r2)
            acc, lam = acc + da, lam + dl
            r1, r2 = self.residual(r6, gamma_U, acc, lam)
            err = self._backward(r6, gamma_U, acc, lam, r1, r2, normK)
        return acc, lam, err
