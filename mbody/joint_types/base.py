"""What a joint type is, as data: its parameters, its reaction components (each one of the
compiled core's constraint primitives), the relative motions it allows, and its names in
other programs. Every joint type is one `JointType` value in its own module of this
folder; `mbody.joint_types` collects them (docs/joint-types.md walks through adding one).

A reaction component is an unknown of the stacked equations, ``<joint>.<component>``:
what it is (`FORCE`, `MOMENT` or `WRENCH`, a force and a moment tied together) and which
primitive of the core (mbody/kernel/src/kernel.h, ``MB_KIND_*``) writes its column of G,
its position error φ, its relative velocity Gᵀv and its γ. The joint frame (fixed to the
parent) is the contract's: planar, x along `axis` where the type has one, else world x;
spatial, z along `axis`, else world z (docs/conventions.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from mbody.kernel import _core

PLANAR, SPATIAL = 2, 3

# the constraint primitives, one home: kernel.h's enum
FORCE_ALONG = _core.KIND_FORCE
"""A force along a joint-frame axis: the joint points stay on a plane across it."""
TILT = _core.KIND_TILT
"""A moment about x or y of a joint turning freely about z: the z axes stay parallel."""
LOCK = _core.KIND_LOCK
"""A moment about a joint-frame axis, the rotation locked (small-rotation vector)."""
RIGHT_ANGLE = _core.KIND_RIGHT_ANGLE
"""The universal joint's moment: its two axes stay at a right angle."""
LINK = _core.KIND_LINK
"""A particle link's tension: a distance held."""
TURN = _core.KIND_TURN
"""A moment about a joint-frame axis, the rotation about it measured as an angle (drivers)."""
SCREW = _core.KIND_SCREW
"""The helical joint's axial wrench: translation tied to rotation by the pitch."""

FORCE, MOMENT, WRENCH = "force", "moment", "wrench"
"""What a component is: a force (N), a moment (N m), or a wrench whose value is its force
(N) with a moment tied to it."""

UNITS = {FORCE: "N", MOMENT: "N m", WRENCH: "N"}

ROTATION, TRANSLATION, BALL = "rotation", "translation", "ball"
"""Kinds of relative motion a joint allows."""


@dataclass(frozen=True)
class Component:
    """One reaction component of a joint type.

    name: the label's suffix (``Fx``); what: `FORCE`, `MOMENT` or `WRENCH`; kind: the core's
    primitive (`FORCE_ALONG`...); axis: the joint-frame axis it acts along or about (0-2);
    meaning: a phrase for docs and free-body tables.
    """

    name: str
    what: str
    kind: int
    axis: int
    meaning: str

    @property
    def unit(self) -> str:
        return UNITS[self.what]


def force(axis: int) -> Component:
    """The force along joint-frame axis `axis` (0-2)."""
    xyz = "xyz"[axis]
    return Component(f"F{xyz}", FORCE, FORCE_ALONG, axis, f"force along the joint {xyz} axis")


def tilt(axis: int) -> Component:
    """The moment about x or y of a joint that turns freely about z."""
    xyz = "xyz"[axis]
    return Component(f"M{xyz}", MOMENT, TILT, axis,
                     f"moment about the joint {xyz} axis (keeps the z axes parallel)")


def lock(axis: int) -> Component:
    """The moment about joint-frame axis `axis` of a joint whose rotation is locked."""
    xyz = "xyz"[axis]
    return Component(f"M{xyz}", MOMENT, LOCK, axis, f"moment about the joint {xyz} axis")


@dataclass(frozen=True)
class Param:
    """A key of the joint's entry in the model file besides name, type, parent, child, at.

    name: the key; what: ``direction`` (a vector, normalised), ``length`` (m, a number);
    required: whether the type needs it; meaning: for messages and docs; default: the
    value when absent (None: none).
    """

    name: str
    what: str
    required: bool
    meaning: str
    default: tuple[float, ...] | float | None = None


@dataclass(frozen=True)
class Motion:
    """A relative motion the joint allows: one generalized coordinate of a tree of joints,
    and what a driver may prescribe.

    name: ``angle`` or ``displacement`` (the coordinate's label suffix); what: `ROTATION`,
    `TRANSLATION` or `BALL` (three rotations); axis: the joint-frame axis (0-2) it is
    about or along (`BALL`: -1); on: ``parent`` (the axis fixed in the parent: the joint
    frame) or ``child`` (a universal joint's second axis, ``axis2``, fixed in the child);
    part: the suffix of its MJCF joint's name (``J:slide``) when the type has several.
    """

    name: str
    what: str
    axis: int
    on: str = "parent"
    part: str = ""


@dataclass(frozen=True)
class JointType:
    """Everything mbody knows about one joint type in one dimension (see the module doc).

    components: the reaction components in label order (exactly the relative motions the
    joint prevents); motions: what it allows; particle: the components when a particle
    (inertia 0) is at an end, by how it is held (``pin``: at the particle; ``link``: a
    rigid link to it), for the types that may connect one; aliases: other programs' names
    for it (did-you-means); mjcf_loop: the MJCF equality that closes a loop with it
    (``connect``, ``weld``) or None; summary: one line for docs and messages.
    """

    name: str
    dimension: int
    summary: str
    components: tuple[Component, ...]
    motions: tuple[Motion, ...]
    params: tuple[Param, ...] = ()
    particle: dict[str, tuple[Component, ...]] = field(default_factory=dict)
    aliases: tuple[str, ...] = ()
    mjcf_loop: str | None = None

    @property
    def component_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.components)

    def param(self, name: str) -> Param | None:
        """The parameter `name` of this type, or None."""
        return next((p for p in self.params if p.name == name), None)

    @property
    def holds_point(self) -> bool:
        """The joint point cannot move relative to the parent (no translation allowed)."""
        return not any(m.what == TRANSLATION for m in self.motions) and not any(
            c.kind == SCREW for c in self.components)


# The components a particle's joint has (docs/model-format.md, Particles): a pin holds the
# particle's position, a link its distance (and, for a spatial revolute, its plane ⟂ the
# axis); no moments, a particle has no orientation.
TENSION = Component("T", FORCE, LINK, 2,
                    "tension of the link (positive pulls the particle toward the joint point)")
