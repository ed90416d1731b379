"""The state an MJCF model is read in: a ``<keyframe>``'s ``<key>`` (by name or index)
with its ``qpos`` and ``qvel``; when none is named, the key ``initial`` if the file has
one (the file's state, as mbody's export writes it), else every joint at its reference
position (MuJoCo's ``qpos0``) at rest. This is the one place that default is decided:
`mbody.load`, every command and ``mbody convert`` read MJCF through it."""

from __future__ import annotations

import numpy as np

from mbody.errors import Issue, ModelError, did_you_mean, option_name
from mbody.io.interop.mjcf_compiler import Compiler
from mbody.io.interop.tree import NV, TreeBody, joint_order, qpos0
from mbody.io.interop.xmlsource import Element

INITIAL = "initial"
"""The key read when no keyframe is named: mbody's MJCF export writes the model's state
as the key of this name, so that a file it wrote reads back in the same state."""


def chosen(root: Element, keyframe: str | None) -> str | None:
    """The keyframe the state is read at: `keyframe` when given, else `INITIAL` when the
    file has a key of that name, else None (the reference pose at rest)."""
    if keyframe is not None:
        return keyframe
    return INITIAL if INITIAL in _keys(root)[1] else None


def described(root: Element, keyframe: str | None) -> str:
    """The state read at `keyframe` (`chosen`'s answer) in words, for a model's
    description: which state a command's numbers are at. A key given by its index is
    named by its name when it has one."""
    if keyframe is None:
        return "at the reference pose, at rest"
    keys, names = _keys(root)
    if keyframe not in names and _index(keyframe) < len(keys):
        keyframe = names[_index(keyframe)]
    return f"at the keyframe '{keyframe if len(keyframe) <= 40 else keyframe[:40] + '...'}'"


def state(r: Compiler, root: Element, bodies: list[TreeBody], keyframe: str | None
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(qpos, qvel, qpos0)`` of the tree `bodies`: at `keyframe`, or at rest at qpos0
    when it is None (`chosen` picks the default). Problems are reported in `r`'s
    issues."""
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
    keys, names = _keys(root)
    if keyframe in names:
        k = keys[names.index(keyframe)]
    elif _index(keyframe) < len(keys):
        k = keys[_index(keyframe)]
    else:
        shown = keyframe if len(keyframe) <= 40 else keyframe[:40] + "..."
        hint = did_you_mean(keyframe, names) or (
            f"the file has: {', '.join(names)}" if names else "the file has no keyframe")
        raise ModelError([Issue(r.file, 0, 0, option_name("keyframe"),
                                f"no keyframe named '{shown}'", hint)])
    qpos, qvel = values(r, k, q0, nv)
    if r.issues:
        raise ModelError(r.issues)
    return qpos, qvel



def _keys(root: Element) -> tuple[list[Element], list[str]]:
    """Every ``<key>`` of the file, and its name (its index when it has none)."""
    keys = [k for kf in root.findall("keyframe") for k in kf.findall("key")]
    return keys, [k.get("name") or str(i) for i, k in enumerate(keys)]


def _index(text: str) -> int:
    """`text` read as a key's index (0-based, ASCII digits), or a number past any key."""
    digits = text.lstrip("0") or "0"
    if text.isascii() and text.isdigit() and len(digits) <= 9:
        return int(digits)
    return 10**9
