"""Pictures: free-body diagrams (planar and spatial) and the body/joint graph.

Arrow length of a force of magnitude F (world units, in the picture):

    ℓ(F) = ℓ_max · (1 + log10(F / F_min)) / (1 + log10(F_max / F_min))

so the smallest known force is one step long and every factor of 10 adds a step: a force
1000 times another is drawn 4 times as long, and both stay readable. Couples use the same
rule on their own scale (N m); unknown reactions have no magnitude and are drawn at a
fixed length, dashed, in the reaction colour, in their positive direction.

Spatial bodies are drawn in an orthographic projection onto a 2-D Axes: a world vector
W_v appears as ``P @ W_v`` with P the (2, 3) matrix of `projection(view)`, so every
arrow's direction on the page is exactly its projected vector. Planar bodies use the top
view (world x right, y up).

This is the only module importing matplotlib for diagrams. Figures are plain
`matplotlib.figure.Figure` objects on the Agg canvas: no pyplot, no global state, no
display needed. Every drawn element carries a gid (``arrow:<kind>:<name>``,
``couple:<kind>:<name>``, ``label:<kind>:<name>``, ``body-outline``, ``mass-centre``,
``equations``...) so that tests and tools can find it in the figure.
"""

from __future__ import annotations

import io
import math
import re
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Polygon, Rectangle, Wedge
from matplotlib.transforms import Bbox, offset_copy

from mbody import conventions as cv
from mbody.conventions import APPLIED, GRAVITY, REACTION
from mbody.equations.spatial import box_equivalent
from mbody.errors import MbodyError, did_you_mean
from mbody.io.atomic import write_atomic

if TYPE_CHECKING:
    from mbody.equations.fbd import FreeBodyDiagram

COLORS = {APPLIED: "#1f4e9c", GRAVITY: "#2e7d32", REACTION: "#c62828"}
"""Arrow colour per force kind: applied blue, gravity green, reactions red."""
BODY_FACE, BODY_EDGE, AXIS_COLOR = "#e3e6ea", "#4d5561", "#7a7a7a"

VIEWS: dict[str, tuple[float, float]] = {
    "iso": (math.degrees(math.atan(1 / math.sqrt(2))), 45.0),
    "front": (0.0, -90.0),
    "top": (90.0, -90.0),
    "side": (0.0, 0.0),
}
"""Named views as (elevation, azimuth) in degrees; the eye looks from
(cos e cos a, cos e sin a, sin e) toward the origin, world z up. iso: the engineering
isometric (x to the lower left, y to the lower right, z up); front: x right, z up;
side: y right, z up; top: x right, y up."""

FORMATS = ("svg", "png", "pdf")
SCALE_NOTE = ("arrow length ∝ 1 + log10(|F| / F_min): each ×10 in force adds one step\n"
              "unknown reactions: fixed length, drawn in their positive direction")

_UNKNOWN_FORCE, _UNKNOWN_MOMENT = 0.62, 0.82  # of ℓ_max
_HEAD = 0.085  # arrowhead length, of ℓ_max
END_ON = 0.2
"""A spatial arrow whose page length is below END_ON times its 3-D length is drawn end-on:
a ring with a dot (toward the eye) or a cross (away); its short shaft stays, for tools."""


# -- views -----------------------------------------------------------------------------
def parse_view(view: str | Sequence[float] | None) -> tuple[float, float]:
    """'iso' | 'front' | 'top' | 'side' | 'ELEV,AZIM' (degrees) | (elev, azim)."""
    if view is None:
        return VIEWS["iso"]
    if isinstance(view, str):
        key = view.strip().lower()
        if key in VIEWS:
            return VIEWS[key]
        parts = key.split(",")
        if len(parts) == 2:
            try:
                elev, azim = float(parts[0]), float(parts[1])
            except ValueError:
                pass
            else:
                if math.isfinite(elev) and math.isfinite(azim):
                    return elev, azim
        hint = did_you_mean(key, VIEWS)
        raise MbodyError(f"unknown view {view!r}" + (f"; {hint}" if hint else "")
                         + "; use one of " + ", ".join(VIEWS)
                         + ", or ELEV,AZIM in degrees (for example 30,-60)")
    try:
        elev, azim = (float(v) for v in view)
    except (TypeError, ValueError):
        raise MbodyError(f"a view is a name or (elevation, azimuth) in degrees, got {view!r}"
                         ) from None
    return elev, azim


def projection(view: str | Sequence[float] | None = "iso") -> np.ndarray:
    """(2, 3) orthographic projection P: page coordinates (right, up) = P @ W_p.

    Rows are the page's right and up directions in world axes, for an eye at elevation
    e and azimuth a: right = (−sin a, cos a, 0), up = (−sin e cos a, −sin e sin a, cos e).
    """
    e, a = (math.radians(v) for v in parse_view(view))
    right = [-math.sin(a), math.cos(a), 0.0]
    up = [-math.sin(e) * math.cos(a), -math.sin(e) * math.sin(a), math.cos(e)]
    P = np.array([right, up])
    P[np.abs(P) < 1e-15] = 0.0
    return P


def _eye(P: np.ndarray) -> np.ndarray:
    """Unit vector from the scene toward the eye: right × up."""
    return np.cross(P[0], P[1])


# -- arrow lengths ---------------------------------------------------------------------
def arrow_lengths(magnitudes: Sequence[float], longest: float) -> np.ndarray:
    """ℓ = longest · (1 + log10(F/F_min)) / (1 + log10(F_max/F_min)); 0 for F = 0.

    magnitudes: (k,) non-negative. Returns (k,) lengths in the units of `longest`.
    """
    m = np.abs(np.asarray(magnitudes, dtype=float))
    out = np.zeros_like(m)
    pos = m > 0
    if not np.any(pos):
        return out
    steps = 1.0 + np.log10(m[pos] / m[pos].min())
    out[pos] = longest * steps / steps.max()
    return out


# -- shapes ----------------------------------------------------------------------------
@dataclass
class _Outline:
    """A body outline in world coordinates: points to fill (convex hull) and edges."""

    points: np.ndarray  # (k, 3)
    edges: list[tuple[np.ndarray, bool]] = field(default_factory=list)  # ((j, 3), visible)
    size: float = 1.0  # largest extent (m)
    curved: bool = False  # its silhouette (the hull) is drawn as an edge


PARTICLE_DOT = 0.05
"""Radius (m) of the dot drawn for a particle (`inertia: 0`) without a shape."""


def _circle(n: int = 72) -> np.ndarray:
    t = np.linspace(0.0, 2.0 * np.pi, n + 1)
    return np.column_stack((np.cos(t), np.sin(t)))


def _outline(fbd: FreeBodyDiagram, eye: np.ndarray) -> _Outline:
    x, R = fbd.W_position, fbd.W_R_B
    shape = fbd.shape
    planar = fbd.dimension == cv.PLANAR
    if shape is None and not np.any(fbd.inertia):  # a particle: a dot
        kind, v = "sphere", {"radius": PARTICLE_DOT}
    elif shape is None:  # a uniform box with the same principal inertias
        if planar:
            side = math.sqrt(6.0 * fbd.inertia[2, 2] / fbd.mass)
            kind, v = "box", [side, side]
        else:
            J_p, V = np.linalg.eigh(fbd.inertia)
            if np.linalg.det(V) < 0:
                V[:, 2] *= -1
            R = R @ V
            kind, v = "box", list(box_equivalent(J_p, fbd.mass))
    else:
        kind, v = next(iter(shape.items()))

    def world(B_p: np.ndarray) -> np.ndarray:
        return x + B_p @ R.T

    if planar:
        if kind == "box":
            w, h = v[0] / 2, v[1] / 2
            pts = np.array([[-w, -h], [w, -h], [w, h], [-w, h], [-w, -h]])
        elif kind == "ellipsoid":
            pts = _circle() * [v[0], v[1]]
        else:
            pts = _circle() * v["radius"]
        p3 = world(np.column_stack((pts, np.zeros(len(pts)))))
        return _Outline(p3, [(p3, True)], float(np.ptp(pts, axis=0).max()))

    if kind == "box":
        a, b, c = (s / 2 for s in v)
        corners = np.array([[i * a, j * b, k * c] for i in (-1, 1) for j in (-1, 1)
                            for k in (-1, 1)])
        W_c = world(corners)
        edges = []
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
        return _Outline(W_c, edges, float(max(v)))
    if kind in ("cylinder", "disc"):
        r = v["radius"]
        half = v["length"] / 2 if kind == "cylinder" else 0.04 * r
        ring = _circle() * r
        ends = [world(np.column_stack((ring, np.full(len(ring), z)))) for z in (-half, half)]
        near = 1 if float(R[:, 2] @ eye) >= 0 else 0  # the end face looking at the eye
        edges = [(ends[near], True)]
        if kind == "cylinder":  # the far rim shows where the side wall faces the eye
            W_radial = np.column_stack((ring, np.zeros(len(ring)))) @ R.T
            edges += _runs(ends[1 - near], W_radial @ eye > 0)
        return _Outline(np.vstack(ends), edges, float(max(2 * r, 2 * half)), curved=True)
    semi = np.array([v["radius"]] * 3 if kind == "sphere" else list(v), dtype=float)
    ring = _circle()
    edges = []
    for i, j in ((0, 1), (1, 2), (0, 2)):
        B_p = np.zeros((len(ring), 3))
        B_p[:, i], B_p[:, j] = ring[:, 0] * semi[i], ring[:, 1] * semi[j]
        W_normal = (B_p / semi**2) @ R.T  # the surface normal ∝ ∇(pᵀ A p)
        edges += _runs(world(B_p), W_normal @ eye > 0)
    # the silhouette is the hull of points over the whole surface
    u, w = np.meshgrid(np.linspace(0, np.pi, 19), np.linspace(0, 2 * np.pi, 37))
    surf = np.column_stack(((np.sin(u) * np.cos(w)).ravel() * semi[0],
                            (np.sin(u) * np.sin(w)).ravel() * semi[1],
                            np.cos(u).ravel() * semi[2]))
    return _Outline(world(surf), edges, float(2 * semi.max()), curved=True)


def _runs(points: np.ndarray, visible: np.ndarray) -> list[tuple[np.ndarray, bool]]:
    """Split a polyline into stretches that are all visible or all hidden."""
    cuts = np.flatnonzero(visible[1:] != visible[:-1]) + 1
    out = []
    for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(points)], strict=True):
        out.append((points[a:min(b + 1, len(points))], bool(visible[a])))
    return out


# -- the picture's elements --------------------------------------------------------------
@dataclass
class _Arrow:
    gid: str
    kind: str
    label: str
    color: str
    dashed: bool
    couple: bool
    tail: np.ndarray  # (2,) page
    vec: np.ndarray  # (2,) page (projected drawn vector); planar couple: (sign, radius)
    arc: np.ndarray | None = None  # planar couple: (k, 2) points
    length3: float = 0.0  # drawn length in 3-D, before projection
    toward: float = 0.0  # its component toward the eye (spatial)
    line: Line2D | None = None


def _fmt(x: float) -> str:
    x = 0.0 if abs(x) < 1e-12 else x
    s = f"{x:.4g}"
    return "0" if s in ("-0", "0") else s.replace("-", "−")


def _tex_safe(s: str) -> str:
    return s.replace("$", r"\$")  # a '$' in a user's name must not start mathtext


def _label(fo) -> str:
    unit = "N m" if fo.couple else "N"
    if fo.kind == REACTION:
        return fo.label if fo.value is None else f"{fo.label} = {_fmt(fo.value)} {unit}"
    if fo.kind == GRAVITY:
        return f"m g = {_fmt(fo.magnitude)} N"
    return f"{fo.name} {_fmt(fo.magnitude)} {unit}"


def _direction(fo) -> np.ndarray:
    """Unit direction drawn: the vector itself, or for a known reaction the positive
    direction of its component (its value then carries the sign)."""
    v = np.asarray(fo.W_vector, dtype=float)
    if fo.kind == REACTION and fo.value is not None and fo.value != 0:
        v = v / fo.value
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def _arrows(fbd: FreeBodyDiagram, P: np.ndarray, lmax: float) -> list[_Arrow]:
    planar = fbd.dimension == cv.PLANAR
    forces = list(fbd.forces)
    known = [fo for fo in forces if not fo.unknown]
    mag = {id(fo): (abs(fo.value) if fo.kind == REACTION else fo.magnitude) for fo in known}
    lengths = {}
    for couple in (False, True):
        group = [fo for fo in known if fo.couple == couple]
        for fo, ell in zip(group, arrow_lengths([mag[id(f)] for f in group], lmax),
                           strict=True):
            lengths[id(fo)] = ell
    out: list[_Arrow] = []
    ring_count: dict[tuple, int] = {}
    for fo in forces:
        kind = fo.kind
        if not fo.unknown and (fo.value == 0 if kind == REACTION else fo.magnitude == 0):
            continue  # nothing to draw; listed under the drawing instead
        ell = lengths.get(id(fo), lmax * (_UNKNOWN_MOMENT if fo.couple else _UNKNOWN_FORCE))
        d = _direction(fo)
        tail3 = np.asarray(fo.W_point, dtype=float)
        tail = P @ tail3
        gid = f"{'couple' if fo.couple else 'arrow'}:{kind}:{fo.label or fo.name}"
        a = _Arrow(gid, kind, _label(fo), COLORS[kind], kind == REACTION, fo.couple,
                   tail, P @ (ell * d), length3=ell, toward=float(ell * d @ _eye(P)))
        if fo.couple and planar:
            sign = 1.0 if d[2] >= 0 else -1.0
            key = tuple(np.round(tail, 9))
            k = ring_count[key] = ring_count.get(key, -1) + 1
            rho = (0.30 * ell + 0.06 * lmax) * (1 + 0.35 * k) if ell > 0 else 0.0
            start = math.radians(-60 + 25 * k)
            t = start + sign * np.linspace(0.0, 1.5 * np.pi, 60)
            a.arc = tail + rho * np.column_stack((np.cos(t), np.sin(t)))
            a.vec = np.array([sign, rho])
        out.append(a)
    # arrows leaving one point along the same page direction (a joint's Mx beside its
    # Fx, two joints' Fy at one pin) move aside a little, so that each stays visible
    seen: list[_Arrow] = []
    for a in out:
        n = np.linalg.norm(a.vec)
        if a.arc is not None or n == 0:
            continue
        d = a.vec / n
        k = 0
        for b in seen:
            e = b.vec / np.linalg.norm(b.vec)
            if (np.linalg.norm(b.tail - a.tail) < 0.05 * lmax and d @ e > 0
                    and abs(d[0] * e[1] - d[1] * e[0]) < 0.14):
                k += 1
        if k:
            a.tail = a.tail + 0.07 * k * lmax * np.array([-d[1], d[0]])
        seen.append(a)
    return out


def _head(tip: np.ndarray, d: np.ndarray, h: float) -> np.ndarray:
    n = np.array([-d[1], d[0]])
    return np.array([tip, tip - h * d + 0.36 * h * n, tip - h * d - 0.36 * h * n])


def _sample(points: np.ndarray, step: float) -> np.ndarray:
    """Points every `step` along a polyline (display units), for overlap tests."""
    pts = [points[:1]]
    for p, q in zip(points[:-1], points[1:], strict=True):
        k = max(1, int(math.ceil(np.linalg.norm(q - p) / step)))
        pts.append(p + (q - p) * (np.arange(1, k + 1) / k)[:, None])
    return np.vstack(pts)


# -- figure ----------------------------------------------------------------------------
def draw_fbd(fbd, *, view: str | Sequence[float] | None = "iso", equations: bool = True,
             width: float = 8.0, title: str | None = None) -> Figure:
    """The free-body diagram of one body as a matplotlib `Figure` (Agg canvas).

    fbd: a `FreeBodyDiagram` (or a `BodyEquations`). view: spatial bodies only, see
    `projection`. equations: write the body's Newton-Euler pair under the drawing.
    """
    from scipy.spatial import ConvexHull  # slow to import; `mbody graph` does not need it

    if hasattr(fbd, "fbd"):
        fbd = fbd.fbd
    planar = fbd.dimension == cv.PLANAR
    P = projection("top" if planar else view)
    eye = _eye(P)
    outline = _outline(fbd, eye)
    reach = max([outline.size] + [2 * float(np.linalg.norm(f.B_r)) for f in fbd.forces])
    lmax = 0.55 * reach
    arrows = _arrows(fbd, P, lmax)
    head = _HEAD * lmax

    eq_lines = _equation_lines(fbd, planar) if equations else []
    zeros = [fo.label or fo.name for fo in fbd.forces if not fo.unknown and (
        fo.value == 0 if fo.kind == REACTION else fo.magnitude == 0)]
    zero_note = textwrap.wrap("zero at this instant (not drawn): " + ", ".join(zeros), 110)
    h_draw, h_title = 5.6, 0.45
    h_band = 1.25 + 0.17 * len(zero_note) if zeros else 1.25
    h_eq = (0.3 + 0.19 * len(eq_lines)) if eq_lines else 0.0
    H = h_title + h_draw + h_band + h_eq
    fig = Figure(figsize=(width, H), dpi=100)
    canvas = FigureCanvasAgg(fig)

    def frac(y0: float, h: float) -> tuple[float, float]:  # inches from top -> figure fraction
        return 1 - (y0 + h) / H, h / H

    b, hh = frac(h_title, h_draw)
    ax = fig.add_axes((0.03, b, 0.94, hh), gid="drawing")
    ax.set_aspect("equal", adjustable="box")
    ax.set_axis_off()
    name = _tex_safe(fbd.body)
    props = (f"m = {_fmt(fbd.mass)} kg, particle" if not np.any(fbd.inertia)
             else f"m = {_fmt(fbd.mass)} kg, I_G = {_fmt(fbd.inertia[2, 2])} kg m²" if planar
             else f"m = {_fmt(fbd.mass)} kg, view {_view_name(view)}")
    fig.text(0.5, 1 - 0.25 / H, title or f"Free-body diagram of {name}   ({props})",
             ha="center", va="center", fontsize=12, weight="bold", gid="title")

    # body outline, hidden edges dotted
    hull_pts = outline.points @ P.T
    hull = ConvexHull(hull_pts, qhull_options="QJ")
    ax.add_patch(Polygon(hull_pts[hull.vertices], closed=True, facecolor=BODY_FACE,
                         edgecolor="none", zorder=1, gid="body-outline"))
    rim = hull_pts[np.r_[hull.vertices, hull.vertices[0]]]
    obstacles: list[tuple[np.ndarray, str]] = [(rim, "outline")]
    if outline.curved:
        ax.add_line(Line2D(rim[:, 0], rim[:, 1], color=BODY_EDGE, lw=1.3, zorder=2,
                           gid="body-edge"))
    for pts, visible in outline.edges:
        pp = pts @ P.T
        ax.add_line(Line2D(pp[:, 0], pp[:, 1], color=BODY_EDGE, lw=1.3 if visible else 0.8,
                           ls="-" if visible else ":", zorder=2, gid="body-edge"))
        obstacles.append((pp, "outline"))

    # mass centre G and body axes
    G = P @ fbd.W_position
    rg = 0.045 * lmax
    ax.add_patch(Circle(G, rg, facecolor="white", edgecolor="black", lw=1, zorder=6,
                        gid="mass-centre"))
    for a0 in (0, 180):
        ax.add_patch(Wedge(G, rg, a0, a0 + 90, facecolor="black", zorder=6))
    label_items: list[tuple] = []
    for k, nm in enumerate("xyz"[:2 if planar else 3]):
        W_a = fbd.W_R_B[:, k] * 0.38 * outline.size
        tip = G + P @ W_a
        seg = np.array([G, tip])
        ax.add_line(Line2D(seg[:, 0], seg[:, 1], color=AXIS_COLOR, lw=1, zorder=3,
                           gid=f"body-axis:{nm}"))
        if np.linalg.norm(tip - G) > 1e-9:
            ax.add_patch(Polygon(_head(tip, (tip - G) / np.linalg.norm(tip - G), 0.6 * head),
                                 color=AXIS_COLOR, zorder=3))
        obstacles.append((seg, "axis"))
        label_items.append((f"${nm}_B$", tip, tip - G, AXIS_COLOR, f"label:body-axis:{nm}",
                            "axis", 8))
    label_items.append(("G", G, np.array([-1.0, 1.0]), "black", "label:mass-centre", "g", 9))

    # joint points and points of application
    for fo in fbd.forces:
        if not fo.couple and np.linalg.norm(fo.B_r) > 0:
            p = P @ fo.W_point
            ax.add_patch(Circle(p, 0.022 * lmax, facecolor="white",
                                edgecolor=COLORS[fo.kind], lw=1.2, zorder=7,
                                gid="joint-point" if fo.kind == REACTION else "load-point"))

    # arrows: a shaft (Line2D, gid = the arrow's) and a filled head (gid + ':head')
    for a in arrows:
        ls = (0, (4, 2.5)) if a.dashed else "-"
        if a.arc is not None:
            pts = a.arc
        else:
            pts = np.array([a.tail, a.tail + a.vec])
        a.line = Line2D(pts[:, 0], pts[:, 1], color=a.color, lw=2.0, ls=ls, zorder=8,
                        gid=a.gid, solid_capstyle="butt")
        ax.add_line(a.line)
        obstacles.append((pts, a.gid))
        if a.arc is not None:
            if a.vec[1] > 0:
                t_end = a.arc[-1] - a.arc[-2]
                ax.add_patch(Polygon(_head(a.arc[-1], t_end / np.linalg.norm(t_end), head),
                                     color=a.color, zorder=9, gid=a.gid + ":head"))
            anchor, direction = a.arc[-1], a.arc[-1] - a.tail
        elif np.linalg.norm(a.vec) < END_ON * a.length3:
            # seen end-on: a dot toward the eye, a cross away from it (two rings: a moment)
            r = 0.05 * lmax
            for k in range(2 if a.couple else 1):
                ax.add_patch(Circle(a.tail, r * (1 + 0.45 * k), fill=False, ec=a.color, lw=1.6,
                                    zorder=9, gid=a.gid + (":end-on" if k == 0 else ":ring2")))
            if a.toward > 0:
                ax.add_patch(Circle(a.tail, 0.3 * r, color=a.color, zorder=9))
            else:
                for s_ in (1, -1):
                    xx = a.tail + 0.7 * r * np.array([[-1, -s_], [1, s_]]) / math.sqrt(2)
                    ax.add_line(Line2D(xx[:, 0], xx[:, 1], color=a.color, lw=1.4, zorder=9))
            ring = a.tail + r * (1.5 if a.couple else 1.0) * _circle(24)
            obstacles.append((ring, a.gid))
            anchor, direction = a.tail + r * np.array([0.7, 0.7]), np.array([1.0, 0.7])
        else:
            n = np.linalg.norm(a.vec)
            tip = a.tail + a.vec
            if n > 1e-9:
                d = a.vec / n
                ax.add_patch(Polygon(_head(tip, d, head), color=a.color, zorder=9,
                                     gid=a.gid + ":head"))
                if a.couple:  # a moment: double head
                    ax.add_patch(Polygon(_head(tip - 0.75 * head * d, d, head), color=a.color,
                                         zorder=9, gid=a.gid + ":head2"))
                obstacles.append((_head(tip, d, head)[[0, 1, 2, 0]], a.gid))
            anchor, direction = tip, (a.vec if n > 1e-9 else np.array([1.0, 0.3]))
        label_items.append((_tex_safe(a.label), anchor, direction, a.color,
                            "label:" + a.gid.split(":", 1)[1], a.gid, 9))

    # limits: geometry first, then grown until every label fits
    geo = np.vstack([o[0] for o in obstacles])
    lo, hi = geo.min(axis=0), geo.max(axis=0)
    span = max(float((hi - lo).max()), 1e-6)
    pad = 0.18 * span
    _set_limits(ax, lo - pad, hi + pad)
    texts = [ax.text(0, 0, s, color=c, fontsize=fs, zorder=10, gid=gid, clip_on=False)
             for s, _, _, c, gid, _, fs in label_items]
    renderer = canvas.get_renderer()
    for _ in range(4):
        ax.apply_aspect()
        boxes = _place_labels(fig, ax, renderer, texts, label_items, obstacles)
        ab = ax.get_window_extent(renderer)
        inside = all(ab.x0 <= bb.x0 and bb.x1 <= ab.x1 and ab.y0 <= bb.y0 and bb.y1 <= ab.y1
                     for bb in boxes)
        if inside:
            break
        inv = ax.transData.inverted()
        corners = np.vstack([inv.transform([[bb.x0, bb.y0], [bb.x1, bb.y1]]) for bb in boxes])
        lo = np.minimum(lo, corners.min(axis=0))
        hi = np.maximum(hi, corners.max(axis=0))
        span = float((hi - lo).max())
        _set_limits(ax, lo - 0.05 * span, hi + 0.05 * span)

    # band: world axes on the left, legend on the right
    if zeros:
        fig.text(0.04, 1 - (h_title + h_draw + 0.04) / H, _tex_safe("\n".join(zero_note)),
                 ha="left", va="top", fontsize=8.5, color=COLORS[REACTION], gid="zero-note")
    b, hh = frac(h_title + h_draw + h_band - 1.25, 1.25)
    tri = fig.add_axes((0.03, b + 0.05 * hh, 0.9 * hh * H / width, 0.9 * hh), gid="world-axes")
    _world_triad(tri, P, planar)
    leg_ax = fig.add_axes((0.2, b, 0.78, hh))
    leg_ax.set_axis_off()
    _legend(leg_ax, fbd, arrows, planar)

    if eq_lines:
        b, hh = frac(h_title + h_draw + h_band, h_eq)
        fig.text(0.04, b + hh - 0.12 / H, "\n".join(eq_lines), ha="left", va="top",
                 family="monospace", fontsize=9, gid="equations", linespacing=1.45)
    return fig


def _view_name(view) -> str:
    if isinstance(view, str) and view.strip().lower() in VIEWS:
        return view.strip().lower()
    e, a = parse_view(view)
    return f"elev {e:g}°, azim {a:g}°"


def _set_limits(ax, lo: np.ndarray, hi: np.ndarray) -> None:
    """Limits covering [lo, hi], widened to the Axes box's shape so that one metre is
    as long across as up (equal aspect without matplotlib moving the box)."""
    fw, fh = ax.get_figure().get_size_inches()
    pos = ax.get_position()
    box = pos.width * fw / (pos.height * fh)
    c, half = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-9)
    if half[0] / half[1] < box:
        half[0] = half[1] * box
    else:
        half[1] = half[0] / box
    ax.set_xlim(c[0] - half[0], c[0] + half[0])
    ax.set_ylim(c[1] - half[1], c[1] + half[1])


def _equation_lines(fbd: FreeBodyDiagram, planar: bool) -> list[str]:
    if not fbd.equations:
        return []
    nn = 2 if planar else 3
    lines = ["Newton (world axes):"]
    for i, e in enumerate(fbd.equations):
        if i == nn:
            lines.append("Euler (about G, " + ("z):" if planar else "body axes):"))
        wrapped = textwrap.wrap(f"{e.row}:  {e}", 96, subsequent_indent="      ",
                                break_on_hyphens=False)
        lines += ["  " + w for w in wrapped]
    return [_tex_safe(x) for x in lines]


def _place_labels(fig, ax, renderer, texts, items, obstacles) -> list[Bbox]:
    """Greedy placement: for each label try spots around its anchor (the arrow tip) and
    keep the one crossing the fewest drawn lines and placed labels, its own arrow worst.

    Works in display pixels; a label's box at a spot follows from its size and alignment
    (text is never rotated), so each candidate costs a few array operations."""
    to_px = ax.transData.transform
    px_per_pt = fig.dpi / 72.0
    step = 1.5 * px_per_pt
    pts_list, tags = [], []
    for pts, tag in obstacles:
        sp = _sample(to_px(pts), step)
        pts_list.append(sp)
        tags += [tag] * len(sp)
    P = np.vstack(pts_list)
    tags_arr = np.array(tags, dtype=object)
    base_w = np.where(tags_arr == "outline", 0.4, 3.0)
    placed = np.zeros((0, 4))  # x0, y0, x1, y1
    ax_box = ax.get_window_extent(renderer)
    pad = 2 * px_per_pt
    frac = {"left": 0.0, "center": 0.5, "right": 1.0, "bottom": 0.0, "top": 1.0}
    for text, (_, anchor, direction, _, _, own, _) in zip(texts, items, strict=True):
        text.set_position(anchor)
        text.set_transform(ax.transData)
        text.set_ha("left")
        text.set_va("bottom")
        ext = text.get_window_extent(renderer)
        w, h = ext.width, ext.height
        weights = np.where(tags_arr == own, 8.0, base_w)
        a_px = to_px(anchor)
        d = np.asarray(direction, dtype=float)
        n = np.linalg.norm(d)
        d = d / n if n > 1e-12 else np.array([1.0, 0.0])
        nrm = np.array([-d[1], d[0]])
        cands = [d * 5, d * 5 + nrm * 9, d * 5 - nrm * 9, nrm * 10, -nrm * 10, d * 18,
                 d * 5 + nrm * 22, d * 5 - nrm * 22, d * 30 + nrm * 10, d * 30 - nrm * 10]
        if own not in ("axis", "g"):  # beside the shaft, half-way
            mid = -0.5 * np.linalg.norm(a_px - to_px(anchor - direction)) / px_per_pt
            cands += [d * mid + nrm * 10, d * mid - nrm * 10]
        # then a ring of spots further out, for crowded joints
        for radius in (14.0, 26.0, 40.0):
            for ang in np.linspace(0, 2 * np.pi, 16, endpoint=False):
                cands.append(radius * (np.cos(ang) * d + np.sin(ang) * nrm))
        best = None
        for off in cands:
            o = off / (np.linalg.norm(off) or 1.0)
            ha = "left" if o[0] > 0.3 else "right" if o[0] < -0.3 else "center"
            va = "bottom" if o[1] > 0.3 else "top" if o[1] < -0.3 else "center"
            x = a_px[0] + off[0] * px_per_pt - frac[ha] * w
            y = a_px[1] + off[1] * px_per_pt - frac[va] * h
            x0, y0, x1, y1 = x - pad, y - pad, x + w + pad, y + h + pad
            inside = (P[:, 0] > x0) & (P[:, 0] < x1) & (P[:, 1] > y0) & (P[:, 1] < y1)
            score = 0.004 * float(np.linalg.norm(off))  # nearer is better, all else equal
            score += float(weights[inside].sum())
            if len(placed):
                ow = np.minimum(x1, placed[:, 2]) - np.maximum(x0, placed[:, 0])
                oh = np.minimum(y1, placed[:, 3]) - np.maximum(y0, placed[:, 1])
                hit = (ow > 0) & (oh > 0)
                score += float(np.sum(200 + 5 * ow[hit] * oh[hit] / px_per_pt**2))
            if not (ax_box.x0 <= x0 and x1 <= ax_box.x1 and ax_box.y0 <= y0
                    and y1 <= ax_box.y1):
                score += 2.0  # allowed (limits grow later) but not preferred
            if best is None or score < best[0] - 1e-9:
                best = (score, off, ha, va, (x0, y0, x1, y1))
        _, off, ha, va, box = best
        text.set_transform(offset_copy(ax.transData, fig=fig, x=off[0], y=off[1],
                                       units="points"))
        text.set_ha(ha)
        text.set_va(va)
        placed = np.vstack((placed, box))
    return [t.get_window_extent(renderer) for t in texts]


def _world_triad(ax, P: np.ndarray, planar: bool) -> None:
    ax.set_xlim(-1.45, 1.45)
    ax.set_ylim(-1.45, 1.45)
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.text(0, -1.42, "world", ha="center", va="bottom", fontsize=8, color="#333")
    for k, nm in enumerate("xyz"[:2 if planar else 3]):
        v = P[:, k] * 0.9
        n = np.linalg.norm(v)
        if n < 0.15:  # along the line of sight: ⊙ out of the page, ⊗ into it
            out = float(_eye(P)[k]) > 0
            ax.add_patch(Circle((0, 0), 0.14, fill=False, lw=1))
            ax.text(0.18, 0.12, nm, fontsize=9)
            ax.plot([0], [0], marker="o" if out else "x", color="black", ms=3)
            continue
        ax.add_line(Line2D([0, v[0]], [0, v[1]], color="black", lw=1.2,
                           gid=f"world-axis:{nm}"))
        ax.add_patch(Polygon(_head(v, v / n, 0.22), color="black"))
        ax.text(*(v + 0.3 * v / n), nm, ha="center", va="center", fontsize=9)


def _legend(ax, fbd: FreeBodyDiagram, arrows: list[_Arrow], planar: bool) -> None:
    handles = [Line2D([], [], color=COLORS[APPLIED], lw=2, label="applied force (name, |F|)"),
               Line2D([], [], color=COLORS[GRAVITY], lw=2, label="gravity m g at G"),
               Line2D([], [], color=COLORS[REACTION], lw=2, ls=(0, (4, 2.5)),
                      label="reaction (unknown name, or known value)")]
    if any(a.couple for a in arrows):
        handles.append(Line2D([], [], color="#555", lw=2, marker=r"$\circlearrowleft$"
                              if planar else r"$\gg$", ms=10,
                              label="couple: curved arrow" if planar
                              else "couple/moment: double head (right-hand rule)"))
    handles.append(Line2D([], [], color="black", marker="o", ls="", mfc="white",
                          label="G mass centre, x_B y_B" + ("" if planar else " z_B")
                          + " body axes"))
    ax.legend(handles=handles, loc="center", ncol=2, fontsize=8.5, frameon=True,
              title=SCALE_NOTE, title_fontsize=8)


# -- body/joint graph ----------------------------------------------------------------------
def _layers(g, roots: list[str]) -> dict[str, tuple[float, float]]:
    """Positions: breadth-first layers from ground (top); parts without ground beside it."""
    import networkx as nx

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


def _count(k: int, word: str) -> str:
    return f"{k} {word if k == 1 else word[:-1] + 'ies' if word.endswith('y') else word + 's'}"


def draw_graph(model, topo=None) -> Figure:
    """The body/joint graph: bodies and ground as nodes, each joint an edge labelled
    with its name, type and number of reaction components (networkx MultiGraph)."""
    import networkx as nx

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
    fig = Figure(figsize=(w_in, h_in), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.01, 0.01, 0.98, 1 - 0.8 / h_in - 0.01), gid="graph")
    ax.set_axis_off()
    ax.set_aspect("equal", adjustable="box")
    _set_limits(ax, lo, hi)
    head = (f"body/joint graph of {_tex_safe(model.name)}: {_count(model.n, 'body')} + "
            f"ground, {_count(len(model.joints), 'joint')}")
    if topo is not None:
        head += (f"; {'a tree' if topo.is_tree else _count(topo.loops, 'closed loop')}, "
                 f"mobility {topo.mobility}")
    head = "\n".join(textwrap.wrap(head, int(w_in * 9)))
    fig.text(0.5, 1 - 0.4 / h_in, head, ha="center", va="center", fontsize=11,
             weight="bold", gid="title")

    groups: dict[tuple[str, str], list] = {}
    for u, v, data in g.edges(data=True):
        groups.setdefault(tuple(sorted((u, v))), []).append(data)
    for (u, v), edges in groups.items():
        pu, pv = np.array(pos[u]), np.array(pos[v])
        normal = np.array([-(pv - pu)[1], (pv - pu)[0]])
        for k, data in enumerate(sorted(edges, key=lambda d: d["joint"])):
            bend = (k - (len(edges) - 1) / 2) * 0.45
            ctrl = (pu + pv) / 2 + bend * normal
            t = np.linspace(0, 1, 40)[:, None]
            curve = (1 - t) ** 2 * pu + 2 * (1 - t) * t * ctrl + t**2 * pv
            ax.add_line(Line2D(curve[:, 0], curve[:, 1], color="#555", lw=1.6, zorder=1,
                               gid=f"joint:{data['joint']}"))
            mid = 0.25 * pu + 0.5 * ctrl + 0.25 * pv
            r = data["reactions"]
            ax.text(mid[0], mid[1], f"{_tex_safe(data['joint'])}: {data['type']}\n"
                    f"{r} reaction{'s' if r != 1 else ''}", ha="center", va="center",
                    fontsize=8, zorder=3, gid=f"joint-label:{data['joint']}",
                    bbox=dict(boxstyle="round,pad=0.25", fc="#fff8e1", ec="#c9a227", lw=0.8))
    for node, (x, y) in pos.items():
        if node == cv.GROUND:
            ax.add_patch(Rectangle((x - 0.45, y - 0.2), 0.9, 0.4, hatch="///", fc="#eeeeee",
                                   ec="black", zorder=2, gid="node:ground"))
            ax.text(x, y + 0.28, "ground", ha="center", va="bottom", fontsize=9, zorder=3)
            continue
        ax.text(x, y, _tex_safe(node), ha="center", va="center", fontsize=9.5, zorder=3,
                gid=f"node:{node}", bbox=dict(boxstyle="round,pad=0.55", fc="#dbe7f6",
                                              ec=COLORS[APPLIED], lw=1.4))
    return fig


# -- output ----------------------------------------------------------------------------
_SVG_PREAMBLE = re.compile(r"<\?xml.*?\?>\s*|<!DOCTYPE.*?>\s*|<metadata>.*?</metadata>\s*",
                           re.S)


def figure_bytes(fig: Figure, fmt: str = "svg", dpi: int = 150) -> bytes:
    """The figure encoded as svg, png or pdf (no dates inside, so output is repeatable)."""
    if fmt not in FORMATS:
        raise MbodyError(f"unknown picture format {fmt!r}; use one of {', '.join(FORMATS)}")
    buf = io.BytesIO()
    meta = {"svg": {"Date": None}, "pdf": {"CreationDate": None}, "png": {}}[fmt]
    fig.savefig(buf, format=fmt, dpi=dpi, metadata=meta, facecolor="white")
    return buf.getvalue()


def figure_svg(fig: Figure) -> str:
    """The figure as an SVG element (no XML prolog or metadata: ready to inline in HTML)."""
    return _SVG_PREAMBLE.sub("", figure_bytes(fig, "svg").decode("utf-8")).strip()


def save_figure(fig: Figure, path: str | Path, fmt: str | None = None, dpi: int = 150) -> Path:
    """Write the figure atomically; the format is `fmt` or the file's extension."""
    path = Path(path)
    fmt = fmt or path.suffix.lstrip(".").lower()
    if fmt not in FORMATS:
        raise MbodyError(f"cannot tell the picture format of {str(path)!r}; "
                         f"use a file name ending in {', '.join('.' + f for f in FORMATS)}")
    return write_atomic(path, figure_bytes(fig, fmt, dpi))
