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
    (J, 3, 3) the joint frame fixed in the parent and in the child; C_axis2: (J, 3) a
    universal joint's child axis (else 0). first: (J,) the joint's first column of G (its
    components are consecutive). link: (J,) a particle link (its first component is T);
    particle_parent: (J,) the parent is a particle; length: (J,) the link's length (0
    otherwise); free_turn: (J,) the joint turns freely about its z axis (revolute,
    cylindrical).
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

    def __repr__(self) -> str:  # the dataclass's would print every array
        return (f"<JointTable: {len(self.names)} joints ({', '.join(self.names[:4])}"
                f"{', ...' if len(self.names) > 4 else ''}); .parent, .child, .P_E3, .first>")


@dataclass(frozen=True, eq=False)
class ReactionTable:
    """One row per reaction unknown (column of G), in label order.

    Stored: `per_joint`, the `JointTable`; joint: (m,) joint index; axis: (m,) 0-2 force
    along joint axis k, 3-5 moment about joint axis k-3, 6 the universal joint's moment
    about axis × axis2, -1 a particle link's tension T. Everything else is derived from
    these on first use (a large model's file is read without building them):

    labels: ``<joint>.<component>``; parent, child: (m,) body index (-1 = ground);
    P_E: (m, 3) the column's joint axis fixed in the parent (body axes; world for ground);
    B_r_child: (m, 3) the joint point on the child, child body axes;
    C_axis2: (m, 3) a universal joint's child axis, child body axes (else 0).
    B_r_parent: (m, 3) the joint point on the parent, parent body axes (world for ground).
    P_E3, C_E3: (m, 3, 3) the whole joint frame fixed in the parent and in the child
    (they coincide at the initial pose); used for position-level constraint errors.
    rot_kind: (m,) for moment components: 1 = about an axis ⟂ a free rotation (revolute,
    cylindrical: measured by the tilt of the joint z axis), 2 = all rotation locked
    (fixed, prismatic: small rotation vector), 3 = universal; 0 for forces.
    link: (m,) True for a particle link's tension T (axis −1): the force along the line
    from the child's attachment point to the parent's, constraint |P_c − P_p| = L.
    particle_parent: (m,) True when the parent is a particle (its moment rows stay 0).
    length: (m,) the link's length L (0 for other components).
    """

    per_joint: JointTable
    joint: np.ndarray
    axis: np.ndarray

    DERIVED = ("labels", "parent", "child", "P_E", "B_r_child", "C_axis2", "B_r_parent",
               "P_E3", "C_E3", "rot_kind", "link", "particle_parent", "length")
    """The per-component fields made from `per_joint` on first use."""

    def __repr__(self) -> str:  # the dataclass's would print every array
        return (f"<ReactionTable: {len(self.joint)} reaction components of "
                f"{len(self.per_joint.names)} joints; .labels, .joint, .axis, .per_joint>")

    @cached_property
    def labels(self) -> tuple[str, ...]:
        """``<joint>.<component>`` per column of G."""
        names = self.per_joint.names
        return tuple(f"{names[j]}.{_COMPONENT[a]}"
                     for j, a in zip(self.joint.tolist(), self.axis.tolist(), strict=True))

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
        column = np.where(self.axis == 6, 2, self.axis % 3)  # Mt's column stores axis z
        return readonly(self.per_joint.P_E3[self.joint, :, column].reshape(-1, 3))

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
    def rot_kind(self) -> np.ndarray:
        """(m,) 0 force, 1 tilt of a free turn, 2 locked rotation, 3 universal."""
        a = self.axis
        free = self.per_joint.free_turn[self.joint]
        return np.where(a < 3, 0, np.where(a == 6, 3, np.where(free, 1, 2))).astype(np.intp)

    @cached_property
    def link(self) -> np.ndarray:
        """(m,) a particle link's tension T."""
        return self.axis == cv.LINK_AXIS

    @cached_property
    def particle_parent(self) -> np.ndarray:
        """(m,) the parent is a particle."""
        return self.per_joint.particle_parent[self.joint]

    @cached_property
    def length(self) -> np.ndarray:
        """(m,) a link's length (0 for other components)."""
        return readonly(np.where(self.link, self.per_joint.length[self.joint], 0.0))


_COMPONENT = {**dict(enumerate(cv.COMPONENTS)), 6: "Mt", cv.LINK_AXIS: cv.LINK}
"""Component name of each `ReactionTable.axis` code."""
AXIS_CODE = {name: code for code, name in _COMPONENT.items()}
