"""Label placement: each label at the free spot nearest its anchor (an arrow's tip).

Greedy: labels in order, each tried at ~60 spots around its anchor; the spot crossing
the fewest drawn lines and placed labels wins, its own arrow counting most. Works in
points with text sizes from `fonts` (no rendering), all spots of one label at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mbody.present.draw.scene import Panel, Text
from mbody.present.draw.svg import text_box


@dataclass(slots=True)
class Label:
    """A text to place near `anchor` (data), away from its arrow along `direction`;
    `own` tags the obstacles it must avoid most (its arrow), or 'axis' / 'g'."""

    text: Text
    anchor: np.ndarray
    direction: np.ndarray
    own: str


def sample(points: np.ndarray, step: float) -> np.ndarray:
    """Points every `step` along a polyline (same units), for overlap tests."""
    d = np.linalg.norm(np.diff(points, axis=0), axis=1)
    k = np.maximum(1, np.ceil(d / step).astype(int))
    seg = np.repeat(np.arange(len(d)), k)
    t = (np.arange(len(seg)) - np.repeat(np.cumsum(k) - k, k) + 1) / np.repeat(k, k)
    inner = points[seg] + (points[seg + 1] - points[seg]) * t[:, None]
    return np.vstack((points[:1], inner))


def _spots(mid: float | None) -> np.ndarray:
    """Candidate offsets (points) as (along, across) the label's direction."""
    c: list[tuple[float, float]] = [(5, 0), (5, 9), (5, -9), (0, 10), (0, -10), (18, 0),
                                    (5, 22), (5, -22), (30, 10), (30, -10)]
    if mid is not None:  # beside the shaft, half-way
        c += [(mid, 10), (mid, -10)]
    ang = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    ring = [(r * math.cos(a), r * math.sin(a)) for r in (14.0, 26.0, 40.0) for a in ang]
    return np.array(c + ring, dtype=float)


def place(panel: Panel, labels: list[Label], obstacles: list[tuple[np.ndarray, str]]
          ) -> np.ndarray:
    """Choose each label's offset and alignment; returns their boxes (k, 4) as x0, y0,
    x1, y1 in points."""
    pts, tags = [], []
    for xy, tag in obstacles:
        sp = sample(panel.to_pt(xy), 1.5)
        pts.append(sp)
        tags += [tag] * len(sp)
    P = np.vstack(pts) if pts else np.zeros((0, 2))
    tag_arr = np.array(tags, dtype=object)
    base_w = np.where(tag_arr == "outline", 0.4, 3.0)
    x0b, y0b, wb, hb = panel.rect
    placed = np.zeros((0, 4))
    pad = 2.0
    for lab in labels:
        t = lab.text
        t.offset, t.ha, t.va = (0.0, 0.0), "left", "bottom"
        _, _, w, h = text_box(t, np.zeros(2))
        weights = np.where(tag_arr == lab.own, 8.0, base_w)
        a_pt = panel.to_pt(lab.anchor)
        d = np.asarray(lab.direction, dtype=float)
        n = np.linalg.norm(d)
        d = d / n if n > 1e-12 else np.array([1.0, 0.0])
        nrm = np.array([-d[1], d[0]])
        mid = None
        if lab.own not in ("axis", "g"):
            mid = -0.5 * float(np.linalg.norm(a_pt - panel.to_pt(lab.anchor - lab.direction)))
        sp = _spots(mid)
        off = sp[:, :1] * d + sp[:, 1:] * nrm  # (c, 2) points
        o = off / np.maximum(np.linalg.norm(off, axis=1, keepdims=True), 1e-12)
        fx = np.where(o[:, 0] > 0.3, 0.0, np.where(o[:, 0] < -0.3, 1.0, 0.5))
        fy = np.where(o[:, 1] > 0.3, 0.0, np.where(o[:, 1] < -0.3, 1.0, 0.5))
        x0 = a_pt[0] + off[:, 0] - fx * w - pad
        y0 = a_pt[1] + off[:, 1] - fy * h - pad
        x1, y1 = x0 + w + 2 * pad, y0 + h + 2 * pad
        score = 0.004 * np.linalg.norm(off, axis=1)  # nearer is better, all else equal
        if len(P):
            inside = ((P[None, :, 0] > x0[:, None]) & (P[None, :, 0] < x1[:, None])
                      & (P[None, :, 1] > y0[:, None]) & (P[None, :, 1] < y1[:, None]))
            score += inside.astype(float) @ weights
        if len(placed):
            ow = np.minimum(x1[:, None], placed[:, 2]) - np.maximum(x0[:, None], placed[:, 0])
            oh = np.minimum(y1[:, None], placed[:, 3]) - np.maximum(y0[:, None], placed[:, 1])
            hit = (ow > 0) & (oh > 0)
            score += np.sum(np.where(hit, 200 + 5 * ow * oh, 0.0), axis=1)
        outside = (x0 < x0b) | (x1 > x0b + wb) | (y0 < y0b) | (y1 > y0b + hb)
        score += 2.0 * outside  # allowed (limits grow later) but not preferred
        k = int(np.argmin(score))  # the first of equal scores, as the spots are ordered
        t.offset = (float(off[k, 0]), float(off[k, 1]))
        t.ha = "left" if fx[k] == 0 else "right" if fx[k] == 1 else "center"
        t.va = "bottom" if fy[k] == 0 else "top" if fy[k] == 1 else "center"
        placed = np.vstack((placed, [x0[k], y0[k], x1[k], y1[k]]))
    return placed
