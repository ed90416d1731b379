"""Universal (Hooke, Cardan) joint: two rotations about perpendicular axes, `axis` fixed
in the parent and `axis2` in the child."""

from mbody.joint_types.base import (
    MOMENT,
    RIGHT_ANGLE,
    ROTATION,
    SPATIAL,
    Component,
    JointType,
    Motion,
    Param,
    force,
)

ORDER = 4
"""Its place in listings (messages, docs tables)."""

SPATIAL_TYPE = JointType(
    name="universal", dimension=SPATIAL,
    summary="the child turns about `axis` (on the parent) and `axis2` (on the child), "
            "which stay perpendicular",
    components=(force(0), force(1), force(2),
                Component("Mt", MOMENT, RIGHT_ANGLE, 2,
                          "moment about axis x axis2 (keeps the two axes perpendicular)")),
    motions=(Motion("angle1", ROTATION, 2, part="1"),
             Motion("angle2", ROTATION, 2, on="child", part="2")),
    params=(Param("axis", "direction", True, "the first rotation axis, fixed in the parent"),
            Param("axis2", "direction", True,
                  "the second rotation axis, fixed in the child, perpendicular to axis")),
    aliases=("cardan", "hooke"))
