"""Spherical (ball) joint: the child turns freely about the joint point."""

from mbody.joint_types.base import BALL, SPATIAL, TENSION, JointType, Motion, Param, force

ORDER = 5
"""Its place in listings (messages, docs tables)."""

SPATIAL_TYPE = JointType(
    name="spherical", dimension=SPATIAL,
    summary="a ball joint: the child turns freely about the joint point",
    components=(force(0), force(1), force(2)),
    motions=(Motion("rotation", BALL, -1),),
    params=(Param("axis", "direction", False,
                  "the joint frame's z axis (the reaction components' directions)"),),
    particle={"pin": (force(0), force(1), force(2)), "link": (TENSION,)},
    aliases=("ball",), mjcf_loop="connect")
