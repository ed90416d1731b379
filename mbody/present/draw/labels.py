"""Label placement: each label at the nearest spot beside what it names (an arrow's tip
or shaft, an axis, a marker) where its box touches no stroke and no other label.

A label's candidate spots are boxes touching its anchor (an arrow's tip; or the ring or
marker it names, from outside) from every direction, a few gaps out, boxes sliding all
along one side or the other of a straight shaft, and boxes around its tail; then boxes
on rings farther out. A box (the text's box from `fonts`, grown by PAD) is scored by the
strokes sampled inside it (every drawn line, arrowhead, outline, axis and marker, its
own arrow included: counted in O(1) a box from a summed table of the samples on a
1-point grid), by the labels it meets, and by how far it is from the tip. Works in
points, without rendering.

A label names its arrow only if it is near it: a free spot whose box is within NEAR
label heights of the label's own strokes (its arrow's shaft and heads, its axis, its
marker) beats any free spot farther out. Labels are placed in turn, each at its best
spot; then each label left without a free near spot tries again, moving the one or two
labels in its way to free near spots of theirs (so that the order they were placed in
matters less). A label that still finds no free spot near enough gets a leader
(`Label.leader`, drawn by the diagram): a thin line from its box to its arrow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mbody.present.draw.scene import Panel, Text
from mbody.present.draw.svg import text_box

PAD = 2.5
"""Clear space (points) kept around a label's text: from strokes and from other labels."""
STEP = 1.0
"""Strokes are sampled every STEP points (below PAD: a stroke near a box has a sample
inside its padded box)."""
NEAR = 1.45
"""A label's box within NEAR times its height of its own strokes is near them (measured
to the strokes' samples, every STEP along them: never nearer than the strokes are)."""
GAPS = (0.5, 3.0, 6.0, 9.0, 12.0)
"""Gaps (points) between a candidate's padded box and its anchor or shaft."""
ALONG = 4.0
"""Candidate boxes beside a shaft are this far apart (points) along it."""
RINGS = (12.0, 20.0, 30.0, 42.0, 58.0, 78.0, 100.0)
"""Farther rings of candidates (points from the anchor), for a label with no near spot."""

FREE, FAR, OUTSIDE = 2.5, 2.5, 2.0
"""Score below FREE: a free near spot. FAR is added for a box farther than NEAR from its
own strokes, OUTSIDE for one outside the panel (allowed: the limits grow later)."""


@dataclass(slots=True)
class Label:
    """A text to place near `anchor` (data), away from its arrow along `direction`;
    `own` tags the obstacles that are its own (its arrow, its axis, its marker)."""

    text: Text
    anchor: np.ndarray
    direction: np.ndarray
    own: str
    shaft: float = 0.0  # a straight arrow's length (data): spots beside it, along it
    radius: float = 0.0  # the anchor's ring or marker (data): spots start beyond it
    leader: np.ndarray | None = None  # (2, 2) data: box to its arrow, when placed far


def sample(points: np.ndarray, step: float) -> np.ndarray:
    """Points every `step` along a polyline (same units), for overlap tests."""
    d = np.linalg.norm(np.diff(points, axis=0), axis=1)
    k = np.maximum(1, np.ceil(d / step).astype(int))
    seg = np.repeat(np.arange(len(d)), k)
    t = (np.arange(len(seg)) - np.repeat(np.cumsum(k) - k, k) + 1) / np.repeat(k, k)
    inner = points[seg] + (points[seg + 1] - points[seg]) * t[:, None]
    return np.vstack((points[:1], inner))


class _Counts:
    """How many stroke samples lie in a box: a summed table of the samples on a 1-point
    grid over the samples' extent (a box counts every cell it touches: at most a point
    more than the box; a box's part outside the grid holds no sample)."""

    def __init__(self, pts: np.ndarray) -> None:
        lo = pts.min(axis=0) if len(pts) else np.zeros(2)
        hi = pts.max(axis=0) if len(pts) else np.zeros(2)
        self.lo = np.floor(lo) - 1.0
        nx, ny = (np.ceil(hi - self.lo) + 2).astype(int)
        self.n = np.array([nx, ny])
        ix = np.floor(pts - self.lo).astype(int) + 1
        grid = np.bincount(ix[:, 1] * (nx + 1) + ix[:, 0], minlength=(ny + 1) * (nx + 1)
                           ).reshape(ny + 1, nx + 1)
        self.table = grid.cumsum(axis=0).cumsum(axis=1)

    def __call__(self, boxes: np.ndarray) -> np.ndarray:
        """(c,) samples inside each box (c, 4): x0, y0, x1, y1 in points."""
        a = np.clip(np.floor(boxes[:, :2] - self.lo).astype(int), 0, self.n - 1)
        b = np.clip(np.floor(boxes[:, 2:] - self.lo).astype(int) + 1, 0, self.n)
        t = self.table
        return t[b[:, 1], b[:, 0]] - t[a[:, 1], b[:, 0]] - t[b[:, 1], a[:, 0]] + t[a[:, 1], a[:, 0]]


def _touching(a: np.ndarray, u: np.ndarray, gap: np.ndarray, hw: float, hh: float
              ) -> np.ndarray:
    """Centres of boxes (half sizes hw, hh) lying `gap` beyond points `a` along unit
    directions u (all broadcast to (..., 2) and (...)): each box in the half plane
    (x − a)·u ≥ gap, touching its edge."""
    reach = hw * np.abs(u[..., 0]) + hh * np.abs(u[..., 1])
    return a + (gap + reach)[..., None] * u


def _candidates(a: np.ndarray, d: np.ndarray, length: float, radius: float, hw: float,
                hh: float) -> tuple[np.ndarray, np.ndarray]:
    """Candidate box centres (c, 2) for a label anchored at `a` (its arrow's tip, or the
    centre of a ring or marker of `radius`) along unit `d`, beside a straight shaft of
    `length` behind the tip (0: none), boxes of half sizes hw, hh (all in points); and the
    preference of each (small: nearer the tip, beyond it first, then beside the shaft,
    then around its tail)."""
    base = math.atan2(d[1], d[0])
    ang = base + np.radians(np.arange(0, 360, 5))
    u = np.column_stack((np.cos(ang), np.sin(ang)))  # (n, 2)
    gaps = np.array(GAPS)[:, None]  # (g, 1)
    behind = 1.0 - u @ d  # 0 beyond the tip, 2 behind it
    centres = [_touching(a, u, radius + gaps, hw, hh).reshape(-1, 2)]
    prefs = [(0.004 * gaps + 0.01 * behind).ravel()]
    if length > 0:
        nrm = np.array([-d[1], d[0]])
        t = np.arange(0.5 * ALONG, length, ALONG)[:, None, None]  # (t, 1, 1)
        sides = np.array([nrm, -nrm])[None, :, None, :]  # (1, 2, 1, 2)
        p = a - t[..., None] * d  # (t, 1, 1, 2)
        g3 = np.array(GAPS)[None, None, :]  # (1, 1, g)
        centres.append(_touching(p, sides, g3, hw, hh).reshape(-1, 2))  # (t, 2, g, 2)
        prefs.append(np.broadcast_to(0.004 * g3 + 0.02 + 0.0015 * t,
                                     (len(t), 2, len(GAPS))).ravel())
        # around the tail, last: where several arrows may start
        centres.append(_touching(a - length * d, u, gaps, hw, hh).reshape(-1, 2))
        prefs.append((0.004 * gaps + 0.03 + 0.0015 * length + 0.01 * (2.0 - behind)).ravel())
    for r in RINGS:
        n = 16 if r < 20 else 24 if r < 40 else 32 if r < 70 else 40
        ang = base + np.linspace(0, 2 * np.pi, n, endpoint=False)
        u = np.column_stack((np.cos(ang), np.sin(ang)))
        centres.append(_touching(a, u, np.full(n, radius + r), hw, hh))
        prefs.append(0.004 * r + 0.01 * (1.0 - u @ d))
    return np.vstack(centres), np.concatenate(prefs)


def _near(mine: np.ndarray, boxes: np.ndarray, gap: float) -> np.ndarray:
    """(c,) whether each box (c, 4) lies within `gap` of one of the points `mine` (k, 2):
    counted in the box grown by `gap` across and along (sure), then, for a point only in
    the grown box's corners, measured."""
    own = _Counts(mine)
    sure = gap - 1.0  # a count takes in every cell a box touches: up to a point more
    g = np.array([sure, 0.0, -sure, 0.0])  # grown left and right; then up and down
    near = (own(boxes - g) + own(boxes - g[[1, 0, 3, 2]])) > 0
    maybe = ~near & (own(boxes - gap * np.array([1.0, 1.0, -1.0, -1.0])) > 0)
    if np.any(maybe):
        b = boxes[maybe]
        near[maybe] = _gap(mine, b[:, 0], b[:, 1], b[:, 2], b[:, 3]) <= gap
    return near


def place(panel: Panel, labels: list[Label], obstacles: list[tuple[np.ndarray, str]]
          ) -> np.ndarray:
    """Choose each label's offset and alignment; returns their boxes (k, 4) as x0, y0,
    x1, y1 in points, padded by PAD.

    Parameters
    ----------
    panel : Panel
        Its limits and rectangle set: data to points.
    labels : list of Label
        Placed in this order; each `text` gets its offset, ha and va.
    obstacles : list of ((k, 2) array, str)
        Polylines in data coordinates, each with its owner's tag.
    """
    pts = [sample(panel.to_pt(xy), STEP) for xy, _ in obstacles]
    P = np.vstack(pts) if pts else np.zeros((0, 2))
    names = {tag: k for k, tag in enumerate(dict.fromkeys(tag for _, tag in obstacles))}
    tags = np.repeat(np.array([names[tag] for _, tag in obstacles] or [-1]),
                     [len(p) for p in pts] or [0])
    x0b, y0b, wb, hb = panel.rect
    anchors = np.array([panel.to_pt(lab.anchor) for lab in labels]).reshape(-1, 2)
    counts = _Counts(P)

    # every label's candidates, scored against the strokes once
    cands: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    sizes = []
    for lab, a_pt in zip(labels, anchors, strict=True):
        t = lab.text
        t.offset, t.ha, t.va, lab.leader = (0.0, 0.0), "center", "center", None
        _, _, w, h = text_box(t, np.zeros(2))
        sizes.append((w, h))
        d = np.asarray(lab.direction, dtype=float)
        n = np.linalg.norm(d)
        d = d / n if n > 1e-12 else np.array([1.0, 0.0])
        hw, hh = w / 2 + PAD, h / 2 + PAD
        c, pref = _candidates(a_pt, d, lab.shaft * panel.scale, lab.radius * panel.scale,
                              hw, hh)
        boxes = np.column_stack((c[:, 0] - hw, c[:, 1] - hh, c[:, 0] + hw, c[:, 1] + hh))
        hits = counts(boxes)
        score = pref + 10.0 * hits
        outside = ((boxes[:, 0] < x0b) | (boxes[:, 2] > x0b + wb) | (boxes[:, 1] < y0b)
                   | (boxes[:, 3] > y0b + hb))
        score += OUTSIDE * outside
        mine = P[tags == names.get(lab.own, -2)] if len(P) else P
        free = hits == 0
        if len(mine) and np.any(free):  # a free spot far from its own strokes: worse than
            # any free spot near them (a spot on a stroke is worse than both)
            score[free] += FAR * ~_near(mine, boxes[free] + [PAD, PAD, -PAD, -PAD],
                                        NEAR * h)
        cands.append((boxes, score, mine))

    placed = np.full((len(labels), 4), np.nan)

    def best(i: int, others: np.ndarray) -> tuple[int, float]:
        """Label i's best candidate beside the boxes `others` (m, 4); its score."""
        boxes, score = cands[i][0], cands[i][1]
        if len(others):
            ow = (np.minimum(boxes[:, None, 2], others[:, 2])
                  - np.maximum(boxes[:, None, 0], others[:, 0]))
            oh = (np.minimum(boxes[:, None, 3], others[:, 3])
                  - np.maximum(boxes[:, None, 1], others[:, 1]))
            hit = (ow > 0) & (oh > 0)
            score = score + np.sum(np.where(hit, 200 + 5 * ow * oh, 0.0), axis=1)
        k = int(np.argmin(score))  # the first of equal scores: candidates are ordered
        return k, float(score[k])

    scores = np.zeros(len(labels))
    for i in range(len(labels)):
        k, s = best(i, placed[:i])
        placed[i], scores[i] = cands[i][0][k], s

    # a label without a free near spot: move the labels in its way, if they have others
    for i in map(int, np.flatnonzero(scores >= FREE)):
        boxes, score = cands[i][0], cands[i][1]
        for spot in np.argsort(score, kind="stable")[:60]:
            if score[spot] >= FREE:
                break
            box = boxes[spot]
            rest = np.delete(np.arange(len(labels)), i)
            ow = np.minimum(box[2], placed[rest, 2]) - np.maximum(box[0], placed[rest, 0])
            oh = np.minimum(box[3], placed[rest, 3]) - np.maximum(box[1], placed[rest, 1])
            blockers = rest[(ow > 0) & (oh > 0)]
            if not 1 <= len(blockers) <= 2:
                continue
            trial, moved = placed.copy(), scores.copy()
            trial[i], moved[i] = box, score[spot]
            for j in blockers:
                kj, moved[j] = best(int(j), np.delete(trial, j, axis=0))
                if moved[j] >= FREE:
                    break
                trial[j] = cands[j][0][kj]
            else:
                placed, scores = trial, moved
                break

    for i, lab in enumerate(labels):
        t = lab.text
        box = placed[i]
        a_pt = anchors[i]
        c = (box[:2] + box[2:]) / 2
        t.offset = (float(c[0] - a_pt[0]), float(c[1] - a_pt[1]))
        mine = cands[i][2]
        if len(mine):
            lo, hi = box[:2] + PAD, box[2:] - PAD
            gaps = np.linalg.norm(mine - np.clip(mine, lo, hi), axis=1)
            j = int(np.argmin(gaps))
            if gaps[j] > NEAR * sizes[i][1]:  # a thin line from the box to its arrow
                ends = np.array([np.clip(mine[j], lo, hi), mine[j]])
                lab.leader = (ends - panel.rect[:2]) / panel.scale + panel.lo
    return placed


def _gap(pts: np.ndarray, x0: np.ndarray, y0: np.ndarray, x1: np.ndarray, y1: np.ndarray
         ) -> np.ndarray:
    """(c,) distance from each box (x0, y0, x1, y1; each (c,)) to the nearest point."""
    dx = np.maximum(np.maximum(x0[:, None] - pts[None, :, 0], pts[None, :, 0] - x1[:, None]),
                    0)
    dy = np.maximum(np.maximum(y0[:, None] - pts[None, :, 1], pts[None, :, 1] - y1[:, None]),
                    0)
    return np.min(np.hypot(dx, dy), axis=1)
