"""Helical (screw) joint: the child turns about `axis` and advances along it by
pitch / 2π per radian (a positive pitch is a right-handed screw).

Its axial component `Wz` is a wrench: a force Wz along the joint z axis on the child at
the joint point together with the moment −(pitch / 2π) Wz about that axis, the pair that
does no work on the screw's one motion (F v + M ω = Wz (h − h) ω = 0, h = pitch / 2π).
"""

from mbody.joint_types.base import (
    ROTATION,
    SCREW,
    SPATIAL,
    WRENCH,
    Component,
    JointType,
    Motion,
    Param,
    force,
    tilt,
)

ORDER = 7
"""Its place in listings (messages, docs tables)."""

SPATIAL_TYPE = JointType(
    name="helical", dimension=SPATIAL,
    summary="a screw: the child turns about `axis` and advances along it by `pitch` per turn",
    components=(force(0), force(1), tilt(0), tilt(1),
                Component("Wz", WRENCH, SCREW, 2,
                          "axial wrench: force Wz along the joint z axis with the moment "
                          "-(pitch/2 pi) Wz about it")),
    motions=(Motion("angle", ROTATION, 2),),
    params=(Param("axis", "direction", True, "the screw's axis"),
            Param("pitch", "length", True,
                  "the advance per turn along the axis (m; positive: right-handed)")),
    aliases=("screw",))
