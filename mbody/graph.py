"""The body/joint graph (networkx) and what it says about the model's topology.

Nodes are the bodies and ``ground``; every joint is an edge (a MultiGraph, since two
bodies may share several joints). Mobility counts 6 per spatial body (3 per planar
body) minus the independent constraints: the rank of G, which is also what exposes
redundant joints (a planar four-bar modelled in 3-D has more reaction components than
independent constraints).
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np
import scipy.linalg

from . import conventions as cv
from .model import Model

RANK_LIMIT = 1500
"""Largest number of reaction components in one connected part whose rank is computed."""


def body_graph(model: Model) -> nx.MultiGraph:
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
    g = model.graph
    parts = [sorted(c, key=lambda s: (s != cv.GROUND, s)) for c in nx.connected_components(g)]
    parts.sort(key=lambda c: (c[0] != cv.GROUND, c[0]))
    loops = g.number_of_edges() - g.number_of_nodes() + nx.number_connected_components(g)
    floating = [b for b in model.body_names if g.degree(b) == 0]
    grounded = sorted(nx.node_connected_component(g, cv.GROUND) - {cv.GROUND})
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
    g = model.graph.copy()
    g.remove_node(cv.GROUND)
    t = model.reaction_table
    rpb = model.rows_per_body
    labels = model.reactions
    total, redundant = 0, []
    G = G.tocsc()
    for part in nx.connected_components(g):
        idx = np.array(sorted(model.index[b] for b in part))
        cols = np.flatnonzero(np.isin(t.child, idx))
        if not len(cols):
            continue
        if len(cols) > RANK_LIMIT:
            return None, []
        rows = (idx[:, None] * rpb + np.arange(rpb)).ravel()
        A = G[rows][:, cols].toarray()
        # QR with column pivoting: the columns pivoted past the rank depend on the others.
        _, Rq, piv = scipy.linalg.qr(A, mode="economic", pivoting=True)
        d = np.abs(np.diag(Rq))
        tol = (d[0] if len(d) else 0.0) * max(A.shape) * np.finfo(float).eps * 10
        r = int(np.sum(d > tol))
        total += r
        redundant += [labels[cols[k]] for k in piv[r:]]
    order = {lab: i for i, lab in enumerate(labels)}
    return total, sorted(redundant, key=order.__getitem__)
