"""The body/joint graph as a `Scene`: bodies and ground as nodes, joints as edges."""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING, Any

import networkx as nx
import numpy as np

from mbody import conventions as cv
from mbody.conventions import APPLIED
from mbody.model.model import count
from mbody.present.draw.scene import IN, Box, Line, Poly, Scene, Text
from mbody.present.draw.style import COLORS

if TYPE_CHECKING:
    from mbody.model.model import Model



def _layers(g: nx.MultiGraph, roots: list[str]) -> dict[str, tuple[float, float]]:
    """Positions: breadth-first layers from ground (top); parts without ground beside it."""

    pos: dict[str, tuple[float, float]] = {}
    x0 = 0.0
    for comp_root in roots:
        depth = nx.single_source_shortest_path_length(g, comp_root)
        layers: dict[int, list[str]] = {}
        for node, dd in depth.items():
            layers.setdefault(dd, []).append(node)
        width = max(len(v) for v in layers.values())
        xs: dict[str, float] = {}
        for dd in sorted(layers):
            nodes = layers[dd]
            if dd:  # order a layer by where its neighbours above sit (fewer crossings)
                bary = {nd: float(np.mean([xs[m] for m in g.neighbors(nd)
                                           if depth.get(m) == dd - 1] or [0.0]))
                        for nd in nodes}
                nodes.sort(key=bary.__getitem__)
            for k, nd in enumerate(nodes):
                xs[nd] = (k - (len(nodes) - 1) / 2) * 2.4
                pos[nd] = (x0 + (width - 1) * 1.2 + xs[nd], -1.7 * dd)
        x0 += width * 2.4 + 0.6
    return pos


def graph_scene(model: Model, topo: Any = None) -> Scene:
    """The body/joint graph as a `Scene`: each joint an edge labelled with its name,
    type and number of reaction components (networkx MultiGraph underneath).

    Parameters
    ----------
    model : Model
    topo : Topology, optional
        `mbody.equations.topology.topology(model, ...)`: adds tree/loops and mobility to the title.

    Returns
    -------
    Scene
    """
    g = model.graph
    roots = [cv.GROUND]
    for comp in nx.connected_components(g):
        if cv.GROUND not in comp:
            roots.append(min(comp, key=lambda b: model.index[b]))
    pos = _layers(g, roots)
    xy = np.array(list(pos.values()))
    lo, hi = xy.min(axis=0) - 0.9, xy.max(axis=0) + 0.9
    w_in = float(np.clip((hi[0] - lo[0]) * 0.95, 6.5, 40.0))
    h_in = float(np.clip((hi[1] - lo[1]) * 0.95 + 0.8, 3.0, 40.0))
    W, H = w_in * IN, h_in * IN
    sc = Scene(W, H)
    ax = sc.panel("graph", (0.01 * W, 0.01 * H, 0.98 * W, H - 0.8 * IN - 0.01 * H), lo, hi)
    head = (f"body/joint graph of {model.name}: {count(model.n, 'body', 'bodies')} + "
            f"ground, {count(len(model.joints), 'joint')}")
    if topo is not None:
        head += (f"; {'a tree' if topo.is_tree else count(topo.loops, 'closed loop')}, "
                 f"mobility {topo.mobility}")
    sc.title = head
    head = "\n".join(textwrap.wrap(head, int(w_in * 9)))
    sc.root.add(Text(head, np.array([W / 2, H - 0.4 * IN]), 11, ha="center", va="center",
                     weight="bold", gid="title"))

    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for u, v, data in g.edges(data=True):
        groups.setdefault((min(u, v), max(u, v)), []).append(data)
    t = np.linspace(0, 1, 40)[:, None]
    joint_box = Box("#fff8e1", "#c9a227", 0.8, 0.25)
    for (u, v), edges in groups.items():
        pu, pv = np.array(pos[u]), np.array(pos[v])
        normal = np.array([-(pv - pu)[1], (pv - pu)[0]])
        for k, data in enumerate(sorted(edges, key=lambda d: d["joint"])):
            bend = (k - (len(edges) - 1) / 2) * 0.45
            ctrl = (pu + pv) / 2 + bend * normal
            curve = (1 - t) ** 2 * pu + 2 * (1 - t) * t * ctrl + t**2 * pv
            ax.add(Line(curve, "#555555", 1.6, zorder=1, gid=f"joint:{data['joint']}"))
            r = data["reactions"]
            ax.add(Text(f"{data['joint']}: {data['type']}\n{r} reaction{'s' if r != 1 else ''}",
                        0.25 * pu + 0.5 * ctrl + 0.25 * pv, 8, ha="center", va="center",
                        zorder=3, gid=f"joint-label:{data['joint']}", box=joint_box))
    node_box = Box("#dbe7f6", COLORS[APPLIED], 1.4, 0.55)
    for node, (x, y) in pos.items():
        if node == cv.GROUND:
            ax.add(Poly(np.array([[x - 0.45, y - 0.2], [x + 0.45, y - 0.2], [x + 0.45, y + 0.2],
                                  [x - 0.45, y + 0.2]]), "#eeeeee", "black", 1.0, zorder=2,
                        gid="node:ground", hatch=True),
                   Text("ground", np.array([x, y + 0.28]), 9, ha="center", va="bottom",
                        zorder=3))
            continue
        ax.add(Text(node, np.array([x, y]), 9.5, ha="center", va="center", zorder=3,
                    gid=f"node:{node}", box=node_box))
    return sc
