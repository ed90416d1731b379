"""Fixed joint: the child is welded to the parent."""

from mbody.joint_types.base import PLANAR, SPATIAL, JointType, Param, force, lock

ORDER = 6
"""Its place in listings (messages, docs tables)."""

ALIASES = ("weld",)
AXIS = Param("axis", "direction", False, "the joint frame (the reaction components' directions)")

PLANAR_TYPE = JointType(
    name="fixed", dimension=PLANAR, summary="the child is welded to the parent",
    components=(force(0), force(1), lock(2)), motions=(), params=(AXIS,),
    aliases=ALIASES, mjcf_loop="weld")

SPATIAL_TYPE = JointType(
    name="fixed", dimension=SPATIAL, summary="the child is welded to the parent",
    components=(force(0), force(1), force(2), lock(0), lock(1), lock(2)), motions=(),
    params=(AXIS,), aliases=ALIASES, mjcf_loop="weld")
