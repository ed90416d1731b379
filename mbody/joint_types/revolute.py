"""Revolute joint: the child turns about one axis through the joint point."""

from mbody.joint_types.base import (
    FORCE,
    FORCE_ALONG,
    PLANAR,
    ROTATION,
    SPATIAL,
    TENSION,
    Component,
    JointType,
    Motion,
    Param,
    force,
    tilt,
)

ORDER = 1
"""Its place in listings (messages, docs tables)."""

ALIASES = ("hinge", "pin", "continuous")

PLANAR_TYPE = JointType(
    name="revolute", dimension=PLANAR,
    summary="a pin: the child turns about world z through the joint point",
    components=(force(0), force(1)),
    motions=(Motion("angle", ROTATION, 2),),
    params=(Param("axis", "direction", False,
                  "the joint frame's x axis (the reaction components' directions)"),),
    particle={"pin": (force(0), force(1)), "link": (TENSION,)},
    aliases=ALIASES, mjcf_loop="connect")

SPATIAL_TYPE = JointType(
    name="revolute", dimension=SPATIAL,
    summary="the child turns about `axis` through the joint point",
    components=(force(0), force(1), force(2), tilt(0), tilt(1)),
    motions=(Motion("angle", ROTATION, 2),),
    params=(Param("axis", "direction", True, "the rotation axis"),),
    particle={"pin": (force(0), force(1), force(2)),
              "link": (TENSION, Component("Fz", FORCE, FORCE_ALONG, 2,
                                          "force along the joint z axis (keeps the particle "
                                          "in the plane across the axis)"))},
    aliases=ALIASES, mjcf_loop="connect")
