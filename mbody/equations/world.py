"""Joint reactions in world axes, on request.

A joint's reaction components are along its joint frame, which is fixed to the parent
(docs/conventions.md): a pin's A.Fx on a crank turns with the crank. To compare with a
hand solution written in world axes, each joint's components are summed into the force
and the moment it puts on its child at the joint point, in world axes:

    F = Σ λ_c e_c  over its force components,   M = Σ λ_c e_c  over its moments,

with e_c each component's direction at the state (a particle link's tension along the
link; a helical joint's axial wrench Wz adds Wz e to F and −(pitch/2π) Wz e to M).
Labels: ``<joint>.Fx, .Fy, .Fz`` and ``<joint>.Mx, .My, .Mz`` along world x, y, z (a
planar model's joints: Fx, Fy and Mz), for the parts the joint has: a pin has no moment,
a weld both. Drivers' efforts stay as they are (a torque about the driven axis).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.equations.joints import ReactionColumns
from mbody.joint_types import base as jb
from mbody.model.model import Model

if TYPE_CHECKING:
    import scipy.sparse as sp

def world_reactions(model: Model, cols: ReactionColumns, values: Mapping[str, float]
                    ) -> dict[str, float]:
    """label -> value of every joint's force and moment in world axes (module doc), then
    the drivers' efforts, from the joint-frame `values` (every component's) and the
    columns at the state."""
    lam = np.array([values[lab] for lab in model.reaction_table.labels], dtype=float)
    labels, series = world_reaction_series(model, cols.W_e[None], lam[None])
    return dict(zip(labels, series[0].tolist(), strict=True))


def world_reaction_series(model: Model, W_e: np.ndarray, lam: np.ndarray
                          ) -> tuple[tuple[str, ...], np.ndarray]:
    """The world-axes labels (module doc) and their values at K states: `W_e` (K, m, 3)
    each component's direction at each state, `lam` (K, m) the joint-frame values."""
    lay = _layout(model)
    K = lam.shape[0]
    values = np.zeros((K, len(lay.labels)))
    # each component's part of each world value, summed in component order
    part = lay.coef * (lam[:, lay.col] * W_e[:, lay.col, lay.axis])
    np.add.at(values.T, lay.row, part.T)  # values.T: a view, rows are the world values
    values[:, lay.driver_rows] = lam[:, lay.driver_cols]
    return lay.labels, values


def world_map(model: Model, W_e: np.ndarray) -> tuple[tuple[str, ...], sp.csc_matrix]:
    """The world-axes labels (module doc) and the linear map T (p, m) from the joint-frame
    values λ (m, in ``model.reactions`` order) to the world-axes ones at one state, world
    = T λ: `W_e` (m, 3) each component's direction there. T is sparse: each world value
    reads its own joint's components only (a driver's effort: 1 on itself)."""
    import scipy.sparse as sp

    lay = _layout(model)
    m = len(model.reaction_table.labels)
    rows = np.concatenate((lay.row, lay.driver_rows))
    cols = np.concatenate((lay.col, lay.driver_cols))
    data = np.concatenate((lay.coef * W_e[lay.col, lay.axis], np.ones(len(lay.driver_rows))))
    T = sp.csc_matrix((data, (rows, cols)), shape=(len(lay.labels), m))
    return lay.labels, T


class _Layout:
    """Where each joint-frame component goes in world axes: world value `row` gets `coef`
    times the component `col`'s value times its direction's `axis` entry (one entry per
    such part, in component order); a driver's effort `driver_cols` is copied to
    `driver_rows`. A plain class, not a NamedTuple: it is made at every simulate's
    import, where a NamedTuple costs 0.1 ms."""

    __slots__ = ("labels", "row", "col", "axis", "coef", "driver_rows", "driver_cols")

    def __init__(self, labels: tuple[str, ...], row: np.ndarray, col: np.ndarray,
                 axis: np.ndarray, coef: np.ndarray, driver_rows: np.ndarray,
                 driver_cols: np.ndarray):
        self.labels, self.row, self.col, self.axis = labels, row, col, axis
        self.coef, self.driver_rows, self.driver_cols = coef, driver_rows, driver_cols


def _layout(model: Model) -> _Layout:
    rt = model.reaction_table
    m = len(rt.labels)
    m_joints = m - len(rt.driver_names)
    nj = len(model.joints)
    has_F = np.zeros(nj, dtype=bool)
    has_M = np.zeros(nj, dtype=bool)
    for c in range(m_joints):
        j = int(rt.joint[c])
        if rt.kind[c] == jb.SCREW:  # the axial wrench: a force and its screw's moment
            has_F[j] = has_M[j] = True
        elif rt.is_moment[c]:
            has_M[j] = True
        else:
            has_F[j] = True
    planar = model.dimension == cv.PLANAR
    labels: list[str] = []
    F_rows: list[list[tuple[int, int]]] = [[] for _ in range(nj)]  # (row, axis)
    M_rows: list[list[tuple[int, int]]] = [[] for _ in range(nj)]
    for j, joint in enumerate(model.joints):
        if has_F[j]:
            for a in ((0, 1) if planar else (0, 1, 2)):
                F_rows[j].append((len(labels), a))
                labels.append(f"{joint.name}.F{'xyz'[a]}")
        if has_M[j]:
            for a in ((2,) if planar else (0, 1, 2)):
                M_rows[j].append((len(labels), a))
                labels.append(f"{joint.name}.M{'xyz'[a]}")
    pitch = model.joint_table.pitch
    parts: list[tuple[int, int, int, float]] = []  # (row, col, axis, coef)
    for c in range(m_joints):
        j = int(rt.joint[c])
        if rt.kind[c] == jb.SCREW:
            parts += [(r, c, a, 1.0) for r, a in F_rows[j]]
            parts += [(r, c, a, -pitch[j] / (2.0 * np.pi)) for r, a in M_rows[j]]
        else:
            parts += [(r, c, a, 1.0) for r, a in (M_rows if rt.is_moment[c] else F_rows)[j]]
    driver_rows = np.arange(len(labels), len(labels) + m - m_joints)
    labels += list(rt.labels[m_joints:])
    table = np.array(parts, dtype=float).reshape(-1, 4)
    return _Layout(tuple(labels), table[:, 0].astype(np.intp), table[:, 1].astype(np.intp),
                   table[:, 2].astype(np.intp), table[:, 3], driver_rows,
                   np.arange(m_joints, m))
