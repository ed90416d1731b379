"""A kinematic tree (what MJCF and URDF both describe) -> the model-file structure.

Both readers turn their file into `TreeBody`s: a frame placed in its parent's frame,
the joints that move it (MuJoCo's rules: each joint's anchor and axis in the body's
frame, applied in order), its mass, mass centre and inertia. This module does the rest
once for both: forward kinematics from joint positions and velocities (numpy; no
MuJoCo at run time), the mapping of each body's joints onto one mbody joint, massless
frames, and the plain values `mbody.model.validate` checks, each with the line and
column of the XML it came from.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mbody.errors import Issue, ModelError
from mbody.io.interop.xmlsource import Element, one_line
from mbody.model.loader import Document, Path_, dotted
from mbody.model.validate import PARTICLE_HINT, Spec, validate
from mbody.util.spatial import axis_angle_quat, quat_mul, quat_to_matrix

GROUND = "ground"
PARALLEL_TOL = 1e-9
"""Two unit axes whose cross product is smaller than this are parallel; a dot product
smaller than this, perpendicular; two anchors closer than this (relative to the model's
size), the same point."""


@dataclass
class TreeJoint:
    """One joint of a body: MuJoCo's hinge, slide, ball or free.

    `pos` and `axis` are in the body's frame; `ref` is the joint position at which the
    body sits where the file puts it (MJCF's ``ref``; 0 for URDF).
    """

    name: str
    type: str
    pos: np.ndarray
    axis: np.ndarray
    element: Element
    ref: float = 0.0


@dataclass
class TreeBody:
    """One body (MJCF ``<body>``, URDF ``<link>``), its frame given in its parent's.

    `com` and `R_inertia` place the inertia frame in the body frame; `inertia` is the
    3x3 tensor about the mass centre in that frame.
    """

    name: str
    parent: int  # index of the parent body, -1 for the world
    pos: np.ndarray
    quat: np.ndarray  # w first, body frame in the parent's
    joints: list[TreeJoint]
    element: Element
    mass: float = 0.0
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    R_inertia: np.ndarray = field(default_factory=lambda: np.eye(3))
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    mass_element: Element | None = None
    """Where the mass was written (``<inertial>``, a geom), for error marks."""
    mass_at: Element | None = None
    """Where the mass itself is, when not at `mass_element` (URDF's ``<mass>``)."""
    shape: dict[str, Any] | None = None
    fixed_name: str = ""
    """The name of the fixed joint a body without joints gets (URDF names it)."""
    fixed_element: Element | None = None


@dataclass
class Loop:
    """A joint that closes a loop (MJCF ``connect``/``weld``): spherical or fixed."""

    name: str
    type: str  # "spherical" or "fixed"
    body1: int  # -1 for the world
    body2: int
    anchor: np.ndarray  # in body1's frame ("connect") or body2's ("weld")
    on_body2: bool
    element: Element


@dataclass
class ImportedDocument(Document):
    """A `Document` read from MJCF or URDF, with the import's warnings (as `Issue`s)."""

    warnings: list[Issue] = field(default_factory=list)
    source_format: str = ""
    files: dict[str, str] = field(default_factory=dict)
    """Dotted model path (``bodies[2].inertia``) -> the file its mark's line is in: an
    ``<include>``d file's own name, not the main file's."""
    terms: dict[str, Term] = field(default_factory=dict)
    """Dotted model path -> what the file has there, in its own terms (``link
    'upper_arm' <inertia>``), with where that is."""

    def locate(self, issue: Issue) -> Issue:
        """`issue` in the file's terms: naming the file its line is in (validation names
        the main file), what is there as the file says it (not the model path of the
        YAML form), and advice in the format's words."""
        file, key = issue.file, issue.key
        while key:
            if key in self.files:
                file = self.files[key]
                break
            key = _parent_key(key)
        named = self.named(issue.key, file, issue.line, issue.column)
        hint = _ENTRY.sub(self._entry, issue.hint)
        return dataclasses.replace(
            issue, file=file, key=named, message=_ENTRY.sub(self._entry, issue.message),
            # advice in the file's words for what the file says (not for a value --set)
            hint=in_words_of(self.source_format, hint) if named != issue.key else hint)

    def _entry(self, m: re.Match[str]) -> str:
        """A model path in a message (``first used by bodies[1]``) as the file names it,
        when its term is still what is marked there (an ``mbody:`` entry or the file's
        order may have replaced or moved it)."""
        t = self.terms.get(m.group())
        if t is None or self.files.get(m.group()) != t.file or self.marks.get(
                (m.group(1), int(m.group(2)))) != (t.line, t.column):
            return m.group()
        return t.words

    def named(self, key: str, file: str, line: int, column: int) -> str:
        """The model path `key`, marked at (`file`, `line`, `column`), as the file names
        what is there: its nearest path with a term made for that very place (a value an
        ``mbody:`` entry gives is marked at the entry and keeps its path)."""
        at = key
        while at:
            t = self.terms.get(at)
            if t is not None and (t.file, t.line, t.column) == (file, line, column):
                rest = key[len(at):].lstrip(".")
                return t.words + (f" ({rest})" if rest else "")
            at = _parent_key(at)
        return key


@dataclass(frozen=True)
class Term:
    """What the file has at one place, in its own words, and where that place is."""

    words: str
    file: str
    line: int
    column: int


_ENTRY = re.compile(r"\b(bodies|joints)\[(\d+)\]")
"""A body or joint of the YAML form named by its path in a message."""


def _parent_key(key: str) -> str:
    """``bodies[2].inertia`` -> ``bodies[2]`` -> ``bodies`` -> ``""``."""
    return key[:max(key.rfind("."), key.rfind("["), 0)]


FORMAT_ADVICE: dict[str, dict[str, str]] = {
    PARTICLE_HINT: {
        "urdf": "an <inertia> whose six entries are 0 makes a point mass, which nothing "
                "turns",
        "mjcf": 'an <inertial> with diaginertia="0 0 0" makes a point mass, which nothing '
                "turns"},
}
"""Advice the model checks give in the YAML file's words -> the same in MJCF's and
URDF's, for a model read from those."""


def in_words_of(fmt: str, hint: str) -> str:
    """`hint` with its YAML advice in the words of format `fmt` ("urdf", "mjcf")."""
    for yaml_words, words in FORMAT_ADVICE.items():
        if fmt in words and yaml_words in hint:
            hint = hint.replace(yaml_words, words[fmt])
    return hint


def name_of(e: Element) -> str:
    """How a message names the element `e`: its tag and name (``link 'upper_arm'``), or
    its tag alone (an unnamed MJCF body: its line and column say which)."""
    n = e.get("name")
    if not n:
        return f"<{e.tag}>"
    return f"{e.tag} '{one_line(n if len(n) <= 60 else n[:40] + '...' + n[-10:])}'"


def term(owner: Element, e: Element, attr: str | None = None) -> str:
    """What is at `e` (at its attribute `attr` when it has it), `owner`'s part, in the
    file's words: ``link 'upper_arm' <inertia>``, ``body 'a' <inertial mass>``,
    ``joint 'elbow' axis``."""
    a = attr if attr is not None and attr in e.attrib else ""
    if e is owner:
        return name_of(owner) + (f" {a}" if a else "")
    return f"{name_of(owner)} <{e.tag}{' ' + a if a else ''}>"


def validate_imported(doc: Document) -> Spec:
    """`mbody.model.validate` of an imported document, each issue at its own file.

    Raises
    ------
    ModelError
        As `validate`, with an included file's issues naming that file.
    """
    if not isinstance(doc, ImportedDocument):
        return validate(doc)
    try:
        spec = validate(doc)
    except ModelError as exc:
        raise ModelError([doc.locate(i) for i in exc.issues]) from None
    spec.warnings[:] = [doc.locate(w) for w in spec.warnings]
    return spec


# ---- rotations (w first) ------------------------------------------------------------

def unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


# ---- the joint coordinates ----------------------------------------------------------

NQ = {"hinge": 1, "slide": 1, "ball": 4, "free": 7}
NV = {"hinge": 1, "slide": 1, "ball": 3, "free": 6}


def joint_order(bodies: list[TreeBody]) -> list[tuple[int, TreeJoint]]:
    """Every joint as (body index, joint), in the order of qpos and qvel."""
    return [(i, j) for i, b in enumerate(bodies) for j in b.joints]


def qpos0(bodies: list[TreeBody]) -> np.ndarray:
    """The joint positions at which every body sits where the file puts it (a free
    joint's body is in the world, so its frame as written is its pose)."""
    out: list[float] = []
    for i, j in joint_order(bodies):
        if j.type in ("hinge", "slide"):
            out.append(j.ref)
        elif j.type == "ball":
            out.extend([1.0, 0.0, 0.0, 0.0])
        else:
            out.extend([*bodies[i].pos, *bodies[i].quat])
    return np.array(out)


@dataclass
class Kinematics:
    """World poses and velocities of every body at one joint state.

    `pos`, `R`: each body frame's origin and orientation; `omega`: angular velocity and
    `vel` the origin's velocity, world axes; `anchor`, `axis`: each joint's, world.
    """

    pos: np.ndarray
    R: np.ndarray
    quat: np.ndarray
    omega: np.ndarray
    vel: np.ndarray
    anchor: dict[int, list[np.ndarray]]
    axis: dict[int, list[np.ndarray]]


def forward(bodies: list[TreeBody], qpos: np.ndarray, qvel: np.ndarray,
            q0: np.ndarray) -> Kinematics:
    """Forward kinematics as MuJoCo's ``mj_kinematics`` does it, with velocities.

    Bodies come parents first. Each body's frame is placed in its parent's, then its
    joints act in order: a hinge turns about its anchor by q - ref, a slide moves along
    its axis by q - ref, a ball turns by its quaternion, a free joint sets the pose.
    """
    n = len(bodies)
    pos = np.zeros((n, 3))
    quat = np.zeros((n, 4))
    omega = np.zeros((n, 3))
    vel = np.zeros((n, 3))
    anchors: dict[int, list[np.ndarray]] = {}
    axes: dict[int, list[np.ndarray]] = {}
    qa = va = 0
    for i, b in enumerate(bodies):
        if b.parent < 0:
            ppos, pq, pw, pv = np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3), np.zeros(3)
        else:
            ppos, pq, pw, pv = pos[b.parent], quat[b.parent], omega[b.parent], vel[b.parent]
        Rp = quat_to_matrix(pq)
        xpos = ppos + Rp @ b.pos
        xquat = quat_mul(pq, b.quat)
        motions: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]] = []
        anchors[i], axes[i] = [], []
        for j in b.joints:
            if j.type == "free":
                xpos = qpos[qa:qa + 3].copy()
                xquat = unit(qpos[qa + 3:qa + 7].copy())
                anchors[i].append(xpos.copy())
                axes[i].append(quat_to_matrix(xquat)[:, 2])
                motions.append(("free", xpos.copy(), np.zeros(3), qvel[va:va + 6].copy()))
            else:
                R = quat_to_matrix(xquat)
                xaxis = R @ j.axis
                xanchor = R @ j.pos + xpos
                anchors[i].append(xanchor)
                axes[i].append(xaxis)
                if j.type == "slide":
                    xpos = xpos + xaxis * (qpos[qa] - q0[qa])
                    motions.append(("slide", xanchor, xaxis, qvel[va:va + 1].copy()))
                else:
                    if j.type == "ball":
                        qloc = unit(qpos[qa:qa + 4].copy())
                        motions.append(("ball", xanchor, xaxis, qvel[va:va + 3].copy()))
                    else:
                        qloc = axis_angle_quat(j.axis, qpos[qa] - q0[qa])
                        motions.append(("hinge", xanchor, xaxis, qvel[va:va + 1].copy()))
                    xquat = quat_mul(xquat, qloc)
                    xpos = xanchor - quat_to_matrix(xquat) @ j.pos
            qa += NQ[j.type]
            va += NV[j.type]
        R = quat_to_matrix(xquat)
        w = pw.copy()
        v = pv + np.cross(pw, xpos - ppos)  # the final origin, carried by the parent
        for kind, anchor, xaxis, qd in motions:  # each joint's rate, at the final origin
            if kind == "free":
                v = qd[:3].copy()
                w = R @ qd[3:]
            elif kind == "slide":
                v = v + xaxis * qd[0]
            elif kind == "hinge":
                w = w + xaxis * qd[0]
                v = v + np.cross(xaxis * qd[0], xpos - anchor)
            else:  # ball: rates about the body's own axes (MuJoCo's cdof)
                wb = R @ qd
                w = w + wb
                v = v + np.cross(wb, xpos - anchor)
        pos[i], quat[i], omega[i], vel[i] = xpos, xquat, w, v
    Rs = quat_to_matrix(np.asarray(quat, dtype=float).reshape(-1, 4))
    return Kinematics(pos, Rs, quat, omega, vel, anchors, axes)


# ---- one mbody joint per body -------------------------------------------------------

@dataclass
class Mapped:
    """What a body's joints become: an mbody joint type with its data, or a problem."""

    type: str | None  # revolute, prismatic, universal, spherical, cylindrical, helical,
    # slot, fixed; None: free
    name: str
    at: np.ndarray | None = None
    axis: np.ndarray | None = None
    axis2: np.ndarray | None = None
    element: Element | None = None
    pitch: float | None = None
    reverse: bool = False
    """The joint's parent is the body and its child the body's tree parent (a pin in a
    slot whose slot turns with the body: a hinge, then a slide)."""


EXPORT_SUFFIXES = ({"1", "2"}, {"slide", "turn"})
"""The suffixes the MJCF export gives the parts of one mbody joint (universal:
``J:1``, ``J:2``; cylindrical: ``J:slide``, ``J:turn``)."""


def joint_name(names: list[str]) -> str:
    """One name for several joints of a body: their common stem (``right_hip_x``,
    ``right_hip_y``, ``right_hip_z`` -> ``right_hip``), else the names joined by ``+``.

    Parts named as the MJCF export names them (``J:1``, ``J:2``; ``J:slide``,
    ``J:turn``) give back ``J`` exactly, whatever its length or characters.
    """
    stems = {n.rpartition(":")[0] for n in names}
    if len(stems) == 1 and "" not in stems and \
            {n.rpartition(":")[2] for n in names} in EXPORT_SUFFIXES:
        return stems.pop()
    stem = names[0]
    for n in names[1:]:
        k = 0
        while k < min(len(stem), len(n)) and stem[k] == n[k]:
            k += 1
        stem = stem[:k]
    stem = stem.rstrip("_-: ")
    return stem if len(stem) >= 2 else "+".join(names)


Screw = tuple[str, str]
"""A slide and a hinge by name (MJCF joints) that a joint equality couples linearly."""


def map_joints(b: TreeBody, kin: Kinematics, i: int, scale: float, *, planar: bool = False,
               screws: dict[Screw, float] | None = None) -> Mapped:
    """The one mbody joint that is exactly a body's MJCF joints, or a `ModelError`.

    `planar`: the file is an mbody planar export (``mbody:dimension`` 2), where a slide
    in the plane and a hinge about z are a pin in a slot. `screws`: (slide, hinge) ->
    the advance h (m/rad) an exactly linear joint equality ties them by, s − s_ref =
    h (θ − θ_ref): with the two on one axis, a helical joint of pitch 2π h."""
    js = b.joints
    anchors, axes = kin.anchor[i], kin.axis[i]
    if not js:
        return Mapped("fixed", b.fixed_name or f"{b.name}_fixed", kin.pos[i], None, None,
                      b.fixed_element or b.element)
    names = [j.name for j in js]
    kinds = [j.type for j in js]
    first = js[0].element
    if "free" in kinds:
        if len(js) > 1:
            raise ModelError([first.issue(
                f"body '{b.name}' has a free joint and other joints", "a free joint must be "
                "the body's only joint")])
        return Mapped(None, names[0])
    tol = PARALLEL_TOL * max(scale, 1.0)
    same_point = all(float(np.linalg.norm(a - anchors[0])) <= tol for a in anchors)
    if len(js) == 1:
        typ = {"hinge": "revolute", "slide": "prismatic", "ball": "spherical"}[kinds[0]]
        return Mapped(typ, names[0], anchors[0],
                      axes[0] if typ != "spherical" else None, None, first)
    name = joint_name(names)
    listing = ", ".join(f"{k} '{n}'" for k, n in zip(kinds, names, strict=True))
    if kinds == ["hinge", "hinge"] and same_point and abs(float(axes[0] @ axes[1])) <= 1e-9:
        return Mapped("universal", name, anchors[0], axes[0], axes[1], first)
    if kinds == ["hinge"] * 3 and same_point and abs(float(np.linalg.det(np.array(axes)))) > 1e-6:
        return Mapped("spherical", name, anchors[0], None, None, first)
    if sorted(kinds) == ["hinge", "slide"]:
        h, sl = kinds.index("hinge"), kinds.index("slide")
        if float(np.linalg.norm(np.cross(axes[0], axes[1]))) <= 1e-9:
            lead = (screws or {}).get((names[sl], names[h]))
            if lead is None:
                return Mapped("cylindrical", name, anchors[h], axes[h], None, first)
            # s along the slide's axis; the screw advances along the hinge's
            sign = 1.0 if float(axes[sl] @ axes[h]) > 0 else -1.0
            return Mapped("helical", name, anchors[h], axes[h], None, first,
                          pitch=2.0 * np.pi * lead * sign)
        if planar and abs(abs(float(axes[h][2])) - 1.0) <= 1e-9 and abs(
                float(axes[sl][2])) <= 1e-9:  # a hinge about z, a slide in the plane
            # the pin (the hinge's anchor) slides along a line fixed in the frame the
            # slide moves in: the parent's when the slide comes first; else the hinge
            # turns the line with the body, whose own line holds its parent's pin
            return Mapped("slot", name, anchors[h], axes[sl], None, first, reverse=h < sl)
    why = _why_not(kinds, same_point, axes)
    hint = ("mbody has no massless intermediate frames; what composes exactly: two hinges "
            "through one point with perpendicular axes (universal), three hinges through "
            "one point (spherical), a hinge and a slide along one axis (cylindrical; "
            "helical when a joint equality ties them linearly), a slide in the plane and a "
            "hinge about z in a planar model (slot). Give the intermediate frame a body "
            "with a mass, or change the joints")
    if kinds.count("slide") == 2 and kinds.count("hinge") <= 1:
        # dm_control's planar walkers and objects: a mass would change their motion
        hint = ("two slides (and a hinge) make the body move in a plane; a spatial mbody "
                "model has no planar joint, and the import reads them as a planar free "
                "body only in mbody's own planar exports (their mbody:dimension entry)")
    raise ModelError([first.issue(
        f"body '{b.name}' has {len(js)} joints ({listing}) that no single mbody joint "
        f"is exactly: {why}", hint)])


def _why_not(kinds: list[str], same_point: bool, axes: list[np.ndarray]) -> str:
    if "ball" in kinds:
        return "a ball joint composes with no other joint"
    if kinds.count("slide") > 1:
        return "mbody has no joint with two sliding directions"
    if "slide" in kinds:
        return "the slide is not along the hinge's axis"
    if not same_point:
        return "their axes do not pass through one point (the anchors differ)"
    if len(kinds) == 2:
        return (f"their axes are not perpendicular (axis . axis = "
                f"{float(axes[0] @ axes[1]):.3g})")
    return "more than three joints, or three hinges whose axes are coplanar"


# ---- the document ---------------------------------------------------------------

class DocBuilder:
    """Plain model-file values with the XML mark of each, for `mbody.model.validate`."""

    def __init__(self, file: str):
        self.file = file
        self.marks: dict[Path_, tuple[int, int]] = {}
        self.key_marks: dict[Path_, tuple[int, int]] = {}
        self.files: dict[str, str] = {}
        self.terms: dict[str, Term] = {}

    def mark(self, path: Path_, e: Element | None, attr: str | None = None,
             owner: Element | None = None) -> None:
        """Mark `path` at `e` (its attribute `attr`), part of `owner` (the link, body or
        joint that messages name it by; none: messages give the path)."""
        if e is None:
            return
        self.marks[path] = e.where(attr)
        self.key_marks[path] = e.where(attr)
        self.files[dotted(path)] = e.file
        if owner is not None:
            self.terms[dotted(path)] = Term(term(owner, e, attr), e.file, *e.where(attr))


def _floats(v: np.ndarray) -> list[float]:
    return [float(x) for x in v]


def build(name: str, description: str, file: str, bodies: list[TreeBody],
          qpos: np.ndarray, qvel: np.ndarray, q0: np.ndarray, gravity: np.ndarray,
          loops: list[Loop], root: Element, fmt: str,
          free_bodies: frozenset[int] = frozenset(), *, planar: bool = False,
          screws: dict[Screw, float] | None = None) -> ImportedDocument:
    """The model-file values of the tree at joint state (qpos, qvel).

    `free_bodies` (tree indices) move freely: their joints are known to be exactly a free
    motion (the slides and hinge the MJCF export writes for a free planar body or particle).
    `planar` and `screws`: as `map_joints` composes a body's joints.

    Bodies without mass that sit welded to their parent (frames: URDF's ``tool0``, a
    bare MJCF body) are left out, their children joined to the nearest body kept; a body
    without mass that moves is an error (mbody needs a mass on every moving body).
    """
    warnings: list[Issue] = []
    for b in bodies:  # "ground" names the world in mbody: a body so named is renamed
        if b.name == GROUND:
            taken = {x.name for x in bodies}
            b.name = next(f"{GROUND}_{k}" if k else f"{GROUND}_body" for k in range(
                len(bodies) + 1) if (f"{GROUND}_{k}" if k else f"{GROUND}_body") not in taken)
            warnings.append(Issue(file, *b.element.where("name"), "", f"the body "
                                  f"'{GROUND}' is named '{b.name}' here: mbody's '{GROUND}' "
                                  "is the fixed world frame"))
    kin = forward(bodies, qpos, qvel, q0)
    scale = float(max([1.0] + [float(np.abs(p).max()) for p in kin.pos]))
    issues: list[Issue] = []
    kept: dict[int, str] = {}  # tree index -> mbody body name
    owner: dict[int, int] = {}  # tree index -> kept tree index it is welded into, or -1
    floating = -2  # a massless frame with a free joint: its first massive part moves freely
    free: set[int] = set()
    points: set[int] = set()  # point masses welded to a body: spherical joints
    extra: dict[int, Any] = {}  # kept tree index -> inertia of massless frames welded to it
    for i, b in enumerate(bodies):
        if b.mass > 0:
            kept[i] = b.name
            owner[i] = i
            if not b.joints and b.parent >= 0 and owner.get(b.parent) == floating:
                owner[b.parent] = i  # URDF's massless root link: the trunk floats
                free.add(i)
            elif not b.joints and b.parent >= 0 and not b.inertia.any():
                # A point mass (mass, no inertia: a URDF contact or sensor link) welded to
                # its parent: mbody's particle, which has no orientation to weld, so a
                # spherical joint at the point holds it exactly (its moment is zero). What
                # is fixed to it is fixed to the body it is welded to.
                points.add(i)
                owner[i] = owner.get(b.parent, -1)
        elif [j.type for j in b.joints] == ["free"]:
            owner[i] = floating
        elif b.joints:
            e = b.joints[0].element
            issues.append(e.issue(
                f"body '{b.name}' has no mass but moves on joint '{b.joints[0].name}'",
                "mbody needs a mass on every moving body (it has no massless intermediate "
                "frames): give the body an inertial with a mass, or geoms with one"))
        else:
            owner[i] = owner.get(b.parent, -1) if b.parent >= 0 else -1
            o = owner[i]
            if o >= 0 and b.inertia.any():
                # A frame with inertia but no mass (bolt's feet) turns with the body it is
                # welded to: with no mass there is no parallel-axis term, so its tensor
                # adds to that body's as it is, turned into the body's inertia axes.
                W = kin.R[i] @ b.R_inertia
                B = kin.R[o] @ bodies[o].R_inertia
                T = B.T @ W
                extra[o] = extra.get(o, 0.0) + T @ b.inertia @ T.T
    carried: set[int] = set()  # the massless frames a freely moving body with a mass is welded to
    for i in free:
        up = bodies[i].parent
        while up >= 0 and up not in kept:
            carried.add(up)
            up = bodies[up].parent
    for i, o in owner.items():  # a free frame that no body with a mass is welded to
        if o == floating and i not in carried and bodies[i].joints:
            e = bodies[i].joints[0].element
            issues.append(e.issue(
                f"body '{bodies[i].name}' has no mass but moves on joint "
                f"'{bodies[i].joints[0].name}'", "mbody needs a mass on every moving body: "
                "give the body an inertial with a mass, or geoms with one, or weld a body "
                "with a mass to it"))
    if issues:
        raise ModelError(issues)
    if not kept:
        raise ModelError([Issue(file, root.line, root.column, "", "the model has no body "
                                "with a mass", "mbody models need at least one")])
    doc = DocBuilder(file)
    out_bodies: list[dict[str, Any]] = []
    out_joints: list[dict[str, Any]] = []
    for i, b in enumerate(bodies):
        if i not in kept:
            continue
        R = kin.R[i]
        Rb = R @ b.R_inertia
        c = kin.pos[i] + R @ b.com
        v = kin.vel[i] + np.cross(kin.omega[i], c - kin.pos[i])
        k = len(out_bodies)
        J = b.inertia + extra.get(i, 0.0)
        entry: dict[str, Any] = {
            "name": b.name, "mass": float(b.mass),
            "inertia": [[float(x) for x in row] for row in 0.5 * (J + J.T)],
            "position": _floats(c), "orientation": {"matrix": [_floats(r) for r in Rb]},
            "velocity": _floats(v), "angular_velocity": _floats(Rb.T @ kin.omega[i])}
        if not J.any():  # a particle: no orientation, no angular velocity
            del entry["orientation"], entry["angular_velocity"]
        if b.shape is not None:
            entry["shape"] = b.shape
        out_bodies.append(entry)
        p: Path_ = ("bodies", k)
        doc.mark(p, b.element, owner=b.element)
        doc.mark((*p, "name"), b.element, "name", owner=b.element)
        doc.mark((*p, "mass"), b.mass_at or b.mass_element or b.element,
                 "value" if b.mass_at is not None else "mass", owner=b.element)
        doc.mark((*p, "inertia"), b.mass_element or b.element, owner=b.element)
        m = (map_joints(b, kin, i, scale, planar=planar, screws=screws)
             if i not in free and i not in free_bodies else Mapped(None, ""))
        if i in points:
            m = Mapped("spherical", m.name, c, None, None, m.element)
        if m.type is None:
            continue
        parent = _parent_name(bodies, b.parent, owner, kept)
        ends = (parent, b.name)
        if m.reverse:
            if parent == GROUND:
                raise ModelError([(m.element or b.element).issue(
                    f"body '{b.name}' turns about a point fixed in the world and slides "
                    f"along its own axis ({m.name}): a pin in a slot whose pin is the "
                    "world's", "mbody's slot joint has the slot in its parent and the pin "
                    "on its child, which cannot be ground: give the pin a body of its own, "
                    "fixed to the world, or slide first, then turn (the slot in the world)")])
            ends = (b.name, parent)
        jd: dict[str, Any] = {"name": m.name, "type": m.type, "parent": ends[0],
                              "child": ends[1], "at": _floats(m.at if m.at is not None
                                                              else kin.pos[i])}
        if m.axis is not None:
            jd["axis"] = _floats(m.axis)
        if m.axis2 is not None:
            jd["axis2"] = _floats(m.axis2)
        if m.pitch is not None:
            jd["pitch"] = float(m.pitch)
        jp: Path_ = ("joints", len(out_joints))
        out_joints.append(jd)
        je = m.element or b.element
        doc.mark(jp, je, owner=je)
        for key in jd:
            if key in ("name", "type") or key in je.attrib:  # MJCF's axis
                doc.mark((*jp, key), je, key, owner=je)
            elif key == "axis" and je.find("axis") is not None:  # URDF's <axis xyz>
                doc.mark((*jp, key), je.find("axis"), "xyz", owner=je)
            else:  # the joint's point, its bodies: what the file says of them is the joint
                doc.mark((*jp, key), je)
    for lp in loops:
        loop = _loop(lp, bodies, kin, owner, kept)
        if loop is None:  # both ends welded into one body (or the world): it always holds
            one = _parent_name(bodies, lp.body1, owner, kept)
            warnings.append(Issue(lp.element.file, *lp.element.where(), "",
                                  f"the {lp.element.tag} '{lp.name}' joins two parts of "
                                  f"one rigid body ('{one}'): it always holds, and is left "
                                  "out"))
            continue
        jp = ("joints", len(out_joints))
        out_joints.append(loop)
        doc.mark(jp, lp.element, owner=lp.element)
    data: dict[str, Any] = {"model": name, "description": description, "dimension": 3,
                            "gravity": _floats(gravity), "bodies": out_bodies}
    if out_joints:
        data["joints"] = out_joints
    doc.marks[()] = (root.line, root.column)
    for key in ("model", "dimension", "gravity", "bodies", "joints"):
        doc.marks[(key,)] = (root.line, root.column)
    return ImportedDocument(data, file, doc.marks, doc.key_marks, warnings=warnings,
                            source_format=fmt, files=doc.files, terms=doc.terms)


def _parent_name(bodies: list[TreeBody], parent: int, owner: dict[int, int],
                 kept: dict[int, str]) -> str:
    if parent < 0:
        return GROUND
    o = owner.get(parent, -1)
    if o == -2:
        raise ModelError([bodies[parent].element.issue(
            f"the free body '{bodies[parent].name}' has no mass", "give it an inertial with a "
            "mass, or fix a link with a mass to it before its moving children")])
    return kept[o] if o >= 0 else GROUND


def _loop(lp: Loop, bodies: list[TreeBody], kin: Kinematics, owner: dict[int, int],
          kept: dict[int, str]) -> dict[str, Any] | None:
    b1 = _parent_name(bodies, lp.body1, owner, kept)
    b2 = _parent_name(bodies, lp.body2, owner, kept)
    if b2 == GROUND:
        b1, b2 = b2, b1
    if b2 == GROUND or b1 == b2:
        return None
    on = lp.body2 if lp.on_body2 else lp.body1
    if on < 0:
        at = lp.anchor
    else:
        at = kin.pos[on] + kin.R[on] @ lp.anchor
    return {"name": lp.name, "type": lp.type, "parent": b1, "child": b2, "at": _floats(at)}
