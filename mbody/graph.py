"""The body/joint graph (networkx) and what it says about the model's topology.

Nodes are the bodies and ``ground``; every joint is an edge (a MultiGraph, since two
bodies may share several joints). Mobility counts 6 per spatial body (3 per planar
body) minus the independent constraints: the rank of G, which is also what exposes
redundant joints (a planar four-bar modelled in 3-D has more reaction components than
independent constraints).

`topology` needs only the connected parts, found here from the joint list directly:
networkx (slow to import) is loaded only for `body_graph` (`Model.graph`), and
scipy.linalg only for a part of G that may be rank-deficient.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from . import conventions as cv
from .model import Model

if TYPE_CHECKING:
    import networkx as nx

RANK_LIMIT = 1500
"""Largest number of reaction components in one connected part whose rank is computed."""


def body_graph(model: Model) -> nx.MultiGraph:
    import networkx as nx

    g = nx.MultiGraph(name=model.name)
    g.add_node(cv.GROUND, ground=True)
    for name in model.body_names:
        g.add_node(name, ground=False, mass=float(model.mass[model.index[name]]))
    for j in model.joints:
        g.add_edge(j.parent, j.child, key=j.name, joint=j.name, type=j.type,
                   reactions=len(j.components))
    return g


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

    @property
    def is_tree(self) -> bool:
        return self.loops == 0


def topology(model: Model, G=None) -> Topology:
    """Analyse the model's graph; `G` (the sparse reaction matrix) enables the rank test."""
    nodes = [cv.GROUND, *model.body_names]
    edges = [(j.parent, j.child) for j in model.joints]
    components = _components(nodes, edges)
    parts = [sorted(c, key=lambda s: (s != cv.GROUND, s)) for c in components]
    parts.sort(key=lambda c: (c[0] != cv.GROUND, c[0]))
    loops = len(edges) - len(nodes) + len(components)
    attached = {b for e in edges for b in e}
    floating = [b for b in model.body_names if b not in attached]
    grounded = sorted(next(c for c in components if cv.GROUND in c) - {cv.GROUND})
    m = len(model.reactions)
    per_body = 3 if model.dimension == cv.PLANAR else 6
    gruebler = per_body * model.n - m
    rank, redundant = (0, []) if m == 0 else (None, [])
    if G is not None and m:
        rank, redundant = _rank(model, G)
    mobility = per_body * model.n - (rank if rank is not None else m)
    return Topology(parts, loops, floating, grounded, m, rank, mobility, gruebler, redundant)


def _rank(model: Model, G) -> tuple[int | None, list[str]]:
    """Rank of G, part by part (ground removed, so parts share no rows)."""
    parts = _components(model.body_names, [(j.parent, j.child) for j in model.joints
                                           if cv.GROUND not in (j.parent, j.child)])
    t = model.reaction_table
    rpb = model.rows_per_body
    labels = model.reactions
    total, redundant = 0, []
    G = G.tocsc()
    for part in parts:
        idx = np.array(sorted(model.index[b] for b in part))
        cols = np.flatnonzero(np.isin(t.child, idx))
        if not len(cols):
            continue
        if len(cols) > RANK_LIMIT:
            return None, []
        rows = (idx[:, None] * rpb + np.arange(rpb)).ravel()
        A = G[rows][:, cols].toarray()
        if _clearly_full_column_rank(A):  # what the pivoted QR below would conclude
            total += A.shape[1]
            continue
        import scipy.linalg  # ~0.1 s to import: only for parts that may be rank-deficient

        # QR with column pivoting: the columns pivoted past the rank depend on the others.
        _, Rq, piv = scipy.linalg.qr(A, mode="economic", pivoting=True)
        d = np.abs(np.diag(Rq))
        tol = (d[0] if len(d) else 0.0) * max(A.shape) * np.finfo(float).eps * 10
        r = int(np.sum(d > tol))
        total += r
        redundant += [labels[cols[k]] for k in piv[r:]]
    order = {lab: i for i, lab in enumerate(labels)}
    return total, sorted(redundant, key=order.__getitem__)


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


def _components(nodes: Iterable[str], edges: Iterable[tuple[str, str]]) -> list[set[str]]:
    """Connected components of the graph with these nodes and edges (union-find), as
    networkx's `connected_components` gives them (node sets; their order is not used)."""
    root = {n: n for n in nodes}

    def find(n: str) -> str:
        while root[n] != n:
            root[n] = root[root[n]]
            n = root[n]
        return n

    for a, b in edges:
        ra, rb = find(a), find(b)
        if ra != rb:
            root[rb] = ra
    out: dict[str, set[str]] = {}
    for n in root:
        out.setdefault(find(n), set()).add(n)
    return list(out.values())
