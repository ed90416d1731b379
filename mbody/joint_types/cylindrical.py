"""Cylindrical joint: the child turns about and slides along one axis."""

from mbody.joint_types.base import (
    ROTATION,
    SPATIAL,
    TRANSLATION,
    JointType,
    Motion,
    Param,
    force,
    tilt,
)

ORDER = 3
"""Its place in listings (messages, docs tables)."""

SPATIAL_TYPE = JointType(
    name="cylindrical", dimension=SPATIAL,
    summary="the child turns about and slides along `axis`",
    components=(force(0), force(1), tilt(0), tilt(1)),
    motions=(Motion("displacement", TRANSLATION, 2, part="slide"),
             Motion("angle", ROTATION, 2, part="turn")),
    params=(Param("axis", "direction", True, "the axis of rotation and sliding"),))
