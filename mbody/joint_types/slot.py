"""Pin-in-slot (planar): a point of the child slides along a line fixed in the parent (the
line through the joint point along `axis`), the child turning freely."""

from mbody.joint_types.base import PLANAR, ROTATION, TRANSLATION, JointType, Motion, Param, force

ORDER = 8
"""Its place in listings (messages, docs tables)."""

PLANAR_TYPE = JointType(
    name="slot", dimension=PLANAR,
    summary="a pin in a slot: the child's pin slides along `axis` (default world x) and "
            "turns freely",
    components=(force(1),),
    motions=(Motion("displacement", TRANSLATION, 0, part="slide"),
             Motion("angle", ROTATION, 2, part="turn")),
    params=(Param("axis", "direction", False, "the slot's direction", (1.0, 0.0, 0.0)),),
    aliases=("pin-in-slot", "pin_slot"))
