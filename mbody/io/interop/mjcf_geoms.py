"""The mass and inertia of a body as MuJoCo computes them: from its ``<inertial>``, or
from its geoms (sphere, capsule, cylinder, ellipsoid, box, height field; ``fromto``;
``mass`` or ``density``; solid or ``shellinertia``; ``inertiagrouprange``), then
``boundmass``, ``boundinertia`` and ``settotalmass``; and a body's drawing shape, its
largest geom's.

Each geom is read and checked once, as MuJoCo's compiler checks it (``mjCGeom::Compile``
in MuJoCo 4.0): its size over its default class's (a shorter ``size`` keeps the class's
trailing numbers), ``fromto`` (a box's or an ellipsoid's cross half-sizes are both
``size[0]``), every size its type uses greater than zero, no ``pos`` beside ``fromto``,
no plane in a moving body; then, for the geoms that give their body its mass, no negative
mass or density, and the geoms MuJoCo leaves out (mass at most ``mjEPS``) left out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mbody.errors import did_you_mean
from mbody.io.interop.attrvalues import BOOLEAN, split
from mbody.io.interop.mjcf_compiler import Compiler, z_to_quat
from mbody.io.interop.mjcf_defaults import Values
from mbody.io.interop.tree import TreeBody
from mbody.io.interop.xmlsource import Element
from mbody.util.spatial import quat_to_matrix

MIN_MASS = 1e-15
"""A body with less mass than this has none (MuJoCo's mjMINVAL is 1e-15)."""
MJ_EPS = 1e-14
"""MuJoCo's mjEPS: a geom of this mass or less is left out of its body's mass, and a
geom whose volume is this or less takes no mass from its ``mass`` attribute."""
GEOM_TYPES = ("plane", "hfield", "sphere", "capsule", "ellipsoid", "cylinder", "box",
              "mesh", "sdf")
SIZES = {"sphere": 1, "capsule": 2, "cylinder": 2, "ellipsoid": 3, "box": 3}
"""The solids mbody computes, and how many of their size numbers they use (MuJoCo's
mjGEOMINFO): each must be greater than zero."""
_SIZE_NAMES = {"sphere": "its radius", "capsule": "its radius and half-length",
               "cylinder": "its radius and half-length", "ellipsoid": "its three radii",
               "box": "its three half-sizes"}
_FROMTO = ("capsule", "cylinder", "ellipsoid", "box")
"""The types ``fromto`` places."""


@dataclass
class Geom:
    """One geom as MuJoCo compiles it: `size` its three numbers after ``fromto`` (half
    lengths, radii), `pos` and `quat` (w first) its frame in its body's."""

    element: Element
    values: Values
    type: str
    size: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    group: int
    mass: float | None
    """Its ``mass`` attribute (None: from its density)."""
    density: float
    shell: bool
    fitted: bool = False
    """Its size is fitted to a mesh (``type="box" mesh="m"``): unknown to mbody."""


class Geoms(Compiler):
    """The mass readers of the MJCF reader (`mbody.io.interop.mjcf` builds on them): a
    body's mass, mass centre and inertia, its drawing shape, the compiler's bounds."""

    def __init__(self, file: str):
        super().__init__(file)
        self._geoms: dict[int, Geom | None] = {}
        self.hfields: dict[str, np.ndarray] = {}
        """Each ``<asset><hfield>``'s size (x and y half-sizes, elevation, base)."""

    def read_hfields(self, root: Element) -> None:
        """The height fields' sizes, which give their geoms' (MuJoCo reads them there)."""
        for a in root.findall("asset"):
            for h in a.findall("hfield"):
                size = self.attr(h, h.attrib, "size", 4)
                if size is not None:
                    self.hfields[h.get("name") or ""] = size

    def mass(self, b: TreeBody, e: Element, childclass: str | None, moving: bool) -> None:
        """`b`'s mass, mass centre and inertia (and drawing shape) from the body `e`;
        `moving`: the body or a body it hangs from has a joint (checks a plane geom)."""
        for g, v in self.geoms(e, childclass):
            geom = self.geom(g, v)
            if geom is not None and geom.type == "plane" and moving:
                self.fail(g, "a plane geom is only allowed in a body that does not move "
                          "(MuJoCo refuses it in a moving body)",
                          "put the plane in <worldbody>", "type" if "type" in g.attrib
                          else None)
        inertial = e.find("inertial")
        b.shape = self.shape(e, childclass)
        if self.inertiafromgeom == "true" or (self.inertiafromgeom == "auto" and
                                               inertial is None):
            self.geom_mass(b, e, childclass)
            if b.mass_element is not None:
                return  # (with inertiafromgeom="true" and no geom of mass, MuJoCo keeps
                # the <inertial>)
        if inertial is not None:
            self.inertial(b, inertial)

    def inertial(self, b: TreeBody, inertial: Element) -> None:
        """`b`'s mass, mass centre and inertia from its ``<inertial>``."""
        iv = inertial.attrib
        m = self.attr(inertial, iv, "mass", 1)
        if m is None:
            self.fail(inertial, "an <inertial> needs a 'mass'")
            return
        b.mass = float(m[0])
        b.com = self.attr(inertial, iv, "pos", 3, np.zeros(3))
        b.R_inertia = quat_to_matrix(self.orientation(inertial, iv))
        b.mass_element = inertial
        if "diaginertia" in iv:
            b.inertia = np.diag(self.attr(inertial, iv, "diaginertia", 3, np.zeros(3)))
        elif "fullinertia" in iv:
            f = self.attr(inertial, iv, "fullinertia", 6, np.zeros(6))
            b.inertia = np.array([[f[0], f[3], f[4]], [f[3], f[1], f[5]],
                                  [f[4], f[5], f[2]]])
        else:
            self.fail(inertial, "an <inertial> needs 'diaginertia' or 'fullinertia'")

    def geoms(self, e: Element, childclass: str | None) -> list[tuple[Element, Values]]:
        return [(g, self.values(g, childclass)) for g in e.findall("geom")]

    def geom(self, g: Element, v: Values) -> Geom | None:
        """The geom `g` (attributes `v`) as MuJoCo compiles it; None when it is wrong
        (reported once, however often it is asked for)."""
        key = id(g)
        if key not in self._geoms:
            self._geoms[key] = self._geom(g, v)
        return self._geoms[key]

    def _geom(self, g: Element, v: Values) -> Geom | None:
        seen = len(self.issues)
        typ = v.get("type", "sphere")
        if typ not in GEOM_TYPES:
            self.fail(self.at(g, v, "type"), f"unknown geom type '{typ}'",
                      did_you_mean(typ, GEOM_TYPES) or
                      f"expected one of: {', '.join(GEOM_TYPES)}", "type")
        size = self.size(g, v)
        ft = self.attr(g, v, "fromto", 6)
        pos = self.attr(g, v, "pos", 3, np.zeros(3))
        quat = self.orientation(g, v)
        group = int(self.attr(g, v, "group", 1, np.zeros(1), integer=True)[0])
        for k in ("contype", "conaffinity"):
            self.attr(g, v, k, 1, integer=True)
        given = self.attr(g, v, "mass", 1)
        density = float(self.attr(g, v, "density", 1, np.array([1000.0]))[0])
        shell = self.keyword(g, v, "shellinertia", BOOLEAN, "false") == "true"
        if len(self.issues) > seen or size is None:
            return None
        if ft is not None:
            if typ not in _FROMTO:
                self.fail(self.at(g, v, "fromto"), f"fromto places a capsule, cylinder, "
                          f"ellipsoid or box, not a {typ}", "give a pos instead", "fromto")
                return None
            if pos.any():
                self.fail(self.at(g, v, "pos"), "a geom with a fromto takes no pos (its "
                          "position is the middle of fromto)", "remove the pos", "pos")
                return None
            a, c = ft[:3], ft[3:]
            half = float(np.linalg.norm(c - a)) / 2
            if half < MJ_EPS:
                self.fail(self.at(g, v, "fromto"), "fromto: the two ends coincide",
                          attr="fromto")
                return None
            size = size.copy()
            size[1] = half
            if typ in ("ellipsoid", "box"):  # MuJoCo: both cross half-sizes are size[0]
                size[1], size[2] = size[0], half
            pos, quat = (a + c) / 2, z_to_quat(c - a)
        fitted = typ in SIZES and "mesh" in v  # MuJoCo fits its size to the mesh
        if typ in SIZES and not fitted and not np.all(size[:SIZES[typ]] > 0):
            n = SIZES[typ]
            given = " ".join(f"{x:g}" for x in size[:n])
            hint = ("give the half-length as a second number, or the ends with fromto"
                    if n == 2 and size[1] == 0 and ft is None else
                    "a shorter size keeps its default class's trailing numbers"
                    if len(v.layers("size")) > 1 else "")
            self.fail(self.at(g, v, "size"), f"a {typ} geom needs {_SIZE_NAMES[typ]} "
                      f"greater than zero; its size is {given}", hint,
                      "size" if "size" in v else None)
            return None
        if typ == "plane" and not size[2] > 0:
            self.fail(self.at(g, v, "size"), "a plane geom's third size (its grid "
                      "spacing) must be greater than zero", attr="size" if "size" in v
                      else None)
            return None
        return Geom(g, v, typ, size, pos, quat, group,
                    None if given is None else float(given[0]), density, shell, fitted)

    def size(self, g: Element, v: Values) -> np.ndarray | None:
        """A geom's three size numbers: each value from its classes down to the geom
        overwrites the numbers it gives and keeps the rest (MuJoCo's rule: a class's
        ``size="0.1 0.2 0.3"`` and a geom's ``size="0.5"`` make ``0.5 0.2 0.3``)."""
        size = np.zeros(3)
        for text, where in v.layers("size"):
            if not split(text):
                continue  # empty: as if not given (MuJoCo)
            x = self.numbers(where, "size", text, 3, lo=1)
            if x is None:
                return None
            size[:len(x)] = x
        return size

    def geom_mass(self, b: TreeBody, e: Element, childclass: str | None) -> None:
        with np.errstate(all="ignore"):  # too large a result is said, not warned about
            self._geom_mass(b, e, childclass)

    def _geom_mass(self, b: TreeBody, e: Element, childclass: str | None) -> None:
        parts = []
        for g, v in self.geoms(e, childclass):
            geom = self.geom(g, v)
            if geom is None or not self.groups[0] <= geom.group <= self.groups[1]:
                continue
            part = self.geom_part(b, geom)
            if part is not None:
                parts.append(part)
        if not parts:
            return
        m = sum(p[0] for p in parts)
        c = np.sum([p[0] * p[1] for p in parts], axis=0) / m
        J = np.zeros((3, 3))
        for mi, pi, Ji, _ in parts:
            d = pi - c
            J += Ji + mi * (float(d @ d) * np.eye(3) - np.outer(d, d))
        b.mass_element = parts[0][3]
        if not (math.isfinite(m) and np.all(np.isfinite(c)) and np.all(np.isfinite(J))):
            self.fail(parts[0][3], f"the mass or inertia of body '{b.name}' is too large to "
                      "compute (beyond 1.8e308)", "check its geoms' sizes, masses and "
                      "densities")
            return
        b.mass, b.com, b.inertia = m, c, J

    def geom_part(self, b: TreeBody, geom: Geom
                  ) -> tuple[float, np.ndarray, np.ndarray, Element] | None:
        """(mass, position, inertia tensor about its centre in body axes, element) of
        one geom that gives its body mass, as MuJoCo computes it; None when it gives
        none (a plane, mass or density 0, a mass of mjEPS or less)."""
        g, v, typ = geom.element, geom.values, geom.type
        given, density = geom.mass, geom.density
        if (given is not None and given < 0) or density < 0:
            which = "mass" if given is not None and given < 0 else "density"
            self.fail(self.at(g, v, which), f"the geom's {which} is negative", attr=which)
            return None
        if (given == 0 if given is not None else density == 0) or typ == "plane":
            return None
        name = g.get("name") or g.get("mesh") or typ
        if typ in ("mesh", "sdf") or geom.fitted:
            fitted = f"its size is fitted to mesh '{v.get('mesh')}'; " if geom.fitted \
                else ""
            self.fail(g, f"body '{b.name}' takes its mass from a {typ} geom ('{name}'): "
                      f"{fitted}mbody does not read meshes", "give the body an <inertial> "
                      "with its mass and inertia", "type" if "type" in g.attrib else None)
            return None
        size = geom.size
        if typ == "hfield":
            h = self.hfields.get(v.get("hfield") or "")
            if h is None:
                self.fail(g, f"the hfield geom '{name}' names no <hfield> asset",
                          attr="hfield" if "hfield" in v else None)
                return None
            size = np.array([h[0], h[1], 0.25 * h[2] + 0.5 * h[3]])
        kind = "box" if typ == "hfield" else typ
        vol, _ = solid(kind, size, geom.shell)
        if given is not None:
            if vol <= MJ_EPS:
                return None  # MuJoCo gives it no mass
            m = given
        else:
            m = density * vol
        if not m > MJ_EPS:
            return None
        R = quat_to_matrix(geom.quat)
        J = R @ np.diag(solid(kind, size, geom.shell, m)[1]) @ R.T
        if not (math.isfinite(m) and np.all(np.isfinite(J))):
            self.fail(g, f"the mass or inertia of geom '{name}' is too large to compute "
                      "(beyond 1.8e308)", "check its size, mass and density")
            return None
        return m, geom.pos, J, g

    def shape(self, e: Element, childclass: str | None) -> dict[str, Any] | None:
        """The drawing shape of a body: its largest geom's, as an mbody shape."""
        best: tuple[float, dict[str, Any]] | None = None
        for g, v in self.geoms(e, childclass):
            geom = self.geom(g, v)
            if geom is None or geom.type not in SIZES or geom.fitted:
                continue
            typ, s = geom.type, geom.size
            with np.errstate(all="ignore"):
                vol, _ = solid(typ, s)
            if not 0 < vol < math.inf:
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
        if self.settotalmass > 0:  # MuJoCo's mj_setTotalmass, its scale bounded below
            total = sum(b.mass for b in bodies)
            k = max(MIN_MASS, self.settotalmass / max(MIN_MASS, total))
            for b in bodies:
                b.mass *= k
                b.inertia = b.inertia * k


def solid(typ: str, size: np.ndarray, shell: bool = False, mass: float = 1.0
          ) -> tuple[float, np.ndarray]:
    """Volume (a shell: its area) and principal inertia of a uniform geom of `mass`
    (default: per unit mass), MuJoCo's sizes (half-lengths, radii), about its centre in
    the geom's axes: MuJoCo's formulas (``mjCGeom::GetVolume`` and ``SetInertia``)."""
    vol, inertia = _solid(typ, np.asarray(size, dtype=float), shell, mass)
    return vol, inertia if typ == "ellipsoid" and shell else inertia * mass


def _solid(typ: str, s: np.ndarray, shell: bool, mass: float) -> tuple[float, np.ndarray]:
    pi = math.pi
    if typ == "sphere":
        r = s[0]
        if shell:
            return 4 * pi * r * r, np.full(3, 2 * r * r / 3)
        return 4 / 3 * pi * r * r * r, np.full(3, 0.4 * r * r)
    if typ == "capsule":
        r, hh, h = s[0], s[1], 2 * s[1]
        if shell:
            a_sphere, a_side = 4 * pi * r * r, 2 * pi * r * h
            if a_sphere + a_side <= 0:
                return 0.0, np.zeros(3)
            ms = a_sphere / (a_sphere + a_side)  # the two hemispheres' share
            mc = 1 - ms
            com = r / 2  # a hemispherical shell's centre, from its flat face
            side = (mc * (6 * r * r + h * h) / 12 + 2 * ms * r * r / 3
                    + ms * ((hh + com) ** 2 - com * com))
            return a_sphere + a_side, np.array([side, side, mc * r * r + 2 * ms * r * r / 3])
        vol = pi * r * r * h + 4 / 3 * pi * r * r * r
        if vol <= 0:
            return 0.0, np.zeros(3)
        ms = 4 * r / (4 * r + 3 * h)  # the two hemispheres' share (MuJoCo's form)
        mc = 1 - ms
        side = mc * (3 * r * r + h * h) / 12 + ms * (0.4 * r * r + h * (3 * r + 2 * h) / 8)
        return vol, np.array([side, side, mc * r * r / 2 + ms * 0.4 * r * r])
    if typ == "cylinder":
        r, hh, h = s[0], s[1], 2 * s[1]
        if shell:
            disk, side_area = pi * r * r, 2 * pi * r * h
            total = 2 * disk + side_area
            if total <= 0:
                return 0.0, np.zeros(3)
            md = disk / total  # each end's share
            mc = 1 - 2 * md
            x = mc * (6 * r * r + h * h) / 12 + 2 * (md * r * r / 4 + md * hh * hh)
            return total, np.array([x, x, mc * r * r + 2 * md * r * r / 2])
        return pi * r * r * h, np.array([(3 * r * r + h * h) / 12] * 2 + [r * r / 2])
    if typ == "ellipsoid":
        a, b, c = s
        if shell:
            p = 1.6075  # Thomsen's approximation of the area, as MuJoCo's
            area = 4 * pi * (((a * b) ** p + (b * c) ** p + (c * a) ** p) / 3) ** (1 / p)
            eps = 1e-6  # MuJoCo: the solid grown by eps, less the solid
            va, vb = 4 * pi * a * b * c / 3, 4 * pi * (a + eps) * (b + eps) * (c + eps) / 3
            density = mass / (vb - va)  # as MuJoCo rounds it: a difference of near
            # equals, 1e-11 relative from the mass's place in the product
            ia = va * density * np.array([b * b + c * c, a * a + c * c, a * a + b * b]) / 5
            ae, be, ce = a + eps, b + eps, c + eps
            ib = vb * density * np.array([be * be + ce * ce, ae * ae + ce * ce,
                                          ae * ae + be * be]) / 5
            return area, ib - ia
        return 4 / 3 * pi * a * b * c, np.array([b * b + c * c, a * a + c * c,
                                                 a * a + b * b]) / 5
    if typ == "box":
        if shell:
            lx, ly, lz = 2 * s
            a0, a1, a2 = lx * ly, ly * lz, lz * lx
            total = 2 * (a0 + a1 + a2)
            if total <= 0:
                return 0.0, np.zeros(3)
            m0, m1, m2 = a0 / total, a1 / total, a2 / total
            s00, s11, s22 = s * s
            ix = 2 * (m0 * s22 + m2 * s11 + m0 * ly * ly / 12 + m1 * (ly * ly + lz * lz) / 12
                      + m2 * lz * lz / 12)
            iy = 2 * (m0 * s22 + m1 * s00 + m0 * lx * lx / 12 + m1 * lz * lz / 12
                      + m2 * (lx * lx + lz * lz) / 12)
            iz = 2 * (m1 * s00 + m2 * s11 + m0 * (lx * lx + ly * ly) / 12 + m1 * ly * ly / 12
                      + m2 * lx * lx / 12)
            return total, np.array([ix, iy, iz])
        a, b, c = 2 * s
        return a * b * c, np.array([b * b + c * c, a * a + c * c, a * a + b * b]) / 12
    return 0.0, np.zeros(3)
