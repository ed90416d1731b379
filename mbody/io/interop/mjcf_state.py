"""The state an MJCF model is read in: every joint at its reference position (MuJoCo's
``qpos0``) at rest, or a ``<keyframe>``'s ``<key>`` (by name or index) with its ``qpos``
and ``qvel``."""

from __future__ import annotations

import numpy as np

from mbody.errors import Issue, ModelError, did_you_mean
from mbody.io.interop.mjcf_compiler import Compiler
from mbody.io.interop.tree import NV, TreeBody, joint_order, qpos0
from mbody.io.interop.xmlsource import Element


def state(r: Compiler, root: Element, bodies: list[TreeBody], keyframe: str | None
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(qpos, qvel, qpos0)`` of the tree `bodies`: at `keyframe`, or at rest at qpos0.
    Problems are reported in `r`'s issues."""
    q0 = qpos0(bodies)
    nv = sum(NV[j.type] for _, j in joint_order(bodies))
    for kf in root.findall("keyframe"):  # every key is checked, as MuJoCo checks them
        for k in kf.findall("key"):
            values(r, k, q0, nv)
    if r.issues:
        raise ModelError(r.issues)
    qpos, qvel = q0.copy(), np.zeros(nv)
    if keyframe is not None:
        qpos, qvel = key(r, root, keyframe, q0, nv)
    return qpos, qvel, q0


def values(r: Compiler, k: Element, q0: np.ndarray, nv: int) -> tuple[np.ndarray, np.ndarray]:
    """``(qpos, qvel)`` of the ``<key>`` `k` (the reference pose and rest where it gives
    none); wrong numbers or counts are reported in `r`'s issues."""
    qpos = r.attr(k, k.attrib, "qpos", None, q0.copy())
    qvel = r.attr(k, k.attrib, "qvel", None, np.zeros(nv))
    r.attr(k, k.attrib, "time", 1)
    if len(qpos) != len(q0):
        r.fail(k, f"qpos has {len(qpos)} numbers; the model has {len(q0)} joint "
               "coordinates", attr="qpos")
    if len(qvel) != nv:
        r.fail(k, f"qvel has {len(qvel)} numbers; the model has {nv} joint rates",
               attr="qvel")
    return qpos, qvel


def key(r: Compiler, root: Element, keyframe: str, q0: np.ndarray, nv: int
        ) -> tuple[np.ndarray, np.ndarray]:
    """``(qpos, qvel)`` of the ``<key>`` named (or numbered) `keyframe`."""
    keys = [k for kf in root.findall("keyframe") for k in kf.findall("key")]
    names = [k.get("name") or str(i) for i, k in enumerate(keys)]
    if keyframe in names:
        k = keys[names.index(keyframe)]
    elif _index(keyframe) < len(keys):
        k = keys[_index(keyframe)]
    else:
        shown = keyframe if len(keyframe) <= 40 else keyframe[:40] + "..."
        hint = did_you_mean(keyframe, names) or (
            f"the file has: {', '.join(names)}" if names else "the file has no keyframe")
        raise ModelError([Issue(r.file, 0, 0, "keyframe",
                                f"no keyframe named '{shown}'", hint)])
    qpos, qvel = values(r, k, q0, nv)
    if r.issues:
        raise ModelError(r.issues)
    return qpos, qvel



def _index(text: str) -> int:
    """`text` read as a key's index (0-based, ASCII digits), or a number past any key."""
    digits = text.lstrip("0") or "0"
    if text.isascii() and text.isdigit() and len(digits) <= 9:
        return int(digits)
    return 10**9
