"""Label placement: each label at the nearest spot around its anchor (an arrow's tip)
where its box touches no stroke and no label placed before it.

Greedy: labels in order, each tried at spots on rings around its anchor, nearest first;
a spot's box (the text's box from `fonts`, grown by PAD) is scored by the strokes
sampled inside it (every drawn line, arrowhead, outline, axis and marker, its own arrow
included) and the labels it meets. The first ring with a free spot wins; only if none
is free anywhere does the least crowded spot win. Works in points, without rendering,
all spots of one ring of one label at once.

A label names its arrow only if it is near it: a free spot whose box is within NEAR
label heights of the label's own strokes (its arrow's shaft and heads, its axis, its
marker) beats any free spot farther out; the first spots tried lie beside the tip and
all along a straight shaft. A label that finds no free spot near enough gets a leader
(`Label.leader`, drawn by the diagram): a thin line from its box to its arrow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mbody.present.draw.scene import Panel, Text
from mbody.present.draw.svg import text_box

PAD = 2.5
"""Clear space (points) kept around a label's text: from strokes and from other labels."""
STEP = 1.0
"""Strokes are sampled every STEP points (below PAD: a stroke near a box has a sample
inside its padded box)."""
NEAR = 1.3
"""A label's box within NEAR times its height of its own strokes is near them."""


@dataclass(slots=True)
class Label:
    """A text to place near `anchor` (data), away from its arrow along `direction`;
    `own` tags the obstacles that are its own (its arrow, its axis, its marker)."""

    text: Text
    anchor: np.ndarray
    direction: np.ndarray
    own: str
    shaft: float = 0.0  # a straight arrow's length (data): spots beside it, along it
    leader: np.ndarray | None = None  # (2, 2) data: box to its arrow, when placed far


def sample(points: np.ndarray, step: float) -> np.ndarray:
    """Points every `step` along a polyline (same units), for overlap tests."""
    d = np.linalg.norm(np.diff(points, axis=0), axis=1)
    k = np.maximum(1, np.ceil(d / step).astype(int))
    seg = np.repeat(np.arange(len(d)), k)
    t = (np.arange(len(seg)) - np.repeat(np.cumsum(k) - k, k) + 1) / np.repeat(k, k)
    inner = points[seg] + (points[seg + 1] - points[seg]) * t[:, None]
    return np.vstack((points[:1], inner))


def _rings(length: float | None) -> list[np.ndarray]:
    """Candidate spots (points), (c, 4) each: offset along and across the label's
    direction, and the side the box lies on from that point (along, across), in groups
    tried in turn: beyond the tip, beside it and beside a straight shaft (`length`
    points) all along it, then rings farther and farther out."""
    first: list[tuple[float, float, float, float]] = [
        (5, 0, 1, 0), (5, 9, 1, 1), (5, -9, 1, -1), (0, 10, 0, 1), (0, -10, 0, -1),
        (-5, 6, -1, 1), (-5, -6, -1, -1)]
    if length is not None:  # beside the shaft, half-way first, then all along it: the
        # box lies to the side (not centred on the shaft)
        for f in (0.5, 0.3, 0.7, 0.15, 0.85, 0.05, 0.95):
            first += [(-f * length, 6, 0, 1), (-f * length, -6, 0, -1)]
    groups = [np.array(first, dtype=float)]
    for r, n in ((12.0, 16), (20.0, 24), (30.0, 24), (42.0, 32), (58.0, 32), (78.0, 40),
                 (100.0, 40)):
        ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
        ring = np.column_stack((r * np.cos(ang), r * np.sin(ang)))
        groups.append(np.hstack((ring, ring)))
    return groups


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
    placed = np.zeros((0, 4))
    for lab in labels:
        t = lab.text
        t.offset, t.ha, t.va = (0.0, 0.0), "left", "bottom"
        lab.leader = None
        _, _, w, h = text_box(t, np.zeros(2))
        a_pt = panel.to_pt(lab.anchor)
        d = np.asarray(lab.direction, dtype=float)
        n = np.linalg.norm(d)
        d = d / n if n > 1e-12 else np.array([1.0, 0.0])
        nrm = np.array([-d[1], d[0]])
        length = lab.shaft * panel.scale if lab.shaft > 0 else None
        mine = P[tags == names.get(lab.own, -2)] if len(P) else P
        near_gap = NEAR * h
        # strokes near enough to matter for this label
        reach = 100.0 + w + h + 2 * PAD + (length or 0.0)  # spots along the shaft too
        near = np.all(np.abs(P - a_pt) < reach, axis=1) if len(P) else np.zeros(0, bool)
        Q = P[near]
        best: tuple[float, float, float, float, float, float, float] | None = None
        for g, sp in enumerate(_rings(length)):
            off = sp[:, :1] * d + sp[:, 1:2] * nrm  # (c, 2) points
            side = sp[:, 2:3] * d + sp[:, 3:4] * nrm
            o = side / np.maximum(np.linalg.norm(side, axis=1, keepdims=True), 1e-12)
            fx = np.where(o[:, 0] > 0.3, 0.0, np.where(o[:, 0] < -0.3, 1.0, 0.5))
            fy = np.where(o[:, 1] > 0.3, 0.0, np.where(o[:, 1] < -0.3, 1.0, 0.5))
            x0 = a_pt[0] + off[:, 0] - fx * w - PAD
            y0 = a_pt[1] + off[:, 1] - fy * h - PAD
            x1, y1 = x0 + w + 2 * PAD, y0 + h + 2 * PAD
            score = 0.004 * np.linalg.norm(off, axis=1)  # nearer is better, all else equal
            if len(Q):
                inside = ((Q[None, :, 0] > x0[:, None]) & (Q[None, :, 0] < x1[:, None])
                          & (Q[None, :, 1] > y0[:, None]) & (Q[None, :, 1] < y1[:, None]))
                score += 10.0 * np.count_nonzero(inside, axis=1)
            if len(placed):
                ow = np.minimum(x1[:, None], placed[:, 2]) - np.maximum(x0[:, None],
                                                                        placed[:, 0])
                oh = np.minimum(y1[:, None], placed[:, 3]) - np.maximum(y0[:, None],
                                                                        placed[:, 1])
                hit = (ow > 0) & (oh > 0)
                score += np.sum(np.where(hit, 200 + 5 * ow * oh, 0.0), axis=1)
            outside = (x0 < x0b) | (x1 > x0b + wb) | (y0 < y0b) | (y1 > y0b + hb)
            score += 2.0 * outside  # allowed (limits grow later) but not preferred
            if len(mine):  # far from its own strokes: worse than any free spot near them
                score += 2.5 * (_gap(mine, x0 + PAD, y0 + PAD, x1 - PAD, y1 - PAD)
                                > near_gap)
            k = int(np.argmin(score))  # the first of equal scores, as the spots are ordered
            if best is None or score[k] < best[0]:
                best = (float(score[k]), float(off[k, 0]), float(off[k, 1]), float(fx[k]),
                        float(fy[k]), float(x0[k]), float(y0[k]))
            # free and near (at most outside the panel for now): take it; once the near
            # rings are tried, any free spot
            if best[0] < 2.5 or (best[0] < 5.0 and g >= 2):
                break
        assert best is not None
        _, ox, oy, bx, by, bx0, by0 = best
        t.offset = (ox, oy)
        t.ha = "left" if bx == 0 else "right" if bx == 1 else "center"
        t.va = "bottom" if by == 0 else "top" if by == 1 else "center"
        box = np.array([bx0, by0, bx0 + w + 2 * PAD, by0 + h + 2 * PAD])
        placed = np.vstack((placed, box))
        if len(mine):
            lo, hi = box[:2] + PAD, box[2:] - PAD
            gaps = np.linalg.norm(mine - np.clip(mine, lo, hi), axis=1)
            j = int(np.argmin(gaps))
            if gaps[j] > near_gap:  # a thin line from the box to its arrow
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

