"""Prismatic joint: the child slides along one axis without turning."""

from mbody.joint_types.base import (
    PLANAR,
    SPATIAL,
    TRANSLATION,
    JointType,
    Motion,
    Param,
    force,
    lock,
)

ORDER = 2
"""Its place in listings (messages, docs tables)."""

ALIASES = ("slide", "slider")

PLANAR_TYPE = JointType(
    name="prismatic", dimension=PLANAR,
    summary="a slider: the child slides along `axis` (default world x) without turning",
    components=(force(1), lock(2)),
    motions=(Motion("displacement", TRANSLATION, 0),),
    params=(Param("axis", "direction", False, "the slide direction", (1.0, 0.0, 0.0)),),
    aliases=ALIASES)

SPATIAL_TYPE = JointType(
    name="prismatic", dimension=SPATIAL,
    summary="the child slides along `axis` without turning",
    components=(force(0), force(1), lock(0), lock(1), lock(2)),
    motions=(Motion("displacement", TRANSLATION, 2),),
    params=(Param("axis", "direction", True, "the slide direction"),),
    aliases=ALIASES)
