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
    rt = model.reaction_table
    labels = rt.labels
    lam = np.array([values[lab] for lab in labels], dtype=float)
    k_drivers = len(rt.driver_names)
    m_joints = len(labels) - k_drivers
    nj = len(model.joints)
    F = np.zeros((nj, 3))
    Mo = np.zeros((nj, 3))
    has_F = np.zeros(nj, dtype=bool)
    has_M = np.zeros(nj, dtype=bool)
    pitch = model.joint_table.pitch
    for c in range(m_joints):
        j = int(rt.joint[c])
        w = lam[c] * cols.W_e[c]
        if rt.kind[c] == jb.SCREW:
            F[j] += w
            Mo[j] -= pitch[j] / (2.0 * np.pi) * w
            has_F[j] = has_M[j] = True
        elif rt.is_moment[c]:
            Mo[j] += w
            has_M[j] = True
        else:
            F[j] += w
            has_F[j] = True
    planar = model.dimension == cv.PLANAR
    out: dict[str, float] = {}
    for j, joint in enumerate(model.joints):
        if has_F[j]:
            for a in range(2 if planar else 3):
                out[f"{joint.name}.F{'xyz'[a]}"] = float(F[j, a])
        if has_M[j]:
            for a in ((2,) if planar else (0, 1, 2)):
                out[f"{joint.name}.M{'xyz'[a]}"] = float(Mo[j, a])
    for lab in labels[m_joints:]:
        out[lab] = float(values[lab])
    return out
