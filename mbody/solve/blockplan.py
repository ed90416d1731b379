"""G_U held per body: the Schur complement S = G_Uᵀ M⁻¹ G_U from batched 6 x k blocks.

Column u of G_U touches two bodies (its child and its parent). Gathering, for every body
b, the k_b columns that touch it into a dense (6, k_max) block G_b gives

    S = Σ_b G_bᵀ M_b⁻¹ G_b,

one batched product over bodies, whose k x k results are scattered (summed) straight into
the banded storage of S. Which entry of which block goes where depends only on the
topology and on which components are unknown, so it is worked out once (`BlockPlan`)
and reused; each solve only fills numbers. No scipy.sparse object is made, which is
where most of the time of the general sparse path goes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

if TYPE_CHECKING:
    from mbody.model.model import Model


MAX_SLOTS = 30
"""Above this many unknown columns on one body (a hub with many joints), the padded
(n, k, k) block products waste too much: the general sparse path is used instead."""
MAX_BAND_ENTRIES = 5e7
"""Largest banded storage ((bandwidth + 1) x unknowns) accepted."""


@dataclass(frozen=True)
class BlockPlan:
    """Topology-only data for one model and one set of unknown components (mu of them).

    inc_u, inc_body, inc_slot, inc_parent: (q,) each incidence of a column on a body:
    which column, which body, its slot in that body's block, and whether it is the
    column's parent half. slot_col: (n, k) the column in each slot (mu = empty).
    block_index, ab_index: (P,) flat positions in the (n, k, k) block products and in
    the (bw + 1, mu) banded storage of the upper triangle of S. perm: ordering of S
    (None = natural), inv: its inverse.
    """

    mu: int
    k: int
    bw: int
    inc_u: np.ndarray
    inc_body: np.ndarray
    inc_slot: np.ndarray
    inc_parent: np.ndarray
    slot_col: np.ndarray
    block_index: np.ndarray
    ab_index: np.ndarray
    perm: np.ndarray | None
    flat_child: np.ndarray  # (mu,) row of each column's child half in the (n k, 6) blocks
    flat_parent: np.ndarray  # (q − mu,) the same for the parent halves
    parent_u: np.ndarray  # (q − mu,) their columns


def make_plan(model: Model, U: np.ndarray) -> BlockPlan | None:
    """The plan for unknown components U, or None when blocks would be too padded or the
    band too wide (then the general sparse path is used)."""
    rt = model.reaction_table
    n, mu = model.n, len(U)
    child, parent = rt.child[U], rt.parent[U]
    on_p = parent >= 0
    inc_u = np.concatenate((np.arange(mu), np.arange(mu)[on_p]))
    inc_body = np.concatenate((child, parent[on_p]))
    inc_parent = np.concatenate((np.zeros(mu, bool), np.ones(int(on_p.sum()), bool)))
    counts = np.bincount(inc_body, minlength=n)
    k = int(counts.max()) if len(counts) else 0
    if k == 0 or k > MAX_SLOTS:
        return None
    order = np.argsort(inc_body, kind="stable")
    starts = np.cumsum(counts) - counts
    inc_slot = np.empty(len(inc_u), dtype=np.intp)
    inc_slot[order] = np.arange(len(inc_u)) - starts[inc_body[order]]
    slot_col = np.full((n, k), mu, dtype=np.intp)
    slot_col[inc_body, inc_slot] = inc_u

    present = np.arange(k)[None, :] < counts[:, None]  # (n, k)
    valid = present[:, :, None] & present[:, None, :]
    ci = np.broadcast_to(slot_col[:, :, None], (n, k, k))
    cj = np.broadcast_to(slot_col[:, None, :], (n, k, k))
    r, c = ci[valid], cj[valid]
    flat = np.flatnonzero(valid)
    perm = None
    bw = int(np.max(np.abs(r - c))) if len(r) else 0
    if bw > 64:  # reorder to narrow the band, as for the sparse path
        pattern = sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(mu, mu))
        p = reverse_cuthill_mckee(pattern, symmetric_mode=True)
        pos = np.empty(mu, dtype=np.intp)
        pos[p] = np.arange(mu)
        bw_p = int(np.max(np.abs(pos[r] - pos[c])))
        if bw_p < bw:
            perm, bw, r, c = p, bw_p, pos[r], pos[c]
    if (bw + 1) * mu > MAX_BAND_ENTRIES:
        return None
    upper = r <= c
    rows = inc_body * k + inc_slot
    return BlockPlan(mu, k, bw, inc_u, inc_body, inc_slot, inc_parent, slot_col,
                     flat[upper], (bw + r[upper] - c[upper]) * mu + c[upper], perm,
                     rows[:mu], rows[mu:], inc_u[mu:])


class BlockOperators:
    """G_U and M⁻¹ G_U of one state as (n, k, 6) blocks (slot-major: each column's six rows
    on a body are contiguous), with the products a solve needs.

    G(lam) -> (6n,) G_U λ; GT(x) -> (mu,) G_Uᵀ x; H(lam) -> (6n,) M⁻¹ G_U λ;
    band() -> (bw + 1, mu) upper banded storage of S = G_Uᵀ M⁻¹ G_U (plan's ordering).
    """

    def __init__(self, model: Model, plan: BlockPlan, child6: np.ndarray,
                 parent6: np.ndarray):
        self.plan = plan
        n, k = model.n, plan.k
        G_rows = np.zeros((n * k, 6))  # (body, slot) rows, flat
        G_rows[plan.flat_child] = child6
        G_rows[plan.flat_parent] = parent6[plan.parent_u]
        Gb = G_rows.reshape(n, k, 6)
        d = model.minv6
        if d is not None:
            Hb = Gb * d[:, None, :]
        else:
            Hb = np.empty_like(Gb)
            Hb[:, :, :3] = Gb[:, :, :3] / model.mass[:, None, None]
            Hb[:, :, 3:] = np.matmul(Gb[:, :, 3:], np.swapaxes(model.J_inv, 1, 2))
        self.Gb, self.Hb = Gb, Hb

    def _expand(self, lam: np.ndarray) -> np.ndarray:
        return np.append(lam, 0.0)[self.plan.slot_col]  # (n, k), empty slots 0

    def G(self, lam: np.ndarray) -> np.ndarray:
        return np.einsum("nkr,nk->nr", self.Gb, self._expand(lam)).ravel()

    def H(self, lam: np.ndarray) -> np.ndarray:
        return np.einsum("nkr,nk->nr", self.Hb, self._expand(lam)).ravel()

    def GT(self, x: np.ndarray) -> np.ndarray:
        vals = np.einsum("nkr,nr->nk", self.Gb, np.reshape(x, (-1, 6)))
        return np.bincount(self.plan.slot_col.ravel(), vals.ravel(),
                           minlength=self.plan.mu + 1)[:self.plan.mu]

    def band(self) -> np.ndarray:
        p = self.plan
        S_blocks = np.matmul(self.Gb, np.swapaxes(self.Hb, 1, 2))  # (n, k, k)
        ab = np.bincount(p.ab_index, S_blocks.ravel()[p.block_index],
                         minlength=(p.bw + 1) * p.mu)
        return ab.reshape(p.bw + 1, p.mu)
