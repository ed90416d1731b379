"""The model's loads and joints as array tables, one row per load, joint or reaction component.

`ForceTable` (point forces and couples), `SpringTable` (spring-dampers), `JointTable` (one row
per joint) and `ReactionTable` (one row per column of G, the rest derived from its
`JointTable` on first use): what the vectorised sums and columns downstream read.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from mbody import conventions as cv
from mbody import joint_types as jt
from mbody.joint_types import base as jb
from mbody.model.expressions import ExpressionTable


def readonly(a: np.ndarray) -> np.ndarray:
    """A contiguous float copy of `a` (or `a` itself) that cannot be written to."""
    a = np.ascontiguousarray(a, dtype=float)
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class ForceTable:
    """Point forces and couples, one row per load (vectorised application).

    body: (k,) body index; vector: (k, 3) force or torque components in its frame;
    in_body: (k,) True when the components are in body axes; B_r: (k, 3) point of
    application from the mass centre, body axes; couple: (k,) True for torques.
    """

    names: tuple[str, ...]
    body: np.ndarray
    vector: np.ndarray
    in_body: np.ndarray
    B_r: np.ndarray
    couple: np.ndarray
    varying: ExpressionTable | None = None
    """Entries of `vector` given as expressions of t (None: every load is constant)."""

    def vector_at(self, t: float | np.ndarray) -> np.ndarray:
        """(k, 3) load components at time `t` (constant loads: `vector` itself).

        An array of times of shape S gives S + (k, 3); each distinct expression is
        evaluated once per call, with numpy.
        """
        if self.varying is None:
            if isinstance(t, float | int) or np.ndim(t) == 0:
                return self.vector
            return np.broadcast_to(self.vector, (*np.shape(t), *self.vector.shape))
        return self.varying.apply(self.vector, t)

    def __repr__(self) -> str:  # the dataclass's would print every array
        varying = "" if self.varying is None else ", some varying in t"
        return (f"<ForceTable: {len(self.names)} point forces and couples{varying}; "
                f".vector_at(t), .body, .B_r>")


@dataclass(frozen=True)
class SpringTable:
    """Linear spring-dampers; index -1 is ground (its point is then in world axes).

    a, b: (k,) end bodies; r_a, r_b: (k, 3) attachment points (body axes, world for
    ground); stiffness, rest_length, damping: (k,).
    """

    names: tuple[str, ...]
    a: np.ndarray
    b: np.ndarray
    r_a: np.ndarray
    r_b: np.ndarray
    stiffness: np.ndarray
    rest_length: np.ndarray
    damping: np.ndarray

    def __repr__(self) -> str:  # the dataclass's would print every array
        return f"<SpringTable: {len(self.names)} spring-dampers; .a, .b, .stiffness>"


@dataclass(frozen=True, eq=False)
class JointTable:
    """One row per joint (J of them), in file order: what every reaction component of
    a joint shares.

    names: (J,) joint names; parent, child: (J,) body index (-1 = ground); B_r_child,
    B_r_parent: (J, 3) the joint point in each body's axes (world for ground); P_E3, C_E3:
    (J, 3, 3) the joint frame fixed in the parent and in the child (the contract's rule at
    the initial pose: the assembled one when `mbody.load` assembled the model,
    `mbody.model.build.frames_at`); C_axis2: (J, 3) a
    universal joint's child axis (else 0). first: (J,) the joint's first column of G (its
    components are consecutive). link: (J,) a particle link (its first component is T);
    particle_parent: (J,) the parent is a particle; length: (J,) the link's length (0
    otherwise); free_turn: (J,) the joint turns freely about its z axis (revolute,
    cylindrical, helical); pitch: (J,) a helical joint's advance per turn (m; else 0).
    """

    names: tuple[str, ...]
    parent: np.ndarray
    child: np.ndarray
    B_r_child: np.ndarray
    B_r_parent: np.ndarray
    P_E3: np.ndarray
    C_E3: np.ndarray
    C_axis2: np.ndarray
    first: np.ndarray
    link: np.ndarray
    particle_parent: np.ndarray
    length: np.ndarray
    free_turn: np.ndarray
    pitch: np.ndarray
    body_points: np.ndarray
    """(J,) the file gives the joint's point on each body (not one world point)."""
    directed: np.ndarray
    """(J,) the frame follows a direction fixed in the parent: the file's `axis`, or its
    type's default one (a planar prismatic's or slot's slide direction); else the frame
    is the world axes at the initial pose (then fixed in the parent)."""

    def __repr__(self) -> str:  # the dataclass's would print every array
        return (f"<JointTable: {len(self.names)} joints ({', '.join(self.names[:4])}"
                f"{', ...' if len(self.names) > 4 else ''}); .parent, .child, .P_E3, .first>")


@dataclass(frozen=True, eq=False)
class ReactionTable:
    """One row per reaction unknown (column of G), in label order.

    Stored: `per_joint`, the `JointTable`; joint: (m,) joint index; component: (m,) the
    component's name as an index into `mbody.joint_types.COMPONENT_NAMES`; kind: (m,) the
    compiled core's constraint primitive that writes its column (`mbody.joint_types.base`,
    kernel.h's ``MB_KIND_*``); frame_axis: (m,) the joint-frame axis (0-2) it acts along
    or about. Everything else is derived from these on first use (a large model's file is
    read without building them):

    labels: ``<joint>.<component>``; parent, child: (m,) body index (-1 = ground);
    P_E: (m, 3) the column's joint axis fixed in the parent (body axes; world for ground);
    B_r_child: (m, 3) the joint point on the child, child body axes;
    C_axis2: (m, 3) a universal joint's child axis, child body axes (else 0).
    B_r_parent: (m, 3) the joint point on the parent, parent body axes (world for ground).
    P_E3, C_E3: (m, 3, 3) the whole joint frame fixed in the parent and in the child
    (they coincide at the file's pose); used for position-level constraint errors.
    is_moment: (m,) the value is a moment (N m). link: (m,) True for a particle link's
    tension T: the force along the line from the child's attachment point to the
    parent's, constraint |P_c − P_p| = L. particle_parent: (m,) True when the parent is a
    particle (its moment rows stay 0). length: (m,) the link's length L (0 for other
    components). axis, rot_kind: the older numeric code of each component (0-2 force
    along axis k, 3-5 moment about axis k-3, 6 the universal joint's moment, -1 a link's
    tension; rot_kind 1 tilt of a free turn, 2 locked rotation, 3 universal, 0 forces).
    """

    per_joint: JointTable
    joint: np.ndarray
    component: np.ndarray
    kind: np.ndarray
    frame_axis: np.ndarray
    driver_names: tuple[str, ...] = ()
    """The drivers whose efforts are the last len(driver_names) components (labelled
    ``<driver>.M`` or ``.F``; their `joint` is the joint they drive)."""

    DERIVED = ("labels", "parent", "child", "P_E", "B_r_child", "C_axis2", "B_r_parent",
               "P_E3", "C_E3", "is_moment", "axis", "rot_kind", "link", "particle_parent",
               "length")
    """The per-component fields made from `per_joint` on first use."""

    def __repr__(self) -> str:  # the dataclass's would print every array
        return (f"<ReactionTable: {len(self.joint)} reaction components of "
                f"{len(self.per_joint.names)} joints; .labels, .joint, .kind, .per_joint>")

    @cached_property
    def labels(self) -> tuple[str, ...]:
        """``<joint>.<component>`` per column of G."""
        names, comp = self.per_joint.names, jt.COMPONENT_NAMES
        k = len(self.joint) - len(self.driver_names)
        owner = [names[j] for j in self.joint[:k].tolist()] + list(self.driver_names)
        return tuple(f"{o}.{comp[c]}"
                     for o, c in zip(owner, self.component.tolist(), strict=True))

    @cached_property
    def parent(self) -> np.ndarray:
        """(m,) the parent body's index (-1 = ground)."""
        return self.per_joint.parent[self.joint]

    @cached_property
    def child(self) -> np.ndarray:
        """(m,) the child body's index."""
        return self.per_joint.child[self.joint]

    @cached_property
    def P_E(self) -> np.ndarray:
        """(m, 3) the column's joint axis fixed in the parent."""
        return readonly(self.per_joint.P_E3[self.joint, :, self.frame_axis].reshape(-1, 3))

    @cached_property
    def B_r_child(self) -> np.ndarray:
        """(m, 3) the joint point on the child, child axes."""
        return readonly(self.per_joint.B_r_child[self.joint])

    @cached_property
    def C_axis2(self) -> np.ndarray:
        """(m, 3) a universal joint's child axis, child axes (else 0)."""
        return readonly(self.per_joint.C_axis2[self.joint])

    @cached_property
    def B_r_parent(self) -> np.ndarray:
        """(m, 3) the joint point on the parent, parent axes (world for ground)."""
        return readonly(self.per_joint.B_r_parent[self.joint])

    @cached_property
    def P_E3(self) -> np.ndarray:
        """(m, 3, 3) the joint frame fixed in the parent."""
        return readonly(self.per_joint.P_E3[self.joint])

    @cached_property
    def C_E3(self) -> np.ndarray:
        """(m, 3, 3) the joint frame fixed in the child."""
        return readonly(self.per_joint.C_E3[self.joint])

    @cached_property
    def is_moment(self) -> np.ndarray:
        """(m,) the component's value is a moment (N m)."""
        return _MOMENT_CODE[self.component]

    @cached_property
    def axis(self) -> np.ndarray:
        """(m,) the older numeric code of each component (class docstring)."""
        k = self.kind
        return np.where(k == jb.FORCE_ALONG, self.frame_axis,
                        np.where(k == jb.RIGHT_ANGLE, 6,
                                 np.where(k == jb.LINK, cv.LINK_AXIS,
                                          3 + self.frame_axis))).astype(np.intp)

    @cached_property
    def rot_kind(self) -> np.ndarray:
        """(m,) 0 force, 1 tilt of a free turn, 2 locked rotation, 3 universal."""
        k = self.kind
        return np.where(k == jb.TILT, 1, np.where(
            (k == jb.LOCK) | (k == jb.TURN), 2, np.where(k == jb.RIGHT_ANGLE, 3, 0))
        ).astype(np.intp)

    @cached_property
    def link(self) -> np.ndarray:
        """(m,) a particle link's tension T."""
        return self.kind == jb.LINK

    @cached_property
    def particle_parent(self) -> np.ndarray:
        """(m,) the parent is a particle."""
        return self.per_joint.particle_parent[self.joint]

    @cached_property
    def length(self) -> np.ndarray:
        """(m,) a link's length (0 for other components)."""
        return readonly(np.where(self.link, self.per_joint.length[self.joint], 0.0))


_MOMENT_CODE = np.array([jt.WHATS[c] == jt.MOMENT for c in jt.COMPONENT_NAMES], dtype=bool)
"""Per `mbody.joint_types.COMPONENT_NAMES` entry: a moment."""
