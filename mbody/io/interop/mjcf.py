"""MJCF (MuJoCo's XML) -> the model-file structure, located at the XML's lines.

What is read: ``<include>`` (relative to the including file), ``<compiler>`` (``angle``,
``eulerseq``, ``inertiafromgeom``, ``inertiagrouprange``, ``boundmass``,
``boundinertia``, ``settotalmass``), ``<option gravity>`` and its gravity flag,
``<default>`` classes and ``childclass``, the body tree with every orientation form
(``quat``, ``axisangle``, ``euler``, ``xyaxes``, ``zaxis``), ``<inertial>``, the mass
and inertia of geoms as MuJoCo computes them (sphere, capsule, cylinder, box, ellipsoid;
``fromto``; ``mass`` or ``density``), hinge/slide/ball/free joints, ``<freejoint>``,
``<equality>`` ``connect``/``weld``, and ``<keyframe>``. Everything else that changes
the motion is listed in one warning (`mbody.io.interop.tree.ImportedDocument.warnings`).

The reading is split by job: `mbody.io.interop.mjcf_source` (includes, names),
`mbody.io.interop.mjcf_compiler` (compiler settings, values, orientations),
`mbody.io.interop.mjcf_defaults` (``<default>`` classes), `mbody.io.interop.mjcf_geoms`
(mass and inertia) and `mbody.io.interop.mjcf_state` (keyframes); this module walks the
body tree into `mbody.io.interop.tree`'s structures.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from mbody.errors import Issue, ModelError, did_you_mean
from mbody.io.interop.attrvalues import BOOLEAN
from mbody.io.interop.custom import Custom, planar_issues, read_custom, reorder, restore
from mbody.io.interop.mjcf_compiler import z_to_quat
from mbody.io.interop.mjcf_geoms import GEOM_TYPES, MIN_MASS, Geoms, solid
from mbody.io.interop.mjcf_source import MAX_INCLUDES, Included, check_names, expand_includes
from mbody.io.interop.mjcf_state import chosen, described, state
from mbody.io.interop.tree import (
    NQ,
    NV,
    ImportedDocument,
    Loop,
    Screw,
    TreeBody,
    TreeJoint,
    build,
    joint_order,
    unit,
)
from mbody.io.interop.xmlsource import MAX_ELEMENTS, Element, read_model_xml

__all__ = ["GEOM_TYPES", "MAX_INCLUDES", "MIN_MASS", "read_mjcf", "solid", "z_to_quat"]
"""`read_mjcf`; the rest is re-exported from where it lives now."""


def read_mjcf(source: str | Path, *, keyframe: str | None = None,
              file: str | None = None) -> ImportedDocument:
    """Read an MJCF model into the plain structure a YAML model file parses to.

    Parameters
    ----------
    source : str or Path
        A path to the ``.xml`` file, or the XML text itself (starting with ``<``).
    keyframe : str, optional
        The name (or index) of a ``<key>`` whose ``qpos``/``qvel`` give the state;
        default: the key ``initial`` when the file has one (the state mbody's export
        writes), else every joint at its reference position (MuJoCo's ``qpos0``), at
        rest. The model's description says which.
    file : str, optional
        The name used in messages (default: the path, or ``<string>`` for text); for
        text, ``<include>`` files are found next to it.

    Returns
    -------
    ImportedDocument
        Ready for `mbody.model.validate.validate`; its `warnings` list what the model
        has that mbody does not map.

    Raises
    ------
    ModelError
        Bad XML, an unknown element or attribute (with a did-you-mean), a value that is
        not a number, or something mbody cannot express (say which element).
    """
    budget = [MAX_ELEMENTS]
    root, name = read_model_xml(source, file, budget, "mjcf")
    if isinstance(source, Path) or not str(source).lstrip().startswith("<"):
        base = Path(source).parent
    else:  # text: its includes are next to the file it is named as
        base = Path(file).parent if file is not None else Path.cwd()
    expand_includes(root, base, budget, Included())
    issues: list[Issue] = []
    check_names(root, "mujoco", issues)
    if issues:
        raise ModelError(issues)
    return _Reader(root, name).read(keyframe)



class _Reader(Geoms):
    def __init__(self, root: Element, file: str):
        super().__init__(file)
        self.root = root
        self.bodies: list[TreeBody] = []
        self.childclasses: dict[int, str | None] = {}
        self.world_geoms: list[Element] = []
        self.body_index: dict[str, int] = {}
        self.moving: list[bool] = []
        """Per body: it or a body it hangs from has a joint."""
        self.screws = {}

    # -- the file --------------------------------------------------------------------
    def read(self, keyframe: str | None) -> ImportedDocument:
        root = self.root
        for c in root.findall("compiler"):
            self.compiler(c)
        gravity = np.array([0.0, 0.0, -9.81])
        for o in root.findall("option"):
            g = self.attr(o, o.attrib, "gravity", 3)
            if g is not None:
                gravity = g
            for f in o.findall("flag"):
                flags = {k: self.keyword(f, f.attrib, k, ("disable", "enable"), "enable")
                         for k in ("gravity", "contact", "constraint")}
                if flags["gravity"] == "disable":
                    gravity = np.zeros(3)
                if flags["contact"] == "disable" or flags["constraint"] == "disable":
                    self.contact_off = True
            for k, n in (("density", 1), ("viscosity", 1), ("wind", 3)):
                x = self.attr(o, o.attrib, k, n)
                if x is not None and x.any():
                    self.note("fluid forces", f"option {k}")
        for d in root.findall("default"):
            self.defaults.read(d, None, self.issues)
        if self.issues:
            raise ModelError(self.issues)
        self.read_hfields(root)
        worlds = root.findall("worldbody")
        for w in worlds:
            for g in w.findall("geom"):
                self.geom(g, self.values(g, None))  # checked as MuJoCo checks it
                if self.contact_off:
                    continue
                self.world_geoms.append(g)
                self.note("contacts", f"world geom '{g.get('name') or g.get('type', '?')}'")
            for c in w.children:
                if c.tag == "body":
                    self.body(c, -1, None)
                elif c.tag in ("frame", "attach", "flexcomp", "replicate"):
                    self.fail(c, f"<{c.tag}> is not read by mbody's MJCF import",
                              "write the bodies out in <worldbody>")
        if self.issues:
            raise ModelError(self.issues)
        self.custom = read_custom(root)
        self.bound_masses(self.bodies)
        loops = self.equality()
        self.others()
        if self.issues:
            raise ModelError(self.issues)
        keyframe = chosen(root, keyframe)
        qpos, qvel, q0 = state(self, root, self.bodies, keyframe)
        self.screw_state(qpos, qvel, q0)
        name = root.get("model") or Path(self.file).stem
        about = f"imported from {Path(self.file).name} (MJCF) {described(root, keyframe)}"
        doc = build(name, about, self.file,
                    self.bodies, qpos, qvel, q0, gravity, loops, root, "mjcf",
                    self.free_motions(), screws={k: h for k, (h, _) in self.screws.items()},
                    planar=self.custom is not None and self.custom.dimension == 2)
        if self.custom is not None:
            off_plane = planar_issues(doc, self.custom)
            if off_plane:
                raise ModelError(off_plane)
            restore(doc.data, [doc.marks, doc.key_marks], self.custom, self.springs())
            reorder(doc, self.custom)
        if self.notes:
            doc.warnings.append(Issue(self.file, 0, 0, "", _summary(self.notes)))
        return doc

    contact_off = False
    custom: Custom | None = None
    screws: dict[Screw, tuple[float, Element]]
    """(slide, hinge) -> (h, the equality): joint equalities that make a screw."""
    joint_index: dict[str, tuple[int, TreeJoint]] | None = None
    """Every joint by name: (its body's index, the joint)."""

    def free_motions(self) -> frozenset[int]:
        """Bodies in the world whose joints are exactly a free motion, as the mbody
        entries say: orthogonal slides along x, y and a hinge about z in a planar model
        (the slides only for a particle), three orthogonal slides for a spatial particle.
        MJCF alone cannot say that a body is planar or a particle."""
        c = self.custom
        if c is None:
            return frozenset()
        out = set()
        for i, b in enumerate(self.bodies):
            particle = c.particle(b.name)
            if c.dimension == 2:
                want = ["slide", "slide"] + ([] if particle else ["hinge"])
            elif particle:
                want = ["slide"] * 3
            else:
                continue
            if b.parent >= 0 or [j.type for j in b.joints] != want:
                continue
            A = np.array([j.axis for j in b.joints])
            if np.allclose(A @ A.T, np.eye(len(A)), rtol=0, atol=1e-12):
                out.add(i)
        return frozenset(out)

    def springs(self) -> dict[str, dict[str, Any]]:
        """The spatial tendons the mbody entries name as springs, as spring loads: two
        sites, ``stiffness``, ``damping`` and ``springlength``."""
        c = self.custom
        assert c is not None
        wanted = set(c.springs)
        if not wanted:
            return {}
        sites: dict[str, tuple[int, np.ndarray]] = {}
        for w in self.root.findall("worldbody"):
            for st in w.findall("site"):
                sites[st.get("name") or ""] = (-1, self.attr(st, st.attrib, "pos", 3,
                                                             np.zeros(3)))
        for i, b in enumerate(self.bodies):
            for st in b.element.findall("site"):
                sites[st.get("name") or ""] = (i, self.attr(st, st.attrib, "pos", 3,
                                                            np.zeros(3)))
        d = c.dimension
        out: dict[str, dict[str, Any]] = {}
        for sec in self.root.findall("tendon"):
            for t in sec.findall("spatial"):
                name = t.get("name") or ""
                if name not in wanted:
                    continue
                ends = [st.get("site") or "" for st in t.findall("site")]
                if len(ends) != 2 or any(e not in sites for e in ends):
                    self.fail(t, f"the spring '{name}' needs a tendon between two sites")
                    continue
                bodies, at = [], []
                for e in ends:
                    i, p = sites[e]
                    if i < 0:
                        bodies.append("ground")
                        at.append([float(x) for x in p[:d]])
                    else:
                        b = self.bodies[i]
                        bodies.append(b.name)
                        at.append([float(x) for x in (b.R_inertia.T @ (p - b.com))[:d]])
                # a polynomial in MuJoCo 4 (up to three coefficients); mbody's springs
                # and dampers are linear
                k = self.attr(t, t.attrib, "stiffness", 3, np.zeros(1), lo=1)
                damp = self.attr(t, t.attrib, "damping", 3, np.zeros(1), lo=1)
                rest = self.attr(t, t.attrib, "springlength", 2, np.zeros(1), lo=1)
                for key, x in (("stiffness", k), ("damping", damp)):
                    if x[1:].any():
                        self.fail(t, f"the spring '{name}' has a {key} that is not linear "
                                  "(more than one coefficient); mbody's springs are linear",
                                  "give one number", key)
                out[name] = {"type": "spring", "bodies": bodies, "at": at,
                             "stiffness": float(k[0]), "rest_length": float(rest[0]),
                             "damping": float(damp[0])}
        missing = sorted(wanted - set(out))
        for entry in (x for x in c.loads if x[0] in missing):
            self.fail(entry[2], "no spatial tendon of this name holds the spring", attr="name")
        if self.issues:
            raise ModelError(self.issues)
        return out

    # -- bodies ------------------------------------------------------------------------
    def body(self, e: Element, parent: int, childclass: str | None) -> None:
        childclass = e.get("childclass") or childclass
        if childclass is not None and childclass not in self.defaults.classes:
            self.fail(e, f"unknown default class '{childclass}'",
                      did_you_mean(childclass, self.defaults.classes), "childclass")
            childclass = None
        name = _name(e.get("name") or f"body{len(self.bodies) + 1}")
        if name in self.body_index:
            self.fail(e, f"duplicate body name '{name}'", attr="name")
        pos = self.attr(e, e.attrib, "pos", 3, np.zeros(3))
        quat = self.orientation(e, e.attrib)
        joints: list[TreeJoint] = []
        for c in e.children:
            if c.tag == "freejoint":
                joints.append(TreeJoint(_name(c.get("name") or f"{name}_free"), "free",
                                        np.zeros(3), np.array([0.0, 0, 1]), c))
            elif c.tag == "joint":
                j = self.joint(c, childclass, name, len(joints))
                if j is not None:
                    joints.append(j)
        if any(j.type == "free" for j in joints) and parent >= 0:
            free = next(j for j in joints if j.type == "free")
            self.fail(free.element, f"a free joint on '{name}', a body inside another "
                      "body", "free joints belong to bodies directly in <worldbody>")
        if self.keyword(e, e.attrib, "mocap", BOOLEAN, "false") == "true":
            self.note("mocap bodies (fixed where the file puts them)", name)
        if self.attr(e, e.attrib, "gravcomp", 1, np.zeros(1)).any():
            self.note("gravity compensation", name)
        b = TreeBody(name, parent, pos, quat, joints, e)
        moving = bool(joints) or (parent >= 0 and self.moving[parent])
        self.mass(b, e, childclass, moving)
        index = len(self.bodies)
        self.moving.append(moving)
        self.childclasses[index] = childclass
        self.bodies.append(b)
        self.body_index[name] = index
        for c in e.children:
            if c.tag == "body":
                self.body(c, index, childclass)
            elif c.tag in ("frame", "attach", "flexcomp", "replicate"):
                self.fail(c, f"<{c.tag}> is not read by mbody's MJCF import",
                          "write the bodies out")

    def joint(self, c: Element, childclass: str | None, body: str, k: int
              ) -> TreeJoint | None:
        v = self.values(c, childclass)
        typ = v.get("type", "hinge")
        if typ not in ("hinge", "slide", "ball", "free"):
            self.fail(c, f"unknown joint type '{typ}'",
                      did_you_mean(typ, ("hinge", "slide", "ball", "free")) or
                      "expected hinge, slide, ball or free", "type")
            return None
        name = _name(c.get("name") or f"{body}_joint{k + 1 if k else ''}")
        pos = self.attr(c, v, "pos", 3, np.zeros(3))
        axis = self.attr(c, v, "axis", 3, np.array([0.0, 0, 1]))
        if np.linalg.norm(axis) < 1e-12:
            self.fail(c, "the joint axis is zero", attr="axis")
            axis = np.array([0.0, 0, 1])
        ref = float(self.attr(c, v, "ref", 1, np.zeros(1))[0])
        if typ == "hinge":
            ref *= self.angle_scale
        limited = self.keyword(c, v, "limited", ("false", "true", "auto"), "auto")
        limits = self.attr(c, v, "range", 2)
        if limits is not None and limited != "false":
            self.note("joint limits", name)
        # damping and stiffness: a polynomial in MuJoCo 4 (up to three coefficients)
        for key, n, what in (("damping", 3, "joint damping"), ("stiffness", 3, "joint springs"),
                             ("armature", 1, "armature (rotor inertia)"),
                             ("frictionloss", 1, "joint friction")):
            x = self.attr(c, v, key, n, lo=1)
            if x is not None and x.any():
                self.note(what, name)
        return TreeJoint(name, typ, pos, unit(axis), c, ref)

    def equality(self) -> list[Loop]:
        loops: list[Loop] = []
        for eq in self.root.findall("equality"):
            for c in eq.children:
                v = self.values(c, None)
                if self.keyword(c, v, "active", BOOLEAN, "true") == "false":
                    continue
                if c.tag == "joint" and self.screw(c, v):
                    continue
                if c.tag not in ("connect", "weld"):
                    self.note("equality constraints", f"{c.tag} '{c.get('name') or ''}'")
                    continue
                if "site1" in v or "site2" in v:
                    self.note("equality constraints", f"{c.tag} between sites")
                    continue
                b1 = self.body_ref(c, v.get("body1"), "body1")
                b2 = self.body_ref(c, v.get("body2", "world"), "body2")
                if b1 is None or b2 is None:
                    continue
                if b1 == b2:  # as MuJoCo refuses it: it would hold nothing
                    self.fail(c, f"the {c.tag} joins body '{v.get('body1')}' to itself",
                              "name two different bodies in body1 and body2; body2 is "
                              "the world when it is not given",
                              "body2" if "body2" in c.attrib else "body1")
                    continue
                anchor = self.attr(c, v, "anchor", 3, np.zeros(3))
                if c.tag == "weld" and ("relpose" in v or "torquescale" in v):
                    self.note("equality constraints", f"weld '{c.get('name') or ''}' "
                              "relpose/torquescale")
                name = _name(c.get("name") or f"{c.tag}{len(loops) + 1}")
                loops.append(Loop(name, "spherical" if c.tag == "connect" else "fixed",
                                  b1, b2, anchor, c.tag == "weld", c))
        if self.issues:
            raise ModelError(self.issues)
        return loops

    def screw(self, c: Element, v: dict[str, str]) -> bool:
        """Whether the joint equality `c` makes a helical joint: it ties a slide and a hinge
        that are the only joints of one body, on one axis, exactly linearly (polycoef "0
        a 0 0 0": joint1 − its ref = a (joint2 − its ref)). It is then the screw itself,
        exact in mbody, not a soft constraint; its solref and solimp are not read."""
        names = (v.get("joint1"), v.get("joint2"))
        if self.joint_index is None:  # once: a file may have many joint equalities
            self.joint_index = {j.name: (i, j) for i, b in enumerate(self.bodies)
                                for j in b.joints}
        found = self.joint_index
        ends = [found.get(_name(n)) if n else None for n in names]
        if ends[0] is None or ends[1] is None:
            return False
        (i1, j1), (i2, j2) = ends[0], ends[1]
        coef = np.array([0.0, 1.0, 0.0, 0.0, 0.0])  # MuJoCo's default
        given = self.attr(c, v, "polycoef", 5, None, lo=1)
        if given is not None:
            coef[:len(given)] = given
        b = self.bodies[i1]
        if (i1 != i2 or coef[0] != 0.0 or coef[2:].any() or len(b.joints) != 2
                or {j1.type, j2.type} != {"slide", "hinge"}
                or float(np.linalg.norm(np.cross(j1.axis, j2.axis))) > 1e-9):
            return False
        a = float(coef[1])
        if j1.type == "slide":  # s = a θ
            self.screws[(j1.name, j2.name)] = (a, c)
        elif a != 0.0:  # θ = a s
            self.screws[(j2.name, j1.name)] = (1.0 / a, c)
        else:  # the hinge locked: no screw
            return False
        return True

    def screw_state(self, qpos: np.ndarray, qvel: np.ndarray, q0: np.ndarray) -> None:
        """Note a screw whose state breaks its coupling: mbody's helical joint starts from
        the pose and rates as given, where MuJoCo pulls them back to the equality."""
        if not self.screws:
            return
        at, rate = {}, {}
        qa = va = 0
        for _, j in joint_order(self.bodies):
            at[j.name], rate[j.name] = qa, va
            qa += NQ[j.type]
            va += NV[j.type]
        scale = max(1.0, float(np.abs(qpos).max(initial=0.0)))
        for (slide, hinge), (h, c) in self.screws.items():
            s, t = at[slide], at[hinge]
            miss = abs((qpos[s] - q0[s]) - h * (qpos[t] - q0[t]))
            speed = abs(qvel[rate[slide]] - h * qvel[rate[hinge]])
            if miss > 1e-9 * scale or speed > 1e-9 * max(1.0, float(np.abs(qvel).max())):
                self.note("screw couplings broken by the state (mbody's screw starts from "
                          "the state as given)", f"{c.get('name') or slide} by {miss:.3g} m, "
                          f"{speed:.3g} m/s")

    def body_ref(self, c: Element, name: str | None, attr: str) -> int | None:
        if name == "world":
            return -1
        if name is None or name not in self.body_index:
            self.fail(c, f"unknown body '{name}'", did_you_mean(name or "",
                                                               self.body_index), attr)
            return None
        return self.body_index[name]

    def others(self) -> None:
        """Note what changes the motion and is not read."""
        r = self.root
        springs = set(self.custom.springs) if self.custom is not None else set()
        for tag, what in (("actuator", "actuators"), ("tendon", "tendons"),
                          ("sensor", "sensors")):
            for sec in r.findall(tag):
                for c in sec.children:
                    if tag == "tendon" and c.tag == "spatial" and c.get("name") in springs:
                        continue  # an mbody spring, read as one
                    self.note(what, c.get("name") or c.tag)
        for sec in r.findall("contact"):
            for c in sec.children:
                self.note("contacts", f"{c.tag} {c.get('name') or ''}".strip())
        if not self.contact_off:
            self.contacts()

    def contacts(self) -> None:
        """Keep in the warning only the geoms that can touch another body's geom: MuJoCo
        tests a pair when (contype1 & conaffinity2) or (contype2 & conaffinity1)."""
        geoms: list[tuple[Element, int, int, int]] = []  # (geom, body or -1, type, affinity)
        owners = [(-1, g, None) for g in self.world_geoms] + [
            (i, g, self.childclasses.get(i)) for i, b in enumerate(self.bodies)
            for g in b.element.findall("geom")]
        for i, g, cls in owners:
            v = self.values(g, cls)
            bits = [self.attr(g, v, k, 1, np.ones(1), integer=True)
                    for k in ("contype", "conaffinity")]
            geoms.append((g, i, int(bits[0][0]), int(bits[1][0])))

        kinds: dict[tuple[int, int], set[int]] = {}  # (type, affinity) -> their bodies
        for _, i, ct, ca in geoms:
            kinds.setdefault((ct, ca), set()).add(i)

        def touches(k: int) -> bool:
            _, i, ct, ca = geoms[k]
            return any((ct & ca2 or ct2 & ca) and bool(owners_ - {i})
                       for (ct2, ca2), owners_ in kinds.items())

        nw = len(self.world_geoms)
        items = self.notes.get("contacts", [])
        kept = [item for k, item in enumerate(items[:nw]) if touches(k)] + items[nw:]
        n = sum(touches(k) for k in range(nw, len(geoms)))
        if n:
            kept.append(f"{n} body geoms collide in MuJoCo")
        if kept:
            self.notes["contacts"] = kept
        else:
            self.notes.pop("contacts", None)


def _name(n: str) -> str:
    """A name mbody accepts: '.' and spaces become '_' (reaction labels are joint.Fx)."""
    return "".join("_" if ch == "." or ch.isspace() else ch for ch in n)


def _summary(notes: dict[str, list[str]]) -> str:
    parts = []
    for what, items in notes.items():
        shown = ", ".join(items[:4]) + (f" and {len(items) - 4} more" if len(items) > 4
                                        else "")
        parts.append(f"{what} ({shown})")
    return ("not imported (mbody models none of these; the motion computed here leaves "
            "them out): " + "; ".join(parts))
