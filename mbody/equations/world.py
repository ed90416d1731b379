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

import numpy as np

from mbody import conventions as cv
from mbody.equations.joints import ReactionColumns
from mbody.joint_types import base as jb
from mbody.model.model import Model


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
    rt = model.reaction_table
    labels = rt.labels
    K = lam.shape[0]
    k_drivers = len(rt.driver_names)
    m_joints = len(labels) - k_drivers
    nj = len(model.joints)
    F = np.zeros((K, nj, 3))
    Mo = np.zeros((K, nj, 3))
    has_F = np.zeros(nj, dtype=bool)
    has_M = np.zeros(nj, dtype=bool)
    pitch = model.joint_table.pitch
    w = lam[:, :m_joints, None] * W_e[:, :m_joints]  # (K, m_joints, 3)
    for c in range(m_joints):
        j = int(rt.joint[c])
        if rt.kind[c] == jb.SCREW:  # the axial wrench: a force and its screw's moment
            F[:, j] += w[:, c]
            Mo[:, j] -= pitch[j] / (2.0 * np.pi) * w[:, c]
            has_F[j] = has_M[j] = True
        elif rt.is_moment[c]:
            Mo[:, j] += w[:, c]
            has_M[j] = True
        else:
            F[:, j] += w[:, c]
            has_F[j] = True
    planar = model.dimension == cv.PLANAR
    out_labels: list[str] = []
    columns: list[np.ndarray] = []
    for j, joint in enumerate(model.joints):
        if has_F[j]:
            for a in range(2 if planar else 3):
                out_labels.append(f"{joint.name}.F{'xyz'[a]}")
                columns.append(F[:, j, a])
        if has_M[j]:
            for a in ((2,) if planar else (0, 1, 2)):
                out_labels.append(f"{joint.name}.M{'xyz'[a]}")
                columns.append(Mo[:, j, a])
    for c in range(m_joints, len(labels)):
        out_labels.append(labels[c])
        columns.append(lam[:, c])
    values = np.stack(columns, axis=1) if columns else np.zeros((K, 0))
    return tuple(out_labels), values
