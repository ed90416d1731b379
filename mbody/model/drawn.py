"""The box a body without a ``shape`` is drawn as: one rule for every picture of a body
(the free-body diagrams and the report, `mbody.present.draw.outline`; the animation,
`mbody.present.animate.scene`).

- A body with two or more distinct points where its joints and loads act (joint points,
  points of application, spring ends; not gravity, which always acts at G) is drawn as a
  **bar** through them: a box along the line through the two points farthest apart, as
  wide as `BAR_WIDTH` of their distance, reaching half that width past each point and
  past the mass centre on every side, so that every point and G lie inside it (a rod
  with pins at its ends looks like a rod with pins at its ends; a bell crank's three pins
  all lie on it).
- Otherwise it is drawn as the **uniform box with its principal moments of inertia**
  (`inertia_box`: a planar body, the square with its I_G), turned to its principal axes.

A particle (no inertia) is drawn by each picture its own way (a dot). The MJCF export
gives a shapeless body the inertia box alone (`inertia_box`): MJCF's geom is read back
as the body's ``shape``, centred at its mass centre and with the body's inertia, which a
bar beside G would not be.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mbody import conventions as cv
from mbody.model.model import Model
from mbody.util.spatial import box_equivalent

BAR_WIDTH = 0.1
"""A bar's width, as a fraction of the distance between the two points farthest apart."""
DISTINCT = 1e-9
"""Points closer than this fraction of the body's size count as one point."""


@dataclass(frozen=True)
class DrawnBox:
    """A box in a body's axes.

    Attributes
    ----------
    size : (d,) array
        Its edge lengths along its own axes (m): 2 for a planar body (its thickness is
        each picture's own), 3 for a spatial one.
    axes : (3, 3) array
        Its own axes in the body's axes (columns; a rotation).
    centre : (3,) array
        Its centre from the mass centre, body axes (m).
    bar : bool
        The bar through the body's points (else its inertia box).
    """

    size: np.ndarray
    axes: np.ndarray
    centre: np.ndarray
    bar: bool


def inertia_box(dimension: int, mass: float, inertia: np.ndarray) -> DrawnBox:
    """The uniform box with the body's principal moments of inertia, centred at G along
    its principal axes (a planar body: the square with its I_G, a² = 6 I_G / m)."""
    J = np.asarray(inertia, dtype=float)
    if dimension == cv.PLANAR:
        side = math.sqrt(max(6.0 * J[2, 2] / mass, 0.0))
        return DrawnBox(np.array([side, side]), np.eye(3), np.zeros(3), False)
    moments, axes = np.linalg.eigh(J)
    if np.linalg.det(axes) < 0:
        axes[:, 2] *= -1.0
    return DrawnBox(np.asarray(box_equivalent(moments, mass), dtype=float), axes,
                    np.zeros(3), False)


def drawn_box(dimension: int, mass: float, inertia: np.ndarray,
              points: np.ndarray) -> DrawnBox:
    """The box a body without a shape is drawn as (module doc): the bar through `points`
    (k, 3), where its joints and loads act in its axes from G, when two of them are
    distinct; else `inertia_box`."""
    box = inertia_box(dimension, mass, inertia)
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(P) < 2:
        return box
    if dimension == cv.PLANAR:
        P = P * [1.0, 1.0, 0.0]
    gaps = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2)
    a, b = np.unravel_index(int(np.argmax(gaps)), gaps.shape)
    length = float(gaps[a, b])
    size = max(float(np.abs(P).max()), float(box.size.max()), 1e-300)
    if not length > DISTINCT * size:
        return box
    u = (P[b] - P[a]) / length
    axes = _bar_axes(u, np.vstack((P, np.zeros(3))), dimension)
    local = np.vstack((P, np.zeros(3))) @ axes  # the points and G along the bar's axes
    width = BAR_WIDTH * length
    lo, hi = local.min(axis=0) - width / 2, local.max(axis=0) + width / 2
    d = 2 if dimension == cv.PLANAR else 3  # a planar box's thickness: each picture's
    return DrawnBox((hi - lo)[:d], axes, axes @ ((lo + hi) / 2), True)


def _bar_axes(u: np.ndarray, P: np.ndarray, dimension: int) -> np.ndarray:
    """A rotation whose first axis is u: in a plane, the second is u turned a quarter
    turn; in space, the direction across u in which the points spread most (or, when they
    lie on one line, the body axis most nearly across it)."""
    if dimension == cv.PLANAR:
        return np.array([[u[0], -u[1], 0.0], [u[1], u[0], 0.0], [0.0, 0.0, 1.0]])
    across = P - np.outer(P @ u, u)
    across = across - across.mean(axis=0)
    _, s, Vt = np.linalg.svd(across)
    v = Vt[0] if s[0] > DISTINCT * max(float(np.abs(P).max()), 1e-300) else None
    if v is None:
        e = np.eye(3)[int(np.argmin(np.abs(u)))]
        v = e - (e @ u) * u
    v = v - (v @ u) * u
    v /= np.linalg.norm(v)
    return np.column_stack((u, v, np.cross(u, v)))


def load_points(model: Model, i: int) -> np.ndarray:
    """(k, 3) the points of body `i` where its joints and loads act, in its axes from its
    mass centre: each joint's point on it, each point force's point of application, each
    spring's end on it (couples and gravity have none)."""
    jt = model.joint_table
    f, s = model.forces, model.springs
    parts = [jt.B_r_child[jt.child == i], jt.B_r_parent[jt.parent == i],
             f.B_r[(f.body == i) & ~f.couple], s.r_a[s.a == i], s.r_b[s.b == i]]
    return np.vstack([np.asarray(p, dtype=float).reshape(-1, 3) for p in parts])


def body_box(model: Model, i: int) -> DrawnBox:
    """`drawn_box` of the model's body `i` (its shape aside): what the animation draws; a
    particle's is its inertia box, of no size (its joints act at the particle)."""
    if model.particle[i]:
        return inertia_box(model.dimension, float(model.mass[i]), model.J[i])
    return drawn_box(model.dimension, float(model.mass[i]), model.J[i], load_points(model, i))
