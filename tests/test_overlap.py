"""Free-body diagrams keep their texts and arrows apart: a measure of overlaps on every
shipped model, every body, planar and the four named spatial views.

The measure reads a diagram's `Scene` (the primitives as drawn, in points; label boxes
from the font metrics that also write the SVG), independently of how the labels were
placed. What counts as an overlap (each pair counted once):

- label / label: their boxes come closer than MARGIN;
- label / anything drawn in the drawing panel: an arrow's shaft or head (straight or
  curved), an end-on ring, the body's outline (filled region's rim and every edge,
  hidden ones too), a body axis and its head, the mass centre marker, a joint point:
  some point of it lies within MARGIN of the label's box. Its own arrow (or axis, or
  the marker the label names) only counts when it enters the box itself;
- arrow / arrow, arrow / outline, arrow / body axis: nearly coincident, i.e. a stretch
  of at least RUN points of one lies within NEAR points of the other and runs parallel
  to it (within 10°): two arrows on top of each other, or an arrow drawn along an edge.
  Shafts and curves count here, not arrowheads or leaders (a head's back edge and the
  dotted leader of an arrow drawn beside its point are short and crosswise).

Two parallel strokes farther apart than NEAR still read as one (`side_by_side`): an arrow
whose centre line runs within SIDE points of another arrow's, or of a body axis, parallel
and across from it along RUN points (B.Fy drawn 6 points beside P.Fy on the slider-crank's
piston, B.Fx 6 points above x_B, a couple's double arrow along z_B). And a title names
the body's mass and, unless it is a particle, its inertia about G, planar or spatial, in
a line (or two) that fits the picture (`title_problems`).

Two more measures of what a reader needs (`far_labels`, `touching_tips`):

- a label far from what it names: the gap between its box and its own arrow (shaft,
  heads, end-on ring; not the dotted leader of an arrow drawn beside its point), axis or
  marker is more than FAR times the label's height, and no label leader
  (``label-leader:<kind>:<name>``) joins it to that arrow;
- an arrow's tip touching another stroke: the point of an arrowhead lies within TIP
  points of the edge of another arrow (shaft or head), of the body's outline or of a body axis.

and how many labels a picture joins to their arrow by a leader (`leaders`): at most
LEADERS per picture, LEADERS_TOTAL over all, none to a body axis seen end-on (drawn
as a ring with a dot or a cross beside G). And no two rings overlap (`ring_overlaps`):
arrows seen end-on and body axes seen end-on, whether at one point (several joints
there, a force and a moment about one axis) or not: two rings drawn on one another read
as one.

Run as a script to print the count per model and view (overlaps and strokes side by
side / far labels / touching tips / leaders).
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

import mbody
from mbody.present.draw import fbd_scene
from mbody.present.draw.scene import Disc, Line, Panel, Poly, Scene, Text
from mbody.present.draw.svg import text_box

ROOT = Path(__file__).resolve().parent.parent
MODELS = sorted((ROOT / "models").glob("*.yaml"))
SPATIAL_VIEWS = ("iso", "front", "top", "side")

MARGIN = 1.0
"""Clearance (points) a label keeps from other labels and from every stroke."""
NEAR, RUN = 2.0, 8.0
"""Two strokes closer than NEAR points and parallel along RUN points coincide."""
STEP = 1.0
"""Strokes are measured at points this far apart (points)."""
FAR = 1.5
"""A label's box keeps within FAR times its height of the arrow (axis, marker) it names."""
TIP = 2.5
"""An arrow's tip keeps this far (points) from the edge of every stroke it does not belong
to (a line's centre less half its width)."""


def _sample(xy: np.ndarray, closed: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Points every STEP along a polyline (points) and the unit tangent at each."""
    xy = np.asarray(xy, dtype=float)
    if closed:
        xy = np.vstack((xy, xy[:1]))
    pts, tan = [xy[:1]], [np.zeros((1, 2))]
    for p, q in zip(xy[:-1], xy[1:], strict=True):
        d = q - p
        n = float(np.linalg.norm(d))
        if n < 1e-9:
            continue
        k = max(1, int(np.ceil(n / STEP)))
        t = np.arange(1, k + 1)[:, None] / k
        pts.append(p + t * d)
        tan.append(np.repeat((d / n)[None], k, axis=0))
    if len(pts) > 1:
        tan[0] = tan[1][:1]
    return np.vstack(pts), np.vstack(tan)


def _circle(c: np.ndarray, r: float) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, max(12, int(2 * np.pi * r / STEP)), endpoint=False)
    return c + r * np.column_stack((np.cos(t), np.sin(t)))


class Stroke:
    """One drawn thing in points: samples along it, tangents, its kind and owner."""

    def __init__(self, name: str, kind: str, pts: np.ndarray, tan: np.ndarray,
                 disc: tuple[np.ndarray, float] | None = None, head: bool = False) -> None:
        self.name, self.kind, self.pts, self.tan, self.disc = name, kind, pts, tan, disc
        self.head = head  # an arrowhead: its back edge crossing a line is no coincidence


def _owner(gid: str) -> str:
    """The arrow, axis or marker a stroke belongs to: its gid without ':head' etc."""
    parts = gid.split(":")
    if parts[0] in ("arrow", "couple", "leader"):
        return ":".join(parts[1:3])
    if parts[0] == "body-axis":
        return "body-axis:" + parts[1]
    return gid


def strokes(panel: Panel) -> list[Stroke]:
    """Every stroke of the drawing panel in points, named by what it belongs to."""
    out = []
    for it in panel.items:
        gid = getattr(it, "gid", None) or ""
        if isinstance(it, Text) or not gid:
            continue
        kind = ("arrow" if gid.startswith(("arrow:", "couple:", "leader:")) else
                "outline" if gid in ("body-outline", "body-edge") else
                "axis" if gid.startswith("body-axis:") else
                "marker" if gid in ("mass-centre", "joint-point", "load-point") else "")
        if not kind:
            continue
        if isinstance(it, Line):
            pts, tan = _sample(panel.to_pt(it.xy))
            # a leader ties a moved arrow to its point, across the arrow: like a head,
            # it crosses what the arrow runs beside
            out.append(Stroke(_owner(gid), kind, pts, tan, head=gid.startswith("leader:")))
        elif isinstance(it, Poly):
            pts, tan = _sample(panel.to_pt(it.xy), closed=True)
            out.append(Stroke(_owner(gid), kind, pts, tan, head=gid.endswith(
                (":head", ":head2"))))
        elif isinstance(it, Disc):
            c, r = panel.to_pt(it.center), it.r * panel.scale
            pts, tan = _sample(_circle(c, r), closed=True)
            out.append(Stroke(_owner(gid), kind, pts, tan, (c, r)))
    return out


def labels(panel: Panel) -> list[tuple[str, np.ndarray]]:
    """(owner, box x0 y0 x1 y1 in points) of every label in the drawing panel."""
    out = []
    for it in panel.items:
        if isinstance(it, Text) and (it.gid or "").startswith("label:"):
            x0, y0, w, h = text_box(it, panel.to_pt(it.xy))
            owner = it.gid[6:]
            owner = "body-axis:" + owner.split(":")[1] if owner.startswith("body-axis") else owner
            out.append((owner, np.array([x0, y0, x0 + w, y0 + h])))
    return out


def _hits_box(s: Stroke, box: np.ndarray, margin: float) -> bool:
    lo, hi = box[:2] - margin, box[2:] + margin
    if s.disc is not None:  # a filled marker or ring: its whole disc
        c, r = s.disc
        return bool(np.linalg.norm(c - np.clip(c, lo, hi)) < r + margin)
    return bool(np.any(np.all((s.pts > lo) & (s.pts < hi), axis=1)))


def _coincide(a: Stroke, b: Stroke, near: float = NEAR) -> bool:
    """A stretch of RUN points of `a` within `near` of `b`, parallel to it."""
    dist, j = cKDTree(b.pts).query(a.pts, distance_upper_bound=near)
    near = np.isfinite(dist)
    close = near & (np.abs(np.sum(a.tan * b.tan[np.minimum(j, len(b.pts) - 1)], axis=1))
                    > np.cos(np.radians(10)))
    return bool(np.count_nonzero(close) * STEP >= RUN)


def overlaps(scene: Scene) -> list[str]:
    """Every overlap in the drawing panel of `scene`, one line each."""
    panel = next(p for p in scene.panels if p.gid == "drawing")
    ss, ls = strokes(panel), labels(panel)
    found = []
    for i, (na, a) in enumerate(ls):
        for nb, b in ls[i + 1:]:
            if (min(a[2], b[2]) - max(a[0], b[0]) > -MARGIN
                    and min(a[3], b[3]) - max(a[1], b[1]) > -MARGIN):
                found.append(f"label {na} / label {nb}")
        hit = set()
        for s in ss:
            own = s.name == na
            if s.name not in hit and _hits_box(s, a, 0.0 if own else MARGIN):
                hit.add(s.name)
                found.append(f"label {na} / {s.kind} {s.name}")
    # strokes merged per owner (a shaft and its heads are one arrow)
    merged: dict[tuple[str, str], list[Stroke]] = {}
    for s in ss:
        if s.kind in ("arrow", "outline", "axis") and s.disc is None and not s.head:
            # a body's outline is one thing: its filled rim and its edges
            merged.setdefault((s.kind, "body" if s.kind == "outline" else s.name),
                              []).append(s)
    whole = [Stroke(n, k, np.vstack([s.pts for s in v]), np.vstack([s.tan for s in v]))
             for (k, n), v in merged.items()]
    for i, a in enumerate(whole):
        for b in whole[i + 1:]:
            if "arrow" not in (a.kind, b.kind) or a.name == b.name:
                continue
            if _coincide(a, b) or _coincide(b, a):
                found.append(f"{a.kind} {a.name} / {b.kind} {b.name} coincide")
    return found


SIDE = 12.0
"""Two parallel strokes whose centre lines run closer than this (points) along RUN points
read as one thick or double line: an arrow beside another arrow, or along a body axis
(a 2-point dashed arrow and its head, 9 points wide, leave a clear gap only beyond it)."""


def side_by_side(scene: Scene) -> list[str]:
    """Every arrow (shaft or curve, not a head or a leader) running within SIDE points of
    another arrow or of a body axis, parallel to it (within 10°) along RUN points: B.Fy
    drawn 6 points beside P.Fy, B.Fx along x_B, a couple's double arrow along z_B."""
    panel = next(p for p in scene.panels if p.gid == "drawing")
    merged: dict[tuple[str, str], list[Stroke]] = {}
    for st in strokes(panel):
        if st.kind in ("arrow", "axis") and st.disc is None and not st.head:
            merged.setdefault((st.kind, st.name), []).append(st)
    whole = [Stroke(n, k, np.vstack([x.pts for x in v]), np.vstack([x.tan for x in v]))
             for (k, n), v in merged.items()]
    found = []
    for i, a in enumerate(whole):
        for b in whole[i + 1:]:
            if "arrow" not in (a.kind, b.kind) or a.name == b.name:
                continue
            if _beside(a, b) or _beside(b, a):
                found.append(f"{a.kind} {a.name} / {b.kind} {b.name} side by side")
    return found


def _beside(a: Stroke, b: Stroke) -> bool:
    """A stretch of RUN points of `a` within SIDE of `b`, parallel to it and across from it
    (the gap between them mostly across the strokes: two strokes that only meet end to
    end, as gravity pointing down from G and y_B pointing up, are not side by side)."""
    dist, j = cKDTree(b.pts).query(a.pts, distance_upper_bound=SIDE)
    ok = np.isfinite(dist)
    j = np.minimum(j, len(b.pts) - 1)
    tb = b.tan[j]
    parallel = np.abs(np.sum(a.tan * tb, axis=1)) > np.cos(np.radians(10))
    gap = a.pts - b.pts[j]
    along = np.abs(np.sum(gap * tb, axis=1))
    across = ok & parallel & (along <= np.maximum(STEP, 0.5 * np.linalg.norm(gap, axis=1)))
    return bool(np.count_nonzero(across) * STEP >= RUN)


def title_problems(scene: Scene, fbd: object) -> list[str]:
    """The title names the body, its mass and (unless a particle) its inertia about G,
    planar or spatial, and fits in the picture."""
    title = next(it for it in scene.root.items if getattr(it, "gid", None) == "title")
    found = []
    if "m = " not in title.s:
        found.append(f"title without the mass: {title.s!r}")
    if np.any(fbd.inertia) and "I_G" not in title.s:
        found.append(f"title without the inertia: {title.s!r}")
    x0, _, w, _ = text_box(title, title.xy)
    if x0 < 0 or x0 + w > scene.width:
        found.append(f"title {w:.0f} pt wide in a picture {scene.width:.0f} pt wide")
    return found


def _own(gid: str, owner: str) -> bool:
    """Whether the item `gid` is part of the arrow, axis or marker `owner` (a label's gid
    without 'label:'), leaders excluded."""
    if owner.startswith("body-axis") or owner == "mass-centre":
        return gid == owner or gid.startswith(owner + ":")
    return any(gid == f"{k}:{owner}" or gid.startswith(f"{k}:{owner}:")
               for k in ("arrow", "couple"))


def _item_points(panel: Panel, it: object) -> tuple[np.ndarray, float]:
    """Points (in points) along a Line, Poly's rim or Disc's centre, and the Disc's radius
    to take off a distance measured from those points."""
    if isinstance(it, Line):
        return _sample(panel.to_pt(it.xy))[0], 0.0
    if isinstance(it, Poly):
        return _sample(panel.to_pt(it.xy), closed=True)[0], 0.0
    assert isinstance(it, Disc)
    return panel.to_pt(it.center)[None], it.r * panel.scale


def far_labels(scene: Scene) -> list[str]:
    """Every label of the drawing panel farther than FAR label heights from the arrow,
    axis or marker it names, without a label leader to it; one line each."""
    panel = next(p for p in scene.panels if p.gid == "drawing")
    gids = {getattr(it, "gid", None) or "" for it in panel.items}
    found = []
    for it in panel.items:
        if not (isinstance(it, Text) and (it.gid or "").startswith("label:")):
            continue
        owner = it.gid[6:]
        if "label-leader:" + owner in gids:
            continue
        x0, y0, w, h = text_box(it, panel.to_pt(it.xy))
        gap = np.inf
        for o in panel.items:
            if isinstance(o, Text) or not _own(getattr(o, "gid", None) or "", owner):
                continue
            pts, r = _item_points(panel, o)
            dx = np.maximum(np.maximum(x0 - pts[:, 0], pts[:, 0] - x0 - w), 0)
            dy = np.maximum(np.maximum(y0 - pts[:, 1], pts[:, 1] - y0 - h), 0)
            gap = min(gap, max(float(np.min(np.hypot(dx, dy))) - r, 0.0))
        if gap > FAR * h:
            found.append(f"label {owner} {gap:.0f} pt from its arrow (> {FAR * h:.0f})")
    return found


def _segment_distance(p: np.ndarray, xy: np.ndarray) -> float:
    """Distance from point p to a polyline xy (k, 2)."""
    a, b = xy[:-1], xy[1:]
    d = b - a
    t = np.clip(np.sum((p - a) * d, axis=1) / np.maximum(np.sum(d * d, axis=1), 1e-18),
                0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * d - p, axis=1)))


def touching_tips(scene: Scene) -> list[str]:
    """Every arrowhead (of a force or couple) whose point lies within TIP points of an
    arrow, outline edge or body axis other than its own; one line each."""
    panel = next(p for p in scene.panels if p.gid == "drawing")
    others = []
    for it in panel.items:
        gid = getattr(it, "gid", None) or ""
        if isinstance(it, (Line, Poly)) and (
                gid.startswith(("arrow:", "couple:", "body-axis:"))
                or gid in ("body-outline", "body-edge")):
            xy = panel.to_pt(it.xy)
            others.append((_owner(gid), np.vstack((xy, xy[:1])) if isinstance(it, Poly)
                           else xy, it.lw / 2))
    found = []
    for it in panel.items:
        gid = getattr(it, "gid", None) or ""
        if not (isinstance(it, Poly) and gid.startswith(("arrow:", "couple:"))
                and gid.endswith(":head")):
            continue
        tip, me = panel.to_pt(it.xy[0]), _owner(gid)
        hit = sorted({n for n, xy, half in others
                      if n != me and _segment_distance(tip, xy) - half < TIP})
        found += [f"tip of {me} on {n}" for n in hit]
    return found


def cases() -> Iterator[tuple[str, str, str]]:
    """(model file stem, body, view) for every body of every shipped model."""
    for path in MODELS:
        m = mbody.load(path)
        for name in m.body_names:
            for view in (SPATIAL_VIEWS if m.dimension == 3 else ("top",)):
                yield path.stem, name, view


def scenes(stem: str) -> Iterator[tuple[str, str, Scene]]:
    m = mbody.load(ROOT / "models" / f"{stem}.yaml")
    asm = mbody.assemble(m)
    for name in m.body_names:
        for view in (SPATIAL_VIEWS if m.dimension == 3 else ("top",)):
            yield name, view, fbd_scene(asm.bodies[name].fbd, view=view, equations=False)


# -- the measure can fail -------------------------------------------------------------------
def test_measure_sees_labels_on_labels_arrows_on_arrows_and_labels_on_outlines():
    from mbody.present.draw.scene import Scene

    sc = Scene(200, 200)
    p = sc.panel("drawing", (0, 0, 200, 200), np.zeros(2), np.array([200.0, 200.0]))
    p.add(Poly(np.array([[50.0, 50], [150, 50], [150, 60], [50, 60]]), "grey",
               gid="body-outline"),
          Line(np.array([[50.0, 100], [120, 100]]), "red", gid="arrow:reaction:A.Fx"),
          Line(np.array([[52.0, 101.5], [110, 101.5]]), "red", gid="arrow:reaction:B.Fx"),
          Text("A.Fx", np.array([60.0, 52]), 9, gid="label:reaction:A.Fx"),
          Text("B.Fx", np.array([64.0, 54]), 9, gid="label:reaction:B.Fx"))
    found = overlaps(sc)
    assert "label reaction:A.Fx / label reaction:B.Fx" in found
    assert "label reaction:A.Fx / outline body-outline" in found
    assert "arrow reaction:A.Fx / arrow reaction:B.Fx coincide" in found
    # apart: nothing
    for t, xy in zip([it for it in p.items if isinstance(it, Text)],
                     ([10.0, 150], [150, 150]), strict=True):
        t.xy = np.array(xy)
    p.items[2].xy = np.array([[52.0, 120], [110, 120]])
    assert overlaps(sc) == []


def test_measure_sees_far_labels_and_touching_tips():
    sc = Scene(200, 200)
    p = sc.panel("drawing", (0, 0, 200, 200), np.zeros(2), np.array([200.0, 200.0]))
    p.add(Line(np.array([[20.0, 100], [80, 100]]), "red", gid="arrow:reaction:A.Fx"),
          Poly(np.array([[80.0, 100], [72, 103], [72, 97]]), "red",
               gid="arrow:reaction:A.Fx:head"),
          Line(np.array([[81.0, 40], [81, 160]]), "green", gid="arrow:gravity:gravity"),
          Text("A.Fx", np.array([150.0, 150]), 9, gid="label:reaction:A.Fx"),
          Text("m g", np.array([84.0, 60]), 9, gid="label:gravity:gravity"))
    assert [f.split(" ")[1] for f in far_labels(sc)] == ["reaction:A.Fx"]
    assert touching_tips(sc) == ["tip of reaction:A.Fx on gravity:gravity"]
    p.items[3].xy = np.array([84.0, 104])  # beside its tip
    p.items[2].xy = np.array([[90.0, 40], [90, 160]])
    assert far_labels(sc) == [] and touching_tips(sc) == []
    # a label leader drawn to a far label names its arrow
    p.items[3].xy = np.array([150.0, 150])
    p.add(Line(np.array([[80.0, 100], [150, 150]]), "red", gid="label-leader:reaction:A.Fx"))
    assert far_labels(sc) == []


def test_measure_sees_arrows_side_by_side_and_along_an_axis_and_a_bare_title():
    sc = Scene(300, 300)
    p = sc.panel("drawing", (0, 0, 300, 300), np.zeros(2), np.array([300.0, 300.0]))
    p.add(Line(np.array([[100.0, 100], [100, 200]]), "red", gid="arrow:reaction:P.Fy"),
          Line(np.array([[106.0, 100], [106, 200]]), "red", gid="arrow:reaction:B.Fy"),
          Line(np.array([[100.0, 100], [200, 100]]), "grey", gid="body-axis:x"),
          Line(np.array([[100.0, 106], [180, 106]]), "red", gid="arrow:reaction:B.Fx"),
          Line(np.array([[100.0, 100], [100, 20]]), "green", gid="arrow:gravity:gravity"))
    assert side_by_side(sc) == [
        "arrow reaction:P.Fy / arrow reaction:B.Fy side by side",
        "axis body-axis:x / arrow reaction:B.Fx side by side"]
    # 6 points apart is not 2: the older measure saw nothing here
    assert [o for o in overlaps(sc) if "coincide" in o] == []
    # gravity down from G and the axes from G only meet there; 14 points apart is clear
    p.items[1].xy = np.array([[114.0, 100], [114, 200]])
    p.items[3].xy = np.array([[100.0, 114], [180, 114]])
    assert side_by_side(sc) == []

    class Body:
        inertia = np.diag([1.0, 2.0, 3.0])

    sc.root.add(Text("Free-body diagram of b   (m = 1 kg, iso)", np.array([150.0, 290]),
                     11, ha="center", va="center", weight="bold", gid="title"))
    assert title_problems(sc, Body()) == [
        "title without the inertia: 'Free-body diagram of b   (m = 1 kg, iso)'"]
    sc.root.items[-1].s = "Free-body diagram of b   (m = 1 kg, I_G = diag(1, 2, 3) kg m²)"
    (problem,) = title_problems(sc, Body())
    assert problem.startswith("title ") and problem.endswith(" pt wide in a picture 300 pt "
                                                             "wide")


# -- every shipped picture ------------------------------------------------------------------
@pytest.mark.parametrize("stem", [p.stem for p in MODELS])
def test_no_overlaps_on_shipped_models(stem):
    bad = [f"{name} ({view}): {o}" for name, view, sc in scenes(stem) for o in overlaps(sc)]
    assert bad == []


@pytest.mark.parametrize("stem", [p.stem for p in MODELS])
def test_no_arrow_runs_beside_another_or_along_a_body_axis_on_shipped_models(stem):
    bad = [f"{name} ({view}): {o}" for name, view, sc in scenes(stem)
           for o in side_by_side(sc)]
    assert bad == []


@pytest.mark.parametrize("stem", [p.stem for p in MODELS])
def test_titles_give_mass_and_inertia_and_fit_on_shipped_models(stem):
    m = mbody.load(ROOT / "models" / f"{stem}.yaml")
    asm = mbody.assemble(m)
    bad = [f"{name} ({view}): {o}" for name, view, sc in scenes(stem)
           for o in title_problems(sc, asm.bodies[name].fbd)]
    assert bad == []


@pytest.mark.parametrize("stem", [p.stem for p in MODELS])
def test_labels_near_their_arrows_on_shipped_models(stem):
    bad = [f"{name} ({view}): {o}" for name, view, sc in scenes(stem) for o in far_labels(sc)]
    assert bad == []


@pytest.mark.parametrize("stem", [p.stem for p in MODELS])
def test_no_arrow_tip_touches_another_stroke_on_shipped_models(stem):
    bad = [f"{name} ({view}): {o}" for name, view, sc in scenes(stem)
           for o in touching_tips(sc)]
    assert bad == []


LEADERS = 6
"""At most this many labels of one picture are joined to their arrow by a leader."""
LEADERS_TOTAL = 64
"""... and at most this many over all shipped pictures (98 before end-on body axes were
drawn as rings and labels could sit beside a whole shaft)."""


def leaders(scene: Scene) -> list[str]:
    """The owners (``<kind>:<name>``) of every label leader in the drawing panel."""
    panel = next(p for p in scene.panels if p.gid == "drawing")
    return [it.gid[len("label-leader:"):] for it in panel.items
            if (getattr(it, "gid", None) or "").startswith("label-leader:")]


def end_on_axis_problems(fbd: object, view: str, scene: Scene) -> list[str]:
    """A body axis seen end-on (page length below END_ON of its length) is drawn as a
    ring with a dot or a cross, its label within FAR label heights, and no leader."""
    from mbody.present.draw import END_ON
    from mbody.present.draw.views import eye, projection

    P = projection(view)
    panel = next(p for p in scene.panels if p.gid == "drawing")
    gids = [getattr(it, "gid", None) or "" for it in panel.items]
    found = []
    for k, nm in enumerate("xyz"):
        axis = np.asarray(fbd.W_R_B)[:, k]
        if np.linalg.norm(P @ axis) >= END_ON:
            continue
        tag = f"body-axis:{nm}"
        if f"label-leader:{tag}" in gids:
            found.append(f"{tag} seen end-on has a leader")
        if f"{tag}:ring" not in gids:
            found.append(f"{tag} seen end-on has no ring")
        mark = f"{tag}:dot" if float(axis @ eye(P)) > 0 else f"{tag}:cross"
        if mark not in gids:
            found.append(f"{tag} seen end-on has no {mark.split(':')[-1]}")
    return found


@functools.cache
def leader_counts(stem: str) -> tuple[tuple[str, str, tuple[str, ...], tuple[str, ...]], ...]:
    """(body, view, leaders, end-on axis problems) of every picture of a shipped model."""
    m = mbody.load(ROOT / "models" / f"{stem}.yaml")
    asm = mbody.assemble(m)
    out = []
    for name, view, sc in scenes(stem):
        bad = (end_on_axis_problems(asm.bodies[name].fbd, view, sc)
               if m.dimension == 3 else [])
        out.append((name, view, tuple(leaders(sc)), tuple(bad)))
    return tuple(out)


def test_measure_sees_leaders_and_end_on_axes():
    sc = Scene(200, 200)
    p = sc.panel("drawing", (0, 0, 200, 200), np.zeros(2), np.array([200.0, 200.0]))
    p.add(Line(np.array([[80.0, 100], [150, 150]]), "red", gid="label-leader:reaction:A.Fx"),
          Line(np.array([[100.0, 100], [100, 100]]), "grey", gid="body-axis:z"),
          Line(np.array([[100.0, 100], [120, 150]]), "grey", gid="label-leader:body-axis:z"))
    assert leaders(sc) == ["reaction:A.Fx", "body-axis:z"]

    class Box:  # a body turned so that its z axis points at the eye in the front view
        W_R_B = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])

    assert end_on_axis_problems(Box(), "front", sc) == [
        "body-axis:z seen end-on has a leader", "body-axis:z seen end-on has no ring",
        "body-axis:z seen end-on has no dot"]
    assert end_on_axis_problems(Box(), "top", sc) == [
        "body-axis:y seen end-on has no ring", "body-axis:y seen end-on has no dot"]


@pytest.mark.parametrize("stem", [p.stem for p in MODELS])
def test_few_label_leaders_and_none_to_an_end_on_axis_on_shipped_models(stem):
    """A body axis seen end-on is a ring beside G, labelled beside it; a picture has at
    most LEADERS label leaders."""
    found = leader_counts(stem)
    bad = [f"{name} ({view}): {o}" for name, view, _, probs in found for o in probs]
    bad += [f"{name} ({view}): {len(ls)} leaders > {LEADERS}: {', '.join(ls)}"
            for name, view, ls, _ in found if len(ls) > LEADERS]
    assert bad == []


def test_label_leaders_over_all_shipped_pictures_within_budget():
    total = sum(len(ls) for path in MODELS for _, _, ls, _ in leader_counts(path.stem))
    assert total <= LEADERS_TOTAL


def legend_problems(scene: Scene) -> list[str]:
    """The legend's frame and texts inside the picture, clear of the world-axes triad."""
    root = scene.root
    frame = next(it for it in root.items if getattr(it, "gid", None) == "legend")
    lo, hi = frame.xy.min(axis=0), frame.xy.max(axis=0)
    found = []
    if lo[0] < 0 or hi[0] > scene.width or lo[1] < 0 or hi[1] > scene.height:
        found.append(f"legend frame {lo.round(1)}..{hi.round(1)} outside the picture "
                     f"{scene.width:.0f} x {scene.height:.0f}")
    for it in root.items:
        if isinstance(it, Text) and it.gid in ("legend-entry", "legend-title"):
            x0, y0, w, h = text_box(it, it.xy)
            if x0 < lo[0] or x0 + w > hi[0]:
                found.append(f"legend text {it.s!r} outside its frame")
    tri = next(p for p in scene.panels if p.gid == "world-axes")
    if tri.rect[0] + tri.rect[2] > lo[0]:
        found.append("legend frame over the world axes")
    return found


@pytest.mark.parametrize("stem", [p.stem for p in MODELS])
def test_legend_fits_in_the_picture(stem):
    """Every legend (a spatial one lists the longest entries) inside the picture and its
    frame, beside the world-axes triad."""
    bad = [f"{name} ({view}): {o}" for name, view, sc in scenes(stem)
           for o in legend_problems(sc)]
    assert bad == []


def ring_overlaps(scene: Scene) -> list[str]:
    """Every pair of rings in the drawing panel (arrows seen end-on, an outer ring for a
    moment; body axes seen end-on) closer than MARGIN, one line each."""
    panel = next(p for p in scene.panels if p.gid == "drawing")
    rings: dict[str, tuple[np.ndarray, float]] = {}
    for it in panel.items:
        gid = getattr(it, "gid", None) or ""
        if isinstance(it, Disc) and gid.endswith((":end-on", ":ring2", ":ring")):
            owner = gid.rsplit(":", 1)[0]
            c, r = panel.to_pt(it.center), it.r * panel.scale
            if owner not in rings or r > rings[owner][1]:
                rings[owner] = (c, r)
    names = sorted(rings)
    return [f"ring {a} / ring {b} overlap" for i, a in enumerate(names) for b in names[i + 1:]
            if np.linalg.norm(rings[a][0] - rings[b][0]) < rings[a][1] + rings[b][1] + MARGIN]


def test_measure_sees_rings_on_rings():
    sc = Scene(200, 200)
    p = sc.panel("drawing", (0, 0, 200, 200), np.zeros(2), np.array([200.0, 200.0]))
    p.add(Disc(np.array([100.0, 100]), 8, None, "red", gid="arrow:reaction:B.Fz:end-on"),
          Disc(np.array([100.0, 100]), 8, None, "red", gid="couple:reaction:B.Mz:end-on"),
          Disc(np.array([100.0, 100]), 11.6, None, "red", gid="couple:reaction:B.Mz:ring2"),
          Disc(np.array([114.0, 100]), 6, "white", "grey", gid="body-axis:z:ring"))
    assert ring_overlaps(sc) == [
        "ring arrow:reaction:B.Fz / ring body-axis:z overlap",
        "ring arrow:reaction:B.Fz / ring couple:reaction:B.Mz overlap",
        "ring body-axis:z / ring couple:reaction:B.Mz overlap"]
    p.items[1].center = p.items[2].center = np.array([100.0, 70])  # 30 apart, 19.6 wide
    p.items[3].center = np.array([115.0, 100])  # 15 from B.Fz: 1 point clear
    assert ring_overlaps(sc) == []


@pytest.mark.parametrize("stem", [p.stem for p in MODELS])
def test_no_ring_on_another_on_shipped_models(stem):
    """Arrows seen end-on at one point (the flyball governor's spindle from the top, a
    Bricard rod seen along its length) are drawn beside each other, never one on
    another."""
    bad = [f"{name} ({view}): {o}" for name, view, sc in scenes(stem) for o in ring_overlaps(sc)]
    assert bad == []


def main() -> int:
    total = far = tips = lead = 0
    only = set(sys.argv[1:])
    for path in MODELS:
        if only and path.stem not in only:
            continue
        per = []
        for name, view, sc in scenes(path.stem):
            found, fl, tt = overlaps(sc) + side_by_side(sc), far_labels(sc), touching_tips(sc)
            ld = leaders(sc)
            total, far, tips = total + len(found), far + len(fl), tips + len(tt)
            lead += len(ld)
            per.append(f"{name}/{view} {len(found)}/{len(fl)}/{len(tt)}/{len(ld)}")
            for f in found + fl + tt + [f"leader to {n}" for n in ld]:
                print(f"    {path.stem} {name} {view}: {f}")
        print(f"{path.stem:<28} " + ", ".join(per), flush=True)
    print("overlaps", total, "far labels", far, "touching tips", tips, "label leaders", lead)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
