"""How a value in an MJCF file is read: ``<compiler>``'s settings (``angle``,
``eulerseq``, and the mass options `mbody.io.interop.mjcf_geoms` applies), numbers at
their element's line, an element's attributes over its ``<default>`` class's, and a frame's
orientation in any of MJCF's five forms (``quat``, ``axisangle``, ``euler``, ``xyaxes``,
``zaxis``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mbody.errors import Issue, did_you_mean
from mbody.io.interop.attrvalues import BOOLEAN, read_keyword, read_numbers, split
from mbody.io.interop.mjcf_defaults import ORIENTATIONS, Defaults, Values
from mbody.io.interop.tree import unit
from mbody.io.interop.xmlsource import Element
from mbody.util.spatial import axis_angle_quat, matrix_to_quat, quat_mul


class Compiler:
    """The reader's base: the file's name, the issues and notes found so far, the
    ``<compiler>`` settings, the ``<default>`` classes, and the readers of values."""

    def __init__(self, file: str):
        self.file = file
        self.issues: list[Issue] = []
        self.notes: dict[str, list[str]] = {}
        self.angle_scale = math.pi / 180
        self.eulerseq = "xyz"
        self.inertiafromgeom = "auto"
        self.groups = (0, 5)
        self.boundmass = 0.0
        self.boundinertia = 0.0
        self.settotalmass = -1.0
        self.defaults = Defaults()

    def note(self, what: str, item: str) -> None:
        self.notes.setdefault(what, []).append(item)

    def fail(self, e: Element, message: str, hint: str = "", attr: str | None = None
             ) -> None:
        self.issues.append(e.issue(message, hint, attr))

    def numbers(self, e: Element, attr: str, value: str | None, n: int | None = None,
                lo: int = 0, integer: bool = False) -> np.ndarray | None:
        """The numbers of `value` (attribute `attr` of `e`): `n` of them, or `lo` to `n`;
        None when the value is absent or empty (as MuJoCo reads it) or wrong (reported)."""
        if value is None or not split(value):
            return None
        return read_numbers(e, attr, value, self.issues, count=n, least=lo or n,
                            integer=integer, hexadecimal=True)

    @staticmethod
    def at(e: Element, values: dict[str, str], name: str) -> Element:
        """The element where attribute `name` of `e` was written (`e`, or its class's)."""
        where = values.origin(name) if isinstance(values, Values) else None
        return where or e

    def attr(self, e: Element, values: dict[str, str], name: str, n: int | None = None,
             default: Any = None, lo: int = 0, integer: bool = False) -> Any:
        """The numbers of attribute `name` in `values` (`e`'s, over its class's), read at
        the element where the value was written; `default` when it is not given."""
        x = self.numbers(self.at(e, values, name), name, values.get(name), n, lo, integer)
        return default if x is None else x

    def keyword(self, e: Element, values: dict[str, str], name: str,
                choices: tuple[str, ...], default: str) -> str:
        """The keyword of attribute `name` (one of `choices`, exactly as MuJoCo wants
        it), or `default` when it is not given or wrong (reported)."""
        text = values.get(name)
        if text is None:
            return default
        return read_keyword(self.at(e, values, name), name, text, choices,
                            self.issues) or default

    def compiler(self, c: Element) -> None:
        angle = c.get("angle")
        if angle is not None:
            if angle not in ("degree", "radian"):
                self.fail(c, f"angle must be 'degree' or 'radian', got '{angle}'",
                          did_you_mean(angle, ("degree", "radian")), "angle")
            self.angle_scale = math.pi / 180 if angle == "degree" else 1.0
        seq = c.get("eulerseq")
        if seq is not None:
            if len(seq) != 3 or any(ch not in "xyzXYZ" for ch in seq):
                self.fail(c, f"eulerseq must be three of x, y, z, X, Y, Z, got '{seq}'",
                          "lower case: axes turning with the frame; upper case: fixed axes",
                          "eulerseq")
            else:
                self.eulerseq = seq
        ifg = c.get("inertiafromgeom")
        if ifg is not None:
            if ifg not in ("true", "false", "auto"):
                self.fail(c, f"inertiafromgeom must be true, false or auto, got '{ifg}'",
                          attr="inertiafromgeom")
            self.inertiafromgeom = ifg
        g = self.attr(c, c.attrib, "inertiagrouprange", 2, integer=True)
        if g is not None:
            self.groups = (int(g[0]), int(g[1]))
        for k in ("boundmass", "boundinertia", "settotalmass"):
            v = self.attr(c, c.attrib, k, 1)
            if v is not None:
                setattr(self, k, float(v[0]))
        if self.keyword(c, c.attrib, "coordinate", ("local", "global"), "local") != "local":
            self.fail(c, "coordinate='global' is not read (MuJoCo itself dropped it)",
                      "write every frame relative to its parent", "coordinate")
        if self.keyword(c, c.attrib, "balanceinertia", BOOLEAN, "false") == "true":
            self.note("compiler options", "balanceinertia")

    def values(self, e: Element, childclass: str | None) -> Values:
        """The element's attributes over its default class's."""
        return self.defaults.values(e, childclass, self.issues)

    def orientation(self, e: Element, values: dict[str, str]) -> np.ndarray:
        """A frame's orientation from whichever of MJCF's five forms is given."""
        forms = [k for k in ORIENTATIONS if k in values]  # all from one element
        if len(forms) > 1:
            self.fail(self.at(e, values, forms[-1]), f"the orientation is given twice "
                      f"({', '.join(forms)})", "give one of quat, axisangle, euler, xyaxes, "
                      "zaxis", forms[-1])
            return np.array([1.0, 0, 0, 0])
        if not forms:
            return np.array([1.0, 0, 0, 0])
        k = forms[0]
        v = self.attr(e, values, k, {"quat": 4, "axisangle": 4, "euler": 3, "xyaxes": 6,
                                     "zaxis": 3}[k])
        if v is None:
            return np.array([1.0, 0, 0, 0])
        if k == "quat":
            if np.linalg.norm(v) < 1e-12:
                self.fail(self.at(e, values, k), "the quaternion is zero", attr=k)
                return np.array([1.0, 0, 0, 0])
            return unit(v)
        if k == "axisangle":
            if np.linalg.norm(v[:3]) < 1e-12:
                self.fail(self.at(e, values, k), "the rotation axis is zero", attr=k)
                return np.array([1.0, 0, 0, 0])
            return axis_angle_quat(unit(v[:3]), v[3] * self.angle_scale)
        if k == "euler":
            q = np.array([1.0, 0, 0, 0])
            for ch, a in zip(self.eulerseq, v * self.angle_scale, strict=True):
                r = axis_angle_quat(np.eye(3)["xyz".index(ch.lower())], a)
                q = quat_mul(q, r) if ch.islower() else quat_mul(r, q)
            return q
        if k == "xyaxes":
            x = unit(v[:3])
            y = v[3:] - (v[3:] @ x) * x
            if np.linalg.norm(x) < 1e-12 or np.linalg.norm(y) < 1e-12:
                self.fail(self.at(e, values, k), "xyaxes: the axes are zero or parallel", attr=k)
                return np.array([1.0, 0, 0, 0])
            y = unit(y)
            return matrix_to_quat(np.column_stack((x, y, np.cross(x, y))))
        return z_to_quat(v)


def z_to_quat(v: np.ndarray) -> np.ndarray:
    """The shortest rotation taking the z axis to `v` (MuJoCo's ``zaxis`` and ``fromto``)."""
    v = unit(np.asarray(v, float))
    axis = np.cross([0.0, 0.0, 1.0], v)
    s = float(np.linalg.norm(axis))
    if s < 1e-10:
        axis = np.array([1.0, 0, 0])
    else:
        axis = axis / s
    return axis_angle_quat(axis, math.atan2(s, v[2]))



