"""The mass and inertia of a body as MuJoCo computes them: from its ``<inertial>``, or
from its geoms (sphere, capsule, cylinder, box, ellipsoid; ``fromto``; ``mass`` or
``density``; ``inertiagrouprange``), then ``boundmass``, ``boundinertia`` and
``settotalmass``; and a body's drawing shape, its largest geom's."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mbody.equations.spatial import quat_to_matrix
from mbody.errors import did_you_mean
from mbody.io.interop.mjcf_compiler import Compiler, z_to_quat
from mbody.io.interop.tree import TreeBody
from mbody.io.interop.xmlsource import Element

MIN_MASS = 1e-15
"""A body with less mass than this has none (MuJoCo's mjMINVAL is 1e-15)."""
GEOM_TYPES = ("plane", "hfield", "sphere", "capsule", "ellipsoid", "cylinder", "box",
              "mesh", "sdf")


class Geoms(Compiler):
    """The mass readers of the MJCF reader (`mbody.io.interop.mjcf` builds on them): a
    body's mass, mass centre and inertia, its drawing shape, the compiler's bounds."""

    def mass(self, b: TreeBody, e: Element, childclass: str | None) -> None:
        inertial = e.find("inertial")
        if inertial is not None and self.inertiafromgeom != "true":
            v = inertial.attrib
            m = self.attr(inertial, v, "mass", 1)
            if m is None:
                self.fail(inertial, "an <inertial> needs a 'mass'")
                return
            b.mass = float(m[0])
            b.com = self.attr(inertial, v, "pos", 3, np.zeros(3))
            b.R_inertia = quat_to_matrix(self.orientation(inertial, v))
            b.mass_element = inertial
            if "diaginertia" in v:
                b.inertia = np.diag(self.attr(inertial, v, "diaginertia", 3, np.zeros(3)))
            elif "fullinertia" in v:
                f = self.attr(inertial, v, "fullinertia", 6, np.zeros(6))
                b.inertia = np.array([[f[0], f[3], f[4]], [f[3], f[1], f[5]],
                                      [f[4], f[5], f[2]]])
            else:
                self.fail(inertial, "an <inertial> needs 'diaginertia' or 'fullinertia'")
            b.shape = self.shape(e, childclass)
            return
        if self.inertiafromgeom == "false":
            b.shape = self.shape(e, childclass)
            return
        self.geom_mass(b, e, childclass)

    def geoms(self, e: Element, childclass: str | None) -> list[tuple[Element, dict]]:
        return [(g, self.values(g, childclass)) for g in e.findall("geom")]

    def geom_frame(self, g: Element, v: dict[str, str]
                   ) -> tuple[str, np.ndarray, np.ndarray, np.ndarray] | None:
        """(type, size, position, quaternion) of a geom in its body's frame."""
        typ = v.get("type", "sphere")
        if typ not in GEOM_TYPES:
            self.fail(g, f"unknown geom type '{typ}'", did_you_mean(typ, GEOM_TYPES) or
                      f"expected one of: {', '.join(GEOM_TYPES)}", "type")
            return None
        size = self.attr(g, v, "size", 3, np.zeros(3), lo=1)
        size = np.concatenate([size, np.zeros(3 - len(size))])
        ft = self.attr(g, v, "fromto", 6)
        if ft is not None and typ in ("capsule", "cylinder", "box", "ellipsoid"):
            a, c = ft[:3], ft[3:]
            d = c - a
            if np.linalg.norm(d) < 1e-12:
                self.fail(g, "fromto: the two ends coincide", attr="fromto")
                return None
            half = float(np.linalg.norm(d)) / 2
            size = size.copy()
            if typ in ("capsule", "cylinder"):
                size[1] = half
            else:
                size[2] = half
                if size[1] == 0:
                    size[1] = size[0]
            return typ, size, (a + c) / 2, z_to_quat(d)
        pos = self.attr(g, v, "pos", 3, np.zeros(3))
        return typ, size, pos, self.orientation(g, v)

    def geom_mass(self, b: TreeBody, e: Element, childclass: str | None) -> None:
        parts = []
        for g, v in self.geoms(e, childclass):
            group = int(float(v.get("group", "0")))
            if not self.groups[0] <= group <= self.groups[1]:
                continue
            seen = len(self.issues)
            frame = self.geom_frame(g, v)
            if frame is None or len(self.issues) > seen:
                continue  # its size or frame is already reported: no second message
            typ, size, pos, quat = frame
            given = self.attr(g, v, "mass", 1)
            if given is not None and float(given[0]) == 0:
                continue
            if typ in ("mesh", "sdf", "hfield", "plane"):
                if typ == "plane" or (typ == "hfield" and given is None):
                    continue
                self.fail(g, f"body '{b.name}' takes its mass from a {typ} geom "
                          f"('{g.get('name') or g.get('mesh') or typ}'): mbody does not "
                          "read meshes", "give the body an <inertial> with its mass and "
                          "inertia", "type" if "type" in g.attrib else None)
                continue
            if v.get("shellinertia") == "true":
                self.fail(g, "shellinertia is not read: the geom's inertia would be a "
                          "solid's", "give the body an <inertial>", "shellinertia")
                continue
            vol, I_unit = solid(typ, size)
            if vol <= 0:
                self.fail(g, f"the {typ} geom has no volume (its size is zero)",
                          attr="size")
                continue
            m = float(given[0]) if given is not None else float(
                self.attr(g, v, "density", 1, np.array([1000.0]))[0]) * vol
            R = quat_to_matrix(quat)
            parts.append((m, pos, R @ np.diag(I_unit * m) @ R.T, g))
        b.shape = self.shape(e, childclass)
        if not parts:
            return
        m = sum(p[0] for p in parts)
        if m <= MIN_MASS:
            return
        c = np.sum([p[0] * p[1] for p in parts], axis=0) / m
        J = np.zeros((3, 3))
        for mi, pi, Ji, _ in parts:
            d = pi - c
            J += Ji + mi * (float(d @ d) * np.eye(3) - np.outer(d, d))
        b.mass, b.com, b.inertia = m, c, J
        b.mass_element = parts[0][3]

    def shape(self, e: Element, childclass: str | None) -> dict[str, Any] | None:
        """The drawing shape of a body: its largest geom's, as an mbody shape."""
        best: tuple[float, dict[str, Any]] | None = None
        for g, v in self.geoms(e, childclass):
            issues = len(self.issues)
            frame = self.geom_frame(g, v)
            del self.issues[issues:]  # reported once, by geom_mass when it matters
            if frame is None:
                continue
            typ, s, _, _ = frame
            vol, _ = solid(typ, s) if typ in ("sphere", "capsule", "cylinder", "box",
                                              "ellipsoid") else (0.0, None)
            if vol <= 0:
                continue
            shape: dict[str, Any]
            if typ == "sphere":
                shape = {"sphere": {"radius": float(s[0])}}
            elif typ == "capsule":
                shape = {"cylinder": {"radius": float(s[0]),
                                      "length": float(2 * s[1] + 2 * s[0])}}
            elif typ == "cylinder":
                shape = {"cylinder": {"radius": float(s[0]), "length": float(2 * s[1])}}
            elif typ == "box":
                shape = {"box": [float(2 * x) for x in s]}
            else:
                shape = {"ellipsoid": [float(x) for x in s]}
            if best is None or vol > best[0]:
                best = (vol, shape)
        return best[1] if best else None

    def bound_masses(self, bodies: list[TreeBody]) -> None:
        for b in bodies:
            if self.boundmass > 0 and b.mass < self.boundmass and (b.mass > 0 or b.joints):
                b.mass = self.boundmass
            if self.boundinertia > 0 and b.mass > 0:
                w, V = np.linalg.eigh(b.inertia)
                b.inertia = V @ np.diag(np.maximum(w, self.boundinertia)) @ V.T
        if self.settotalmass > 0:
            total = sum(b.mass for b in bodies)
            if total > 0:
                k = self.settotalmass / total
                for b in bodies:
                    b.mass *= k
                    b.inertia = b.inertia * k


def solid(typ: str, size: np.ndarray) -> tuple[float, np.ndarray]:
    """Volume and principal inertia per unit mass of a uniform solid geom, MuJoCo's sizes
    (half-lengths, radii), about its centre in the geom's axes."""
    s = size
    if typ == "sphere":
        r = s[0]
        return 4 / 3 * math.pi * r ** 3, np.full(3, 0.4 * r * r)
    if typ == "capsule":
        r, h = s[0], 2 * s[1]
        vol = math.pi * r * r * h + 4 / 3 * math.pi * r ** 3
        if vol <= 0:
            return 0.0, np.zeros(3)
        ms = (4 / 3 * math.pi * r ** 3) / vol  # the two hemispheres' share
        mc = 1 - ms
        side = mc * (3 * r * r + h * h) / 12 + ms * (0.4 * r * r + h * (3 * r + 2 * h) / 8)
        return vol, np.array([side, side, mc * r * r / 2 + ms * 0.4 * r * r])
    if typ == "cylinder":
        r, h = s[0], 2 * s[1]
        return math.pi * r * r * h, np.array([(3 * r * r + h * h) / 12] * 2 + [r * r / 2])
    if typ == "ellipsoid":
        a, b, c = s
        return 4 / 3 * math.pi * a * b * c, np.array([b * b + c * c, a * a + c * c,
                                                      a * a + b * b]) / 5
    if typ == "box":
        a, b, c = 2 * s
        return a * b * c, np.array([b * b + c * c, a * a + c * c, a * a + b * b]) / 12
    return 0.0, np.zeros(3)
