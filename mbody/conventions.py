"""The single source of truth for labels, component names and frame rules.

Everything here is data that exports repeat verbatim, so that a matrix read in MATLAB or
on paper says which row is which body and which column is which joint.

Internally every body is spatial: a planar body lives in the world x-y plane, turns
about world z, and its three stacked rows are rows (x, y, 3) of the spatial six
``[x, y, z, w1, w2, w3]`` (for a planar body, body axis 3 is world z).
"""

from __future__ import annotations

import numpy as np

from mbody import joint_types
from mbody.errors import MbodyError

PLANAR, SPATIAL = 2, 3

SPATIAL_ROWS = ("x", "y", "z", "w1", "w2", "w3")
"""Row suffixes of a spatial body: Newton in world axes, then Euler in body axes."""
PLANAR_ROWS = ("x", "y", "theta")
"""Row suffixes of a planar body: Newton in world x, y, then Euler about z."""
PLANAR_SELECT = np.array([0, 1, 5])
"""Which of the six spatial rows a planar body keeps."""

ACCELERATION_NAMES = {
    "x": "a_x", "y": "a_y", "z": "a_z",
    "w1": "alpha_1", "w2": "alpha_2", "w3": "alpha_3", "theta": "alpha",
}
"""How the unknown acceleration of each row is written in equations."""

COMPONENTS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
"""The force and moment components along and about the three joint-frame axes."""

LINK = "T"
"""The tension of a particle's link (positive pulls the particle toward the joint point)."""
LINK_AXIS = -1
"""`ReactionTable.axis` of a link's tension T (a force along the link, not a frame axis)."""

# Views of the joint-type registry (mbody.joint_types, where each type is defined once),
# for the exports' conventions data and older callers.
JOINT_COMPONENTS: dict[int, dict[str, tuple[str, ...]]] = {
    d: {name: jt.component_names for name, jt in types.items()}
    for d, types in joint_types.TYPES.items()}
"""Reaction components of each joint type: exactly the relative motions it prevents."""

PARTICLE_COMPONENTS: dict[int, dict[str, dict[str, tuple[str, ...]]]] = {
    d: {name: {k: tuple(c.name for c in cs) for k, cs in jt.particle.items()}
        for name, jt in types.items() if jt.particle}
    for d, types in joint_types.TYPES.items()}
"""Reaction components of a joint with a particle at an end: a pin (joint point at the
particle) holds its position, a link (joint point away from it) its distance (and, for a
spatial revolute, its plane ⟂ the axis: Fz); no moments (a particle has no orientation)."""

AXIS_REQUIRED = {
    d: {name for name, jt in types.items() if (p := jt.param("axis")) and p.required}
    for d, types in joint_types.TYPES.items()}
"""Joint types that need an `axis` (universal also needs `axis2`, helical `pitch`). None
in a planar model: a prismatic (or a slot) without one slides along world x (its joint
frame's rule), as the model-file reference says."""

GROUND = "ground"

SIGN_RULE = (
    "the reaction acts on the child as +R at the joint point and on the parent as -R "
    "(Newton's third law); components are along the joint frame axes, which are fixed "
    "to the parent (to the world for ground)"
)

EQUATION = "M vdot + b = Q + G lambda"


AXES = ("joint", "world")
"""The axes reactions are given in: each component along its joint frame (the default),
or each joint's force and moment on its child in world axes (`mbody.equations.world`)."""


def check_axes(axes: str) -> None:
    """Refuse anything but one of `AXES` (an `MbodyError`)."""
    if axes not in AXES:
        raise MbodyError(f"axes must be 'joint' or 'world', got {axes!r}")


def coordinate_labels(names: list[str], dimension: int) -> list[str]:
    """Row labels in stacking order: ``plate.x, plate.y, plate.theta, ...``."""
    rows = PLANAR_ROWS if dimension == PLANAR else SPATIAL_ROWS
    return [f"{n}.{r}" for n in names for r in rows]


def rows_per_body(dimension: int) -> int:
    return 3 if dimension == PLANAR else 6


def conventions(dimension: int) -> dict[str, object]:
    """The conventions as data, repeated in every export."""
    planar = dimension == PLANAR
    return {
        "equation": EQUATION,
        "dimension": dimension,
        "units": "SI (kg, m, s, N, N m, rad)",
        "rows_per_body": rows_per_body(dimension),
        "row_order": list(PLANAR_ROWS if planar else SPATIAL_ROWS),
        "newton_rows": "m a_G, mass-centre acceleration in world axes",
        "euler_rows": ("I_G alpha about the mass centre (world z)" if planar else
                       "J omega_dot + omega x (J omega), body axes, about the mass centre"),
        "b": "gyroscopic vector: 0 on Newton rows, omega x (J omega) on Euler rows",
        "Q": "applied forces (world axes) and their moments about the mass centre "
             "(body axes), gravity and springs included",
        "G": "one column per reaction unknown; G lambda is what the reactions put into each "
             "body's rows; G^T v is the relative velocity each joint forbids",
        "reaction_sign": SIGN_RULE,
        "orientation": "planar: angle theta about world z; spatial: unit quaternion "
                       "[w, x, y, z] (w first) of the body-to-world rotation W_R_B",
        "angular_velocity": "planar: theta_dot; spatial: components along body axes",
    }

APPLIED, GRAVITY, REACTION = "applied", "gravity", "reaction"
"""The kinds of force on a free body (`ForceOnBody.kind`): an applied load, the body's
weight, a joint reaction."""
