"""Arrows: the log length rule, one arrow per drawn force or couple, and their labels.

Arrow length of a force of magnitude F (world units, in the picture):

    ℓ(F) = ℓ_max · (1 + log10(F / F_min)) / (1 + log10(F_max / F_min))

so the smallest known force is one step long and every factor of 10 adds a step: a force
1000 times another is drawn 4 times as long, and both stay readable. Couples use the same
rule on their own scale (N m); unknown reactions have no magnitude and are drawn at a
fixed length, dashed, in the reaction colour, along their joint axis: labelled A.Fx on
the joint's child, −A.Fx on its parent (where the reaction acts as −R). A driver's effort
(motor.M) is such an unknown too, drawn the same way but as an actuator's effort: in
its own colour and dash (`style.EFFORT`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.conventions import GRAVITY, REACTION
from mbody.model.drivers import EFFORT as DRIVER_EFFORT
from mbody.present.draw.style import COLORS, DASHES, EFFORT
from mbody.present.draw.views import eye
from mbody.util.formatting import quiet

if TYPE_CHECKING:
    from mbody.equations.fbd import ForceOnBody, FreeBodyDiagram

UNKNOWN_FORCE, UNKNOWN_MOMENT = 0.62, 0.82
"""Drawn length of an unknown reaction force and moment, of ℓ_max."""
HEAD = 0.085
"""Arrowhead length, of ℓ_max."""
END_ON = 0.2
"""A spatial arrow whose page length is below END_ON times its 3-D length is drawn end-on:
a ring with a dot (toward the eye) or a cross (away); its short shaft stays, for tools."""


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


@dataclass
class Arrow:
    """One arrow as drawn: page coordinates (the projection's right, up)."""

    gid: str
    kind: str
    label: str
    color: str
    dash: tuple[float, ...] | None  # its dash pattern (line widths); None: solid
    couple: bool
    tail: np.ndarray  # (2,) page
    vec: np.ndarray  # (2,) page (projected drawn vector); planar couple: (sign, radius)
    arc: np.ndarray | None = None  # planar couple: (k, 2) points
    length3: float = 0.0  # drawn length in 3-D, before projection
    toward: float = 0.0  # its component toward the eye (spatial)
    moved_from: np.ndarray | None = None  # (2,) where it acts, when drawn beside it


def fmt(x: float) -> str:
    """A number in 4 significant digits, with a true minus sign and no -0."""
    s = f"{quiet(x):.4g}"
    return "0" if s in ("-0", "0") else s.replace("-", "−")


def _label(fo: ForceOnBody) -> str:
    unit = "N m" if fo.couple else "N"
    if fo.kind == REACTION:  # −A.Fx on the parent: the value of what the arrow carries
        name = fo.signed_label
        return name if fo.value is None else f"{name} = {fmt(fo.side * fo.value)} {unit}"
    if fo.kind == GRAVITY:
        return f"m g = {fmt(fo.magnitude)} N"
    return f"{fo.name} {fmt(fo.magnitude)} {unit}"


def drawn_kind(fo: ForceOnBody) -> str:
    """The kind an arrow is drawn as: the force's kind, or `EFFORT` for a driver's effort
    (a reaction whose component, ``M`` or ``F``, only drivers have: `mbody.model.drivers`)."""
    if fo.kind == REACTION and fo.label.rpartition(".")[2] in DRIVER_EFFORT.values():
        return EFFORT
    return fo.kind


def _direction(fo: ForceOnBody) -> np.ndarray:
    """Unit direction drawn: the vector itself, or for a reaction the positive direction
    of its joint axis (its label, A.Fx or −A.Fx, and value then carry the sign)."""
    v = np.asarray(fo.W_vector, dtype=float)
    if fo.kind == REACTION:
        v = v * fo.side / (fo.value if fo.value else 1.0)
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def arrows(fbd: FreeBodyDiagram, P: np.ndarray, lmax: float) -> list[Arrow]:
    """The arrows of every force and couple that is unknown or not zero, projected by P
    (2, 3); `lmax` is the longest arrow's length (m)."""
    planar = fbd.dimension == cv.PLANAR
    forces = list(fbd.forces)
    known = [fo for fo in forces if not fo.unknown]
    mag = {id(fo): (abs(fo.value) if fo.value is not None else fo.magnitude) for fo in known}
    lengths: dict[int, float] = {}
    for couple in (False, True):
        group = [fo for fo in known if fo.couple == couple]
        for fo, ell in zip(group, arrow_lengths([mag[id(f)] for f in group], lmax),
                           strict=True):
            lengths[id(fo)] = ell
    out: list[Arrow] = []
    ring_count: dict[tuple[float, ...], int] = {}
    for fo in forces:
        if not fo.unknown and (fo.value == 0 if fo.kind == REACTION else fo.magnitude == 0):
            continue  # nothing to draw; listed under the drawing instead
        ell = lengths.get(id(fo), lmax * (UNKNOWN_MOMENT if fo.couple else UNKNOWN_FORCE))
        d = _direction(fo)
        tail3 = np.asarray(fo.W_point, dtype=float)
        tail = P @ tail3
        kind = drawn_kind(fo)
        gid = f"{'couple' if fo.couple else 'arrow'}:{kind}:{fo.label or fo.name}"
        a = Arrow(gid, kind, _label(fo), COLORS[kind], DASHES.get(kind), fo.couple,
                   tail, P @ (ell * d), length3=ell, toward=float(ell * d @ eye(P)))
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
    return out


def head(tip: np.ndarray, d: np.ndarray, h: float) -> np.ndarray:
    """(3, 2) arrowhead triangle of length h with its point at `tip`, along unit `d`."""
    n = np.array([-d[1], d[0]])
    return np.array([tip, tip - h * d + 0.36 * h * n, tip - h * d - 0.36 * h * n])
