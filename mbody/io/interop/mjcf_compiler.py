"""How a value in an MJCF file is read: ``<compiler>``'s settings (``angle``,
``eulerseq``, and the mass options `mbody.io.interop.mjcf_geoms` applies), numbers at
their element's line, an element's attributes over its ``<default>`` class's, and a frame's
orientation in any of MJCF's five forms (``quat``, ``axisangle``, ``euler``, ``xyaxes``,
``zaxis``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mbody.equations.spatial import axis_angle_quat, matrix_to_quat, quat_mul
from mbody.errors import Issue, did_you_mean
from mbody.io.interop.mjcf_defaults import Defaults
from mbody.io.interop.tree import unit
from mbody.io.interop.xmlsource import Element


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
                lo: int = 0) -> np.ndarray | None:
        if value is None:
            return None
        try:
            x = np.array([float(t) for t in value.split()])
        except ValueError:
            bad = next(t for t in value.split() if not _is_float(t))
            self.fail(e, f"'{bad}' is not a number", "values are decimal numbers separated "
                      "by spaces, such as \"0 0 1\"", attr)
            return None
        if not np.all(np.isfinite(x)):
            self.fail(e, "expected finite numbers", attr=attr)
            return None
        if n is not None and not (lo or n) <= len(x) <= n:
            want = f"{n}" if not lo else f"{lo} to {n}"
            self.fail(e, f"expected {want} number{'s' if n > 1 else ''}, got {len(x)}",
                      attr=attr)
            return None
        return x

    def attr(self, e: Element, values: dict[str, str], name: str, n: int | None = None,
             default: Any = None, lo: int = 0) -> Any:
        x = self.numbers(e, name, values.get(name), n, lo)
        return default if x is None else x

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
        g = self.attr(c, c.attrib, "inertiagrouprange", 2)
        if g is not None:
            self.groups = (int(g[0]), int(g[1]))
        for k in ("boundmass", "boundinertia", "settotalmass"):
            v = self.attr(c, c.attrib, k, 1)
            if v is not None:
                setattr(self, k, float(v[0]))
        if c.get("coordinate", "local") != "local":
            self.fail(c, "coordinate='global' is not read (MuJoCo itself dropped it)",
                      "write every frame relative to its parent", "coordinate")
        if c.get("balanceinertia") == "true":
            self.note("compiler options", "balanceinertia")

    def values(self, e: Element, childclass: str | None) -> dict[str, str]:
        """The element's attributes over its default class's."""
        return self.defaults.values(e, childclass, self.issues)

    def orientation(self, e: Element, values: dict[str, str]) -> np.ndarray:
        """A frame's orientation from whichever of MJCF's five forms is given."""
        forms = [k for k in ("quat", "axisangle", "euler", "xyaxes", "zaxis") if k in values]
        if len(forms) > 1:
            here = [k for k in forms if k in e.attrib] or forms
            self.fail(e, f"the orientation is given twice ({', '.join(forms)})",
                      "give one of quat, axisangle, euler, xyaxes, zaxis", here[-1])
            return np.array([1.0, 0, 0, 0])
        if not forms:
            return np.array([1.0, 0, 0, 0])
        k = forms[0]
        v = self.numbers(e, k, values[k], {"quat": 4, "axisangle": 4, "euler": 3,
                                           "xyaxes": 6, "zaxis": 3}[k])
        if v is None:
            return np.array([1.0, 0, 0, 0])
        if k == "quat":
            if np.linalg.norm(v) < 1e-12:
                self.fail(e, "the quaternion is zero", attr=k)
                return np.array([1.0, 0, 0, 0])
            return unit(v)
        if k == "axisangle":
            if np.linalg.norm(v[:3]) < 1e-12:
                self.fail(e, "the rotation axis is zero", attr=k)
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
                self.fail(e, "xyaxes: the axes are zero or parallel", attr=k)
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


def _is_float(t: str) -> bool:
    try:
        float(t)
    except ValueError:
        return False
    return True

