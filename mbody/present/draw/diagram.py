"""The free-body diagram of one body as a `Scene`: title, drawing, world axes, legend
and the body's Newton-Euler pair.

Spatial bodies are drawn in an orthographic projection: a world vector W_v appears as
``P @ W_v`` with P the (2, 3) matrix of `projection(view)`, so every arrow's direction on
the page is exactly its projected vector. Planar bodies use the top view (world x
right, y up). Every element carries a gid (``arrow:<kind>:<name>``,
``couple:<kind>:<name>``, ``label:<kind>:<name>``, ``body-outline``, ``mass-centre``,
``equations``...; kind applied, gravity, reaction or effort, a driver's) so that tests
and tools can find it.
"""

from __future__ import annotations

import math
import textwrap
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import ConvexHull

from mbody import conventions as cv
from mbody.conventions import REACTION
from mbody.present.draw.arrows import END_ON, HEAD, Arrow, arrows, fmt, head
from mbody.present.draw.fonts import layout
from mbody.present.draw.labels import Label, place
from mbody.present.draw.outline import circle, outline
from mbody.present.draw.scene import IN, Disc, Item, Line, Panel, Poly, Scene, Text, Wedge
from mbody.present.draw.spacing import separate
from mbody.present.draw.style import (
    AXIS_COLOR,
    BODY_EDGE,
    BODY_FACE,
    COLORS,
    DASHES,
    DOTTED,
    EFFORT,
    SCALE_NOTE,
)
from mbody.present.draw.views import View, eye, projection, view_name

if TYPE_CHECKING:
    from mbody.equations.fbd import FreeBodyDiagram

__all__ = ["END_ON", "fbd_scene"]


def fbd_scene(fbd: FreeBodyDiagram, *, view: View = "iso", equations: bool = True,
              width: float = 8.0, title: str | None = None) -> Scene:
    """The free-body diagram of one body as a `Scene` (write it with `save_figure` or
    `figure_svg`, or turn it into a matplotlib figure with `scene_figure`).

    Parameters
    ----------
    fbd : FreeBodyDiagram
        Or a `BodyEquations` (its ``.fbd``).
    view : str or (float, float)
        Spatial bodies only, see `projection`.
    equations : bool
        Write the body's Newton-Euler pair under the drawing.
    width : float
        Picture width (inches).
    title : str, optional
        Instead of "Free-body diagram of <body> (...)".

    Returns
    -------
    Scene
    """
    fbd = getattr(fbd, "fbd", fbd)
    planar = fbd.dimension == cv.PLANAR
    P = projection("top" if planar else view)
    E = eye(P)
    shape = outline(fbd, E)
    reach = max([shape.size] + [2 * float(np.linalg.norm(f.B_r)) for f in fbd.forces])
    lmax = 0.55 * reach
    arrs = arrows(fbd, P, lmax)

    eq_lines = _equation_lines(fbd, planar) if equations else []
    zeros = [fo.signed_label for fo in fbd.forces if not fo.unknown and (
        fo.value == 0 if fo.kind == REACTION else fo.magnitude == 0)]
    zero_note = textwrap.wrap("zero at this instant (not drawn): " + ", ".join(zeros), 110)
    h_draw, h_title = 5.6, 0.45
    h_band = 1.25 + 0.17 * len(zero_note) if zeros else 1.25
    h_eq = (0.3 + 0.19 * len(eq_lines)) if eq_lines else 0.0
    H = h_title + h_draw + h_band + h_eq
    W = width * IN
    sc = Scene(W, H * IN)

    def top(y0: float) -> float:  # inches from the top -> points from the bottom
        return (H - y0) * IN

    sc.title = title or f"Free-body diagram of {fbd.body}   ({_properties(fbd, planar, view)})"
    sc.root.add(_title(sc.title, np.array([W / 2, top(0.25)]), 0.96 * W, h_title * IN))
    ax = sc.panel("drawing", (0.03 * W, top(h_title + h_draw), 0.94 * W, h_draw * IN))

    # body outline, hidden edges dotted
    hull_pts = shape.points @ P.T
    hull = ConvexHull(hull_pts, qhull_options="QJ")
    ax.add(Poly(hull_pts[hull.vertices], BODY_FACE, zorder=1, gid="body-outline"))
    rim = hull_pts[np.r_[hull.vertices, hull.vertices[0]]]
    obstacles: list[tuple[np.ndarray, str]] = [(rim, "outline")]
    if shape.curved:
        ax.add(Line(rim, BODY_EDGE, 1.3, zorder=2, gid="body-edge"))
    for pts, visible in shape.edges:
        pp = pts @ P.T
        ax.add(Line(pp, BODY_EDGE, 1.3 if visible else 0.8, None if visible else DOTTED,
                    zorder=2, gid="body-edge"))
        obstacles.append((pp, "outline"))

    # the symbols' size (heads, rings, markers) follows the arrows' up to SYMBOLS points:
    # a long thin body seen end-on, small on the page beside its arrows, keeps them small
    G = P @ fbd.W_position
    axes3 = [fbd.W_R_B[:, k] * 0.38 * shape.size for k in range(2 if planar else 3)]
    ax.set_limits(*_padded(np.vstack([hull_pts, G + np.array([P @ v for v in axes3])]
                                     + [(P @ fo.W_point)[None] for fo in fbd.forces]
                                     + _arrow_extents(arrs))))
    sym = min(lmax, SYMBOLS / ax.scale)
    hd = HEAD * sym

    # mass centre G and body axes
    rg = 0.045 * sym
    _centre_mark(ax, G, rg, zorder=6, gid="mass-centre")
    fixed = [o[0] for o in obstacles]  # strokes an arrow must not lie on: outline...
    obstacles.append((G + rg * circle(24), "mass-centre"))
    lines: list[np.ndarray] = []  # ... and body axes, which it must keep farther from
    marks: list[tuple[np.ndarray, float]] = []  # the rings of body axes seen end-on
    labels: list[Label] = []
    end_on_labels: list[Label] = []  # theirs
    for k, nm in enumerate("xyz"[:len(axes3)]):
        tag = f"body-axis:{nm}"
        tip = G + P @ axes3[k]
        if not planar and np.linalg.norm(tip - G) < END_ON * np.linalg.norm(axes3[k]):
            # seen end-on: a small ring beside G, a dot toward the eye, a cross away
            c, r, u = _end_on_axis(G, rg, sym, [P @ v for v in axes3]
                                   + [a.vec for a in arrs if a.arc is None
                                      and np.linalg.norm(a.tail - G) < 2 * rg])
            # its short shaft stays under G's marker, for tools (as an end-on arrow's)
            ax.add(Line(np.array([G, tip]), AXIS_COLOR, 1.0, zorder=3, gid=tag),
                   Disc(c, r, "white", AXIS_COLOR, 1.0, zorder=3, gid=f"{tag}:ring"))
            if float(fbd.W_R_B[:, k] @ E) > 0:
                ax.add(Disc(c, 0.3 * r, AXIS_COLOR, zorder=3, gid=f"{tag}:dot"))
            else:
                for s_ in (1, -1):
                    xx = c + 0.7 * r * np.array([[-1, -s_], [1, s_]]) / math.sqrt(2)
                    ax.add(Line(xx, AXIS_COLOR, 1.0, zorder=3, gid=f"{tag}:cross"))
            ring = c + r * circle(16)
            obstacles.append((ring, tag))
            fixed.append(ring)
            marks.append((c, r))
            end_on_labels.append(Label(Text(f"${nm}_B$", c, 8, AXIS_COLOR, math=True,
                                            zorder=10, gid=f"label:{tag}"), c, u, tag,
                                       radius=r))
            continue
        seg = np.array([G, tip])
        ax.add(Line(seg, AXIS_COLOR, 1.0, zorder=3, gid=tag))
        if np.linalg.norm(tip - G) > 1e-9:
            arrowhead = head(tip, (tip - G) / np.linalg.norm(tip - G), 0.6 * hd)
            ax.add(Poly(arrowhead, AXIS_COLOR, zorder=3, gid=f"{tag}:head"))
            obstacles.append((arrowhead[[0, 1, 2, 0]], tag))
        obstacles.append((seg, tag))
        lines.append(seg)
        labels.append(Label(Text(f"${nm}_B$", tip, 8, AXIS_COLOR, math=True, zorder=10,
                                 gid=f"label:{tag}"), tip, tip - G, tag,
                            float(np.linalg.norm(tip - G))))
    labels.append(Label(Text("G", G, 9, zorder=10, gid="label:mass-centre"), G,
                        np.array([-1.0, 1.0]), "mass-centre", radius=rg))

    # joint points and points of application
    for fo in fbd.forces:
        if not fo.couple and np.linalg.norm(fo.B_r) > 0:
            c, r = P @ fo.W_point, 0.022 * sym
            ax.add(Disc(c, r, "white", COLORS[fo.kind], 1.2, zorder=7,
                        gid="joint-point" if fo.kind == REACTION else "load-point"))
            obstacles.append((np.vstack((c + r * circle(12), c)), "point"))

    # limits: geometry first, then grown until every label fits; arrows are kept apart
    # and labels placed again at each scale, both measured in points
    ax.set_limits(*_padded(np.vstack([o[0] for o in obstacles] + _arrow_extents(arrs))))
    lo, hi = ax.lo.copy(), ax.hi.copy()
    x0, y0, w, h = ax.rect
    for attempt in range(5):
        drawn: list[Item] = []
        arrow_obstacles: list[tuple[np.ndarray, str]] = []
        arrow_labels = [_arrow(drawn, a, sym, hd, arrow_obstacles)
                        for a in separate(arrs, fixed, ax.scale, G, hd, lines, 0.05 * sym,
                                             marks, rg)]
        # arrows' labels before the axes' and G's (an axis label has room all around
        # its tip), the longest arrows' first: over the shipped pictures this order needs
        # the fewest leaders (tests/test_overlap.py counts them); but the label of an
        # axis seen end-on first of all: its ring beside G is where the crowd is, and it
        # must be labelled right beside it
        every = end_on_labels + sorted(arrow_labels, key=lambda lb: -lb.shaft) + labels
        boxes = place(ax, every, obstacles + arrow_obstacles)
        if attempt == 4 or (np.all(boxes[:, 0] >= x0) and np.all(boxes[:, 2] <= x0 + w)
                            and np.all(boxes[:, 1] >= y0) and np.all(boxes[:, 3] <= y0 + h)):
            break  # the last try keeps its scale: what was placed is what is drawn
        s = ax.scale
        corners = (np.vstack((boxes[:, :2], boxes[:, 2:])) - ax.rect[:2]) / s + ax.lo
        lo = np.minimum(lo, corners.min(axis=0))
        hi = np.maximum(hi, corners.max(axis=0))
        span = float((hi - lo).max())
        ax.set_limits(lo - 0.05 * span, hi + 0.05 * span)
    ax.add(*drawn)
    for lab in every:  # a label placed far from its arrow: a thin line to it
        if lab.leader is not None:
            ax.add(Line(lab.leader, lab.text.color, 0.6, zorder=8,
                        gid="label-leader:" + (lab.text.gid or "label:")[6:]))
    ax.add(*(lab.text for lab in every))

    # band: world axes on the left, legend on the right
    if zeros:
        sc.root.add(Text("\n".join(zero_note), np.array([0.04 * W, top(h_title + h_draw + 0.04)]),
                         8.5, COLORS[REACTION], va="top", gid="zero-note"))
    band = top(h_title + h_draw + h_band)
    side = 0.9 * 1.25 * IN
    tri = sc.panel("world-axes", (0.03 * W, band + 0.05 * 1.25 * IN, side, side),
                   np.array([-1.45, -1.45]), np.array([1.45, 1.45]))
    _world_triad(tri, P, planar)
    _legend(sc.root, (0.2 * W, band, 0.78 * W, 1.25 * IN), arrs, planar, hd * ax.scale)

    if eq_lines:
        sc.root.add(Text("\n".join(eq_lines),
                         np.array([0.04 * W, top(h_title + h_draw + h_band) - 0.12 * IN]), 9,
                         va="top", family="mono", gid="equations", linespacing=1.45))
    return sc


def _properties(fbd: FreeBodyDiagram, planar: bool, view: View) -> str:
    """The title's mass and inertia about G: I_G planar; spatial, the tensor in body axes
    as diag(...) when it is diagonal there, else its principal moments."""
    m = f"m = {fmt(fbd.mass)} kg"
    J = np.asarray(fbd.inertia, dtype=float)
    if not np.any(J):
        return f"{m}, particle"
    if planar:
        return f"{m}, I_G = {fmt(J[2, 2])} kg m²"
    off = J - np.diag(np.diag(J))
    if np.max(np.abs(off)) <= 1e-12 * np.max(np.abs(J)):
        inertia = f"I_G = diag({', '.join(fmt(x) for x in np.diag(J))}) kg m²"
    else:
        principal = np.linalg.eigvalsh((J + J.T) / 2)
        inertia = f"I_G principal {', '.join(fmt(x) for x in principal)} kg m²"
    return f"{m}, {inertia}, view {view_name(view)}"


TITLE_SIZES = (12.0, 5.0)
"""The title's type size (points), and the smallest it is set in to fit the picture."""


def _title(s: str, xy: np.ndarray, width: float, height: float) -> Text:
    """The title centred at `xy` within `width` points: on one line at the full size if it
    fits, else on two (the body, then its properties in parentheses), the type made
    smaller until it fits in `width` and `height` (a long name: a smaller title)."""
    big, small = TITLE_SIZES
    spacing = 1.2
    if layout(s, big, weight="bold").width > width and "   (" in s:
        head, _, rest = s.partition("   (")
        s, spacing = f"{head}\n({rest}", 1.05
    lay = layout(s, big, weight="bold", linespacing=spacing)
    size = max(small, min(big, big * width / lay.width, big * height / lay.height))
    return Text(s, xy, size, ha="center", va="center", weight="bold", gid="title",
                linespacing=spacing, align="center")


SYMBOLS = 170.0
"""Heads, rings and markers are sized as fractions of the longest arrow's length, but of
no more than this many points (`HEAD` of it is an arrowhead's length)."""


def _arrow_extents(arrs: list[Arrow]) -> list[np.ndarray]:
    """The points each arrow reaches on the page: a straight one's tail and tip, a
    curved one's arc."""
    return [a.arc if a.arc is not None else np.array([a.tail, a.tail + a.vec]) for a in arrs]


def _padded(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Limits around `pts` (k, 2), 18 % of their span to spare on every side."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = max(float((hi - lo).max()), 1e-6)
    return lo - 0.18 * span, hi + 0.18 * span


def _arrow(ax: list[Item], a: Arrow, sym: float, hd: float,
           obstacles: list[tuple[np.ndarray, str]]) -> Label:
    """Draw arrow `a` into `ax`: a shaft (gid = the arrow's) and a filled head (gid +
    ':head') of length `hd`, or an end-on ring of radius 0.05 `sym`; its strokes go to
    `obstacles`; returns its label."""
    dash = a.dash
    shaft = 0.0  # curved and end-on arrows: no spots half-way along
    end_on = a.arc is None and np.linalg.norm(a.vec) < END_ON * a.length3
    radius = 0.0  # what its label keeps beyond its anchor: an end-on arrow's ring
    r = 0.05 * sym  # an end-on arrow's ring; a moment's outer ring is 1.45 times that
    outer = r * (1.45 if a.couple else 1.0)
    pts = a.arc if a.arc is not None else np.array([a.tail, a.tail + a.vec])
    if end_on:  # its short shaft, kept for tools, within its ring
        pts = np.array([a.tail, a.tail + a.vec * min(1.0, 0.8 * r / max(
            float(np.linalg.norm(a.vec)), 1e-300))])
    ax.append(Line(pts, a.color, 2.0, dash, zorder=8, gid=a.gid))
    obstacles.append((pts, a.gid))
    if a.moved_from is not None:  # drawn beside its point: a leader back to it
        lead = np.array([a.moved_from, a.tail])
        if end_on:  # to the ring's rim
            d_lead = lead[1] - lead[0]
            lead[1] -= outer * d_lead / max(float(np.linalg.norm(d_lead)), 1e-300)
        ax.append(Line(lead, a.color, 0.9, DOTTED, zorder=8,
                       gid="leader:" + a.gid.split(":", 1)[1]))
        obstacles.append((lead, "leader:" + a.gid))
    if a.arc is not None:
        if a.vec[1] > 0:
            t_end = a.arc[-1] - a.arc[-2]
            tri = head(a.arc[-1], t_end / np.linalg.norm(t_end), hd)
            ax.append(Poly(tri, a.color, zorder=9, gid=a.gid + ":head"))
            obstacles.append((tri[[0, 1, 2, 0]], a.gid))
        anchor, direction = a.arc[-1], a.arc[-1] - a.tail
    elif end_on:
        # seen end-on: a dot toward the eye, a cross away from it (two rings: a moment)
        for k in range(2 if a.couple else 1):
            ax.append(Disc(a.tail, r * (1 + 0.45 * k), None, a.color, 1.6, zorder=9,
                        gid=a.gid + (":end-on" if k == 0 else ":ring2")))
        if a.toward > 0:
            ax.append(Disc(a.tail, 0.3 * r, a.color, zorder=9))
        else:
            for s_ in (1, -1):
                xx = a.tail + 0.7 * r * np.array([[-1, -s_], [1, s_]]) / math.sqrt(2)
                ax.append(Line(xx, a.color, 1.4, zorder=9))
        obstacles.append((a.tail + outer * circle(24), a.gid))
        # its label beside the ring, first on the side away from the point it acts at
        anchor, direction, radius = a.tail, np.array([1.0, 0.7]), outer
        if a.moved_from is not None and np.linalg.norm(a.tail - a.moved_from) > 0:
            direction = a.tail - a.moved_from
    else:
        n = np.linalg.norm(a.vec)
        tip = a.tail + a.vec
        if n > 1e-9:
            d = a.vec / n
            ax.append(Poly(head(tip, d, hd), a.color, zorder=9, gid=a.gid + ":head"))
            if a.couple:  # a moment: double head
                tri2 = head(tip - 0.75 * hd * d, d, hd)
                ax.append(Poly(tri2, a.color, zorder=9, gid=a.gid + ":head2"))
                obstacles.append((tri2[[0, 1, 2, 0]], a.gid))
            obstacles.append((head(tip, d, hd)[[0, 1, 2, 0]], a.gid))
        anchor, direction = tip, (a.vec if n > 1e-9 else np.array([1.0, 0.3]))
        shaft = float(n)
    text = Text(a.label, anchor, 9, a.color, zorder=10, gid="label:" + a.gid.split(":", 1)[1])
    return Label(text, anchor, direction, a.gid, shaft, radius)


def _end_on_axis(G: np.ndarray, rg: float, sym: float, away: list[np.ndarray]
                 ) -> tuple[np.ndarray, float, np.ndarray]:
    """Where a body axis seen end-on is drawn: a ring of radius r (0.04 `sym`) centred at
    c beside G's marker (radius rg), in the direction u farthest from the strokes leaving
    G (`away`: page vectors of the other axes and of the arrows at G); the label goes on
    along u."""
    dirs = [v / np.linalg.norm(v) for v in away if np.linalg.norm(v) > 1e-9 * sym]
    ang = np.radians(np.arange(0, 360, 15) - 45.0)  # lower right first, on ties
    cand = np.column_stack((np.cos(ang), np.sin(ang)))
    worst = np.max(cand @ np.array(dirs).T, axis=1) if dirs else np.zeros(len(cand))
    u = cand[int(np.argmin(np.round(worst, 6)))]
    r = 0.04 * sym
    return G + (rg + 1.8 * r) * u, r, u


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
    return lines


def _world_triad(ax: Panel, P: np.ndarray, planar: bool) -> None:
    ax.add(Text("world", np.array([0.0, -1.42]), 8, "#333333", ha="center", va="bottom"))
    for k, nm in enumerate("xyz"[:2 if planar else 3]):
        v = P[:, k] * 0.9
        n = np.linalg.norm(v)
        if n < 0.15:  # along the line of sight: ⊙ out of the page, ⊗ into it
            ax.add(Disc(np.zeros(2), 0.14, None, "black", 1.0),
                   Text(nm, np.array([0.18, 0.12]), 9))
            if float(eye(P)[k]) > 0:
                ax.add(Disc(np.zeros(2), 0.04, "black"))
            else:
                for s_ in (1, -1):
                    ax.add(Line(np.array([[-0.05, -0.05 * s_], [0.05, 0.05 * s_]]), "black"))
            continue
        ax.add(Line(np.array([[0, 0], v]), "black", 1.2, gid=f"world-axis:{nm}"),
               Poly(head(v, v / n, 0.22), "black"),
               Text(nm, v + 0.3 * v / n, 9, ha="center", va="center"))


def _centre_mark(panel: Panel, G: np.ndarray, r: float, zorder: float,
                 gid: str | None = None) -> None:
    """The mass centre's symbol: a circle quartered black and white."""
    panel.add(Disc(G, r, "white", "black", 1.0, zorder=zorder, gid=gid))
    for a0 in (0, 180):
        panel.add(Wedge(G, r, a0, a0 + 90, "black", zorder=zorder))


def _legend(root: Panel, rect: tuple[float, float, float, float], arrs: list[Arrow],
            planar: bool, head_pt: float) -> None:
    """A framed legend centred in `rect` (points): the scale note, then two columns.
    Each symbol is drawn as in the picture: arrows with their head, width and dash, the
    mass centre's quartered circle."""
    entries: list[tuple[str, str]] = [
        ("applied", "applied force (name, |F|)"), ("gravity", "gravity m g at G"),
        ("reaction", "reaction (unknown name, or known value)")]
    if any(a.kind == EFFORT for a in arrs):
        entries.append((EFFORT, "driver effort: the actuator's torque or force"))
    if any(a.kind in (REACTION, EFFORT) and a.label.startswith("−") for a in arrs):
        entries.append(("parent", "−A.Fx: on the joint's parent (−R)"))
    if any(a.couple for a in arrs):
        entries.append(("couple", "couple: curved arrow" if planar
                        else "couple/moment: double head (right-hand rule)"))
    entries.append(("G", "G mass centre, x_B y_B" + ("" if planar else " z_B") + " body axes"))
    rows = (len(entries) + 1) // 2
    cols = [entries[:rows], entries[rows:]]
    fs, fs_note = 8.5, 8.0
    for _ in range(3):  # a spatial legend's entries are longer: smaller type to fit `rect`
        handle, gap, sep = 2.6 * fs, 0.8 * fs, 2.0 * fs
        # 4 % to spare: png and pdf text (hinted by matplotlib) can run a little wider
        col_w = [1.04 * max(layout(s, fs).width for _, s in c) + handle + gap for c in cols]
        note = layout(SCALE_NOTE, fs_note)
        inner_w = max(sum(col_w) + sep, note.width)
        room = rect[2] - 0.8 * fs  # the frame's padding on both sides
        if inner_w <= room:
            break
        fs, fs_note = fs * 0.98 * room / inner_w, fs_note * 0.98 * room / inner_w
    row_h = layout("lp", fs).height + 0.5 * fs
    inner_h = note.height + 0.5 * fs + rows * row_h
    pad = 0.4 * fs
    x0 = rect[0] + (rect[2] - inner_w) / 2
    y_top = rect[1] + (rect[3] + inner_h) / 2
    cx = x0 + inner_w / 2
    frame = np.array([[x0 - pad, y_top + pad], [x0 + inner_w + pad, y_top + pad],
                      [x0 + inner_w + pad, y_top - inner_h - pad],
                      [x0 - pad, y_top - inner_h - pad]])
    root.add(Poly(frame, "white", "#cccccc", 0.8, gid="legend", zorder=4),
             Text(SCALE_NOTE, np.array([cx, y_top]), fs_note, ha="center", va="top", zorder=5,
                  gid="legend-title", linespacing=1.2, align="left"))
    hd = min(max(head_pt, 4.0), 7.0)
    right = np.array([1.0, 0.0])
    x = x0 + (inner_w - sum(col_w) - sep) / 2
    for c, cw in zip(cols, col_w, strict=True):
        y = y_top - note.height - 0.5 * fs - row_h / 2
        for key, s in c:
            h0, h1 = np.array([x, y]), np.array([x + handle, y])
            gid = f"legend-handle:{key}"
            if key in COLORS or key == "parent":
                color = COLORS[REACTION if key == "parent" else key]
                dash = DASHES.get(REACTION if key == "parent" else key)
                root.add(Line(np.array([h0, h1]), color, 2.0, dash, zorder=5, gid=gid),
                         Poly(head(h1, right, hd), color, zorder=5, gid=gid + ":head"))
            elif key == "couple":  # as the picture's first couple: its colour and dash
                first = next(a for a in arrs if a.couple)
                color, dash = first.color, first.dash
                if planar:  # a curved arrow, as drawn about a point
                    mid = (h0 + h1) / 2
                    t = np.linspace(math.radians(-60), math.radians(210), 20)
                    arc = mid + 5.0 * np.column_stack((np.cos(t), np.sin(t)))
                    d = arc[-1] - arc[-2]
                    root.add(Line(arc, color, 2.0, dash, zorder=5, gid=gid),
                             Poly(head(arc[-1], d / np.linalg.norm(d), hd), color,
                                  zorder=5, gid=gid + ":head"))
                else:  # a double head
                    root.add(Line(np.array([h0, h1]), color, 2.0, dash, zorder=5, gid=gid),
                             Poly(head(h1, right, hd), color, zorder=5, gid=gid + ":head"),
                             Poly(head(h1 - 0.75 * hd * right, right, hd), color, zorder=5,
                                  gid=gid + ":head2"))
            else:
                _centre_mark(root, (h0 + h1) / 2, 3.5, zorder=5, gid=gid)
            root.add(Text(s, np.array([x + handle + gap, y]), fs, va="center", zorder=5,
                          gid="legend-entry"))
            y -= row_h
        x += cw + sep
