"""Body outlines in world coordinates: a body's shape (box, cylinder, disc, sphere,
ellipsoid), else the box `mbody.model.drawn` draws it as (a bar through the points where
its joints and loads act, or its inertia box), or a dot for a particle, with visible and
hidden edges for a given eye direction."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody import conventions as cv
from mbody.conventions import APPLIED, REACTION
from mbody.model.drawn import drawn_box

if TYPE_CHECKING:
    from mbody.equations.fbd import FreeBodyDiagram


@dataclass
class Outline:
    """A body outline in world coordinates: points to fill (convex hull) and edges."""

    points: np.ndarray  # (k, 3)
    edges: list[tuple[np.ndarray, bool]] = field(default_factory=list)  # ((j, 3), visible)
    size: float = 1.0  # largest extent (m)
    curved: bool = False  # its silhouette (the hull) is drawn as an edge


PARTICLE_DOT = 0.05
"""Radius (m) of the dot drawn for a particle (`inertia: 0`) without a shape."""


def circle(n: int = 72) -> np.ndarray:
    """(n + 1, 2) points around the unit circle, closed."""
    t = np.linspace(0.0, 2.0 * np.pi, n + 1)
    return np.column_stack((np.cos(t), np.sin(t)))


def drawn_points(fbd: FreeBodyDiagram) -> np.ndarray:
    """(k, 3) the points of the body where the diagram's joints and loads act (the joint
    and load points it draws), in body axes from G: what a body without a shape is drawn
    through (`mbody.model.drawn`)."""
    pts = [fo.B_r for fo in fbd.forces
           if fo.kind == REACTION or (fo.kind == APPLIED and not fo.couple)]
    return np.array(pts, dtype=float).reshape(-1, 3)


def outline(fbd: FreeBodyDiagram, eye: np.ndarray) -> Outline:
    """The outline of `fbd`'s body (its shape, else a dot or `mbody.model.drawn`'s box),
    with edges split into the stretches seen and hidden from `eye` (unit vector toward
    it)."""
    x, R = fbd.W_position, fbd.W_R_B
    shape = fbd.shape
    planar = fbd.dimension == cv.PLANAR
    kind: str
    v: Any  # the shape's sizes: a list of lengths or a dict of named ones
    if shape is None and not np.any(fbd.inertia):  # a particle: a dot
        kind, v = "sphere", {"radius": PARTICLE_DOT}
    elif shape is None:  # a bar through its points, or the box with its inertia
        box = drawn_box(fbd.dimension, fbd.mass, fbd.inertia, drawn_points(fbd))
        x, R = x + R @ box.centre, R @ box.axes
        kind, v = "box", list(box.size)
    else:
        kind, v = next(iter(shape.items()))

    def world(B_p: np.ndarray) -> np.ndarray:
        return x + B_p @ R.T

    if planar:
        if kind == "box":
            w, h = v[0] / 2, v[1] / 2
            pts = np.array([[-w, -h], [w, -h], [w, h], [-w, h], [-w, -h]])
        elif kind == "ellipsoid":
            pts = circle() * [v[0], v[1]]
        else:
            pts = circle() * v["radius"]
        p3 = world(np.column_stack((pts, np.zeros(len(pts)))))
        return Outline(p3, [(p3, True)], float(np.ptp(pts, axis=0).max()))

    if kind == "box":
        a, b, c = (s / 2 for s in v)
        corners = np.array([[i * a, j * b, k * c] for i in (-1, 1) for j in (-1, 1)
                            for k in (-1, 1)])
        W_c = world(corners)
        edges: list[tuple[np.ndarray, bool]] = []
        for p in range(8):
            for q in range(p + 1, 8):
                diff = np.flatnonzero(corners[p] != corners[q])
                if len(diff) != 1:
                    continue
                # an edge is visible when one of its two faces looks toward the eye
                ax_e = diff[0]
                others = [k for k in range(3) if k != ax_e]
                normals = [np.sign(corners[p][k]) * R[:, k] for k in others]
                visible = any(float(n @ eye) > 1e-9 for n in normals)
                edges.append((W_c[[p, q]], visible))
        return Outline(W_c, edges, float(max(v)))
    if kind in ("cylinder", "disc"):
        r = v["radius"]
        half = v["length"] / 2 if kind == "cylinder" else 0.04 * r
        ring = circle() * r
        ends = [world(np.column_stack((ring, np.full(len(ring), z)))) for z in (-half, half)]
        near = 1 if float(R[:, 2] @ eye) >= 0 else 0  # the end face looking at the eye
        edges = [(ends[near], True)]
        if kind == "cylinder":  # the far rim shows where the side wall faces the eye
            W_radial = np.column_stack((ring, np.zeros(len(ring)))) @ R.T
            edges += runs(ends[1 - near], W_radial @ eye > 0)
        return Outline(np.vstack(ends), edges, float(max(2 * r, 2 * half)), curved=True)
    semi = np.array([v["radius"]] * 3 if kind == "sphere" else list(v), dtype=float)
    ring = circle()
    edges = []
    for i, j in ((0, 1), (1, 2), (0, 2)):
        B_p = np.zeros((len(ring), 3))
        B_p[:, i], B_p[:, j] = ring[:, 0] * semi[i], ring[:, 1] * semi[j]
        W_normal = (B_p / semi**2) @ R.T  # the surface normal ∝ ∇(pᵀ A p)
        edges += runs(world(B_p), W_normal @ eye > 0)
    # the silhouette is the hull of points over the whole surface
    u, w = np.meshgrid(np.linspace(0, np.pi, 19), np.linspace(0, 2 * np.pi, 37))
    surf = np.column_stack(((np.sin(u) * np.cos(w)).ravel() * semi[0],
                            (np.sin(u) * np.sin(w)).ravel() * semi[1],
                            np.cos(u).ravel() * semi[2]))
    return Outline(world(surf), edges, float(2 * semi.max()), curved=True)


def runs(points: np.ndarray, visible: np.ndarray) -> list[tuple[np.ndarray, bool]]:
    """Split a polyline into stretches that are all visible or all hidden."""
    cuts = np.flatnonzero(visible[1:] != visible[:-1]) + 1
    out: list[tuple[np.ndarray, bool]] = []
    for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(points)], strict=True):
        out.append((points[a:min(b + 1, len(points))], bool(visible[a])))
    return out
