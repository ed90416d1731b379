"""A validated specification's loads and joints -> the model's tables and records.

`located_loads` and `point_loads` make the `ForceTable` (and the `Load` records) of the
located and the fast path; `joint_tables` computes every joint's frame and points in each
body's axes at once, the `ReactionTable`, and the `Joint` records made on first use.
`mbody.model.model` puts them together into a `Model`. `frames_at` takes the frames again
at the pose `mbody.load` assembles a model to, when that turned a joint's parent.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody import joint_types
from mbody.joint_types.base import TILT, Component
from mbody.model.drivers import DriverTable
from mbody.model.expressions import ExpressionTable
from mbody.model.records import Joint, Load, Records, field_names, record
from mbody.model.tables import ForceTable, JointTable, ReactionTable, readonly
from mbody.model.validate import JointSpecTable, LoadSpec, LoadTable
from mbody.util.spatial import (
    FRAME_TIE,
    joint_frame_planar,
    joint_frame_spatial,
    joint_frames_spatial,
    least_aligned,
    quat_conj,
    quat_mul,
    quat_to_matrix,
)

if TYPE_CHECKING:
    from mbody.model.model import State

LOAD, JOINT = ("load", "loads"), ("joint", "joints")
"""What the records are, for their messages (`Records`)."""


def located_loads(specs: list[LoadSpec], idx: dict[str, int]
                  ) -> tuple[Records[Load], ForceTable]:
    """The loads of the located path, and the force table of its point loads."""
    made = tuple(Load(ld.name, ld.type, ld.bodies, ld.vector, ld.frame, ld.at,
                      ld.stiffness, ld.rest_length, ld.damping, dict(ld.expressions))
                 for ld in specs)
    loads = Records(tuple(ld.name for ld in made), made.__getitem__, LOAD)
    point = [ld for ld in specs if ld.type in ("force", "torque")]
    forces = ForceTable(
        tuple(ld.name for ld in point),
        np.array([idx[ld.bodies[0]] for ld in point], dtype=np.intp),
        readonly(np.array([ld.vector for ld in point]).reshape(-1, 3)),
        np.array([ld.frame == "body" for ld in point], dtype=bool),
        readonly(np.array([ld.at[0] for ld in point]).reshape(-1, 3)),
        np.array([ld.type == "torque" for ld in point], dtype=bool),
        ExpressionTable.build([(row, k, e) for row, ld in enumerate(point)
                               for k, e in ld.expressions.items()]),
    )
    return loads, forces


def point_loads(t: LoadTable, names: tuple[str, ...]) -> tuple[Records[Load], ForceTable]:
    """The fast path's loads (force and torque, constant): their force table, and their
    records, made on first use from it."""
    vector, at = readonly(t.vector), readonly(t.at)
    body = np.asarray(t.body, dtype=np.intp)
    forces = ForceTable(tuple(t.names), body, vector,
                        np.array([f == "body" for f in t.frames], dtype=bool), at,
                        np.array([typ == "torque" for typ in t.types], dtype=bool),
                        ExpressionTable.build([]))
    fields_ = field_names(Load)
    load_names, types, frames = forces.names, t.types, t.frames

    def make(i: int) -> Load:
        return record(Load, fields_, (load_names[i], types[i], (names[body[i]],), vector[i],
                                      frames[i], (at[i],), 0.0, 0.0, 0.0, {}))

    return Records(load_names, make, LOAD), forces


def joint_tables(dimension: int, js: JointSpecTable, names: tuple[str, ...],
                  initial: State, particle: np.ndarray, drivers: DriverTable | None = None
                  ) -> tuple[Records[Joint], ReactionTable]:
    """The joints and their reaction table, computed for all joints at once.

    Per joint: the joint frame W_E0 at the initial pose (one call of the contract's rule
    per distinct axis), then the frame and the joint point in each body's axes,
    ``P_E = R_p^T W_E0``, ``B_r = R^T (at - x)``, kept per joint (`JointTable`); the
    reaction table holds one row per component, each naming its joint and axis, and
    derives the rest on first use. The `Joint` records are made on first use too.
    """
    nj = len(js.names)
    planar = dimension == cv.PLANAR
    W_E0 = readonly(_frames(js.axis, js.has_axis, planar))
    at = readonly(js.at)
    p, c = js.parent, js.child
    ground = p < 0
    R0 = quat_to_matrix(initial.quaternion)  # State.W_R_B's values, not kept on the state
    x0 = initial.position
    # the world frame stands in for ground: I @ v is v exactly
    Rp = np.where(ground[:, None, None], np.eye(3), R0[p] if nj else np.zeros((0, 3, 3)))
    xp = np.where(ground[:, None], 0.0, x0[p] if nj else np.zeros((0, 3)))
    Rc, xc = R0[c], x0[c]
    del R0
    RpT, RcT = Rp.transpose(0, 2, 1), Rc.transpose(0, 2, 1)
    P_E = RpT @ W_E0  # joint frame fixed in the parent (the world for ground)
    C_E = RcT @ W_E0
    B_r_child = (RcT @ (at - xc)[:, :, None])[:, :, 0]
    B_r_parent = np.where(ground[:, None], at, (RpT @ (at - xp)[:, :, None])[:, :, 0])
    if (js.body_points is not None and js.body_points.any()  # the file gives them
            and js.at_child is not None and js.at_parent is not None):
        on = js.body_points
        B_r_child[on] = js.at_child[on]
        B_r_parent[on] = js.at_parent[on]
    C_axis2 = (RcT @ js.axis2[:, :, None])[:, :, 0]
    # a particle end is attached at the particle itself (no offset, no moment)
    p_particle = particle[p] & ~ground
    c_particle = particle[c]
    B_r_child[c_particle] = 0.0
    B_r_parent[p_particle] = 0.0
    kinds = js.particle_joint
    link = np.array([k == "link" for k in kinds], dtype=bool)
    length = np.zeros(nj)
    if link.any():  # attachment points: the particle(s), else the joint point
        P_c = xc + (Rc @ B_r_child[:, :, None])[:, :, 0]
        P_p = np.where(ground[:, None], B_r_parent,
                       xp + (Rp @ B_r_parent[:, :, None])[:, :, 0])
        length[link] = np.linalg.norm((P_c - P_p)[link], axis=1)
    del Rp, Rc, RpT, RcT, xp, xc

    types = js.types
    registry = joint_types.TYPES[dimension]
    comps = ([registry[typ].components for typ in types] if not any(kinds) else
             [registry[typ].particle[k] if k else registry[typ].components
              for typ, k in zip(types, kinds, strict=True)])
    # the distinct component lists (a few), and each joint's
    distinct: dict[tuple[Component, ...], int] = {}
    code = np.fromiter((distinct.setdefault(cs, len(distinct)) for cs in comps),
                       dtype=np.intp, count=nj)
    width = max((len(cs) for cs in distinct), default=1)
    table_of = np.zeros((3, max(len(distinct), 1), width), dtype=np.intp)  # name, kind, axis
    sizes = np.zeros(table_of.shape[1], dtype=np.intp)
    for cs, k in distinct.items():
        table_of[:, k, :len(cs)] = [[joint_types.COMPONENT_CODE[comp.name] for comp in cs],
                                    [comp.kind for comp in cs], [comp.axis for comp in cs]]
        sizes[k] = len(cs)
    counts = sizes[code]
    first = np.cumsum(counts) - counts
    row_joint = np.repeat(np.arange(nj, dtype=np.intp), counts)
    component, kind, frame_axis = table_of[:, code[row_joint],
                                           np.arange(len(row_joint)) - first[row_joint]]
    free_turn = np.array([any(c.kind == TILT for c in registry[typ].components)
                          for typ in types], dtype=bool)
    defaults = {typ: _default_axis(registry[typ]) for typ in set(types)}
    directed = js.has_axis | np.array([defaults[typ] for typ in types], dtype=bool).reshape(nj)
    per_joint = JointTable(tuple(js.names), p, c, readonly(B_r_child), readonly(B_r_parent),
                           readonly(P_E), readonly(C_E), readonly(C_axis2), first, link, p_particle,
                           readonly(length), free_turn, readonly(js.pitch),
                           np.zeros(nj, dtype=bool) if js.body_points is None
                           else np.asarray(js.body_points, dtype=bool), directed)
    if drivers is not None and len(drivers):  # the drivers' efforts: last components
        row_joint = np.concatenate((row_joint, drivers.joint))
        component = np.concatenate((component, [joint_types.COMPONENT_CODE[c]
                                                for c in drivers.component]))
        kind = np.concatenate((kind, drivers.kind))
        frame_axis = np.concatenate((frame_axis, drivers.axis))
    table = ReactionTable(per_joint, row_joint, component, kind, frame_axis,
                          drivers.names if drivers is not None else ())

    fields_ = field_names(Joint)
    axis1 = readonly(js.axis)
    axis2 = readonly(js.axis2)
    jnames, parents, children = js.names, p, c
    has1, has2 = js.has_axis, js.has_axis2

    def make(j: int) -> Joint:
        pj = int(parents[j])
        return record(Joint, fields_, (
            jnames[j], types[j], names[pj] if pj >= 0 else cv.GROUND, names[children[j]],
            at[j], W_E0[j], tuple(comp.name for comp in comps[j]),
            axis1[j] if has1[j] else None,
            axis2[j] if has2[j] else None, kinds[j]))

    return Records(js.names, make, JOINT), table


def _default_axis(typ: joint_types.JointType) -> bool:
    """Whether a joint of type `typ` without an `axis` has one all the same (a planar
    prismatic's or slot's slide direction, world x at the file's pose)."""
    prm = typ.param("axis")
    return prm is not None and prm.default is not None


def frames_at(joints: Sequence[Joint], table: ReactionTable, dimension: int,
              file_pose: State, pose: State, turn_tol: float
              ) -> tuple[Sequence[Joint], ReactionTable]:
    """The joint frames by the contract's rule at `pose` (the pose `mbody.load` assembles
    the model to, `mbody.solve.kinematics.assembled`) rather than at `file_pose`, where
    `joint_tables` took them: `joints` and `table` with those frames (themselves when no
    frame changes).

    A frame is fixed in its parent, so only a joint whose parent turned between the two
    poses (by more than `turn_tol`, rad: the assembly's own resolution, below which the
    file's pose already held the joint) can change:

    - without a direction (no `axis`, no default one), the frame is the world axes at
      `pose`;
    - with one, the direction is fixed in the parent (as the file gives it, world axes at
      the file's pose) and turned with it to `pose`, and the rule is applied there. In
      the plane that is the frame turned with its parent: nothing changes. In space z is
      the turned axis and x is the world axis that the rule chose for the axis as the
      file gives it, with its component along z removed: a small turn in assembly does
      not swap world x for world y when the axis is along a world axis (where the rule's
      choice is a tie) or close to such a tie. Only a turn so large that the turned
      axis is more aligned with that world axis than 1/√3 (the least aligned world
      axis never is) takes the rule's own choice at `pose`.

    The child's frame C_E3 turns with the parent's, ``C_E3 Q`` where ``P_E3 Q`` is the new
    parent frame: the two still coincide at the file's pose, so the relative turn a
    driver or a generalized coordinate measures from there is unchanged (for a joint that
    turns about an axis, Q turns about it too), and the constraints span the same
    motions."""
    jt = table.per_joint
    p = jt.parent
    # the parents' turns from file_pose to pose: 2 |vector part| of the relative
    # quaternion is the angle to within its cube
    turn = 2.0 * np.linalg.norm(
        quat_mul(pose.quaternion, quat_conj(file_pose.quaternion))[:, 1:], axis=1)
    planar = dimension == cv.PLANAR
    moved = (p >= 0) & (turn[np.maximum(p, 0)] > turn_tol) if len(p) else np.zeros(0, bool)
    if planar:  # a direction turned with its parent is the rule's frame there already
        moved &= ~jt.directed
    k = np.flatnonzero(moved)
    if not len(k):
        return joints, table
    P_old = jt.P_E3[k]
    R_p = quat_to_matrix(pose.quaternion[p[k]])
    W = np.tile(np.eye(3), (len(k), 1, 1))  # no direction: the world axes at `pose`
    along = jt.directed[k]
    if along.any():  # spatial, with a direction
        z_file = (quat_to_matrix(file_pose.quaternion[p[k[along]]]) @ P_old[along])[:, :, 2]
        z = (R_p[along] @ P_old[along])[:, :, 2]
        z /= np.linalg.norm(z, axis=1, keepdims=True)
        choice = least_aligned(z_file)
        far = np.abs(z[np.arange(len(z)), choice]) > 1.0 / np.sqrt(3.0) + FRAME_TIE
        choice[far] = least_aligned(z[far])
        W[along] = joint_frames_spatial(z, choice)
    P_new = R_p.transpose(0, 2, 1) @ W
    P_E3, C_E3 = jt.P_E3.copy(), jt.C_E3.copy()
    C_E3[k] = C_E3[k] @ (P_old.transpose(0, 2, 1) @ P_new)
    P_E3[k] = P_new
    new_table = replace(table, per_joint=replace(jt, P_E3=readonly(P_E3),
                                                 C_E3=readonly(C_E3)))
    W_E0 = dict(zip(k.tolist(), W, strict=True))

    def make(j: int) -> Joint:
        old = joints[j]
        return replace(old, W_E0=readonly(W_E0[j])) if j in W_E0 else old

    return Records(jt.names, make, JOINT), new_table


def _frames(axis: np.ndarray, has_axis: np.ndarray, planar: bool) -> np.ndarray:
    """(k, 3, 3) the joint frame of each axis (None where `has_axis` is False), by the
    contract's rule, computed once per distinct axis (the same bits, not the same value:
    -0.0 and 0.0 are two axes)."""
    k = len(axis)
    if k == 0:
        return np.zeros((0, 3, 3))
    bits = np.ascontiguousarray(axis, dtype=float).view(np.int64)
    key = np.concatenate((bits, has_axis[:, None].astype(np.int64)), axis=1)
    if np.all(key == key[0]):  # one axis for all (a chain...)
        first, inverse = np.zeros(1, dtype=np.intp), np.zeros(k, dtype=np.intp)
    else:  # rows sorted, then runs of equal rows (np.unique would import numpy.ma)
        order = np.lexsort(key.T[::-1])
        ordered = key[order]
        new = np.ones(k, dtype=bool)
        new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
        first = order[new]  # a joint with each axis
        inverse = np.empty(k, dtype=np.intp)
        inverse[order] = np.cumsum(new) - 1
    rule = joint_frame_planar if planar else joint_frame_spatial
    frames = np.array([rule(axis[i] if has_axis[i] else None) for i in first.tolist()])
    return frames.reshape(-1, 3, 3)[inverse]
