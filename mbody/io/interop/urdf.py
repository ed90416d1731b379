"""URDF -> the model-file structure, located at the XML's lines.

Links with an ``<inertial>`` become bodies (mass centre and inertia frame from its
``origin``, ``xyz`` and ``rpy``; the tensor's entries as written); joints: revolute and
continuous -> revolute, prismatic -> prismatic, fixed -> fixed (a link without mass on a
fixed joint is a frame: left out, its children joined to the body it is fixed to). The
root link is fixed to the world (its mass belongs to the ground, as Pinocchio reads a
fixed base) unless ``floating_base`` is set, when it moves freely. Joint limits,
dynamics, mimic joints and transmissions are listed in one warning.
"""

from __future__ import annotations

import difflib
import functools
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mbody.errors import Issue, ModelError, did_you_mean, option_name
from mbody.io.interop.attrvalues import read_numbers
from mbody.io.interop.tree import (
    NV,
    ImportedDocument,
    TreeBody,
    TreeJoint,
    build,
    joint_order,
    qpos0,
    unit,
)
from mbody.io.interop.xmlsource import (
    MAX_ELEMENTS,
    Element,
    read_model_xml,
    second,
    unknown_name,
)
from mbody.model.checks import MAX_ANGLE, MAX_MAGNITUDE
from mbody.util.spatial import quat_to_matrix

_ATTRS: dict[str, tuple[str, ...]] = {
    "robot": ("name", "version", "xmlns:xacro"), "link": ("name", "type"),
    "inertial": (), "origin": ("xyz", "rpy"), "mass": ("value",),
    "inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), "visual": ("name",),
    "collision": ("name",), "geometry": (), "box": ("size",),
    "cylinder": ("radius", "length"), "sphere": ("radius",),
    "capsule": ("radius", "length"), "mesh": ("filename", "scale"),
    "material": ("name",), "color": ("rgba",), "texture": ("filename",),
    "joint": ("name", "type"), "parent": ("link",), "child": ("link",), "axis": ("xyz",),
    "calibration": ("rising", "falling", "reference_position"),
    "dynamics": ("damping", "friction"), "limit": ("lower", "upper", "effort", "velocity"),
    "mimic": ("joint", "multiplier", "offset"),
    "safety_controller": ("soft_lower_limit", "soft_upper_limit", "k_position",
                          "k_velocity"),
}
"""URDF's attributes per element (ROS's urdf XML specification)."""
_CHILDREN: dict[str, tuple[str, ...]] = {
    "robot": ("link", "joint", "material", "transmission", "gazebo", "mujoco"),
    "link": ("inertial", "visual", "collision"),
    "inertial": ("origin", "mass", "inertia"),
    "visual": ("origin", "geometry", "material"), "collision": ("origin", "geometry"),
    "geometry": ("box", "cylinder", "sphere", "capsule", "mesh"),
    "material": ("color", "texture"),
    "joint": ("origin", "parent", "child", "axis", "calibration", "dynamics", "limit",
              "mimic", "safety_controller"),
}
_ONCE: dict[str, tuple[str, ...]] = {
    "link": ("inertial",), "inertial": ("origin", "mass", "inertia"),
    "visual": ("origin", "geometry", "material"), "collision": ("origin", "geometry"),
    "material": ("color", "texture"), "joint": _CHILDREN["joint"],
}
"""The children URDF gives an element at most once; a <geometry> holds one shape."""
_OPEN = ("transmission", "gazebo", "mujoco")
"""Elements whose content belongs to other tools; not checked."""
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


def read_urdf(source: str | Path, *, joint_positions: Mapping[str, float] | None = None,
              joint_velocities: Mapping[str, float] | None = None,
              floating_base: bool = False, file: str | None = None) -> ImportedDocument:
    """Read a URDF model into the plain structure a YAML model file parses to.

    Parameters
    ----------
    source : str or Path
        A path to the ``.urdf`` file, or the XML text itself (starting with ``<``).
    joint_positions, joint_velocities : mapping of str to float, optional
        Joint name -> position (rad or m) and rate (rad/s or m/s); every other joint at 0.
    floating_base : bool, optional
        The root link moves freely (a legged robot) instead of being fixed to the world
        (an arm's base, the default).
    file : str, optional
        The name used in messages.

    Returns
    -------
    ImportedDocument

    Raises
    ------
    ModelError
        Bad XML, an unknown element or attribute (with a did-you-mean), an unknown joint
        name in `joint_positions`, or what mbody cannot express (a planar joint).
    """
    root, name = read_model_xml(source, file, [MAX_ELEMENTS], "urdf")
    issues: list[Issue] = []
    ignored: list[str] = []
    _check_names(root, issues, ignored)
    if issues:
        raise ModelError(issues)
    reader = _Reader(root, name)
    if ignored:
        reader.notes["elements and attributes outside the URDF specification"] = ignored
    return reader.read(dict(joint_positions or {}), dict(joint_velocities or {}),
                                    floating_base)


TYPO_CUTOFF = 0.8
"""How alike (difflib's ratio) an unknown URDF name must be to one of URDF's to be taken
for a misspelling: ``orgin``, ``inertail``, ``nme`` are (0.86 to 0.91), and so is any
name one edit away (``rpi``: 0.67); the extensions real files carry, ``command_effort``
(ANYmal), ``gear_velocity``, ``collision_checking`` (0.6 to 0.76), are not."""


def _one_edit(a: str, b: str) -> bool:
    """`a` and `b` differ by one letter changed, added, dropped or two swapped."""
    if abs(len(a) - len(b)) > 1:
        return False
    i = 0
    while i < min(len(a), len(b)) and a[i] == b[i]:
        i += 1
    return (a[i + 1:] == b[i + 1:] or a[i:] == b[i + 1:] or a[i + 1:] == b[i:]
            or a[i:i + 2] == b[i:i + 2][::-1] and a[i + 2:] == b[i + 2:])


@functools.lru_cache(maxsize=4096)
def _misspelt(name: str, known: tuple[str, ...]) -> bool:
    return any(_one_edit(name, k) or _alike(name, k) for k in known)


def _alike(a: str, b: str) -> bool:
    """difflib's ratio of `a` and `b` is at least TYPO_CUTOFF (its cheap upper bounds
    first, as get_close_matches does: most names are ruled out by their lengths)."""
    m = difflib.SequenceMatcher(None, a, b)
    return (m.real_quick_ratio() >= TYPO_CUTOFF and m.quick_ratio() >= TYPO_CUTOFF
            and m.ratio() >= TYPO_CUTOFF)


def _check_names(root: Element, issues: list[Issue], ignored: list[str]) -> None:
    """A name very close to one of URDF's is misspelt (an error with a did-you-mean);
    any other unknown name is a tool's extension (Gazebo's, a vendor's): noted, not read.
    """
    noted = set(ignored)  # (the list keeps file order; the set answers 'seen?' at once)

    def note(what: str) -> None:
        if what not in noted:
            noted.add(what)
            ignored.append(what)

    stack = [root]
    while stack:
        e = stack.pop()
        if e.tag in _OPEN:
            continue
        known = _ATTRS.get(e.tag, ())
        for a in e.attrib:
            if a not in known and ":" not in a:
                if _misspelt(a, known):
                    issues.append(unknown_name(e, a, known, f"attribute of <{e.tag}>", a,
                                               len(issues) < ModelError.SHOWN))
                else:
                    note(f"{e.tag} {a}")
        kids = _CHILDREN.get(e.tag, ())
        once = _ONCE.get(e.tag, ())
        first: dict[str, Element] = {}
        for c in e.children:
            if c.tag in kids:
                stack.append(c)
                if c.tag in once and c.tag in first:
                    issues.append(second(c, e, first[c.tag], "URDF"))
                elif e.tag == "geometry" and first:
                    shape = next(iter(first.values()))
                    issues.append(c.issue(
                        f"a second shape <{c.tag}> in <geometry> (the first, <{shape.tag}>, "
                        f"is at line {shape.line}, column {shape.column})", "a <geometry> "
                        "holds one shape: give the other one a <visual> or <collision> of "
                        "its own"))
                first.setdefault(c.tag, c)
            elif _misspelt(c.tag, kids):
                issues.append(unknown_name(c, c.tag, kids, f"element in <{e.tag}>",
                                           hint=len(issues) < ModelError.SHOWN))
            else:
                note(f"<{c.tag}> in <{e.tag}>")
    issues.sort(key=lambda i: (i.line, i.column))


def rpy_quat(rpy: np.ndarray) -> np.ndarray:
    """URDF's roll, pitch, yaw (fixed axes x, then y, then z) as a quaternion."""
    r, p, y = rpy / 2
    cr, sr, cp, sp, cy, sy = (math.cos(r), math.sin(r), math.cos(p), math.sin(p),
                              math.cos(y), math.sin(y))
    return np.array([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])


class _Reader:
    def __init__(self, root: Element, file: str):
        self.root, self.file = root, file
        self.issues: list[Issue] = []
        self.notes: dict[str, list[str]] = {}

    def note(self, what: str, item: str) -> None:
        self.notes.setdefault(what, []).append(item)

    def numbers(self, e: Element | None, attr: str, n: int, default: np.ndarray
                ) -> np.ndarray:
        """The `n` numbers of attribute `attr` of `e`; `default` when it is not there, or
        when they are wrong (reported)."""
        if e is None or e.get(attr) is None:
            return default
        x = read_numbers(e, attr, e.get(attr) or "", self.issues, count=n)
        return default if x is None else x

    def origin(self, e: Element) -> tuple[np.ndarray, np.ndarray]:
        o = e.find("origin")
        xyz = self.numbers(o, "xyz", 3, np.zeros(3))
        rpy = self.numbers(o, "rpy", 3, np.zeros(3))
        return xyz, rpy_quat(rpy)

    def read(self, qpos_by_name: dict[str, float], qvel_by_name: dict[str, float],
             floating: bool) -> ImportedDocument:
        links = {}
        for ln in self.root.findall("link"):
            n = ln.get("name")
            if not n:
                self.issues.append(ln.issue("a <link> needs a 'name'"))
                continue
            if n in links:
                self.issues.append(ln.issue(f"duplicate link name '{n}'", attr="name"))
            links[n] = ln
        joints_of: dict[str, Element] = {}  # child link -> joint
        parent_of: dict[str, str] = {}  # child link -> parent link
        children: dict[str, list[str]] = {}
        joint_names: set[str] = set()
        for j in self.root.findall("joint"):
            jn = j.get("name") or "?"
            if j.get("name") and jn in joint_names:
                self.issues.append(j.issue(f"duplicate joint name '{jn}'", attr="name"))
            joint_names.add(jn)
            typ = j.get("type")
            if typ not in JOINT_TYPES:
                self.issues.append(j.issue(f"unknown joint type '{typ}'", did_you_mean(
                    typ or "", JOINT_TYPES) or f"expected one of: {', '.join(JOINT_TYPES)}",
                    "type"))
                continue
            parent, child = j.find("parent"), j.find("child")
            if parent is None or child is None:
                self.issues.append(j.issue(f"joint '{jn}' needs a <parent> and a <child>"))
                continue
            pl, cl = parent.get("link") or "", child.get("link") or ""
            for el, ln_name in ((parent, pl), (child, cl)):
                if ln_name not in links:
                    self.issues.append(el.issue(f"unknown link '{ln_name}'",
                                                did_you_mean(ln_name, links), "link"))
            if cl in joints_of:
                self.issues.append(child.issue(f"link '{cl}' is the child of two joints",
                                               "URDF describes a tree", "link"))
            joints_of[cl], parent_of[cl] = j, pl
            children.setdefault(pl, []).append(cl)
        if self.issues:
            raise ModelError(self.issues)
        roots = [n for n in links if n not in joints_of]
        if not links:
            raise ModelError([self.root.issue(
                "the robot has no <link>", "a file of xacro macros holds none: run xacro on "
                "the robot's own .urdf.xacro")])
        if len(roots) != 1:
            raise ModelError([self.root.issue(
                f"expected one root link (a link that is no joint's child), found "
                f"{len(roots)}" + (f": {', '.join(roots[:5])}" if roots else " (a loop)"))])
        bodies: list[TreeBody] = []
        index: dict[str, int] = {}
        order = [roots[0]]
        for n in order:  # parents first
            order.extend(children.get(n, []))
        if len(order) < len(links):
            raise ModelError(_cycles(links, joints_of, parent_of, set(order), roots[0]))
        for n in order:
            ln = links[n]
            joint = joints_of.get(n)
            if joint is None:
                b = TreeBody(_name(n), -1, np.zeros(3), np.array([1.0, 0, 0, 0]), [], ln)
                self.inertial(b, ln)
                if floating:
                    b.joints = [TreeJoint(f"{n}_free", "free", np.zeros(3),
                                          np.array([0.0, 0, 1]), ln)]
                elif b.mass > 0:
                    self.note("the root link is fixed to the world (its mass is part of "
                              f"the ground; {option_name('floating_base', 'True')} lets it "
                              "move)", n)
                    b.mass = 0.0
                    if not any(links[c].find("inertial") is not None for c in joints_of):
                        # nothing else has a mass: a drone's or a free object's one link
                        raise ModelError([ln.issue(
                            f"the root link '{n}' is the only link with a mass, and it "
                            "is fixed to the world (a URDF's root is, unless it floats): "
                            "nothing moves", f"{option_name('floating_base', 'True')} "
                            "lets it move freely")])
            else:
                pos, quat = self.origin(joint)
                parent_link = joint.find("parent")
                assert parent_link is not None
                b = TreeBody(_name(n), index[parent_link.get("link") or ""], pos, quat,
                             self.joint(joint), ln,
                             fixed_name=joint.get("name") or f"{n}_fixed",
                             fixed_element=joint)
                self.inertial(b, ln)
            b.shape = self.shape(ln)
            index[n] = len(bodies)
            bodies.append(b)
        for t in ("transmission", "gazebo"):
            for e in self.root.findall(t):
                self.note(f"{t}s", e.get("name") or e.get("reference") or t)
        if self.issues:
            raise ModelError(self.issues)
        q0 = qpos0(bodies)
        qpos, qvel = self.state(bodies, q0, qpos_by_name, qvel_by_name)
        name = self.root.get("name") or Path(self.file).stem
        doc = build(name, f"imported from {Path(self.file).name} (URDF)", self.file, bodies,
                    qpos, qvel, q0, np.array([0.0, 0.0, -9.81]), [], self.root, "urdf")
        if self.notes:
            parts = []
            for what, items in self.notes.items():
                shown = ", ".join(items[:4]) + (f" and {len(items) - 4} more"
                                                if len(items) > 4 else "")
                parts.append(f"{what} ({shown})")
            doc.warnings.append(Issue(self.file, 0, 0, "", "not imported (mbody models none "
                                      "of these; the motion computed here leaves them out): "
                                      + "; ".join(parts)))
        return doc

    def joint(self, j: Element) -> list[TreeJoint]:
        typ = j.get("type")
        name = _name(j.get("name") or "joint")
        if typ == "fixed":
            return []
        if typ in ("floating", "planar"):
            self.issues.append(j.issue(
                f"a {typ} joint ('{name}') is not read", f"use "
                f"{option_name('floating_base', 'True')} for a free-floating root link"
                if typ == "floating" else "mbody has no planar joint", "type"))
            return []
        axis = self.numbers(j.find("axis"), "xyz", 3, np.array([1.0, 0, 0]))
        if np.linalg.norm(axis) < 1e-12:
            ax = j.find("axis")
            self.issues.append((ax or j).issue("the joint axis is zero", attr="xyz"))
            axis = np.array([1.0, 0, 0])
        lim = j.find("limit")
        if lim is not None and typ != "continuous":
            self.note("joint limits", name)
        dyn = j.find("dynamics")
        if dyn is not None:
            for k, what in (("damping", "joint damping"), ("friction", "joint friction")):
                if self.numbers(dyn, k, 1, np.zeros(1)).any():
                    self.note(what, name)
        if j.find("mimic") is not None:
            self.note("mimic joints (they move freely here)", name)
        return [TreeJoint(name, "slide" if typ == "prismatic" else "hinge", np.zeros(3),
                          unit(axis), j)]

    def inertial(self, b: TreeBody, ln: Element) -> None:
        i = ln.find("inertial")
        if i is None:
            return
        m = i.find("mass")
        if m is None:
            self.issues.append(i.issue("an <inertial> needs a <mass>"))
            return
        mass = float(self.numbers(m, "value", 1, np.zeros(1))[0])
        if mass < 0:
            self.issues.append(m.issue(f"link '{b.name}': the mass is negative", attr="value"))
            return
        xyz, quat = self.origin(i)
        t = i.find("inertia")
        J = np.zeros((3, 3))
        if t is not None:
            g = {k: float(self.numbers(t, k, 1, np.zeros(1))[0]) for k in _ATTRS["inertia"]}
            J = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]],
                          [g["ixz"], g["iyz"], g["izz"]]])
        b.mass, b.com, b.R_inertia, b.inertia = mass, xyz, quat_to_matrix(quat), J
        b.mass_element, b.mass_at = (t if t is not None else m), m

    def shape(self, ln: Element) -> dict[str, Any] | None:
        best: tuple[float, dict[str, Any]] | None = None
        for v in ln.findall("visual") + ln.findall("collision"):
            g = v.find("geometry")
            for s in g.children if g is not None else []:
                shape: dict[str, Any]
                if s.tag == "box":
                    size = [float(x) for x in self.numbers(s, "size", 3, np.zeros(3))]
                    vol, shape = float(np.prod(size)), {"box": size}
                elif s.tag in ("cylinder", "capsule"):
                    r, L = (float(self.numbers(s, k, 1, np.zeros(1))[0])
                            for k in ("radius", "length"))
                    L += 2 * r if s.tag == "capsule" else 0
                    vol, shape = math.pi * r * r * L, {"cylinder": {"radius": r,
                                                                    "length": L}}
                elif s.tag == "sphere":
                    r = float(self.numbers(s, "radius", 1, np.zeros(1))[0])
                    vol, shape = 4 * r * r * r, {"sphere": {"radius": r}}
                else:
                    continue
                if vol > 0 and (best is None or vol > best[0]):
                    best = (vol, shape)
        return best[1] if best else None

    def state(self, bodies: list[TreeBody], q0: np.ndarray, qp: dict[str, float],
              qv: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
        names: dict[str, tuple[int, int]] = {}
        hinges = set()  # their positions are angles: bounded as a model file's angles are
        a = v = 0
        for _, j in joint_order(bodies):
            names[j.name] = (a, v)
            if j.type == "hinge":
                hinges.add(j.name)
            a += 4 if j.type == "ball" else 7 if j.type == "free" else 1
            v += NV[j.type]
        qpos, qvel = q0.copy(), np.zeros(v)
        problems = []
        for given, target, keyword in ((qp, qpos, "joint_positions"),
                                       (qv, qvel, "joint_velocities")):
            what = option_name(keyword)
            for k, x in given.items():
                where = names.get(k)
                if where is None or k.endswith("_free"):
                    hint = did_you_mean(k, [n for n in names if not n.endswith("_free")])
                    problems.append(Issue(self.file, 0, 0, what, f"no joint named '{k}' moves "
                                          "in this model", hint))
                    continue
                try:
                    value = float(x)
                except (TypeError, ValueError):
                    problems.append(Issue(self.file, 0, 0, what,
                                          f"joint '{k}': expected a number, got {x!r}"))
                    continue
                if not math.isfinite(value):
                    problems.append(Issue(self.file, 0, 0, what,
                                          f"joint '{k}': expected a finite number"))
                    continue
                angle = target is qpos and k in hinges
                limit = MAX_ANGLE if angle else MAX_MAGNITUDE
                if abs(value) > limit:
                    problems.append(Issue(self.file, 0, 0, what, f"joint '{k}': " + (
                        f"expected an angle of at most {limit:.6g} rad in magnitude"
                        if angle else f"expected a number of magnitude at most {limit:.6g}")
                        + f", as in a model file, got {value:.6g}"))
                    continue
                target[where[0] if target is qpos else where[1]] = value
        if problems:
            raise ModelError(problems)
        return qpos, qvel


def _name(n: str) -> str:
    return "".join("_" if ch == "." or ch.isspace() else ch for ch in n)


def _cycles(links: dict[str, Element], joints_of: dict[str, Element],
            parent_of: dict[str, str], reached: set[str], root: str) -> list[Issue]:
    """Each cycle of joints that the links not `reached` from the `root` link hang from.

    Every link but the root is the child of exactly one joint, so following parents from a
    link the root does not reach never ends at the root: it runs into a cycle. Each cycle
    is said at its first joint in the file, with every link that is lost with it."""
    cycle_of: dict[str, int] = {}  # unreached link -> the cycle it hangs from
    cycles: list[list[str]] = []  # each cycle's links, in the order its joints run
    for start in links:
        if start in reached or start in cycle_of:
            continue
        path: list[str] = []
        at: dict[str, int] = {}
        n = start
        while n not in cycle_of and n not in at:
            at[n] = len(path)
            path.append(n)
            n = parent_of[n]
        if n in cycle_of:
            k = cycle_of[n]
        else:  # a new cycle: path[at[n]:]
            k = len(cycles)
            cycles.append(path[at[n]:])
        for m in path:
            cycle_of[m] = k
    lost: list[list[str]] = [[] for _ in cycles]  # each cycle's links and theirs
    for n in links:
        if n in cycle_of:
            lost[cycle_of[n]].append(n)
    issues = []
    for k, ring in enumerate(cycles):
        joints = sorted((joints_of[n] for n in ring), key=lambda j: (j.line, j.column))
        names = _listed([f"'{j.get('name') or '?'}'" for j in joints])
        what = (f"joint {names} has link '{ring[0]}' as its parent and its child"
                if len(ring) == 1 else f"joints {names} form a cycle")
        shown = _listed([f"'{n}'" for n in lost[k]])
        fix = ("name in its <parent> the link it hangs from" if len(ring) == 1 else
               "one of these joints names the wrong <parent> or <child>")
        issues.append(joints[0].issue(
            f"{what}: a URDF describes a tree", f"link{'s' if len(lost[k]) > 1 else ''} "
            f"{shown} {'are' if len(lost[k]) > 1 else 'is'} not connected to the root link "
            f"'{root}': {fix}"))
    return sorted(issues, key=lambda i: (i.file, i.line, i.column))


def _listed(items: list[str], most: int = 10) -> str:
    """The first `most` of `items`, with how many more there are."""
    return ", ".join(items[:most]) + (f" and {len(items) - most} more"
                                      if len(items) > most else "")
