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
carry their values.
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


def segments(polylines: list[np.ndarray]) -> np.ndarray:
    """(k, 2, 2) segments of polylines (data coordinates), zero-length ones dropped."""
    segs = [np.stack((p[:-1], p[1:]), axis=1) for p in polylines if len(p) > 1]
    if not segs:
        return np.zeros((0, 2, 2))
    s = np.vstack(segs)
    return s[np.linalg.norm(s[:, 1] - s[:, 0], axis=1) > 1e-12]


def _lies_on(a: np.ndarray, b: np.ndarray, clear: float, run: float,
             grow: float | None = None) -> bool:
    """Whether segment a (2, 2) runs within `clear` of a parallel segment of b (k, 2, 2)
    along at least `run`, a's ends grown by `grow` (default `clear`; all in the same
    units)."""
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
    b = b[par]
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
    return bool(np.any((hi - lo > 0) & (inside >= run)))


def separate(arrs: list[Arrow], fixed: list[np.ndarray], scale: float, centre: np.ndarray,
             hd: float = 0.0, lines: list[np.ndarray] | None = None) -> list[Arrow]:
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

    Returns
    -------
    list of Arrow
        New arrows (the given ones are left as they are).
    """
    unit = 1.0 / scale  # one point in data units
    outline = segments(fixed)
    placed = segments(list(lines or []))  # body axes, then each arrow placed
    near = np.vstack((outline, placed))  # what a tip keeps clear of: strokes and heads
    tips = np.zeros((0, 2))
    clear = TIP * unit if hd > 0 else -1.0
    order = sorted(range(len(arrs)), key=lambda i: arrs[i].kind in GIVES_WAY)
    out: dict[int, Arrow] = {}
    for i in order:
        a = arrs[i]
        n = float(np.linalg.norm(a.vec))
        if a.arc is not None or n < 1e-12:  # an end-on arrow keeps a short shaft: it moves
            out[i] = a
            if a.arc is not None:
                placed = np.vstack((placed, segments([a.arc])))
                near = np.vstack((near, segments([a.arc])))
            continue
        d = a.vec / n
        side = np.array([-d[1], d[0]])
        headed = n >= END_ON * a.length3  # drawn with a head (not end-on)
        factors = LENGTHS if a.kind in GIVES_WAY and headed and hd > 0 else (1.0,)
        away = 1.0 if float((a.tail + 0.5 * a.vec - centre) @ side) >= 0 else -1.0
        shift, f = 0.0, 1.0
        for k in range(13):  # 0, then ±1, ±2, ... steps, away from G first
            shift = 0.0 if k == 0 else away * ((k + 1) // 2) * (1 if k % 2 else -1)
            t0 = a.tail + shift * STEP * unit * side
            ok = False
            for f in factors:
                seg = np.array([t0, t0 + f * a.vec])
                if _lies_on(seg, outline, CLEAR * unit, RUN * unit) or _lies_on(
                        seg, placed, CLEAR_LINE * unit, RUN * unit, CLEAR * unit):
                    continue
                if headed and clear > 0 and (
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
        if headed:
            near = np.vstack((near, _strokes(seg, d, hd, a.couple)))
            tips = np.vstack((tips, seg[1:]))
        else:
            near = np.vstack((near, seg[None]))
    return [out[i] for i in range(len(arrs))]
