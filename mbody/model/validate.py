"""Every rule of the model-file contract, checked at the boundary.

`validate(doc)` walks the loaded document once, collects every problem as an `Issue`
with the file, line and column of the offending key or value, and raises one
`ModelError` listing them all. On success it returns a `Spec`: the file's content
normalised (defaults filled in, angles in radians, planar vectors padded to 3-D) and
ready for `Model` to turn into arrays. Hot paths downstream carry no checks.

The checking primitives (one value: its type, range, length, name, with a did-you-mean)
are `mbody.model.checks.Checker`'s; this module holds the contract's rules built from
them: the top level, bodies, loads, joints, known reactions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody import joint_types
from mbody.errors import Issue, ModelError, did_you_mean
from mbody.model.checks import (
    _TOL,
    MIN_MAGNITUDE,
    MIN_NORM,
    PERPENDICULAR_TOL,
    UNIT_TOL,
    Checker,
    _kind,
    _quoted,
    _show,
    asymmetry,
    quat_norm,
    realisable,
    vec_norm,
)
from mbody.model.drivers import DriverSpec, read_drivers
from mbody.model.expressions import (
    CHECK_SPAN,
    Expression,
    ExpressionError,
    check_finite,
    compile_expression,
    first_nonfinite,
)
from mbody.model.loader import Document, Path_, Unrepresentable
from mbody.util import colours
from mbody.util.spatial import euler_to_quat, matrix_to_quat, quat_to_matrix, shape_inertia

TOP_KEYS = ("model", "dimension", "gravity", "bodies", "loads", "joints", "reactions",
            "drivers", "description")
BODY_KEYS = ("name", "mass", "inertia", "position", "orientation", "angle", "velocity",
             "angular_velocity", "shape", "color")
LOAD_KEYS = {
    "force": ("name", "type", "body", "force", "at", "frame"),
    "torque": ("name", "type", "body", "torque", "frame"),
    "spring": ("name", "type", "bodies", "at", "stiffness", "rest_length", "damping"),
}
PARAM_KEYS = tuple(dict.fromkeys(p.name for types in joint_types.TYPES.values()
                                 for t in types.values() for p in t.params))
"""Every joint type's own keys (axis, axis2, pitch...: mbody.joint_types)."""
JOINT_KEYS = ("name", "type", "parent", "child", "at", *PARAM_KEYS)
ORIENTATION_KEYS = ("quaternion", "euler", "sequence", "matrix")
SHAPES = {
    cv.PLANAR: ("box", "disc", "ellipsoid", "sphere", "cylinder"),
    cv.SPATIAL: ("box", "cylinder", "sphere", "ellipsoid", "disc"),
}
FRAMES = ("world", "body")
DEFAULT_EULER_SEQUENCE = "ZYX"
"""Intrinsic z-y'-x'' (yaw, pitch, roll), scipy's upper-case convention."""


@dataclass
class BodySpec:
    name: str
    mass: float
    inertia: np.ndarray  # (3, 3) body axes about the mass centre
    position: np.ndarray  # (3,) world
    quaternion: np.ndarray  # (4,) w first, body to world
    velocity: np.ndarray  # (3,) world
    omega: np.ndarray  # (3,) body axes
    shape: dict[str, Any] | None
    color: str | None
    line: int
    particle: bool = False
    """`inertia: 0`: a point mass (translation only; see docs "Particles")."""


@dataclass
class LoadSpec:
    name: str
    type: str
    bodies: tuple[str, ...]
    vector: np.ndarray | None = None  # force or torque, 3-D
    frame: str = "world"
    at: tuple[np.ndarray, ...] = ()  # body axes (world for ground), 3-D
    stiffness: float = 0.0
    rest_length: float = 0.0
    damping: float = 0.0
    line: int = 0
    expressions: dict[int, Expression] = field(default_factory=dict)
    """Time-varying components of `vector`: component index -> expression of t."""


@dataclass
class JointSpec:
    name: str
    type: str
    parent: str
    child: str
    at: np.ndarray  # (3,) world, initial pose
    axis: np.ndarray | None
    axis2: np.ndarray | None
    line: int = 0
    particle_joint: str = ""
    """With a particle at an end: "pin" (the joint point is at the particle(s)) or "link"
    (a massless rigid link from the joint point to the particle); "" otherwise."""
    pitch: float = 0.0
    """A helical joint's advance per turn along its axis (m; positive: right-handed)."""
    body_points: tuple[np.ndarray, np.ndarray] | None = None
    """The joint's point on each body, when the file gives them (``at: [[parent point],
    [child point]]``): the parent's in its axes from its mass centre (world for ground),
    the child's in its axes; `at` is then the child's point at the file's pose."""


@dataclass
class BodyTable:
    """Every body as arrays with a leading body axis (what `Model` is built from).

    mass: (n,) kg; inertia: (n, 3, 3) body axes about the mass centre; position: (n, 3)
    world; quaternion: (n, 4) w first, body to world; velocity: (n, 3) world; omega:
    (n, 3) body axes; particle: (n,) point masses; shape, color: per body, or None.
    """

    names: tuple[str, ...]
    mass: np.ndarray
    inertia: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    particle: np.ndarray
    shape: list[dict[str, Any] | None]
    color: list[str | None]

    @classmethod
    def from_specs(cls, bodies: list[BodySpec]) -> BodyTable:
        """The table of a list of per-body records (the located path's output)."""
        n = len(bodies)

        def stack(key: str, *shape: int) -> np.ndarray:
            return np.array([getattr(b, key) for b in bodies], dtype=float).reshape(n, *shape)

        return cls(tuple(b.name for b in bodies), stack("mass"), stack("inertia", 3, 3),
                   stack("position", 3), stack("quaternion", 4), stack("velocity", 3),
                   stack("omega", 3), np.array([b.particle for b in bodies], dtype=bool),
                   [b.shape for b in bodies], [b.color for b in bodies])


@dataclass
class LoadTable:
    """Force and torque loads with constant components as arrays, in file order (the
    fast path gives this instead of a `LoadSpec` each): names, types ('force' or
    'torque'); body: (k,) index of the body it acts on; frames ('world' or 'body');
    vector: (k, 3) components in the frame; at: (k, 3) point of application, body axes."""

    names: list[str]
    types: list[str]
    body: np.ndarray
    frames: list[str]
    vector: np.ndarray
    at: np.ndarray


@dataclass
class JointSpecTable:
    """Every joint as columns, in file order (what `Model` builds its joint tables from).

    names, types; parent, child: (k,) body indices (-1 = ground); at: (k, 3) the joint
    point, world, initial pose; axis, axis2: (k, 3) unit axes, zero where `has_axis`,
    `has_axis2` are False; particle_joint: "pin", "link" or "" per joint; pitch: (k,) a
    helical joint's advance per turn (m; 0 for other types); body_points: (k,) the file
    gives the joint's point on each body (then at_parent, at_child (k, 3) hold them, in
    the parent's axes or the world for ground, and in the child's axes; else zeros).
    """

    names: list[str]
    types: list[str]
    parent: np.ndarray
    child: np.ndarray
    at: np.ndarray
    axis: np.ndarray
    has_axis: np.ndarray
    axis2: np.ndarray
    has_axis2: np.ndarray
    particle_joint: list[str]
    pitch: np.ndarray
    body_points: np.ndarray | None = None
    at_parent: np.ndarray | None = None
    at_child: np.ndarray | None = None

    @classmethod
    def from_specs(cls, joints: list[JointSpec], index: dict[str, int]) -> JointSpecTable:
        """The table of a list of per-joint records (the located path's output).

        Parameters
        ----------
        joints : list of JointSpec
            The joints, in file order.
        index : dict of str to int
            Body name -> index (ground is absent: -1).

        Returns
        -------
        JointSpecTable
        """
        k = len(joints)
        zero = np.zeros(3)

        def stack(vectors: list[np.ndarray | None]) -> np.ndarray:
            return np.array([zero if v is None else v for v in vectors],
                            dtype=float).reshape(k, 3)

        axes = [j.axis for j in joints]
        axes2 = [j.axis2 for j in joints]
        return cls([j.name for j in joints], [j.type for j in joints],
                   np.array([index.get(j.parent, -1) for j in joints], dtype=np.intp),
                   np.array([index[j.child] for j in joints], dtype=np.intp),
                   stack([j.at for j in joints]), stack(axes),
                   np.array([a is not None for a in axes], dtype=bool), stack(axes2),
                   np.array([a is not None for a in axes2], dtype=bool),
                   [j.particle_joint for j in joints],
                   np.array([j.pitch for j in joints], dtype=float).reshape(k),
                   np.array([j.body_points is not None for j in joints], dtype=bool),
                   stack([j.body_points[0] if j.body_points else None for j in joints]),
                   stack([j.body_points[1] if j.body_points else None for j in joints]))


@dataclass
class Spec:
    name: str
    file: str
    dimension: int
    gravity: np.ndarray
    bodies: list[BodySpec]
    loads: list[LoadSpec]
    joints: list[JointSpec]
    reactions: dict[str, float]
    description: str = ""
    warnings: list[Issue] = field(default_factory=list)
    reaction_expressions: dict[str, Expression] = field(default_factory=dict)
    """Known reaction values given as expressions of t (their t = 0 value is in reactions)."""
    body_table: BodyTable | None = None
    """The bodies as arrays; the fast path gives only this (and `bodies` empty)."""
    load_table: LoadTable | None = None
    """The fast path's loads (then `loads` is empty): force and torque loads only."""
    joint_table: JointSpecTable | None = None
    """The fast path's joints (then `joints` is empty)."""
    drivers: list[DriverSpec] = field(default_factory=list)
    """Joint coordinates prescribed in time (`mbody.model.drivers`)."""
    document: Document | None = None
    """The document an MJCF or URDF import validated (its YAML form), kept so that values
    can be set in it (`Model.with_values`); None otherwise."""

    def table(self) -> BodyTable:
        """The bodies as arrays, from `body_table` or else from `bodies`."""
        return self.body_table if self.body_table is not None else BodyTable.from_specs(
            self.bodies)


def validate(doc: Document) -> Spec:
    """Check a loaded document against the contract.

    Parameters
    ----------
    doc : Document
        The file's values with their line marks (`mbody.model.loader.load_text`).

    Returns
    -------
    Spec
        The content normalised: defaults filled in, angles in radians, vectors 3-D.

    Raises
    ------
    ModelError
        Listing every problem found, each with its file, line and column.
    """
    c = Checker(doc)
    name, description, gravity = header(c)
    data = doc.data
    bodies = _bodies(c, data.get("bodies"))
    loads, joints, reactions, reaction_expressions, drivers = rest(c, bodies, None)
    if not getattr(doc, "source_format", ""):  # what a person wrote (docstring of the check)
        _far_joint_points(c, bodies, joints)
    _coincident_springs(c, bodies, loads)
    return Spec(str(name), doc.file, c.dim, gravity, bodies, loads, joints, reactions,
                description, c.warnings, reaction_expressions, drivers=drivers)


def header(c: Checker) -> tuple[str, str, np.ndarray]:
    """Check the top level, set ``c.dim``; return the name, description and gravity.

    Raises `ModelError` at once when the document is not a mapping or the dimension is
    not 2 or 3 (every vector length depends on it: checking on would only add noise).
    """
    data = c.doc.data
    if not c.mapping((), data, TOP_KEYS, ("dimension", "bodies"), what="a model mapping"):
        raise ModelError(c.issues)

    dim = data.get("dimension")
    if dim not in (2, 3) or isinstance(dim, bool):
        if "dimension" in data:
            c.err(("dimension",), f"expected 2 (planar) or 3 (spatial), got {_kind(dim)}")
        # Every vector length depends on the dimension: checking on would only add noise.
        raise ModelError(c.issues)
    c.dim = int(dim)
    name = data.get("model", None)
    if name is None:
        name = c.doc.file.rsplit("/", 1)[-1].removesuffix(".yaml").removesuffix(".yml")
    elif not isinstance(name, str):
        c.err(("model",), f"expected the model's name as text, got {_kind(name)}")
    description = data.get("description", "")
    if not isinstance(description, str):
        c.err(("description",), f"expected text, got {_kind(description)}")
        description = ""

    gravity = np.zeros(3)
    if data.get("gravity") is not None:
        g = c.vec3(("gravity",), data["gravity"])
        gravity = g if g is not None else gravity
    return str(name), description, gravity


def rest(c: Checker, bodies: list[BodySpec], loads: list[LoadSpec] | None,
         joints: list[JointSpec] | None = None
         ) -> tuple[list[LoadSpec], list[JointSpec], dict[str, float], dict[str, Expression],
                    list[DriverSpec]]:
    """Check loads and joints (unless given: the fast path's), reactions and drivers,
    after the bodies (whose names are in ``c.body_names``); raise `ModelError` if
    anything was found, in file order."""
    data = c.doc.data
    # A body with a bad mass is still a body: references to it are not problems too.
    names = c.body_names
    if loads is None:
        loads = _loads(c, data.get("loads"), names)
    if joints is None:
        joints = _joints(c, data.get("joints"), names, bodies)
    reaction_expressions: dict[str, Expression] = {}
    reactions = _reactions(c, data.get("reactions"), joints, reaction_expressions)
    drivers = read_drivers(c, data.get("drivers"), c.joint_types)
    if c.issues:  # in file order, as an editor goes through them
        raise ModelError(sorted(c.issues, key=lambda i: i.line))
    return loads, joints, reactions, reaction_expressions, drivers


def _list(c: Checker, path: Path_, value: Any, what: str, required: bool) -> list:
    if value is None:
        if required and path[-1] in c.doc.data:  # absent: already reported as missing
            c.err(path, f"expected a list of {what}, got nothing")
        return []
    if not isinstance(value, list):
        c.err(path, f"expected a list of {what}, got {_kind(value)}")
        return []
    if required and not value:
        c.err(path, f"the model needs at least one of the {what}")
    return value


def _bodies(c: Checker, value: Any) -> list[BodySpec]:
    out: list[BodySpec] = []
    seen: dict[str, int] = c.body_names
    for i, b in enumerate(_list(c, ("bodies",), value, "bodies", True)):
        p: Path_ = ("bodies", i)
        if not c.mapping(p, b, BODY_KEYS, ("name", "mass"), "a body mapping"):
            continue
        name = c.name((*p, "name"), b.get("name"), "body") if "name" in b else None
        if name == cv.GROUND:
            c.err((*p, "name"), "'ground' is reserved for the fixed world frame")
            name = None
        if name is not None and name in seen:
            c.err((*p, "name"), f"duplicate body name '{name}'",
                  f"first used by bodies[{seen[name]}]")
        elif name is not None:
            seen[name] = i
        mass = (c.number((*p, "mass"), b.get("mass"), positive=True, scale=True)
                if "mass" in b else None)
        shape = _shape(c, (*p, "shape"), b["shape"]) if "shape" in b else None
        inertia = None
        particle = "inertia" in b and _zero_inertia(b["inertia"])
        if particle:  # a dummy inertia inside the solver; nothing turns it (docs: Particles)
            inertia = np.eye(3) * (mass if mass is not None else 1.0)
        elif "inertia" in b:
            inertia = _inertia(c, (*p, "inertia"), b["inertia"])
        elif "mass" in b:
            if shape is None:
                if "shape" not in b and (p, "inertia") not in c.meant:
                    c.err(p, "missing required key 'inertia'",
                          "give 'inertia', or a 'shape' to use a uniform solid's inertia")
            elif mass is not None:
                I = shape_inertia(shape, mass, c.dim)
                inertia = (np.diag([I[0] / 2, I[0] / 2, I[0]]) if c.dim == cv.PLANAR
                           else np.diag(I))
        if inertia is not None and not particle:
            inertia = _reciprocable(c, (*p, "inertia" if "inertia" in b else "shape"), inertia)
        zero = np.zeros(3)
        pos = c.vec3((*p, "position"), b["position"]) if "position" in b else zero
        vel = c.vec3((*p, "velocity"), b["velocity"]) if "velocity" in b else zero
        q = np.array([1.0, 0.0, 0.0, 0.0])
        omega = zero
        if c.dim == cv.PLANAR:
            if "orientation" in b:
                c.err((*p, "orientation"), "planar bodies give their angle with 'angle'",
                      "write angle: 0.3 or angle: '30 deg'", key=True)
            if "angle" in b:
                th = c.angle((*p, "angle"), b["angle"])
                if th is not None:
                    q = np.array([math.cos(th / 2), 0.0, 0.0, math.sin(th / 2)])
            if "angular_velocity" in b:
                w = c.angle((*p, "angular_velocity"), b["angular_velocity"], rate=True)
                omega = np.array([0.0, 0.0, w if w is not None else 0.0])
        else:
            if "angle" in b:
                c.err((*p, "angle"), "spatial bodies give their attitude with 'orientation'",
                      "write orientation: {euler: [0, 0, 0.3], sequence: ZYX}", key=True)
            if "orientation" in b:
                qq = _orientation(c, (*p, "orientation"), b["orientation"])
                q = qq if qq is not None else q
            if "angular_velocity" in b:
                w3 = c.vector((*p, "angular_velocity"), b["angular_velocity"], 3, rates=True)
                omega = w3 if w3 is not None else zero
        if particle:
            _particle_pose(c, p, b, q, omega)
        color = b.get("color")
        if color is not None and not isinstance(color, str):
            c.err((*p, "color"), f"expected {colours.EXPECTED}, got {_kind(color)}")
            color = None
        elif color is not None and colours.colour_hex(color) is None:
            c.err((*p, "color"), f"{_quoted(color)} is not a colour", colours.colour_hint(color))
            color = None
        if name is None or mass is None or inertia is None or pos is None or vel is None:
            continue
        out.append(BodySpec(name, mass, inertia, pos, q, vel, omega, shape, color,
                            c.doc.where(p)[0], particle))
        if particle:
            c.particles.add(name)
    return out


def _particle_pose(c: Checker, p: Path_, b: dict, q: np.ndarray, omega: np.ndarray) -> None:
    """A particle (inertia 0) has no orientation and no angular velocity."""
    hint = "a particle (inertia: 0) has no orientation; remove the key, or give the body an inertia"
    if np.any(q[1:] != 0.0):
        key = "angle" if c.dim == cv.PLANAR else "orientation"
        c.err((*p, key), f"a particle (inertia: 0) cannot have a nonzero {key}", hint)
    if np.any(omega != 0.0):
        c.err((*p, "angular_velocity"), "a particle (inertia: 0) cannot have a nonzero "
              "angular_velocity", hint)


def _zero_inertia(value: Any) -> bool:
    """`inertia: 0` (planar or spatial), [0, 0, 0] or a 3x3 zero matrix: a particle."""
    def zero(x: Any) -> bool:
        return (not isinstance(x, bool) and isinstance(x, int | float)
                and not isinstance(x, Unrepresentable) and x == 0)
    if zero(value):
        return True
    if isinstance(value, list) and len(value) == 3:
        return all(zero(x) for x in value) or all(
            isinstance(r, list) and len(r) == 3 and all(zero(x) for x in r) for r in value)
    return False


PARTICLE_HINT = "'inertia: 0' makes a particle: a point mass, which nothing turns"
"""What an inertia refused for its sign also allows (docs/model-format: Particles)."""


def _inertia(c: Checker, path: Path_, value: Any) -> np.ndarray | None:
    if c.dim == cv.PLANAR:
        I = c.number(path, value, positive=True, sign_hint=PARTICLE_HINT) \
            if not isinstance(value, list) else None
        if isinstance(value, list):
            c.err(path, "a planar body's inertia is the scalar I_G about its mass centre "
                  f"(kg m^2), got {_kind(value)}")
        return None if I is None else np.diag([I / 2, I / 2, I])
    if isinstance(value, list) and value and all(isinstance(r, list) for r in value):
        J = c.matrix3(path, value)
        if J is None:
            return None
        off, scale = asymmetry(J)
        if off > _TOL * scale:
            i, j = np.unravel_index(np.argmax(np.abs(J - J.T)), J.shape)
            c.err(path, f"the inertia tensor is not symmetric: row {i + 1}, column {j + 1} "
                  f"is {J[i, j]:g} but row {j + 1}, column {i + 1} is {J[j, i]:g}",
                  "entry (i, j) must equal entry (j, i)")
            return None
        principal = np.linalg.eigvalsh(J)
    else:
        v = c.vector(path, value, 3) if isinstance(value, list) else None
        if not isinstance(value, list):
            c.err(path, "expected principal moments [I1, I2, I3] or a 3x3 inertia tensor, "
                  f"got {_kind(value)}")
        if v is None:
            return None
        J, principal = np.diag(v), v
    if np.any(principal <= 0):
        c.err(path, "the inertia tensor is not positive definite "
              f"(principal moments {_fmt(principal)})",
              "every principal moment must be > 0; " + PARTICLE_HINT)
        return None
    a, b, d = np.sort(principal)
    if not realisable(principal):
        c.err(path, f"the inertia is not physically realisable: the principal moments "
              f"{_fmt(principal)} break the triangle inequality ({a:g} + {b:g} < {d:g})",
              "every moment must be <= the sum of the other two")
        return None
    return J


def _reciprocable(c: Checker, path: Path_, J: np.ndarray) -> np.ndarray | None:
    """`J` unless a principal moment is nonzero but below `MIN_MAGNITUDE` (5e-324, or a
    tiny mass times a tiny shape): its inverse, used in every solve, would overflow."""
    moments = [J[2, 2]] if c.dim == cv.PLANAR else np.linalg.eigvalsh(J)
    tiny = [m for m in moments if 0 < abs(m) < MIN_MAGNITUDE]
    if not tiny:
        return J
    c.err(path, f"a moment of inertia of {tiny[0]:.3g} kg m^2 is below "
          f"{MIN_MAGNITUDE:g}", "its inverse would leave double precision; give a "
          "realistic value")
    return None


def _fmt(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:g}" for x in v) + ")"


def _orientation(c: Checker, path: Path_, value: Any) -> np.ndarray | None:
    if not c.mapping(path, value, ORIENTATION_KEYS, what="an orientation mapping"):
        return None
    given = [k for k in ("quaternion", "euler", "matrix") if k in value]
    if len(given) != 1:
        c.err(path, "give exactly one of 'quaternion', 'euler' or 'matrix'"
              + (f" (got {', '.join(given)})" if given else ""))
        return None
    kind = given[0]
    if "sequence" in value and kind != "euler":
        c.err((*path, "sequence"), "'sequence' goes with 'euler'",
              "remove it, or give the angles as euler: [a, b, c]", key=True)
    if kind == "quaternion":
        q = c.vector((*path, "quaternion"), value["quaternion"], 4)
        if q is None:
            return None
        n = float(quat_norm(q))
        if n < MIN_NORM:
            c.err((*path, "quaternion"), "the quaternion is zero", "identity is [1, 0, 0, 0]")
            return None
        if abs(n - 1) > UNIT_TOL:
            c.warn((*path, "quaternion"), f"the quaternion has norm {n:.6g}; it was normalised")
        return q / n
    if kind == "euler":
        seq = value.get("sequence", DEFAULT_EULER_SEQUENCE)
        if not (isinstance(seq, str) and len(seq) == 3 and (seq.isupper() or seq.islower())
                and set(seq.lower()) <= set("xyz") and seq[0] != seq[1] and seq[1] != seq[2]):
            c.err((*path, "sequence"), f"invalid Euler sequence {_quoted(seq)}",
                  "three axes such as ZYX (intrinsic, upper case) or zyx (extrinsic, lower "
                  "case), no axis twice in a row")
            return None
        ang = c.vector((*path, "euler"), value["euler"], 3, angles=True)
        return None if ang is None else euler_to_quat(ang, seq)
    R = c.matrix3((*path, "matrix"), value["matrix"])
    if R is None:
        return None
    off, det = float(np.max(np.abs(R.T @ R - np.eye(3)))), float(np.linalg.det(R))
    if off > _TOL or det < 0:
        c.err((*path, "matrix"), "not a rotation matrix: "
              + (f"R^T R differs from I by up to {off:.3g}" if off > _TOL else "")
              + ("; " if off > _TOL and det < 0 else "")
              + (f"determinant {det:.3g} (a reflection)" if det < 0 else ""),
              "it must be orthonormal (R^T R = I within 1e-6) with determinant +1")
        return None
    return matrix_to_quat(R)


def _shape(c: Checker, path: Path_, value: Any) -> dict[str, Any] | None:
    allowed = SHAPES[c.dim]
    if not c.mapping(path, value, allowed, what="a shape mapping such as {box: [a, b, c]}"):
        return None
    if any(k not in allowed for k in value):  # already reported, with a did-you-mean
        return None
    if len(value) != 1:
        c.err(path, f"give exactly one shape, one of: {', '.join(allowed)}")
        return None
    kind, v = next(iter(value.items()))
    p = (*path, kind)
    if kind == "box" or kind == "ellipsoid":
        n = c.dim
        vec = c.vector(p, v, n, scale=True)
        if vec is None:
            return None
        if np.any(vec <= 0):
            c.err(p, "every size must be > 0")
            return None
        return {kind: [float(x) for x in vec]}
    keys = ("radius", "length") if kind == "cylinder" else ("radius",)
    if not c.mapping(p, v, keys, keys, f"a mapping with {' and '.join(keys)}"):
        return None
    out = {}
    for k in keys:
        x = c.number((*p, k), v.get(k), positive=True, scale=True) if k in v else None
        if x is None:
            return None
        out[k] = x
    return {kind: out}


def _loads(c: Checker, value: Any, names: dict[str, int]) -> list[LoadSpec]:
    out: list[LoadSpec] = []
    seen: dict[str, int] = {}
    counters: dict[str, int] = {}
    items = _list(c, ("loads",), value, "loads", False)
    given = {ld["name"] for ld in items if isinstance(ld, dict) and isinstance(ld.get("name"), str)}
    for i, ld in enumerate(items):
        p: Path_ = ("loads", i)
        if not isinstance(ld, dict):
            c.err(p, f"expected a load mapping, got {_kind(ld)}")
            continue
        if "type" not in ld:
            c.err(p, "missing required key 'type'", "one of: force, torque, spring")
            continue
        typ = c.choice((*p, "type"), ld["type"], tuple(LOAD_KEYS), "load type")
        if typ is None:
            continue
        counters[typ] = counters.get(typ, 0) + 1
        required = {"force": ("body", "force"), "torque": ("body", "torque"),
                    "spring": ("bodies", "at", "stiffness")}[typ]
        c.mapping(p, ld, LOAD_KEYS[typ], required)
        if "name" in ld:
            name = c.name((*p, "name"), ld["name"], "load")
        else:  # <type><n>, never a name the file gives to another load
            name = f"{typ}{counters[typ]}"
            while name in given or name in seen:
                counters[typ] += 1
                name = f"{typ}{counters[typ]}"
        if name is not None and name in seen:
            c.err((*p, "name"), f"duplicate load name '{name}'",
                  f"first used by loads[{seen[name]}]")
        elif name is not None:
            seen[name] = i
        line = c.doc.where(p)[0]
        if typ in ("force", "torque"):
            body = c.body_ref((*p, "body"), ld["body"], names, False) if "body" in ld else None
            frame = ld.get("frame", "world")
            frame = c.choice((*p, "frame"), frame, FRAMES, "frame")
            exprs: dict[int, Expression] = {}
            if typ == "force":
                vec = (_varying(c, (*p, "force"), ld["force"], exprs, Checker.vec3)
                       if "force" in ld else None)
                at = c.vec3((*p, "at"), ld["at"]) if "at" in ld else np.zeros(3)
            else:
                vec = (_varying(c, (*p, "torque"), ld["torque"], exprs, _torque)
                       if "torque" in ld else None)
                at = np.zeros(3)
            if body in c.particles:
                if typ == "torque":
                    c.err((*p, "type"), f"a torque cannot act on the particle '{body}'",
                          "a particle (inertia: 0) has no rotation; only forces at the "
                          "particle act on it")
                    continue
                if at is not None and np.any(at != 0.0):
                    c.err((*p, "at"), f"a force on the particle '{body}' acts at the particle",
                          "remove 'at' (or give [0, 0]): a particle has no extent")
                    continue
                if frame == "body":
                    c.err((*p, "frame"), f"the particle '{body}' has no body axes",
                          "give the force in world axes (frame: world)")
                    continue
            if name is None or body is None or frame is None or vec is None or at is None:
                continue
            out.append(LoadSpec(name, typ, (body,), vec, frame, (at,), line=line,
                                expressions=exprs))
        else:
            pair = ld.get("bodies")
            refs: list[str | None] = []
            if not (isinstance(pair, list) and len(pair) == 2):
                if "bodies" in ld:
                    c.err((*p, "bodies"), f"expected two body names (or ground), got "
                          f"{_kind(pair)}")
            else:
                refs = [c.body_ref((*p, "bodies", k), pair[k], names, True) for k in (0, 1)]
                if refs[0] is not None and refs[0] == refs[1]:
                    c.err((*p, "bodies"), "a spring needs two different ends")
                    refs = []
            at = ld.get("at")
            pts: list[np.ndarray | None] = []
            if not (isinstance(at, list) and len(at) == 2):
                if "at" in ld:
                    c.err((*p, "at"), "expected two attachment points "
                          "[[..body axes or world for ground..], [..]]")
            else:
                pts = [c.vec3((*p, "at", k), at[k]) for k in (0, 1)]
                for k in (0, 1):
                    if (len(refs) == 2 and refs[k] in c.particles and pts[k] is not None
                            and np.any(pts[k] != 0.0)):
                        c.err((*p, "at", k), f"a spring attaches to the particle "
                              f"'{refs[k]}' at the particle", "give [0, 0] (body axes): a "
                              "particle has no extent")
                        pts[k] = None
            stiffness = c.number((*p, "stiffness"), ld["stiffness"], nonneg=True) \
                if "stiffness" in ld else None
            L0 = c.number((*p, "rest_length"), ld.get("rest_length", 0.0), nonneg=True)
            damping = c.number((*p, "damping"), ld.get("damping", 0.0), nonneg=True)
            ends = [r for r in refs if r is not None]
            points = [q for q in pts if q is not None]
            if (len(ends) != 2 or len(points) != 2 or name is None or stiffness is None
                    or L0 is None or damping is None):
                continue
            out.append(LoadSpec(name, "spring", tuple(ends), None, "world", tuple(points),
                                stiffness, L0, damping, line))
    return out


def expression(c: Checker, path: Path_, text: str) -> Expression | None:
    """Compile a load expression of t; on error an issue naming the character."""
    try:
        e = compile_expression(text)
    except ExpressionError as exc:
        pos = exc.position
        c.err(path, f"invalid expression: {exc.reason} at character {pos + 1} "
              f"(marked |): \"{exc.text[:pos]}|{exc.text[pos:]}\"",
              exc.hint or "see docs/expressions.md for the grammar")
        return None
    problem = check_finite(e, 0.0)
    if problem:
        c.err(path, f"{problem}: \"{text}\"")
        return None
    if e.constant and c.number(path, e.value) is None:  # "1e60*1e60" is a number too
        return None
    bad = first_nonfinite(e, CHECK_SPAN)
    if bad is not None:
        c.warn(path, f"the expression \"{text}\" is not finite at t = {bad[0]:g} s ({bad[1]}); "
               "a simulation cannot go past that time", f"sampled every millisecond from 0 "
               f"to {CHECK_SPAN:g} s, simulate's default span")
    return e


def _varying(c: Checker, path: Path_, value: Any, exprs: dict[int, Expression],
             read) -> np.ndarray | None:
    """A load vector (or planar scalar torque) whose components may be expressions of t.

    Each text component is compiled into `exprs` (by 3-D component index) and replaced by
    its value at t = 0, so the vector is the load at the initial state.
    """
    planar_scalar = not isinstance(value, list)
    if planar_scalar and not (read is _torque and c.dim == cv.PLANAR):
        return read(c, path, value)  # not a vector: let the reader say what was expected
    items = [value] if planar_scalar else list(value)
    found: dict[int, Expression] = {}
    ok = True
    for i, v in enumerate(items):
        if isinstance(v, str):
            e = expression(c, path if planar_scalar else (*path, i), v)
            ok = ok and e is not None
            if e is not None:
                found[2 if planar_scalar else i] = e
            items[i] = 0.0
    if not ok:
        return None
    vec = read(c, path, items[0] if planar_scalar else items)
    if vec is None:
        return None
    for k, e in found.items():
        vec[k] = e.value
    exprs.update({k: e for k, e in found.items() if not e.constant})  # "2*pi" is a number
    return vec


def _torque(c: Checker, path: Path_, value: Any) -> np.ndarray | None:
    if c.dim == cv.PLANAR:
        if isinstance(value, list):
            c.err(path, "a planar torque is a scalar (N m about z)", f"got {_kind(value)}")
            return None
        t = c.number(path, value)
        return None if t is None else np.array([0.0, 0.0, t])
    return c.vector(path, value, 3)


def _joints(c: Checker, value: Any, names: dict[str, int],
            bodies: list[BodySpec]) -> list[JointSpec]:
    out: list[JointSpec] = []
    seen: dict[str, int] = {}
    types = joint_types.type_names(c.dim)
    synonyms = joint_types.ALIASES[c.dim]  # other programs' names (hinge, slide, ball...)
    for i, j in enumerate(_list(c, ("joints",), value, "joints", False)):
        p: Path_ = ("joints", i)
        if not c.mapping(p, j, JOINT_KEYS, ("name", "type", "parent", "child", "at"),
                         "a joint mapping"):
            continue
        name = c.name((*p, "name"), j["name"], "joint") if "name" in j else None
        if name is not None and name in seen:
            c.err((*p, "name"), f"duplicate joint name '{name}'",
                  f"first used by joints[{seen[name]}]")
        elif name is not None:
            seen[name] = i
        typ = None
        other = joint_types.type_names(cv.PLANAR + cv.SPATIAL - c.dim)
        if isinstance(j.get("type"), str) and j["type"] in other and j["type"] not in types:
            here, there = ("planar", "spatial") if c.dim == cv.PLANAR else ("spatial", "planar")
            c.err((*p, "type"), f"'{j['type']}' is a {there} joint type; a {here} model "
                  f"(dimension: {c.dim}) has: {', '.join(types)}")
        elif "type" in j:
            typ = c.choice((*p, "type"), j["type"], types,
                           f"{'planar' if c.dim == 2 else 'spatial'} joint type", synonyms)
        parent = c.body_ref((*p, "parent"), j["parent"], names, True) if "parent" in j else None
        child = c.body_ref((*p, "child"), j["child"], names, True) if "child" in j else None
        if child == cv.GROUND:
            c.err((*p, "child"), "the child of a joint must be a body",
                  "put ground as the parent")
            child = None
        if parent is not None and parent == child:
            c.err((*p, "child"), f"the joint connects '{child}' to itself",
                  "parent and child must be different bodies (or ground as the parent)")
            child = None
        at, points = (_joint_at(c, p, j["at"], parent, child, bodies) if "at" in j
                      else (None, None))
        params = _joint_params(c, p, j, typ)
        if params is None:
            continue
        axis, axis2, pitch = params
        if name is not None and typ is not None:
            c.joint_types.setdefault(name, typ)
        if name is None or typ is None or parent is None or child is None or at is None:
            continue
        kind = ""
        if parent in c.particles or child in c.particles:
            found = _particle_joint(c, p, typ, parent, child, at, bodies)
            if found is None:
                continue
            kind = found
            c.particle_joints.setdefault(name, kind)
        out.append(JointSpec(name, typ, parent, child, at, axis, axis2, c.doc.where(p)[0],
                             kind, pitch, points))
    return out


def _joint_at(c: Checker, p: Path_, value: Any, parent: str | None, child: str | None,
              bodies: list[BodySpec]
              ) -> tuple[np.ndarray | None, tuple[np.ndarray, np.ndarray] | None]:
    """(the joint point in world coordinates at the file's pose, or None; the points on
    each body when the file gives them: ``at: [[parent point], [child point]]``, each in
    its body's axes from the mass centre, world coordinates for ground)."""
    if not (isinstance(value, list) and len(value) == 2
            and all(isinstance(v, list) for v in value)):
        return c.vec3((*p, "at"), value), None
    rp = c.vec3((*p, "at", 0), value[0])
    rc = c.vec3((*p, "at", 1), value[1])
    pose = {b.name: b for b in bodies}
    if rp is None or rc is None or child not in pose:
        return None, None
    b = pose[child]  # where the child's point is at the file's pose
    return b.position + quat_to_matrix(b.quaternion) @ rc, (rp, rc)


def _joint_params(c: Checker, p: Path_, j: dict, typ: str | None
                  ) -> tuple[np.ndarray | None, np.ndarray | None, float] | None:
    """The joint type's own keys (mbody.joint_types: axis, axis2, pitch), checked: (axis,
    axis2, pitch), or None when the joint is to be left out (a rule of its type broken)."""
    jt = joint_types.TYPES[c.dim].get(typ) if typ is not None else None
    got: dict[str, Any] = {}
    for key in PARAM_KEYS:
        prm = jt.param(key) if jt is not None else None
        if key in j:
            if jt is not None and prm is None:
                owners = [t.name for t in joint_types.TYPES[c.dim].values() if t.param(key)]
                c.err((*p, key), f"'{key}' belongs to {' and '.join(owners) or 'no'} joints",
                      f"remove it, or use type: {' or '.join(owners)}" if owners else
                      "remove it", key=True)
            elif prm is None or prm.what == "direction":
                got[key] = _axis(c, (*p, key), j[key])
            else:
                got[key] = c.number((*p, key), j[key])
        elif prm is not None and prm.required:
            article = "an " if key == "axis" else ""  # "needs an 'axis'", "needs 'axis2'"
            c.err(p, f"a {typ} joint needs {article}'{key}'", prm.meaning)
    axis, axis2 = got.get("axis"), got.get("axis2")
    if axis is not None and axis2 is not None and abs(float(axis @ axis2)) > PERPENDICULAR_TOL:
        c.err((*p, "axis2"), f"a {typ} joint's axes must be perpendicular",
              f"axis . axis2 = {float(axis @ axis2):.3g}")
        return None
    pitch = got.get("pitch")
    return axis, axis2, float(pitch) if pitch is not None else 0.0


JOINT_REACH_GYRATION = 4.0
"""A joint point farther than this many radii of gyration ρ from a body's mass centre is
beyond the body (ρ² = I_G/m in the plane, (I1 + I2 + I3)/2m in space: the mean squared
distance of its mass from the mass centre). No point of a uniform convex body is that far:
a rod's ends are at √3 ρ = 1.7 ρ, a slender triangle's apex at 2.8 ρ, a slender cone's,
the extreme, at 3.9 ρ."""
JOINT_REACH_SHAPE = 2.0
"""A body with a shape reaches at least this many times its shape's farthest point from
the mass centre (an axle or a light arm a shape leaves out stays within it)."""


def shape_extent(shape: dict[str, Any], planar: bool) -> float:
    """The distance from the mass centre (m) of a shape's farthest point (in the plane,
    for a planar model): a box's half-diagonal, a cylinder's rim..."""
    kind, v = next(iter(shape.items()))
    if kind == "box":
        return 0.5 * math.hypot(*v)
    if kind == "ellipsoid":
        return float(max(v))
    if kind == "cylinder" and not planar:  # seen end-on in the plane: a disc
        return math.hypot(v["radius"], 0.5 * v["length"])
    return float(v["radius"])  # sphere, disc, a planar cylinder


def body_reach(mass: float, inertia: np.ndarray, shape: dict[str, Any] | None,
               planar: bool) -> tuple[float, str]:
    """How far from its mass centre (m) a joint point may lie on a body of this mass,
    inertia (body axes, about the mass centre) and shape, and on what that rests:
    `JOINT_REACH_GYRATION` radii of gyration, or `JOINT_REACH_SHAPE` times the shape's
    extent when that is farther."""
    reach = float(reach_of_bodies(np.array([mass]), inertia[None], planar)[0])
    basis = f"{JOINT_REACH_GYRATION:g} radii of gyration"
    if shape is not None:
        drawn = JOINT_REACH_SHAPE * shape_extent(shape, planar)
        if drawn > reach:
            reach, basis = drawn, f"{JOINT_REACH_SHAPE:g} times its shape's extent"
    return reach, basis


def reach_of_bodies(mass: np.ndarray, inertia: np.ndarray, planar: bool) -> np.ndarray:
    """(n,) `body_reach` of bodies without a shape, at once: `JOINT_REACH_GYRATION` radii
    of gyration."""
    rho2 = (inertia[:, 2, 2] if planar else np.trace(inertia, axis1=1, axis2=2) / 2.0) / mass
    return JOINT_REACH_GYRATION * np.sqrt(np.maximum(rho2, 0.0))


def far_joint_points(at: np.ndarray, parent: np.ndarray, child: np.ndarray,
                     position: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """(k,) whether each joint's point `at` (k, 3, world) lies beyond the reach of every
    body it joins: `parent`, `child` (k,) body indices into `position` (n, 3, mass centres,
    world) and `reach` (n,), or -1 for an end not counted (ground, a particle). A joint
    with no end counted is never far."""
    far = np.ones(len(at), dtype=bool)
    counted = np.zeros(len(at), dtype=bool)
    for end in (parent, child):
        has = end >= 0
        i = np.where(has, end, 0)
        d = np.linalg.norm(at - position[i], axis=1) if len(at) else np.zeros(0)
        far &= ~has | (d > reach[i])
        counted |= has
    return far & counted


def _far_joint_points(c: Checker, bodies: list[BodySpec], joints: list[JointSpec]) -> None:
    """Warn where a joint's point lies beyond every body it joins (`body_reach`): a point
    given in a body's axes instead of the world's, in mm, with a sign or a body's position
    wrong. Ground and particles are not counted (a joint to a particle away from it is a
    light link). Only for files a person writes: an MJCF or URDF reader puts each joint at
    its anchor, and a robot link's inertia is what its CAD gave (Baxter's gripper base
    has its joint 390 radii of gyration away)."""
    if not joints:
        return
    planar = c.dim == cv.PLANAR
    index = {b.name: k for k, b in enumerate(bodies)}
    reach = [body_reach(b.mass, b.inertia, b.shape, planar) for b in bodies]

    def counted(name: str) -> int:
        k = index.get(name, -1)
        return -1 if k < 0 or bodies[k].particle else k

    parent = np.array([counted(j.parent) for j in joints], dtype=np.intp)
    child = np.array([counted(j.child) for j in joints], dtype=np.intp)
    far = far_joint_points(np.array([j.at for j in joints]), parent, child,
                           np.array([b.position for b in bodies]).reshape(-1, 3),
                           np.array([r for r, _ in reach]))
    where = {j.get("name"): i for i, j in enumerate(c.doc.data.get("joints") or [])
             if isinstance(j, dict)}
    for j, p, ch, is_far in zip(joints, parent.tolist(), child.tolist(), far.tolist(),
                                strict=True):
        if not is_far:
            continue
        ends = [k for k in (p, ch) if k >= 0]
        parts = [f"{float(np.linalg.norm(j.at - bodies[k].position)):.4g} m from the mass "
                 f"centre of '{bodies[k].name}' (beyond {reach[k][0]:.3g} m, {reach[k][1]})"
                 for k in ends]
        shown = ", ".join(f"{x:g}" for x in (j.at[:2] if planar else j.at))
        c.warn(("joints", where.get(j.name, 0), "at"),
               f"the joint point ({shown}) lies off "
               f"{'the body' if len(ends) == 1 else 'both bodies'} it joins: "
               + " and ".join(parts),
               "'at' is in world coordinates, where the bodies meet at the pose the file "
               "gives them; check it and the bodies' positions and angles")


SPRING_COINCIDENT = 1e-12
"""Spring ends closer than this (m) have no direction: the compiled core (loads.c,
`spring_state`) then applies no force, whatever the tension."""


def _coincident_springs(c: Checker, bodies: list[BodySpec], loads: list[LoadSpec]) -> None:
    """Warn where a spring's ends coincide at the file's pose while its tension k(L − L0)
    is not zero: the force has no direction there, and none is applied (a spring whose
    rest length is 0 has no tension there, and loses nothing). `loads` are the file's
    loads in its order (`rest` raised on any problem)."""
    at = {b.name: (b.position, quat_to_matrix(b.quaternion[None])[0]) for b in bodies}
    for i, ld in enumerate(loads):
        if ld.type != "spring" or ld.stiffness * ld.rest_length == 0.0:
            continue
        ends = []
        for body, point in zip(ld.bodies, ld.at, strict=True):
            if body == "ground":
                ends.append(point)
            else:
                pos, R = at[body]
                ends.append(pos + R @ point)
        length = float(np.linalg.norm(ends[1] - ends[0]))
        if length > SPRING_COINCIDENT:
            continue
        tension = ld.stiffness * (length - ld.rest_length)
        c.warn(("loads", i), f"the spring's ends coincide while its tension k(L − L0) = "
               f"{ld.stiffness:g} × (0 − {ld.rest_length:g}) = {tension:.6g} N is not zero: "
               "the force has no direction there, so none is applied while they coincide",
               "move a body or an attachment point so that the ends are apart, or give "
               "rest_length: 0 if they are meant to meet")


PARTICLE_JOINTS = {cv.PLANAR: ("revolute",), cv.SPATIAL: ("revolute", "spherical")}
"""Joint types that may connect a particle (they constrain its position only)."""
PARTICLE_RTOL = 1e-9
"""A joint point within this distance (relative to the model's size) of a particle is at
the particle (a pin); farther, the joint is a rigid link of that length to it."""


def _particle_joint(c: Checker, p: Path_, typ: str, parent: str, child: str,
                    at: np.ndarray, bodies: list[BodySpec]) -> str | None:
    """"pin" or "link" for a joint with a particle at an end (docs: Particles), or None
    after reporting why such a joint is not allowed."""
    ends = [e for e in (parent, child) if e in c.particles]
    allowed = PARTICLE_JOINTS[c.dim]
    if typ not in allowed:
        c.err((*p, "type"), f"a {typ} joint cannot connect the particle '{ends[0]}': a "
              "particle (inertia: 0) has no orientation to constrain",
              f"use {' or '.join(allowed)} (it constrains the particle's position only)")
        return None
    pos = {b.name: b.position for b in bodies}
    if any(e not in pos for e in ends):
        return None  # a body with problems of its own, already reported
    scale = max([float(np.abs(at).max())] + [float(np.abs(x).max()) for x in pos.values()])
    tol = PARTICLE_RTOL * scale
    at_particle = [e for e in ends if float(np.linalg.norm(at - pos[e])) <= tol]
    if len(at_particle) == len(ends):
        return "pin"
    if len(ends) == 2 and not at_particle:
        c.err((*p, "at"), f"the joint point of two particles ('{parent}', '{child}') must "
              "be at one of them", "at one particle: a rigid link to the other; at both: "
              "a pin")
        return None
    return "link"


def _axis(c: Checker, path: Path_, value: Any) -> np.ndarray | None:
    a = c.vec3(path, value)
    if a is None:
        return None
    n = float(vec_norm(a))
    if n < MIN_NORM:
        c.err(path, "the axis is the zero vector", "give a direction, such as "
              + ("[1, 0]" if c.dim == cv.PLANAR else "[0, 0, 1]"))
        return None
    return a / n


def _reactions(c: Checker, value: Any, joints: list[JointSpec],
               expressions: dict[str, Expression]) -> dict[str, float]:
    if value is None:
        return {}
    if not isinstance(value, dict):
        c.err(("reactions",), f"expected a mapping of reaction labels to values, got "
              f"{_kind(value)}")
        return {}
    # From every joint with a valid name and type, so that a joint with a bad point does
    # not turn each of its known reactions into a second problem.
    labels = [f"{n}.{k}" for n, t in c.joint_types.items()
              for k in (cv.PARTICLE_COMPONENTS[c.dim][t][c.particle_joints[n]]
                        if n in c.particle_joints else cv.JOINT_COMPONENTS[c.dim][t])]
    out: dict[str, float] = {}
    for label, v in value.items():
        p: Path_ = ("reactions", label)
        if label not in labels:
            c.err(p, f"no reaction component '{_show(label)}'",
                  did_you_mean(label, labels)
                  or (f"the model's reaction components are: {', '.join(labels[:12])}"
                      if labels else "the model has no joints"), key=True)
            continue
        if isinstance(v, str):  # a known value that varies in time, e.g. "40*cos(20*t)"
            e = expression(c, p, v)
            if e is not None:
                out[label] = e.value
                if not e.constant:
                    expressions[label] = e
            continue
        x = c.number(p, v)
        if x is not None:
            out[label] = x
    return out
