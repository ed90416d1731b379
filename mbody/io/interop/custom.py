"""What MJCF cannot say about an mbody model, kept in MuJoCo's own ``<custom>`` element.

MuJoCo stores ``<custom><numeric>`` and ``<custom><text>`` entries in the model and
otherwise ignores them, so a file carrying them loads in MuJoCo unchanged. The export
(`mbody.io.interop.mjcf_write`) writes one small entry per piece that MJCF's own elements
lose, each named ``mbody:<kind>[:<key>]``; the import (`mbody.io.interop.mjcf`) reads
them back and restores what the mbody model had. Bodies, masses, inertias, the joints
MJCF holds, gravity and the state always come from MJCF's native elements.

========================  ========  ===================================================
name                      element   data
========================  ========  ===================================================
``mbody:dimension``       numeric   2 (planar) or 3 (spatial)
``mbody:body:B``          text      JSON object of body B's keys MJCF cannot hold:
                                    ``{"inertia": 0}`` for a particle; the file's pose
                                    and velocities of a model assembled at load
``mbody:joint:J``         text      JSON object. With ``type``: the whole joint J (MJCF
                                    has no element that is exactly it: fixed joints, a
                                    particle's pin, joints that close loops). Without:
                                    the keys that differ from what MJCF says (``parent``
                                    and ``child`` when the joint runs against the tree,
                                    a screw's ``pitch``, the file's ``at`` and axes)
``mbody:load:L``          text      JSON object of load L as the model file writes it;
                                    ``{"type": "spring"}``: the spatial tendon L
``mbody:reaction:R``      numeric   the known value of reaction component R
``mbody:reaction:R``      text      the same, an expression of t
``mbody:driver:D``        text      JSON object of driver D as the model file writes
                                    it, but its name (``{"joint": "O", "speed": 10}``)
``mbody:order``           text      JSON object: the model file's order of its
                                    ``bodies`` and ``joints`` (names), which MJCF's
                                    nesting does not keep
========================  ========  ===================================================

A model that `mbody.load` assembles (joint points per body, drivers) is exported at its
assembled pose; its body and joint entries hold the file's pose, points and axes, so
that the document read back is the file that was written, and assembles the same way.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, TypeVar
from xml.sax.saxutils import quoteattr

import numpy as np

from mbody import joint_types
from mbody.errors import Issue, ModelError, did_you_mean
from mbody.io.interop.attrvalues import read_numbers
from mbody.io.interop.tree import ImportedDocument
from mbody.io.interop.xmlsource import Element, one_line
from mbody.model.loader import dotted

PREFIX = "mbody:"
KINDS = ("dimension", "body", "joint", "load", "reaction", "driver", "order")
WHOLE = ("dimension", "order")
"""Kinds of one entry for the model, without a key."""
ORDERED = ("bodies", "joints")
"""The lists of the model file whose order ``mbody:order`` keeps."""
T = TypeVar("T")
ONE = {"bodies": "body", "joints": "joint"}
"""An item of each of `ORDERED`, named in a message."""


@dataclass
class Custom:
    """The ``mbody:`` entries of an MJCF file, each with its element (for messages)."""

    dimension: int = 3
    dimension_element: Element | None = None
    bodies: dict[str, tuple[dict[str, Any], Element]] = field(default_factory=dict)
    joints: dict[str, tuple[dict[str, Any], Element]] = field(default_factory=dict)
    loads: list[tuple[str, dict[str, Any], Element]] = field(default_factory=list)
    reactions: dict[str, tuple[float | str, Element]] = field(default_factory=dict)
    drivers: list[tuple[str, dict[str, Any], Element]] = field(default_factory=list)
    order: tuple[dict[str, list[str]], Element] | None = None

    def particle(self, body: str) -> bool:
        """Whether the entries make `body` a particle (``inertia: 0``)."""
        entry = self.bodies.get(body)
        return entry is not None and entry[0].get("inertia") == 0

    @property
    def springs(self) -> list[str]:
        """The loads that are spatial tendons of the file, by name."""
        return [n for n, d, _ in self.loads if d.get("type") == "spring"]


# -- writing -----------------------------------------------------------------------------


def numeric(key: str, values: list[float]) -> str:
    """A ``<numeric>`` entry (numbers as Python's repr: they read back as the same double)."""
    data = " ".join(_num(x) for x in values)
    return f"<numeric name={quoteattr(PREFIX + key)} data=\"{data}\"/>"


def text(key: str, value: Any) -> str:
    """A ``<text>`` entry; mappings as compact JSON (exact for doubles)."""
    data = value if isinstance(value, str) else json.dumps(value, separators=(", ", ": "))
    return f"<text name={quoteattr(PREFIX + key)} data={quoteattr(data)}/>"


def _num(x: float) -> str:
    x = float(x)
    if x == 0.0:
        return "0"
    return str(int(x)) if x == int(x) and abs(x) < 1e15 else repr(x)


# -- reading -----------------------------------------------------------------------------


def read_custom(root: Element) -> Custom | None:
    """The ``mbody:`` entries of the ``<custom>`` elements of `root`; None when there are
    none (a plain MJCF file, read as MuJoCo reads it).

    Raises
    ------
    ModelError
        An unknown ``mbody:`` kind, data that is not what the kind holds.
    """
    out = Custom()
    found = False
    issues: list[Issue] = []
    for c in root.findall("custom"):
        for e in c.children:
            name = e.get("name") or ""
            if e.tag not in ("numeric", "text") or not name.startswith(PREFIX):
                continue
            found = True
            kind, _, key = name[len(PREFIX):].partition(":")
            data = e.get("data") or ""
            if kind not in KINDS:
                issues.append(e.issue(f"unknown mbody entry kind '{kind}'",
                                      did_you_mean(kind, KINDS) or
                                      f"expected mbody:{', mbody:'.join(KINDS)}", "name"))
                continue
            if (kind in WHOLE) != (key == ""):
                issues.append(e.issue(f"'{name}': "
                                      + (f"mbody:{kind} takes no key" if kind in WHOLE
                                         else f"mbody:{kind} needs a key (mbody:{kind}:NAME)"),
                                      attr="name"))
                continue
            if e.tag == "numeric":
                if kind not in ("dimension", "reaction"):
                    issues.append(e.issue(f"'{name}': a <numeric> entry holds "
                                          "mbody:dimension or mbody:reaction",
                                          "other entries are <text>", attr="name"))
                    continue
                values = read_numbers(e, "data", data, issues, count=1, hexadecimal=True)
                if values is None:
                    continue
                if kind == "dimension":
                    if values[0] not in (2.0, 3.0):
                        issues.append(e.issue(f"mbody:dimension must be 2 or 3, got "
                                              f"{values[0]:g}", attr="data"))
                        continue
                    out.dimension = int(values[0])
                    out.dimension_element = e
                else:
                    out.reactions[key] = (float(values[0]), e)
                continue
            if kind == "reaction":
                out.reactions[key] = (data, e)
                continue
            if kind == "dimension":
                issues.append(e.issue("mbody:dimension is a <numeric> entry", attr="name"))
                continue
            try:
                value = json.loads(data)
            except ValueError as exc:
                issues.append(e.issue(f"'{name}': the data is not JSON ({exc})",
                                      'such as {"inertia": 0}', "data"))
                continue
            if not isinstance(value, dict):
                issues.append(e.issue(f"'{name}': expected a JSON object", attr="data"))
                continue
            if kind == "body":
                out.bodies[key] = (value, e)
            elif kind == "joint":
                out.joints[key] = (value, e)
            elif kind == "driver":
                out.drivers.append((key, value, e))
            elif kind == "order":
                order = _order(value, e, issues)
                if order is not None:
                    out.order = (order, e)
            else:
                out.loads.append((key, value, e))
    if issues:
        raise ModelError(issues)
    return out if found else None


def _order(value: dict[str, Any], e: Element, issues: list[Issue]
           ) -> dict[str, list[str]] | None:
    """The lists of names of an ``mbody:order`` entry, or None (the problem in
    `issues`)."""
    unknown = [k for k in value if k not in ORDERED]
    if unknown:
        issues.append(e.issue(f"mbody:order: unknown key '{unknown[0]}'",
                              did_you_mean(unknown[0], ORDERED) or
                              f"expected {' and '.join(ORDERED)}", "data"))
        return None
    out: dict[str, list[str]] = {}
    for key, names in value.items():
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            issues.append(e.issue(f"mbody:order: {key} must be a list of names",
                                  attr="data"))
            return None
        if len(set(names)) != len(names):
            twice = next(n for n in names if names.count(n) > 1)
            issues.append(e.issue(f"mbody:order: {key} names '{twice}' twice", attr="data"))
            return None
        out[key] = names
    return out


def reorder(doc: ImportedDocument, custom: Custom) -> None:
    """Put the document's bodies and joints back in the model file's order, as the
    ``mbody:order`` entry lists them (in place, with their marks). MJCF's nesting puts a
    body after its parent and the joints in the tree's order, so without it a model
    written to MJCF and read back would have its bodies and joints, hence the rows and
    columns of its equations, in another order. What the entry does not name (a body
    added to the file by hand) follows in the file's order; a name the file does not
    have is an error at the entry."""
    if custom.order is None:
        return
    order, e = custom.order
    issues: list[Issue] = []
    for key in ORDERED:
        items = doc.data.get(key, [])
        have = [x["name"] for x in items]
        missing = [n for n in order.get(key, []) if n not in have]
        if missing:
            issues.append(e.issue(f"mbody:order: no {ONE[key]} '{missing[0]}' in the file",
                                  did_you_mean(missing[0], have), "data"))
            continue
        rank = {n: i for i, n in enumerate(order.get(key, []))}
        perm = sorted(range(len(items)), key=lambda k: (0, rank[have[k]]) if have[k] in rank
                      else (1, k))
        if perm != list(range(len(items))):
            _permute(doc, key, perm)
    if issues:
        raise ModelError(issues)


def _permute(doc: ImportedDocument, key: str, perm: list[int]) -> None:
    """``doc.data[key]`` reordered so that its k-th item is the old ``perm[k]``-th, with
    every mark and file name under it moved along (one left from an item no longer
    there, after `restore` replaced joints, is dropped)."""
    doc.data[key] = [doc.data[key][k] for k in perm]
    new = {old: k for k, old in enumerate(perm)}
    for table in (doc.marks, doc.key_marks):
        moved = {p: w for p, w in table.items()
                 if len(p) > 1 and p[0] == key and isinstance(p[1], int)}
        for p in moved:
            del table[p]
        for p, w in moved.items():
            if p[1] in new:
                table[(key, new[p[1]], *p[2:])] = w
    doc.files = _moved(doc.files, key, new)
    doc.terms = _moved(doc.terms, key, new)


def _moved(table: dict[str, T], key: str, new: dict[int, int]) -> dict[str, T]:
    """`table` (by dotted path) with the paths under ``key[i]`` moved to ``key[new[i]]``
    (dropped where `new` has no `i`)."""
    out = {}
    for path, value in table.items():
        head, _, rest = path.partition("]")
        index = head[len(key) + 1:]
        if head.startswith(f"{key}[") and index.isdigit() and rest[:1] in ("", ".", "["):
            if int(index) not in new:
                continue
            path = f"{key}[{new[int(index)]}]{rest}"
        out[path] = value
    return out


PLANE_TOL = 1e-9
"""How far out of the world x-y plane (relative to the model's size, speeds and gravity)
a planar model may put a body, a joint or a velocity: rounding, no more."""


def planar_issues(doc: ImportedDocument, custom: Custom) -> list[Issue]:
    """Where the file puts the model out of the x-y plane that ``mbody:dimension`` 2
    says it moves in (a body off z = 0 or tilted, a velocity or gravity out of the
    plane, a hinge not about z, a slide not in the plane): read as planar, those would be
    dropped without a word.

    Returns
    -------
    list of Issue
        At the body or joint, in its own file; empty for a spatial model.
    """
    if custom.dimension != 2:
        return []
    data = doc.data
    out: list[Issue] = []
    dim = custom.dimension_element

    def say(path: tuple[Any, ...], what: str) -> None:
        line, col = doc.marks.get(path, (0, 0))
        out.append(doc.locate(Issue(doc.file, line, col, dotted(path), one_line(
            f"mbody:dimension 2 (line {dim.line if dim else '?'}) says the model moves in "
            f"the world x-y plane, but {what}"), "write it in the plane, or remove "
            "mbody:dimension to read the model as spatial")))

    positions = [np.asarray(b["position"], float) for b in data["bodies"]]
    size = max([1.0] + [float(np.abs(x).max()) for x in positions])
    g = np.asarray(data["gravity"], float)
    if abs(g[2]) > PLANE_TOL * max(1.0, float(np.abs(g).max())):
        say(("gravity",), f"gravity has a z component ({g[2]:.6g})")
    for k, b in enumerate(data["bodies"]):
        p: tuple[Any, ...] = ("bodies", k)
        name = b["name"]
        if abs(positions[k][2]) > PLANE_TOL * size:
            say(p, f"body '{name}' is at z = {positions[k][2]:.6g}")
        R = np.asarray(b.get("orientation", {"matrix": np.eye(3)})["matrix"], float)
        if np.abs(R[:2, 2]).max() > PLANE_TOL or R[2, 2] < 0:
            say(p, f"body '{name}' is turned out of the plane (its z axis is "
                f"{', '.join(f'{x:.3g}' for x in R[:, 2])})")
        v = np.asarray(b["velocity"], float)
        w = R @ np.asarray(b.get("angular_velocity", [0.0, 0.0, 0.0]), float)
        if abs(v[2]) > PLANE_TOL * max(1.0, float(np.abs(v).max())):
            say(p, f"body '{name}' moves along z ({v[2]:.6g})")
        if np.abs(w[:2]).max() > PLANE_TOL * max(1.0, float(np.abs(w).max())):
            say(p, f"body '{name}' turns about an axis out of z")
    for k, j in enumerate(data.get("joints", [])):
        p = ("joints", k)
        at = np.asarray(j["at"], float)
        if abs(at[2]) > PLANE_TOL * size:
            say(p, f"joint '{j['name']}' is at z = {at[2]:.6g}")
        axis = np.asarray(j.get("axis", [0.0, 0.0, 1.0]), float)
        if j["type"] == "revolute" and np.abs(axis[:2]).max() > PLANE_TOL:
            say(p, f"the hinge '{j['name']}' turns about an axis out of z")
        if _slides(j["type"]) and abs(axis[2]) > PLANE_TOL:
            say(p, f"the slide '{j['name']}' leaves the plane")
    return out


def restore(data: dict[str, Any], marks: list[dict[Any, tuple[int, int]]],
            custom: Custom, springs: dict[str, dict[str, Any]]) -> None:
    """Give the imported document `data` back what `custom` says (in place).

    `marks` are the document's mark tables (updated for the entries' elements);
    `springs` the spring loads read from their tendons, by name.
    """
    if custom.dimension == 2:
        _planar(data, custom, marks)
    issues: list[Issue] = []
    index = {b["name"]: k for k, b in enumerate(data["bodies"])}
    for name, (entry, e) in custom.bodies.items():
        if name not in index:
            issues.append(e.issue(f"mbody:body:{name}: no body '{name}'",
                                  did_you_mean(name, index), "name"))
            continue
        body = data["bodies"][index[name]]
        body.update(entry)
        for table in marks:  # a key the entry gives is reported at the entry
            for key in entry:
                table[("bodies", index[name], key)] = e.where("data")
        if entry.get("inertia") == 0:  # a particle has no orientation and no spin
            for key in ("orientation", "angle", "angular_velocity"):
                body.pop(key, None)
    joints: list[tuple[dict[str, Any], Any]] = [
        (j, _marks_of(marks, ("joints", k))) for k, j in enumerate(data.get("joints", []))]
    for name, (entry, e) in custom.joints.items():
        if "type" in entry:
            ends = {entry.get("parent"), entry.get("child")}
            joints = [(j, m) for j, m in joints if not (
                j["name"] in (name, f"{name}:axis") or
                (j["type"] == "fixed" and j["name"].endswith("_fixed") and
                 {j["parent"], j["child"]} == ends))]
            joints.append(({"name": name, **entry}, _element_marks(e)))
            continue
        match = [(j, m) for j, m in joints if j["name"] == name]
        if not match:
            issues.append(e.issue(f"mbody:joint:{name}: no joint '{name}' in the file",
                                  did_you_mean(name, [j["name"] for j, _ in joints]),
                                  "name"))
            continue
        j, where = match[0]
        for table in where:  # a key the entry gives is reported at the entry
            for key in entry:
                table[(key,)] = e.where("data")
        if entry.get("parent") == j["child"] and entry.get("child") == j["parent"] and \
                "axis2" in j:  # the tree ran child -> parent: the axes swap back too
            j["axis"], j["axis2"] = j["axis2"], j["axis"]
        j.update(entry)
    if issues:
        raise ModelError(issues)
    if joints:
        data["joints"] = [j for j, _ in joints]
        for table in marks:
            for p in [p for p in table if p[:1] == ("joints",) and len(p) > 1]:
                del table[p]
        for k, (_, m) in enumerate(joints):
            for t, table in enumerate(marks):
                for sub, where in m[t].items():
                    table[("joints", k, *sub)] = where
    loads = []
    for name, entry, e in custom.loads:
        loads.append({"name": name, **(springs[name] if entry.get("type") == "spring"
                                       else entry)})
        for table in marks:
            table[("loads", len(loads) - 1)] = e.where("data")
    if loads:
        data["loads"] = loads
    if custom.reactions:
        data["reactions"] = {label: v for label, (v, _) in custom.reactions.items()}
        for label, (_, e) in custom.reactions.items():
            for table in marks:
                table[("reactions", label)] = e.where("data")
    if custom.drivers:
        data["drivers"] = [{"name": name, **entry} for name, entry, _ in custom.drivers]
        for k, (_, _, e) in enumerate(custom.drivers):
            for table in marks:
                table[("drivers", k)] = e.where("data")


def _slides(typ: str) -> bool:
    """Whether a planar joint type slides (its `axis` is a direction in the plane)."""
    jt = joint_types.TYPES[joint_types.PLANAR].get(typ)
    return jt is not None and any(m.what == joint_types.TRANSLATION for m in jt.motions)


def _marks_of(marks: list[dict[Any, tuple[int, int]]], path: tuple[Any, ...]
              ) -> list[dict[tuple[Any, ...], tuple[int, int]]]:
    """Each mark table's entries under `path`, keyed by the rest of the path."""
    n = len(path)
    return [{p[n:]: w for p, w in table.items() if p[:n] == path} for table in marks]


def _element_marks(e: Element) -> list[dict[tuple[Any, ...], tuple[int, int]]]:
    return [{(): e.where("data")}, {(): e.where("data")}]


def _planar(data: dict[str, Any], custom: Custom,
            marks: list[dict[Any, tuple[int, int]]]) -> None:
    """A planar model written in 3-D (world x-y plane, turning about z) made planar again:
    x, y and the angle about z of each body; the scalar inertia about z."""
    data["dimension"] = 2
    data["gravity"] = data["gravity"][:2]
    for k, b in enumerate(data["bodies"]):
        # a body read without inertia (a point mass: MJCF's diaginertia 0) has no
        # orientation, and its inertia is the number 0
        orientation = b.pop("orientation", None)
        J = b.get("inertia")
        if isinstance(J, list):
            b["inertia"] = float(J[2][2])
        b["position"] = b["position"][:2]
        if orientation is not None:
            R = np.array(orientation["matrix"], dtype=float)
            b["angle"] = float(np.arctan2(R[1, 0], R[0, 0]))
        b["velocity"] = b["velocity"][:2]
        if isinstance(b.get("angular_velocity"), list):
            b["angular_velocity"] = float(b["angular_velocity"][2])
        shape = b.get("shape")
        if shape and ("box" in shape or "ellipsoid" in shape):
            kind = next(iter(shape))
            b["shape"] = {kind: shape[kind][:2]}
        for table in marks:
            if ("bodies", k, "orientation") in table:
                table[("bodies", k, "angle")] = table[("bodies", k, "orientation")]
    for j in data.get("joints", []):
        j["at"] = j["at"][:2]
        if _slides(j["type"]):  # the slide's direction in the plane (prismatic, slot)
            j["axis"] = j["axis"][:2]
        else:
            j.pop("axis", None)
            j.pop("axis2", None)
