"""The body/joint graph: nodes are the bodies and ``ground``, every joint an edge (a
MultiGraph, since two bodies may share several joints), as networkx builds it
(`body_graph`, `Model.graph`; networkx is slow to import and loaded only here), and its
connected parts from the joint list directly (`connected_parts`). What the graph says
about mobility and redundant joints needs G as well: `mbody.equations.topology`.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

from mbody import conventions as cv

if TYPE_CHECKING:
    import networkx as nx

    from mbody.model.model import Model


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


def connected_parts(nodes: Iterable[str], edges: Iterable[tuple[str, str]]
                    ) -> list[set[str]]:
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
