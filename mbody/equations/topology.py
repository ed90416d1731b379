"""What the body/joint graph and G say about a model's topology: its connected parts,
closed loops, floating bodies, and the mobility count with the redundant constraints.

Mobility counts 6 per spatial body (3 per planar body) minus the independent
constraints: the rank of G, which is also what exposes redundant joints (a planar
four-bar modelled in 3-D has more reaction components than independent constraints).
The parts come from the joint list (`mbody.model.graph.connected_parts`: networkx is not
loaded). The rank test works on dense blocks of G, one per connected part; given the
reaction columns (as `mbody check` does) it builds them with numpy alone, and its pivoted
QR is numpy's for a part of up to `NUMPY_QR_LIMIT` components (scipy.linalg, ~0.1-0.2 s
to import, only for a larger part that may be rank-deficient).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.equations.joints import g_block
from mbody.model.graph import connected_parts

if TYPE_CHECKING:
    from mbody.equations.joints import ReactionColumns
    from mbody.model.model import Model

RANK_LIMIT = 1500
"""Largest number of reaction components in one connected part whose rank is computed."""

NUMPY_QR_LIMIT = 120
"""Largest number of reaction components in one connected part whose pivoted QR is
`pivoted_qr` (numpy); scipy.linalg.qr above (the same algorithm, LAPACK's ?geqp3, whose
rounding decides exact ties)."""

PIVOT_TIE = 1e-9
"""Relative difference below which two remaining column norms tie in `pivoted_qr`."""


@dataclass(frozen=True)
class Topology:
    """What the graph says: parts, loops, floating bodies and the mobility count.

    parts: connected parts of the graph (ground included as a node), each a sorted list.
    loops: independent closed loops (cyclomatic number E − V + C).
    floating: bodies attached to nothing. grounded: bodies connected to ground.
    constraints: reaction components in all (Grübler's count).
    rank: independent constraints (None when too large to compute).
    mobility: degrees of freedom (per-body freedoms minus `rank`, or minus
    `constraints` when the rank is unknown). redundant: reaction components that are
    linear combinations of the others (one valid choice among equivalents).
    indeterminate: one group per indeterminacy (a self-stress: reaction values that
    balance each other and leave every body alone), naming every component it involves,
    whose values the equations therefore do not fix.
    """

    parts: list[list[str]]
    loops: int
    floating: list[str]
    grounded: list[str]
    constraints: int
    rank: int | None
    mobility: int
    gruebler: int
    redundant: list[str]
    indeterminate: list[tuple[str, ...]] = field(default_factory=list)

    @property
    def is_tree(self) -> bool:
        return self.loops == 0

    def __repr__(self) -> str:  # the dataclass's would list every part and body
        shape = "a tree" if self.is_tree else f"{self.loops} closed loop(s)"
        return (f"<Topology: {shape}, {len(self.parts)} connected part(s), mobility "
                f"{self.mobility}, {self.constraints} reaction components "
                f"({len(self.redundant)} redundant); .parts, .redundant>")


def topology(model: Model, G=None, *, columns: ReactionColumns | None = None) -> Topology:
    """Analyse the model's graph. `G` (the reaction matrix, sparse or dense) or `columns`
    (`Assembly.columns`, from which the blocks of G are built without scipy.sparse)
    enables the rank test."""
    nodes = [cv.GROUND, *model.body_names]
    edges = [(j.parent, j.child) for j in model.joints]
    components = connected_parts(nodes, edges)
    parts = [sorted(c, key=lambda s: (s != cv.GROUND, s)) for c in components]
    parts.sort(key=lambda c: (c[0] != cv.GROUND, c[0]))
    loops = len(edges) - len(nodes) + len(components)
    attached = {b for e in edges for b in e}
    floating = [b for b in model.body_names if b not in attached]
    grounded = sorted(next(c for c in components if cv.GROUND in c) - {cv.GROUND})
    m = len(model.reactions)
    coords = len(model.coordinates)  # a particle has translations only
    gruebler = coords - m
    rank: int | None = 0 if m == 0 else None
    redundant: list[str] = []
    groups: list[tuple[str, ...]] = []
    if m and (G is not None or columns is not None):
        rank, redundant, groups = _rank(model, G, columns)
    mobility = coords - (rank if rank is not None else m)
    return Topology(parts, loops, floating, grounded, m, rank, mobility, gruebler, redundant,
                    groups)


def _rank(model: Model, G, columns: ReactionColumns | None
          ) -> tuple[int | None, list[str], list[tuple[str, ...]]]:
    """Rank of G, part by part (ground removed, so parts share no rows), the columns past
    the rank, and the components of each indeterminacy (`self_stresses`); G's blocks come
    from `G` or else from `columns`."""
    parts = connected_parts(model.body_names, [(j.parent, j.child) for j in model.joints
                                           if cv.GROUND not in (j.parent, j.child)])
    rt = model.reaction_table
    rpb = model.rows_per_body
    labels = model.reactions
    total, redundant, groups = 0, [], []
    if G is not None and hasattr(G, "tocsc"):  # scipy.sparse
        G = G.tocsc()
    for part in parts:
        idx = np.array(sorted(model.index[b] for b in part))
        cols = np.flatnonzero(np.isin(rt.child, idx))
        if not len(cols):
            continue
        if len(cols) > RANK_LIMIT:
            return None, [], []
        if G is None:
            if columns is None:  # neither G nor its columns: no rank test (see `topology`)
                return None, [], []
            A = g_block(model, columns, idx, cols)
        else:
            rows = (np.concatenate([model.body_rows(i) for i in idx]) if model.has_particles
                    else (idx[:, None] * rpb + np.arange(rpb)).ravel())
            A = (G[rows][:, cols].toarray() if hasattr(G, "toarray")
                 else np.asarray(G, dtype=float)[np.ix_(rows, cols)])
        if _clearly_full_column_rank(A):  # what the pivoted QR below would conclude
            total += A.shape[1]
            continue
        # QR with column pivoting: the columns pivoted past the rank depend on the others.
        if A.shape[1] <= NUMPY_QR_LIMIT:
            d, piv = pivoted_qr(A)
        else:
            import scipy.linalg  # ~0.1-0.2 s to import: only for large parts

            _, Rq, piv = scipy.linalg.qr(A, mode="economic", pivoting=True)
            d = np.diag(Rq)
        d = np.abs(d)
        tol = (d[0] if len(d) else 0.0) * max(A.shape) * np.finfo(float).eps * 10
        r = int(np.sum(d > tol))
        total += r
        redundant += [labels[cols[k]] for k in piv[r:]]
        groups += [tuple(labels[cols[k]] for k in g) for g in self_stresses(A, A.shape[1] - r)]
    order = {lab: i for i, lab in enumerate(labels)}
    return total, sorted(redundant, key=order.__getitem__), groups


SELF_STRESS_TOL = 1e-8
"""A component belongs to an indeterminacy when its share of the (unit) self-stress is
above this: as the solve flags components that are not unique."""


def self_stresses(A: np.ndarray, d: int) -> list[list[int]]:
    """The columns each of the d independent self-stresses of A involves (λ ≠ 0 with
    A λ = 0: reaction values that put nothing into any body), as groups of column
    indices. The null space's basis is put in reduced row echelon form with the largest
    entry of each column as pivot, so that each basis vector involves as few components
    as any basis allows (for d = 1, every component the self-stress touches)."""
    if d <= 0:
        return []
    scale = np.abs(A).max(axis=0)
    scale[scale == 0] = 1.0
    _, _, Vt = np.linalg.svd(A / scale, full_matrices=True)  # columns on one scale
    N = Vt[A.shape[1] - d:].copy()  # (d, n): rows span the null space
    for i in range(d):  # reduced row echelon form, pivoting on the largest entry
        rest = N[i:]
        k = int(np.argmax(np.abs(rest).max(axis=0)))
        r = i + int(np.argmax(np.abs(rest[:, k])))
        N[[i, r]] = N[[r, i]]
        N[i] /= N[i, k]
        for j in range(d):
            if j != i:
                N[j] -= N[j, k] * N[i]
    out = []
    for row in N:
        big = np.abs(row).max()
        out.append([int(c) for c in np.flatnonzero(np.abs(row) > SELF_STRESS_TOL * big)])
    return out


FULL_RANK_MARGIN = 1e-8
"""`_clearly_full_column_rank` needs λ_min(AᵀA) > FULL_RANK_MARGIN ‖A‖_F², i.e. σ_min(A) above
1e-4 ‖A‖_F: far above the pivoted QR's rank tolerance (‖A‖ max(m, n) ε 10) and above the
rounding of AᵀA and of its eigenvalues (about n ε ‖A‖_F²)."""


def _clearly_full_column_rank(A: np.ndarray) -> bool:
    """True when A's columns are independent by a wide margin, so that the pivoted QR of
    `_rank` would find rank = number of columns and no redundant column (every |R_kk| is at
    least σ_min(A)). False means "not sure" (rank-deficient or nearly so): `_rank` then
    computes the QR. Needs only numpy, not scipy.linalg, for the common case."""
    m, n = A.shape
    if n > m:
        return False
    scale = float(np.einsum("ij,ij->", A, A))
    return 0 < scale < np.inf and float(np.linalg.eigvalsh(A.T @ A)[0]) > FULL_RANK_MARGIN * scale


def pivoted_qr(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """QR with column pivoting of A (m, n): (diag(R) (min(m, n),), the column order piv).

    Householder QR that moves forward, at each step, the column of largest remaining norm
    (Businger and Golub; LAPACK's ?geqp3, which scipy.linalg.qr(pivoting=True) calls,
    is the same algorithm), so that the columns pivoted past the rank are combinations of
    the others. Remaining norms within `PIVOT_TIE` of the largest are a tie, won by the
    column first in A: symmetric mechanisms have exact ties, which rounding would
    otherwise decide (differently from one BLAS build to another). The remaining norms
    are recomputed at every step, not downdated, so that rounding stays far below
    `PIVOT_TIE`. Numpy only: for the small blocks of `_rank`, where importing
    scipy.linalg would cost more than everything else `mbody check` does.
    """
    A = np.array(A, dtype=float)
    m, n = A.shape
    piv = np.arange(n)
    d = np.empty(min(m, n))
    for i in range(len(d)):
        rest = A[i:, i:]
        norms = np.sqrt(np.einsum("ij,ij->j", rest, rest))
        tied = np.flatnonzero(norms >= (1.0 - PIVOT_TIE) * norms.max())
        p = i + tied[np.argmin(piv[i + tied])]
        if p != i:
            A[:, [i, p]] = A[:, [p, i]]
            piv[[i, p]] = piv[[p, i]]
        # Householder reflector H = I - tau v vᵀ (v[0] = 1) taking A[i:, i] to (beta, 0, ...)
        alpha = A[i, i]
        xnorm = float(np.sqrt(A[i + 1:, i] @ A[i + 1:, i]))
        if xnorm == 0.0:
            d[i] = alpha
            continue
        beta = -np.copysign(np.hypot(alpha, xnorm), alpha)
        d[i] = beta
        if i + 1 < n:
            v = np.concatenate(([1.0], A[i + 1:, i] / (alpha - beta)))
            A[i:, i + 1:] -= np.outer(((beta - alpha) / beta) * v, v @ A[i:, i + 1:])
    return d, piv


