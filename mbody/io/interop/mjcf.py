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
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from mbody.equations.spatial import axis_angle_quat, matrix_to_quat, quat_mul, quat_to_matrix
from mbody.errors import Issue, ModelError, did_you_mean
from mbody.io.interop.custom import Custom, read_custom, restore
from mbody.io.interop.mjcf_schema import SCHEMA
from mbody.io.interop.tree import (
    NV,
    ImportedDocument,
    Loop,
    TreeBody,
    TreeJoint,
    build,
    joint_order,
    qpos0,
    unit,
)
from mbody.io.interop.xmlsource import MAX_ELEMENTS, Element, parse_xml, read_xml, unknown_name

MAX_INCLUDES = 100
"""Most ``<include>`` files read for one model."""
MIN_MASS = 1e-15
"""A body with less mass than this has none (MuJoCo's mjMINVAL is 1e-15)."""
GEOM_TYPES = ("plane", "hfield", "sphere", "capsule", "ellipsoid", "cylinder", "box",
              "mesh", "sdf")


def read_mjcf(source: str | Path, *, keyframe: str | None = None,
              file: str | None = None) -> ImportedDocument:
    """Read an MJCF model into the plain structure a YAML model file parses to.

    Parameters
    ----------
    source : str or Path
        A path to the ``.xml`` file, or the XML text itself (starting with ``<``).
    keyframe : str, optional
        The name (or index) of a ``<key>`` whose ``qpos``/``qvel`` give the state;
        default: every joint at its reference position (MuJoCo's ``qpos0``), at rest.
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
    if isinstance(source, Path) or not str(source).lstrip().startswith("<"):
        path = Path(source)
        name = str(source) if file is None else file
        root = read_xml(path, name, budget)
        base = path.parent
    else:
        name = "<string>" if file is None else file
        root = parse_xml(str(source), name, budget)
        base = Path(file).parent if file is not None else Path.cwd()
    if root.tag != "mujoco":
        hint = ("this is a URDF file: read it as URDF (a .urdf name, or --format urdf)"
                if root.tag == "robot" else "an MJCF model starts with <mujoco>")
        raise ModelError([root.issue(f"expected <mujoco> as the root element, got "
                                     f"<{root.tag}>", hint)])
    _expand_includes(root, base, budget, [0])
    issues: list[Issue] = []
    _check_names(root, "mujoco", issues)
    if issues:
        raise ModelError(issues)
    return _Reader(root, name).read(keyframe)


def _expand_includes(e: Element, base: Path, budget: list[int], count: list[int],
                     chain: tuple[str, ...] = ()) -> None:
    """Replace each ``<include file=...>`` by the children of that file's root."""
    out: list[Element] = []
    for c in e.children:
        if c.tag != "include":
            _expand_includes(c, base, budget, count, chain)
            out.append(c)
            continue
        rel = c.get("file")
        if not rel:
            raise ModelError([c.issue("an <include> needs a 'file'")])
        path = (base / rel).resolve()
        count[0] += 1
        if count[0] > MAX_INCLUDES:
            raise ModelError([c.issue(f"more than {MAX_INCLUDES} included files")])
        if str(path) in chain:
            raise ModelError([c.issue(f"'{rel}' includes itself (through "
                                      f"{' -> '.join(chain)})", attr="file")])
        if not path.is_file():
            raise ModelError([c.issue(f"the included file '{rel}' does not exist",
                                      f"looked for {path}", attr="file")])
        sub = read_xml(path, str(path), budget)
        if sub.tag != "mujoco":
            raise ModelError([sub.issue(f"an included file's root must be <mujoco>, got "
                                        f"<{sub.tag}>")])
        _expand_includes(sub, path.parent, budget, count, (*chain, str(path)))
        out.extend(sub.children)
    e.children = out


def _schema_path(path: str, tag: str) -> str:
    if tag in ("worldbody", "body") and path in ("mujoco", "mujoco/body"):
        return "mujoco/body"
    if tag == "default" and path in ("mujoco", "mujoco/default"):
        return "mujoco/default"
    return f"{path}/{tag}"


def _check_names(e: Element, path: str, issues: list[Issue]) -> None:
    """Every element and attribute name against MuJoCo's schema, with did-you-means."""
    stack = [(e, path)]
    while stack:
        el, p = stack.pop()
        attrs, kids = SCHEMA.get(p, (frozenset(), frozenset()))
        if p in SCHEMA:
            for a in el.attrib:
                if a not in attrs:
                    issues.append(unknown_name(el, a, attrs, f"attribute of <{el.tag}>", a))
        for c in el.children:
            if p in SCHEMA and c.tag not in kids and not (p == "mujoco/body" and
                                                           c.tag == "frame"):
                issues.append(unknown_name(c, c.tag, kids, f"element in <{el.tag}>"))
                continue
            stack.append((c, _schema_path(p, c.tag)))
    issues.sort(key=lambda i: (i.line, i.column))


class _Reader:
    def __init__(self, root: Element, file: str):
        self.root, self.file = root, file
        self.issues: list[Issue] = []
        self.notes: dict[str, list[str]] = {}
        self.angle_scale = math.pi / 180
        self.eulerseq = "xyz"
        self.inertiafromgeom = "auto"
        self.groups = (0, 5)
        self.boundmass = 0.0
        self.boundinertia = 0.0
        self.settotalmass = -1.0
        self.defaults: dict[str, dict[str, dict[str, str]]] = {}
        self.default_parent: dict[str, str] = {}
        self.bodies: list[TreeBody] = []
        self.childclasses: dict[int, str | None] = {}
        self.world_geoms: list[Element] = []
        self.body_index: dict[str, int] = {}

    # -- small readers ---------------------------------------------------------------
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
                if f.get("gravity") == "disable":
                    gravity = np.zeros(3)
                if f.get("contact") == "disable" or f.get("constraint") == "disable":
                    self.contact_off = True
            for k in ("density", "viscosity"):
                if float(o.get(k, "0") or 0) != 0:
                    self.note("fluid forces", f"option {k}")
            if o.get("wind") and any(float(t) for t in (o.get("wind") or "").split()):
                self.note("fluid forces", "option wind")
        for d in root.findall("default"):
            self.default_class(d, None)
        if self.issues:
            raise ModelError(self.issues)
        worlds = root.findall("worldbody")
        for w in worlds:
            for g in w.findall("geom") if not self.contact_off else ():
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
        self.bound_masses()
        loops = self.equality()
        self.others()
        q0 = qpos0(self.bodies)
        nv = sum(NV[j.type] for _, j in joint_order(self.bodies))
        qpos, qvel = q0.copy(), np.zeros(nv)
        if keyframe is not None:
            qpos, qvel = self.key(keyframe, q0, nv)
        name = root.get("model") or Path(self.file).stem
        doc = build(name, f"imported from {Path(self.file).name} (MJCF)", self.file,
                    self.bodies, qpos, qvel, q0, gravity, loops, root, "mjcf",
                    self.free_motions())
        if self.custom is not None:
            restore(doc.data, [doc.marks, doc.key_marks], self.custom, self.springs())
        if self.notes:
            doc.warnings.append(Issue(self.file, 0, 0, "", _summary(self.notes)))
        return doc

    contact_off = False
    custom: Custom | None = None

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
                k = self.attr(t, t.attrib, "stiffness", 1, np.zeros(1))
                damp = self.attr(t, t.attrib, "damping", 1, np.zeros(1))
                rest = self.attr(t, t.attrib, "springlength", 2, np.zeros(1), lo=1)
                out[name] = {"type": "spring", "bodies": bodies, "at": at,
                             "stiffness": float(k[0]), "rest_length": float(rest[0]),
                             "damping": float(damp[0])}
        missing = sorted(wanted - set(out))
        for entry in (x for x in c.loads if x[0] in missing):
            self.fail(entry[2], "no spatial tendon of this name holds the spring", attr="name")
        if self.issues:
            raise ModelError(self.issues)
        return out

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

    def default_class(self, d: Element, parent: str | None) -> None:
        name = d.get("class") or ("main" if parent is None else None)
        if name is None:
            self.fail(d, "a nested <default> needs a 'class'")
            return
        base = self.defaults.get(parent or "", {}) if parent is not None else {}
        own: dict[str, dict[str, str]] = {k: dict(v) for k, v in base.items()}
        if name in self.defaults and parent is not None:
            self.fail(d, f"the default class '{name}' is defined twice", attr="class")
        for c in d.children:
            if c.tag == "default":
                continue
            own.setdefault(c.tag, {}).update(c.attrib)
        if name in self.defaults:  # a second top-level <default>: adds to main
            for k, v in own.items():
                self.defaults[name].setdefault(k, {}).update(v)
        else:
            self.defaults[name] = own
        for c in d.findall("default"):
            self.default_class(c, name)

    def values(self, e: Element, childclass: str | None) -> dict[str, str]:
        """The element's attributes over its default class's."""
        cls = e.get("class") or childclass or "main"
        if cls not in self.defaults and cls != "main":
            self.fail(e, f"unknown default class '{cls}'",
                      did_you_mean(cls, self.defaults), "class" if e.get("class")
                      else None)
            cls = "main"
        out = dict(self.defaults.get(cls, {}).get(e.tag, {}))
        out.update(e.attrib)
        return out

    # -- bodies ------------------------------------------------------------------------
    def body(self, e: Element, parent: int, childclass: str | None) -> None:
        childclass = e.get("childclass") or childclass
        if childclass is not None and childclass not in self.defaults:
            self.fail(e, f"unknown default class '{childclass}'",
                      did_you_mean(childclass, self.defaults), "childclass")
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
        if e.get("mocap") == "true":
            self.note("mocap bodies (fixed where the file puts them)", name)
        if e.get("gravcomp") and float(e.get("gravcomp") or 0) != 0:
            self.note("gravity compensation", name)
        b = TreeBody(name, parent, pos, quat, joints, e)
        self.mass(b, e, childclass)
        index = len(self.bodies)
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
        limited = v.get("limited", "auto")
        if "range" in v and limited != "false":
            self.note("joint limits", name)
        for key, what in (("damping", "joint damping"), ("stiffness", "joint springs"),
                          ("armature", "armature (rotor inertia)"),
                          ("frictionloss", "joint friction")):
            x = self.attr(c, v, key, 1)
            if x is not None and float(x[0]) != 0:
                self.note(what, name)
        return TreeJoint(name, typ, pos, unit(axis), c, ref)

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

    def bound_masses(self) -> None:
        for b in self.bodies:
            if self.boundmass > 0 and b.mass < self.boundmass and (b.mass > 0 or b.joints):
                b.mass = self.boundmass
            if self.boundinertia > 0 and b.mass > 0:
                w, V = np.linalg.eigh(b.inertia)
                b.inertia = V @ np.diag(np.maximum(w, self.boundinertia)) @ V.T
        if self.settotalmass > 0:
            total = sum(b.mass for b in self.bodies)
            if total > 0:
                k = self.settotalmass / total
                for b in self.bodies:
                    b.mass *= k
                    b.inertia = b.inertia * k

    def equality(self) -> list[Loop]:
        loops: list[Loop] = []
        for eq in self.root.findall("equality"):
            for c in eq.children:
                v = self.values(c, None)
                if v.get("active", "true") == "false":
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
            bits = [self.attr(g, v, k, 1, np.ones(1)) for k in ("contype", "conaffinity")]
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

    def key(self, keyframe: str, q0: np.ndarray, nv: int) -> tuple[np.ndarray, np.ndarray]:
        keys = [k for kf in self.root.findall("keyframe") for k in kf.findall("key")]
        names = [k.get("name") or str(i) for i, k in enumerate(keys)]
        if keyframe in names:
            k = keys[names.index(keyframe)]
        elif keyframe.isdigit() and int(keyframe) < len(keys):
            k = keys[int(keyframe)]
        else:
            hint = did_you_mean(keyframe, names) or (
                f"the file has: {', '.join(names)}" if names else "the file has no keyframe")
            raise ModelError([Issue(self.file, 0, 0, "keyframe",
                                    f"no keyframe named '{keyframe}'", hint)])
        qpos = self.attr(k, k.attrib, "qpos", None, q0.copy())
        qvel = self.attr(k, k.attrib, "qvel", None, np.zeros(nv))
        if len(qpos) != len(q0):
            self.fail(k, f"qpos has {len(qpos)} numbers; the model has {len(q0)} joint "
                      "coordinates", attr="qpos")
        if len(qvel) != nv:
            self.fail(k, f"qvel has {len(qvel)} numbers; the model has {nv} joint rates",
                      attr="qvel")
        if self.issues:
            raise ModelError(self.issues)
        return qpos, qvel


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
