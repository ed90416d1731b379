"""Arrows kept apart: an arrow lying on another arrow, on the body's outline or on a body
axis moves sideways, parallel to itself, by the least number of steps that clears it
(CLEAR from an edge of the outline; CLEAR_LINE, about one label's height, from another
arrow or a body axis, which it would otherwise seem to double).

Two reactions at one pin along the same axis (the piston's B.Fy and P.Fy), a force along
a rod's edge, gravity inside a thin vertical link, a force along x_B: each would hide the
other stroke. Moving an arrow parallel to itself keeps its direction and label exact;
the step is a few points, small beside any body, and a dotted leader (drawn by the
diagram) ties the moved tail to the point where the force acts. Works in points (the
panel's scale), as a reader sees the picture.

An arrow's tip must not touch another stroke either (the crank's O.Fx ending on the
gravity line): its point keeps TIP points from every stroke placed before it, and no tip
placed before it lies that near its shaft or head. An unknown reaction, whose length
says nothing, is first drawn a little shorter (or longer) to clear; any arrow is then
moved sideways as above. Known forces (applied, gravity) and couples are placed first,
so that a reaction (or a driver's effort) gives way to them: their lengths and points
carry their values. Where many parallel arrows start at one point on the page (several
joints there, or a long thin body seen end-on, whose joints all fall on its centre),
the steps sideways go as far as they must: two more a side for every arrow drawn.

An arrow seen end-on (a ring with a dot or a cross) is placed after every straight one.
It stays at its point unless a ring is drawn there already (gravity's at G, another
joint's, another component's); then it goes beside the point, on the nearest circle
about it with room for it (RING_GAP from every stroke, RING_ROOM from every ring, its
leader clear of them), where that circle is farthest from them, with a dotted leader
back to the point: two rings drawn one on top of the other would read as one.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mbody.conventions import REACTION
from mbody.present.draw.arrows import END_ON, Arrow, head
from mbody.present.draw.style import EFFORT

CLEAR = 5.5
"""An arrow keeps this far (points) from a parallel edge of the body's outline."""
CLEAR_LINE = 12.5
"""... and this far from a parallel arrow or body axis: two arrows 6 points apart read as
one double line (B.Fy beside P.Fy at the piston's pin), an arrow that close to x_B as
drawn along the axis."""
STEP = 6.5
"""Sideways step (points) tried in turn on both sides: ±1, ±2, ... steps."""
PARALLEL = np.cos(np.radians(12.0))
"""Strokes within 12° of each other are parallel."""
RUN = 4.0
"""A stretch (points) of an arrow beside a parallel stroke that counts as lying on it."""
TIP = 5.0
"""An arrow's tip keeps this far (points) from the centre line of every other stroke."""
LENGTHS = (1.0, 0.86, 0.72, 1.14)
"""Lengths (of its own) tried in turn for an unknown reaction at each sideways place."""
GIVES_WAY = (REACTION, EFFORT)
"""The kinds of arrow placed last, whose length may change: reactions, drivers' efforts."""


_CIRCLE = np.column_stack((np.cos(np.linspace(0, 2 * np.pi, 25)),
                           np.sin(np.linspace(0, 2 * np.pi, 25))))
"""A unit circle as a closed polyline of 24 segments."""


def _next(ids: np.ndarray) -> int:
    """The number of the next polyline after those numbered `ids`."""
    return int(ids.max()) + 1 if len(ids) else 0


def _to_each(p: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Distance from point p (2,) to each of the segments (k, 2, 2)."""
    a, d = segs[:, 0], segs[:, 1] - segs[:, 0]
    t = np.clip(np.sum((p - a) * d, axis=1) / np.maximum(np.sum(d * d, axis=1), 1e-300),
                0, 1)
    return np.linalg.norm(a + t[:, None] * d - p, axis=1)


def _distance(p: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Distance from each point p (m, 2) to the nearest of the segments (k, 2, 2)."""
    if not len(segs) or not len(p):
        return np.full(len(p), np.inf)
    a, d = segs[:, 0], segs[:, 1] - segs[:, 0]
    rel = p[:, None, :] - a[None]  # (m, k, 2)
    t = np.clip(np.sum(rel * d, axis=2) / np.maximum(np.sum(d * d, axis=1), 1e-18), 0, 1)
    return np.min(np.linalg.norm(rel - t[..., None] * d, axis=2), axis=1)


def _strokes(seg: np.ndarray, d: np.ndarray, hd: float, couple: bool) -> np.ndarray:
    """The segments an arrow draws: its shaft and its head's (heads') edges."""
    out = [seg[None]]
    if hd > 0:
        for back in ((0.0, 0.75) if couple else (0.0,)):
            tri = head(seg[1] - back * hd * d, d, hd)
            out.append(np.stack((tri, tri[[1, 2, 0]]), axis=1))
    return np.vstack(out)


def segments(polylines: list[np.ndarray], first: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(k, 2, 2) segments of polylines (data coordinates), zero-length ones dropped, and
    (k,) the polyline each comes from, numbered from `first`."""
    segs = [np.stack((p[:-1], p[1:]), axis=1) for p in polylines if len(p) > 1]
    if not segs:
        return np.zeros((0, 2, 2)), np.zeros(0, dtype=int)
    ids = np.concatenate([np.full(len(sg), first + k) for k, sg in enumerate(segs)])
    s = np.vstack(segs)
    keep = np.linalg.norm(s[:, 1] - s[:, 0], axis=1) > 1e-12
    return s[keep], ids[keep]


def _lies_on(a: np.ndarray, b: np.ndarray, ids: np.ndarray, clear: float, run: float,
             grow: float | None = None) -> bool:
    """Whether segment a (2, 2) runs within `clear` of parallel segments of one polyline
    of b (k, 2, 2; `ids` (k,) says which) along at least `run` in all, a's ends grown by
    `grow` (default `clear`; all in the same units). A curve's short segments add up: an
    arrow along an ellipse seen almost edge-on lies on it."""
    if not len(b):
        return False
    da = a[1] - a[0]
    la = float(np.linalg.norm(da))
    if la < run:
        return False
    ua = da / la
    db = b[:, 1] - b[:, 0]
    lb = np.linalg.norm(db, axis=1)
    par = np.abs(db @ ua) / lb > PARALLEL
    if not np.any(par):
        return False
    b, ids = b[par], ids[par]
    # b's ends in a's frame: along (s) and across (n)
    rel = b - a[0]
    s = rel @ ua
    n = rel @ np.array([-ua[1], ua[0]])
    # a's stretch grown at both ends: a stroke that starts just past a's tip still runs
    # on it
    grow = clear if grow is None else grow
    lo = np.maximum(np.minimum(s[:, 0], s[:, 1]), -grow)
    hi = np.minimum(np.maximum(s[:, 0], s[:, 1]), la + grow)
    # across-distance at the two ends of the shared stretch (b is straight: linear)
    ds = np.where(np.abs(s[:, 1] - s[:, 0]) > 1e-12, s[:, 1] - s[:, 0], 1.0)
    n_lo = n[:, 0] + (lo - s[:, 0]) / ds * (n[:, 1] - n[:, 0])
    n_hi = n[:, 0] + (hi - s[:, 0]) / ds * (n[:, 1] - n[:, 0])
    # the part of the shared stretch where b is within `clear` across (n is linear in s:
    # b may cross a at a small angle)
    span = np.maximum(hi - lo, 1e-12)
    k = (n_hi - n_lo) / span
    flat = np.abs(k) < 1e-9
    k = np.where(flat, 1.0, k)
    e1, e2 = (-clear - n_lo) / k, (clear - n_lo) / k
    inside = np.where(flat, np.where(np.abs(n_lo) < clear, span, 0.0),
                      np.minimum(np.maximum(e1, e2), span) - np.maximum(np.minimum(e1, e2), 0))
    inside = np.where(hi - lo > 0, np.maximum(inside, 0.0), 0.0)
    return bool(np.max(np.bincount(ids, weights=inside)) >= run)


def separate(arrs: list[Arrow], fixed: list[np.ndarray], scale: float, centre: np.ndarray,
             hd: float = 0.0, lines: list[np.ndarray] | None = None, ring: float = 0.0,
             marks: list[tuple[np.ndarray, float]] | None = None, marker: float = 0.0
             ) -> list[Arrow]:
    """The arrows, each straight one moved sideways where it would lie on a stroke drawn
    before it (`fixed` polylines: the outline, within CLEAR; `lines`, the body axes, and
    the arrows before it, within CLEAR_LINE), or where its tip would touch one (an
    unknown reaction first drawn shorter or longer).

    Parameters
    ----------
    arrs : list of Arrow
        In drawing order; the first keeps its place where it can.
    fixed : list of (k, 2) arrays
        Strokes that stay where they are (data coordinates).
    lines : list of (k, 2) arrays, optional
        Strokes that stay where they are and that an arrow keeps CLEAR_LINE from (the
        body axes).
    scale : float
        Points per data unit of the panel.
    centre : (2,) array
        The mass centre on the page: of two equal moves, the one away from it wins.
    hd : float
        Arrowhead length (data units); 0: tips are not checked.
    ring : float
        The radius (data units) of an arrow seen end-on (a moment's outer ring: 1.45
        times that); 0: end-on arrows stay where they act.
    marks : list of ((2,) array, float), optional
        Rings already drawn (centre, radius; data units): the body axes seen end-on. A
        ring moved beside its point keeps as far from them as from another ring.
    marker : float
        The radius (data units) of G's marker at `centre`: tips and moved rings keep
        clear of it; an arrow from G crosses it, and an end-on ring at G goes round it.

    Returns
    -------
    list of Arrow
        New arrows (the given ones are left as they are).
    """
    unit = 1.0 / scale  # one point in data units
    outline, outline_ids = segments(fixed)
    placed, placed_ids = segments(list(lines or []))  # body axes, then each arrow placed
    # what a tip keeps clear of: strokes, heads and G's marker
    near = np.vstack((outline, placed, segments([centre + marker * _CIRCLE])[0]))
    tips = np.zeros((0, 2))
    clear = TIP * unit if hd > 0 else -1.0
    order = sorted(range(len(arrs)), key=lambda i: arrs[i].kind in GIVES_WAY)
    out: dict[int, Arrow] = {}
    end_on = [i for i in order if arrs[i].arc is None
              and float(np.linalg.norm(arrs[i].vec)) < END_ON * arrs[i].length3]
    tries = 13 + 2 * len(arrs)  # 0, ±1, ... ±6 steps, and two more a side per arrow
    for i in order:
        a = arrs[i]
        n = float(np.linalg.norm(a.vec))
        if a.arc is not None or i in end_on:  # end-on: placed last, below
            if a.arc is not None:
                out[i] = a
                arc, arc_ids = segments([a.arc], _next(placed_ids))
                placed, placed_ids = np.vstack((placed, arc)), np.r_[placed_ids, arc_ids]
                near = np.vstack((near, arc))
            continue
        d = a.vec / n
        side = np.array([-d[1], d[0]])
        factors = LENGTHS if a.kind in GIVES_WAY and hd > 0 else (1.0,)
        away = 1.0 if float((a.tail + 0.5 * a.vec - centre) @ side) >= 0 else -1.0
        shift, f = 0.0, 1.0
        for k in range(tries):  # 0, then ±1, ±2, ... steps, away from G first
            shift = 0.0 if k == 0 else away * ((k + 1) // 2) * (1 if k % 2 else -1)
            t0 = a.tail + shift * STEP * unit * side
            ok = False
            for f in factors:
                seg = np.array([t0, t0 + f * a.vec])
                if _lies_on(seg, outline, outline_ids, CLEAR * unit, RUN * unit) or _lies_on(
                        seg, placed, placed_ids, CLEAR_LINE * unit, RUN * unit, CLEAR * unit):
                    continue
                if clear > 0 and (
                        _distance(seg[1:], near)[0] < clear
                        or np.any(_distance(tips, _strokes(seg, d, hd, a.couple)) < clear)):
                    continue
                ok = True
                break
            if ok:
                break
        else:
            shift, f = 0.0, 1.0  # nowhere clear: leave it where it acts
        b = (replace(a, tail=a.tail + shift * STEP * unit * side, moved_from=a.tail)
             if shift else a)
        if f != 1.0:
            b = replace(b, vec=f * a.vec)
        out[i] = b
        seg = np.array([b.tail, b.tail + b.vec])
        placed = np.vstack((placed, seg[None]))
        placed_ids = np.r_[placed_ids, _next(placed_ids)]
        near = np.vstack((near, _strokes(seg, d, hd, a.couple)))
        tips = np.vstack((tips, seg[1:]))
    rings: list[tuple[np.ndarray, float]] = list(marks or [])
    for i in end_on:
        a = arrs[i]
        radius = ring * (1.45 if a.couple else 1.0)
        c = _ring_place(a.tail, radius, rings, near, unit) if ring > 0 else a.tail
        out[i] = a if np.array_equal(c, a.tail) else replace(a, tail=c, moved_from=a.tail)
        rings.append((c, radius))
    return [out[i] for i in range(len(arrs))]


RING_GAP = 5.0
"""Clear space (points) from an end-on ring moved beside its point to other strokes..."""
RING_ROOM = 13.0
"""... and between two end-on rings, about a label's height: room for one's label."""


def _ring_place(p: np.ndarray, radius: float, rings: list[tuple[np.ndarray, float]],
                strokes: np.ndarray, unit: float) -> np.ndarray:
    """Where an arrow seen end-on at `p` is drawn: at p if no ring is drawn there yet,
    else beside p, on the nearest circle about it that has a free spot, farthest there
    from the strokes (k, 2, 2) and rings around (all in data units; `unit`: a point)."""
    gap, apart = RING_GAP * unit, RING_ROOM * unit
    if all(np.linalg.norm(p - c) >= radius + r + unit for c, r in rings):
        return p  # (a ring that fits at p stays there, however near the others)
    here = max([r for c, r in rings if np.linalg.norm(c - p) < max(r, radius)],
               default=0.0)
    ang = np.radians(np.arange(0.0, 360.0, 15.0) - 45.0)  # lower right first, on ties
    u = np.column_stack((np.cos(ang), np.sin(ang)))
    best, best_room = p, -np.inf
    for j in range(8):
        cand = p + (here + radius + gap + j * (radius + gap)) * u
        room = _distance(cand, strokes) - radius
        for c, r in rings:  # (beside another ring, the room left for a label)
            room = np.minimum(room, np.linalg.norm(cand - c, axis=1) - radius - r
                              - (apart - gap))
            if np.linalg.norm(c - p) > r:  # its leader from p passes clear of the ring
                lead = np.stack((np.broadcast_to(p, cand.shape), cand), axis=1)
                room = np.minimum(room, _to_each(c, lead) - r)
        k = int(np.argmax(np.round(room / unit, 1)))
        if room[k] >= gap:
            return cand[k]
        if room[k] > best_room:
            best, best_room = cand[k], float(room[k])
    return best
