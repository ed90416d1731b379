"""`Model` (what the file says, as arrays) and `State` (where the bodies are and how fast).

A `Model` is immutable and holds no state: masses ``(n,)``, inertia tensors ``(n, 3, 3)``
in body axes, and the loads and joints as tables of index arrays, so that everything
downstream is vectorised over bodies. Planar bodies are stored as spatial ones in the
world x-y plane (see `conventions`).
"""

from __future__ import annotations

import operator
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from typing import Any, TypeVar, overload

import numpy as np

from mbody import conventions as cv
from mbody.equations.plan import ModelPlan
from mbody.equations.spatial import joint_frame_planar, joint_frame_spatial, quat_to_matrix
from mbody.errors import Issue
from mbody.model.expressions import Expression, ExpressionTable
from mbody.model.fast import fast_spec
from mbody.model.graph import body_graph
from mbody.model.loader import Document, load_text, read_file
from mbody.model.validate import JointSpecTable, LoadSpec, LoadTable, Spec, validate


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=float)
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class State:
    """Positions and velocities of all bodies; every array has a leading body axis.

    Parameters
    ----------
    position : (n, 3) array
        Mass centres, world axes (m).
    quaternion : (n, 4) array
        Body-to-world rotations ``W_R_B`` as unit quaternions, ``[w, x, y, z]``.
    velocity : (n, 3) array
        Mass-centre velocities, world axes (m/s).
    omega : (n, 3) array
        Angular velocities, body axes (rad/s).
    t : float, optional
        Time (s), for loads and known reactions that vary in time.
    """

    position: np.ndarray
    quaternion: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    t: float = 0.0

    @cached_property
    def W_R_B(self) -> np.ndarray:
        """(n, 3, 3) body-to-world rotation matrices."""
        return quat_to_matrix(self.quaternion)

    def replace(self, **changes: Any) -> State:
        """A copy with some fields changed, e.g. ``state.replace(t=1.0)``.

        Parameters
        ----------
        **changes
            Field name -> new value.

        Returns
        -------
        State
        """
        return replace(self, **changes)

    @classmethod
    def planar(cls, position: np.ndarray, angle: np.ndarray, velocity: np.ndarray,
               angular_velocity: np.ndarray, t: float = 0.0) -> State:
        """A planar state: bodies in the world x-y plane, turning about z.

        Parameters
        ----------
        position : (n, 2) array
            Mass centres, world x and y (m).
        angle : (n,) array
            Rotation angles about z (rad).
        velocity : (n, 2) array
            Mass-centre velocities, world x and y (m/s).
        angular_velocity : (n,) array
            θ̇ about z (rad/s).
        t : float, optional
            Time (s).

        Returns
        -------
        State
        """
        n = len(angle)
        pos = np.zeros((n, 3))
        pos[:, :2] = position
        vel = np.zeros((n, 3))
        vel[:, :2] = velocity
        q = np.zeros((n, 4))
        q[:, 0] = np.cos(np.asarray(angle) / 2)
        q[:, 3] = np.sin(np.asarray(angle) / 2)
        om = np.zeros((n, 3))
        om[:, 2] = angular_velocity
        return cls(pos, q, vel, om, t)

    def __repr__(self) -> str:  # the dataclass's would print four (n, k) arrays
        return (f"<State of {count(len(self.position), 'body', 'bodies')} at t = {self.t:g} s; "
                ".position, .quaternion, .velocity, .omega, .replace(t=...)>")


@dataclass(frozen=True)
class Body:
    """One rigid body as given in the file (a read-only view of the model's arrays).

    Parameters
    ----------
    name : str
        As in the file.
    index : int
        Its place in the stacking order (`Model.body_names`).
    mass : float
        kg.
    inertia : (3, 3) array
        About the mass centre, body axes (kg m²); planar: I_G at ``[2, 2]``.
    shape : dict or None
        The drawing shape from the file (``{box: [...]}``...).
    color : str or None
        The drawing colour from the file.
    particle : bool, optional
        A point mass (``inertia: 0``): translation rows only; `inertia` holds a dummy.
    """

    name: str
    index: int
    mass: float  # kg
    inertia: np.ndarray  # (3, 3) body axes about the mass centre, kg m^2 (planar: I_G at [2, 2])
    shape: dict[str, Any] | None
    color: str | None
    particle: bool = False
    """A point mass (`inertia: 0`): translation rows only; `inertia` holds a dummy."""

    @property
    def I_G(self) -> float:
        """Planar moment of inertia about the mass centre (the z-z entry)."""
        return float(self.inertia[2, 2])

    def __repr__(self) -> str:  # the dataclass's would print the inertia tensor
        J = "particle" if self.particle else "I " + _vec(np.diag(self.inertia)) + " kg m^2" + (
            "" if np.count_nonzero(self.inertia - np.diag(np.diag(self.inertia))) == 0
            else " (and products)")
        return f"<Body {self.name!r} (#{self.index}): m {self.mass:g} kg, {J}; .inertia, .shape>"


@dataclass(frozen=True)
class Load:
    """An applied load as given in the file: force, torque or spring.

    Parameters
    ----------
    name : str
        As in the file.
    type : str
        ``force``, ``torque`` or ``spring``.
    bodies : tuple of str
        The body it acts on (a spring: its two ends, ``ground`` allowed).
    vector : (3,) array or None
        Force (N) or torque (N m) components in `frame`; None for a spring.
    frame : str
        ``world`` or ``body``: the axes `vector` is given in.
    at : tuple of (3,) arrays
        Attachment points, body axes from the mass centre (world for ground) (m).
    stiffness, rest_length, damping : float, optional
        A spring's k (N/m), rest length (m) and damping (N s/m).
    expressions : dict, optional
        Components of `vector` that vary in time (index 0-2 -> expression of t);
        `vector` holds their values at t = 0.
    """

    name: str
    type: str
    bodies: tuple[str, ...]
    vector: np.ndarray | None  # force or torque, in `frame`, 3-D
    frame: str
    at: tuple[np.ndarray, ...]  # attachment points: body axes (world for ground)
    stiffness: float = 0.0
    rest_length: float = 0.0
    damping: float = 0.0
    expressions: dict[int, Expression] = field(default_factory=dict)
    """Components of `vector` that vary in time (3-D index -> expression of t);
    `vector` holds their values at t = 0."""

    def __repr__(self) -> str:  # the dataclass's would print its arrays
        on = " - ".join(self.bodies)
        if self.type == "spring":
            what = f"k {self.stiffness:g} N/m, rest {self.rest_length:g} m"
        else:
            unit = "N m" if self.type == "torque" else "N"
            what = f"{_vec(np.zeros(3) if self.vector is None else self.vector)} {unit} " \
                   f"({self.frame} axes)" + (", varies in time" if self.expressions else "")
        return f"<Load {self.name!r}: {self.type} on {on}, {what}>"


@dataclass(frozen=True)
class Joint:
    """A joint: its reaction components and its frame at the initial pose.

    Parameters
    ----------
    name : str
        As in the file; reaction labels are ``<name>.<component>``.
    type : str
        ``revolute``, ``prismatic``, ``spherical``, ``universal``, ``fixed``...
    parent, child : str
        The bodies it joins (``ground`` for the world).
    at : (3,) array
        The joint point at the initial pose, world axes (m).
    W_E0 : (3, 3) array
        The joint frame at the initial pose, axes as columns (world).
    components : tuple of str
        Its reaction components (``Fx``, ``Fy``, ``Mz``...), the columns of G in order.
    axis, axis2 : (3,) array, optional
        The joint's axis (and a universal joint's second axis), where it has one.
    particle_joint : str, optional
        With a particle at an end: ``pin`` or ``link`` (docs "Particles"); else "".
    """

    name: str
    type: str
    parent: str
    child: str
    at: np.ndarray  # (3,) world, initial pose
    W_E0: np.ndarray  # (3, 3) joint frame at the initial pose, axes as columns (world)
    components: tuple[str, ...]
    axis: np.ndarray | None = None
    axis2: np.ndarray | None = None
    particle_joint: str = ""
    """With a particle at an end: "pin" or "link" (see docs "Particles"); else ""."""

    @property
    def labels(self) -> list[str]:
        """Its reaction labels, ``<name>.<component>``."""
        return [f"{self.name}.{k}" for k in self.components]

    def __repr__(self) -> str:  # the dataclass's would print its frame
        return (f"<Joint {self.name!r}: {self.type}, {self.parent} -> {self.child} at "
                f"{_vec(self.at)} m; reactions {', '.join(self.labels)}>")


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
        return _ro(self.per_joint.P_E3[self.joint, :, column].reshape(-1, 3))

    @cached_property
    def B_r_child(self) -> np.ndarray:
        """(m, 3) the joint point on the child, child axes."""
        return _ro(self.per_joint.B_r_child[self.joint])

    @cached_property
    def C_axis2(self) -> np.ndarray:
        """(m, 3) a universal joint's child axis, child axes (else 0)."""
        return _ro(self.per_joint.C_axis2[self.joint])

    @cached_property
    def B_r_parent(self) -> np.ndarray:
        """(m, 3) the joint point on the parent, parent axes (world for ground)."""
        return _ro(self.per_joint.B_r_parent[self.joint])

    @cached_property
    def P_E3(self) -> np.ndarray:
        """(m, 3, 3) the joint frame fixed in the parent."""
        return _ro(self.per_joint.P_E3[self.joint])

    @cached_property
    def C_E3(self) -> np.ndarray:
        """(m, 3, 3) the joint frame fixed in the child."""
        return _ro(self.per_joint.C_E3[self.joint])

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
        return _ro(np.where(self.link, self.per_joint.length[self.joint], 0.0))


_COMPONENT = {**dict(enumerate(cv.COMPONENTS)), 6: "Mt", cv.LINK_AXIS: cv.LINK}
"""Component name of each `ReactionTable.axis` code."""
_AXIS = {name: code for code, name in _COMPONENT.items()}


@dataclass(frozen=True, eq=False)
class Model:
    """A validated multibody model: bodies, applied loads and joints, as arrays.

    Made by `mbody.load`; immutable, and holds no state but the file's `initial` one.

    Parameters
    ----------
    name, file, description : str
        The model's name, the file it came from, its description.
    dimension : int
        2 (planar) or 3 (spatial).
    body_names : tuple of str
        The stacking order (file order).
    mass : (n,) array
        kg.
    J, J_inv : (n, 3, 3) arrays
        Inertia tensors about the mass centres, body axes (kg m²), and their inverses.
    gravity : (3,) array
        World axes (m/s²).
    initial : State
        The state written in the file.
    bodies : mapping of str to Body
        Each body by name, in the stacking order (each record is made on first use).
    loads : sequence of Load
        The applied loads, in file order.
    joints : sequence of Joint
        The joints, in file order (records made on first use).
    forces, springs : ForceTable, SpringTable
        The loads as arrays, for the vectorised sums.
    reaction_table : ReactionTable
        One row per reaction component (a column of G), for the vectorised columns.
    known_reactions : dict of str to float
        Reaction values given in the file (at t = 0).
    warnings : tuple of Issue, optional
        What validation noticed without refusing the file.
    known_expressions : dict, optional
        Known reaction values that vary in time (label -> expression of t).
    """

    name: str
    file: str
    dimension: int
    body_names: tuple[str, ...]
    mass: np.ndarray
    J: np.ndarray
    J_inv: np.ndarray
    gravity: np.ndarray
    initial: State
    bodies: Mapping[str, Body]
    loads: Sequence[Load]
    joints: Sequence[Joint]
    forces: ForceTable
    springs: SpringTable
    reaction_table: ReactionTable
    known_reactions: dict[str, float]
    description: str = ""
    warnings: tuple[Issue, ...] = field(default_factory=tuple)
    known_expressions: dict[str, Expression] = field(default_factory=dict)
    """Known reaction values that vary in time (label -> expression of t)."""

    def __repr__(self) -> str:  # the dataclass's would print every array (2-9 KB)
        kind = "planar" if self.dimension == cv.PLANAR else "spatial"
        bodies = _names(self.body_names)
        return (f"<Model {self.name!r}: {kind}, {count(self.n, 'body', 'bodies')} "
                f"({bodies}), {count(len(self.loads), 'load')}, "
                f"{count(len(self.joints), 'joint')}, "
                f"{count(len(self.reactions), 'reaction component')}; mbody.assemble(model) "
                "for its equations>")

    def known_reactions_at(self, t: float) -> dict[str, float]:
        """The known reaction values at a time.

        Parameters
        ----------
        t : float
            Time (s); `known_reactions` holds t = 0.

        Returns
        -------
        dict of str to float
            Label -> value (N or N m).
        """
        if not self.known_expressions:
            return dict(self.known_reactions)
        return {**self.known_reactions,
                **{k: float(e(t)) for k, e in self.known_expressions.items()}}

    # -- sizes and labels --------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of bodies."""
        return len(self.body_names)

    @property
    def rows_per_body(self) -> int:
        """Rows of a rigid body in the stacked system: 3 planar, 6 spatial."""
        return cv.rows_per_body(self.dimension)

    @cached_property
    def particle(self) -> np.ndarray:
        """(n,) True for the point masses (`inertia: 0`)."""
        if isinstance(self.bodies, BodyRecords):  # without making every record
            return self.bodies.particle.copy()
        return np.array([self.bodies[b].particle for b in self.body_names], dtype=bool)

    @cached_property
    def has_particles(self) -> bool:
        """Whether any body is a point mass (translation rows only)."""
        return bool(self.particle.any())

    @cached_property
    def all_coordinates(self) -> list[str]:
        """The solver's uniform rows: `rows_per_body` per body, particles included."""
        return cv.coordinate_labels(list(self.body_names), self.dimension)

    @cached_property
    def rows(self) -> np.ndarray:
        """Indices into `all_coordinates` of the rows shown (`coordinates`): a particle's
        rotation rows are dropped (they carry nothing: its ω stays 0)."""
        rpb = self.rows_per_body
        keep = np.ones((self.n, rpb), dtype=bool)
        keep[self.particle, cv.rows_per_body(self.dimension) - (1 if self.dimension
                                                                   == cv.PLANAR else 3):] = False
        return np.flatnonzero(keep.reshape(-1))

    @cached_property
    def coordinates(self) -> list[str]:
        """Row labels of the stacked equations (a particle has translation rows only)."""
        if not self.has_particles:
            return self.all_coordinates
        full = self.all_coordinates
        return [full[i] for i in self.rows]

    def body_rows(self, i: int) -> np.ndarray:
        """Where one body's equations are in the stacked system.

        Parameters
        ----------
        i : int
            The body's index (`Model.index`).

        Returns
        -------
        (k,) int array
            Indices into `coordinates` of its rows (3 planar, 6 spatial, fewer for a
            particle).
        """
        if not self.has_particles:
            rpb = self.rows_per_body
            return np.arange(i * rpb, (i + 1) * rpb)
        rpb = self.rows_per_body
        return np.flatnonzero((self.rows >= i * rpb) & (self.rows < (i + 1) * rpb))

    @cached_property
    def reactions(self) -> list[str]:
        """Reaction labels, the column order of G (do not modify the list)."""
        return list(self.reaction_table.labels)

    @cached_property
    def minv6(self) -> np.ndarray | None:
        """(n, 6) diagonal of M⁻¹ per body [1/m ×3, 1/J11, 1/J22, 1/J33] when every
        inertia tensor is diagonal in body axes (principal axes given); else None."""
        off = self.J - np.einsum("nii->ni", self.J)[:, :, None] * np.eye(3)
        if np.any(off):
            return None
        out = np.empty((self.n, 6))
        out[:, :3] = 1.0 / self.mass[:, None]
        out[:, 3:] = 1.0 / np.einsum("nii->ni", self.J)
        return out

    @cached_property
    def joint_table(self) -> JointTable:
        """One row per joint: what its reaction components share (`JointTable`)."""
        return self.reaction_table.per_joint

    @cached_property
    def reaction_index(self) -> dict[str, int]:
        """reaction label -> column of G."""
        return {r: i for i, r in enumerate(self.reaction_table.labels)}

    @cached_property
    def index(self) -> dict[str, int]:
        """Body name -> its index in the stacking order."""
        return {n: i for i, n in enumerate(self.body_names)}

    @cached_property
    def plan(self):  # -> mbody.plan.ModelPlan: what every evaluation needs, made once
        """The model's evaluation plan (`mbody.plan.ModelPlan`), made on first use."""

        return ModelPlan(self)

    @cached_property
    def graph(self):  # -> networkx.MultiGraph; imported lazily, it is slow to import
        """The body/joint graph: bodies and ``ground`` as nodes, joints as edges."""

        return body_graph(self)

    @classmethod
    def from_spec(cls, spec: Spec) -> Model:
        """Build the arrays from a validated specification (what `load` does last).

        Parameters
        ----------
        spec : Spec
            The output of `mbody.model.validate.validate`.

        Returns
        -------
        Model
        """
        return _build(spec)

    def _repr_html_(self) -> str:  # notebook display: summary tables and the graph
        from mbody.present.rich import model_html  # a display hook (tools/check_imports.py)

        return model_html(self)


def load(source: str | os.PathLike[str] | dict, *, max_bytes: int | None = None,
         format: str | None = None, **options: Any) -> Model:
    """Read, validate and build a model.

    Parameters
    ----------
    source : str, os.PathLike or dict
        A path to a model file: YAML, MJCF (``.xml``) or URDF (``.urdf``); or a dict
        with a YAML file's content (for scripts).
    max_bytes : int, optional
        The largest file read (default `mbody.model.loader.MAX_BYTES`, 32 MiB, or the
        command line's ``--max-bytes``); a larger file is refused before it is read.
        Raise it for very large models (a 100 000-body file is about 80 MB).
    format : {"yaml", "mjcf", "urdf"}, optional
        The file's format, when its extension does not say it.
    **options
        The state of an imported model: ``keyframe="name"`` (MJCF; default its
        reference pose at rest), ``joint_positions={...}``, ``joint_velocities={...}``
        and ``floating_base=True`` (URDF; default every joint at 0, the root fixed).
        See `mbody.io.interop.read_document`.

    Returns
    -------
    Model

    Raises
    ------
    mbody.ModelError
        Listing every problem, each with its file, line and column.
    """
    if isinstance(source, dict):
        return Model.from_spec(validate(Document(source, "<dict>")))
    if format or options or str(source).lower().endswith((".xml", ".mjcf", ".urdf")):
        from mbody.io.interop import import_spec  # MJCF, URDF: defusedxml, only for them

        spec = import_spec(source, format, max_bytes=max_bytes, **options)
        if spec is not None:
            return Model.from_spec(spec)
    text = read_file(source, max_bytes)
    spec = fast_spec(text, str(source)) or validate(load_text(text, str(source)))
    del text  # before the arrays are built: the text is the largest thing held
    return Model.from_spec(spec)


def loads(text: str, file: str = "<string>") -> Model:
    """Like `load`, from YAML text.

    Parameters
    ----------
    text : str
        The model file's content.
    file : str, optional
        The name used in error messages.

    Returns
    -------
    Model

    Notes
    -----
    A large, regular file (block YAML as ``yaml.dump`` writes it) is read and checked in
    bulk (`mbody.model.fast`); anything that path does not handle, and every file with a
    problem, goes through the located path, which reports each problem where it is.
    """
    spec = fast_spec(text, file)
    if spec is None:
        spec = validate(load_text(text, file))
    return Model.from_spec(spec)


def _build(spec: Spec) -> Model:
    t = spec.table()
    n = len(t.names)
    names = t.names
    # name -> index, for the located path's records (the fast path's tables hold indices)
    idx = {nm: i for i, nm in enumerate(names)} if spec.loads or spec.joints else {}
    mass = _ro(t.mass)
    J = _ro(t.inertia.reshape(n, 3, 3))
    J_inv = np.linalg.inv(J)
    initial = State(_ro(t.position.reshape(n, 3)), _ro(t.quaternion.reshape(n, 4)),
                    _ro(t.velocity.reshape(n, 3)), _ro(t.omega.reshape(n, 3)))
    bodies = BodyRecords(names, mass, J, t.shape, t.color, t.particle)

    loads: Sequence[Load]
    if spec.load_table is not None:
        loads, forces = _point_loads(spec.load_table, names)
    else:
        loads, forces = _loads(spec.loads, idx)
    sp = [ld for ld in spec.loads if ld.type == "spring"]
    springs = SpringTable(
        tuple(ld.name for ld in sp),
        np.array([idx.get(ld.bodies[0], -1) for ld in sp], dtype=np.intp),
        np.array([idx.get(ld.bodies[1], -1) for ld in sp], dtype=np.intp),
        _ro(np.array([ld.at[0] for ld in sp]).reshape(-1, 3)),
        _ro(np.array([ld.at[1] for ld in sp]).reshape(-1, 3)),
        _ro(np.array([ld.stiffness for ld in sp], dtype=float)),
        _ro(np.array([ld.rest_length for ld in sp], dtype=float)),
        _ro(np.array([ld.damping for ld in sp], dtype=float)),
    )

    js = spec.joint_table
    if js is None:
        js = JointSpecTable.from_specs(spec.joints, idx)
    joints, table = _joint_tables(spec.dimension, js, names, initial, t.particle)
    return Model(spec.name, spec.file, spec.dimension, names, mass, J, _ro(J_inv),
                 _ro(spec.gravity), initial, bodies, loads, joints, forces, springs,
                 table, dict(spec.reactions), spec.description, tuple(spec.warnings),
                 dict(spec.reaction_expressions))


def _loads(specs: list[LoadSpec], idx: dict[str, int]) -> tuple[tuple[Load, ...], ForceTable]:
    """The loads of the located path, and the force table of its point loads."""
    loads = tuple(Load(ld.name, ld.type, ld.bodies, ld.vector, ld.frame, ld.at,
                       ld.stiffness, ld.rest_length, ld.damping, dict(ld.expressions))
                  for ld in specs)
    point = [ld for ld in specs if ld.type in ("force", "torque")]
    forces = ForceTable(
        tuple(ld.name for ld in point),
        np.array([idx[ld.bodies[0]] for ld in point], dtype=np.intp),
        _ro(np.array([ld.vector for ld in point]).reshape(-1, 3)),
        np.array([ld.frame == "body" for ld in point], dtype=bool),
        _ro(np.array([ld.at[0] for ld in point]).reshape(-1, 3)),
        np.array([ld.type == "torque" for ld in point], dtype=bool),
        ExpressionTable.build([(row, k, e) for row, ld in enumerate(point)
                               for k, e in ld.expressions.items()]),
    )
    return loads, forces


def _point_loads(t: LoadTable, names: tuple[str, ...]) -> tuple[Records[Load], ForceTable]:
    """The fast path's loads (force and torque, constant): their force table, and their
    records, made on first use from it."""
    vector, at = _ro(t.vector), _ro(t.at)
    body = np.asarray(t.body, dtype=np.intp)
    forces = ForceTable(tuple(t.names), body, vector,
                        np.array([f == "body" for f in t.frames], dtype=bool), at,
                        np.array([typ == "torque" for typ in t.types], dtype=bool),
                        ExpressionTable.build([]))
    fields_ = _field_names(Load)
    load_names, types, frames = forces.names, t.types, t.frames

    def make(i: int) -> Load:
        return _record(Load, fields_, (load_names[i], types[i], (names[body[i]],), vector[i],
                                       frames[i], (at[i],), 0.0, 0.0, 0.0, {}))

    return Records(len(load_names), make), forces


_FREE_TURN = ("revolute", "cylindrical")
"""Joint types whose moment components measure the tilt of the joint z axis."""


def _joint_tables(dimension: int, js: JointSpecTable, names: tuple[str, ...],
                  initial: State, particle: np.ndarray
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
    W_E0 = _ro(_frames(js.axis, js.has_axis, planar))
    at = _ro(js.at)
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
    by_type = cv.JOINT_COMPONENTS[dimension]
    comps = ([by_type[typ] for typ in types] if not any(kinds) else
             [cv.PARTICLE_COMPONENTS[dimension][typ][k] if k else by_type[typ]
              for typ, k in zip(types, kinds, strict=True)])
    # the distinct component lists (a few), and each joint's
    distinct: dict[tuple[str, ...], int] = {}
    code = np.fromiter((distinct.setdefault(cs, len(distinct)) for cs in comps),
                       dtype=np.intp, count=nj)
    axes = np.zeros((max(len(distinct), 1), 7), dtype=np.intp)
    sizes = np.zeros(len(axes), dtype=np.intp)
    for cs, k in distinct.items():
        axes[k, :len(cs)] = [_AXIS[comp] for comp in cs]
        sizes[k] = len(cs)
    counts = sizes[code]
    first = np.cumsum(counts) - counts
    row_joint = np.repeat(np.arange(nj, dtype=np.intp), counts)
    axis = axes[code[row_joint], np.arange(len(row_joint)) - first[row_joint]]
    free_turn = np.array([typ in _FREE_TURN for typ in types], dtype=bool)
    per_joint = JointTable(tuple(js.names), p, c, _ro(B_r_child), _ro(B_r_parent),
                           _ro(P_E), _ro(C_E), _ro(C_axis2), first, link, p_particle,
                           _ro(length), free_turn)
    table = ReactionTable(per_joint, row_joint, axis)

    fields_ = _field_names(Joint)
    axis1 = _ro(js.axis)
    axis2 = _ro(js.axis2)
    jnames, parents, children = js.names, p, c
    has1, has2 = js.has_axis, js.has_axis2

    def make(j: int) -> Joint:
        pj = int(parents[j])
        return _record(Joint, fields_, (
            jnames[j], types[j], names[pj] if pj >= 0 else cv.GROUND, names[children[j]],
            at[j], W_E0[j], comps[j], axis1[j] if has1[j] else None,
            axis2[j] if has2[j] else None, kinds[j]))

    return Records(nj, make), table


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


def _field_names(cls: type) -> list[str]:
    return [f.name for f in fields(cls)]


def _record(cls: type, names: list[str], row: tuple[Any, ...]) -> Any:
    """An instance of the frozen dataclass `cls` from a tuple of all its fields.

    A frozen dataclass's ``__init__`` sets each field through ``object.__setattr__``;
    filling the instance's ``__dict__`` at once is about 4x faster (the class must take
    every field from the tuple: no ``__post_init__``, no slots).
    """
    obj: Any = object.__new__(cls)
    obj.__dict__.update(zip(names, row, strict=True))
    return obj


T = TypeVar("T")


class Records(Sequence[T]):
    """A read-only sequence of records, each made on first use and then kept.

    A large model's file is read without making a record per load or joint (a few
    hundred bytes and about a microsecond each); the arrays they view are the model's.

    Parameters
    ----------
    n : int
        How many records.
    make : callable
        Index -> its record.
    """

    __slots__ = ("_n", "_make", "_made")

    def __init__(self, n: int, make: Callable[[int], T]):
        self._n = n
        self._make = make
        self._made: list[T | None] = [None] * n

    def __len__(self) -> int:
        return self._n

    @overload
    def __getitem__(self, i: int) -> T: ...

    @overload
    def __getitem__(self, i: slice) -> tuple[T, ...]: ...

    def __getitem__(self, i: int | slice) -> T | tuple[T, ...]:
        if isinstance(i, slice):
            return tuple(self[k] for k in range(*i.indices(self._n)))
        k = operator.index(i)
        if k < 0:
            k += self._n
        if not 0 <= k < self._n:
            raise IndexError(f"record index {i} out of range ({self._n} records)")
        made = self._made[k]
        if made is None:
            made = self._made[k] = self._make(k)
        return made

    def __iter__(self) -> Iterator[T]:
        for k in range(self._n):
            yield self[k]

    def __repr__(self) -> str:
        return f"<{self._n} records; made so far: {self._n - self._made.count(None)}>"


class BodyRecords(Mapping[str, Body]):
    """Each body's `Body` record by name, in the stacking order, made on first use.

    Parameters
    ----------
    names : tuple of str
        The stacking order.
    mass : (n,) array
    inertia : (n, 3, 3) array
        Read-only: each record's ``inertia`` is a view of its row.
    shape, color : list
        Per body, or None.
    particle : (n,) bool array
        The point masses.
    """

    __slots__ = ("_names", "_mass", "_inertia", "_shape", "_color", "particle", "_index",
                 "_records")

    def __init__(self, names: tuple[str, ...], mass: np.ndarray, inertia: np.ndarray,
                 shape: list[dict[str, Any] | None], color: list[str | None],
                 particle: np.ndarray):
        self._names = names
        self._mass = mass
        self._inertia = inertia
        self._shape = shape
        self._color = color
        self.particle = particle
        self._index: dict[str, int] | None = None
        fields_ = _field_names(Body)

        def make(i: int) -> Body:
            return _record(Body, fields_, (names[i], i, float(mass[i]), inertia[i], shape[i],
                                           color[i], bool(particle[i])))

        self._records = Records(len(names), make)

    def _where(self, name: object) -> int | None:
        if self._index is None:
            self._index = {nm: i for i, nm in enumerate(self._names)}
        return self._index.get(name) if isinstance(name, str) else None

    def __getitem__(self, name: str) -> Body:
        i = self._where(name)
        if i is None:
            raise KeyError(name)
        return self._records[i]

    def __contains__(self, name: object) -> bool:
        return self._where(name) is not None

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)

    def __repr__(self) -> str:
        return f"<{count(len(self._names), 'body', 'bodies')}: {_names(self._names)}>"


def _names(names, most: int = 5) -> str:
    """The first `most` names, and how many more (for short reprs)."""
    names = list(names)
    more = len(names) - most
    return ", ".join(names[:most]) + (f", … {more} more" if more > 0 else "")


def count(k: int, word: str, plural: str = "") -> str:
    """'1 body', '3 bodies' (for short reprs)."""
    return f"{k} {word if k == 1 else plural or word + 's'}"


def _vec(x: np.ndarray) -> str:
    """'(1, 0, 2.5)' (for short reprs)."""
    return "(" + ", ".join(f"{0.0 if abs(v) < 1e-12 else v:.4g}" for v in x) + ")"
