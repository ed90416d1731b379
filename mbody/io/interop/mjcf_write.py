"""A model as MuJoCo's MJCF: bodies nested along a spanning tree of the joint graph.

Each MuJoCo body frame is the mbody body frame at the initial pose (origin at the mass
centre, axes = body axes), so ``xipos`` is the mass centre, ``xmat`` is ``W_R_B`` and
every reference configuration (``qpos0``) is the file's initial pose. A joint of the
tree sits in its child body (``pos`` = the joint point in the child's axes); a joint
that closes a loop becomes an equality constraint, which MuJoCo enforces softly.

Joint types: revolute → hinge, prismatic → slide, cylindrical → slide + hinge on one
axis, helical → slide + hinge on one axis coupled by a joint equality (soft in MuJoCo),
slot (planar) → slide along the slot, then a hinge at the pin, spherical → ball,
universal → two hinges in the child body (MuJoCo composes a body's joints in order: the
first axis stays fixed in the parent, the second turns with the first and is fixed in
the child, which is the universal joint exactly; no massless intermediate body is
needed, so the equations keep their bodies), fixed → no joint (the child is welded by
nesting). A body with no joint to the tree's root gets a free joint (spatial), or slides
along world x, y and a hinge about z (planar; slides only for a particle). Planar models
are written in 3-D: every planar joint turns about world z or slides in the plane, so
the motion stays planar.

A model that `mbody.load` assembles (joint points given per body, drivers) is written
at its assembled pose, where every joint closes: the state MuJoCo starts from is the one
mbody starts from. The file's own form (its pose, its joint points and axes, the
drivers) goes into ``mbody:`` entries, so that reading the file back gives the model
file that was written, which assembles the same way.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from mbody import __version__, joint_types
from mbody import conventions as cv
from mbody.io.interop.custom import numeric, text
from mbody.joint_types.base import SCREW
from mbody.model.drawn import inertia_box
from mbody.model.model import Joint, Model, count
from mbody.util.atomic import write_atomic
from mbody.util.spatial import (
    matrix_to_quat,
    quat_conj,
    quat_mul,
    quat_to_matrix,
)

PARTICLE_INERTIA = 1e-12
"""A particle's principal moments in MuJoCo, as a fraction of m ℓ² (ℓ the model's length
scale): MuJoCo refuses a moving body without rotational inertia. The relative change of
the accelerations is of this order."""

LOOP_SOLIMP = "0.9999 0.9999 0.001 0.5 2"
"""Impedance of the loop-closing equality constraints and the screws' couplings: MuJoCo's
stiffest (its default, 0.9, lets a loop give by about 10 % of the force that holds it
together)."""

_TREE_FIRST = {None: 0, "weld": 1, "connect": 2}
"""Which joints go into the tree first, by the MuJoCo equality that would close a loop
with them (mbody.joint_types: mjcf_loop): those that have none (prismatic, cylindrical,
universal...), then fixed (weld), then revolute and spherical, whose loop-closing form
(connect) is the closest."""

_HEX = re.compile(r"#[0-9a-fA-F]{6}")


@dataclass
class _Tree:
    """The spanning forest: each body's tree parent and joint, and the loop closures."""

    parent: dict[str, str]  # body -> tree parent (a body or ground)
    joint: dict[str, Joint | None]  # body -> the joint to its tree parent (None: a root)
    children: dict[str, list[str]]  # ground or body -> its tree children, in order
    loops: list[Joint] = field(default_factory=list)


def spanning_tree(model: Model) -> _Tree:
    """The joint tree MuJoCo nests, and the joints left over to close loops.

    Kruskal's rule on the body/joint graph: joints taken in the order of `_TREE_FIRST`
    (file order within a kind), each kept unless it closes a loop. Bodies reached from
    ground hang from it; every other connected part hangs from its first body in file
    order, which gets a free joint.

    Parameters
    ----------
    model : Model

    Returns
    -------
    _Tree
    """
    root = {n: n for n in (cv.GROUND, *model.body_names)}

    def find(n: str) -> str:
        while root[n] != n:
            root[n] = root[root[n]]
            n = root[n]
        return n

    order = sorted(range(len(model.joints)),
                   key=lambda k: (_TREE_FIRST[joint_types.joint_type(
                       model.dimension, model.joints[k].type).mjcf_loop], k))
    kept: list[Joint] = []
    loops: list[Joint] = []
    for k in order:
        j = model.joints[k]
        a, b = find(j.parent), find(j.child)
        if a == b:
            loops.append(j)
        else:
            root[b] = a
            kept.append(j)
    kept.sort(key=model.joints.index)
    loops.sort(key=model.joints.index)
    adjacent: dict[str, list[Joint]] = {n: [] for n in root}
    for j in kept:
        adjacent[j.parent].append(j)
        adjacent[j.child].append(j)
    tree = _Tree({}, {}, {n: [] for n in root}, loops)
    starts = [cv.GROUND] + list(model.body_names)
    seen: set[str] = set()
    for start in starts:
        if start in seen:
            continue
        seen.add(start)
        if start != cv.GROUND:
            tree.parent[start], tree.joint[start] = cv.GROUND, None
            tree.children[cv.GROUND].append(start)
        queue = [start]
        while queue:
            node = queue.pop(0)
            for j in adjacent[node]:
                other = j.child if j.parent == node else j.parent
                if other in seen:
                    continue
                seen.add(other)
                tree.parent[other], tree.joint[other] = node, j
                tree.children[node].append(other)
                queue.append(other)
    return tree


@dataclass(frozen=True)
class _Geometry:
    """Every joint where the export writes it: at the initial state, world axes.

    point: (k, 3) the joint point on the child (a slot's pin; the parent's point for a
    particle child); frame: (k, 3, 3) the joint frame fixed in the parent, axes as
    columns; axis2: (k, 3) a universal joint's child axis. A model whose initial state is
    the file's pose gives them as its joints' records do (the file's numbers); an
    assembled one from its joint table, carried to the assembled pose.
    """

    point: np.ndarray
    frame: np.ndarray
    axis2: np.ndarray
    index: dict[str, int]


def _geometry(m: Model) -> _Geometry:
    """Where the export writes each joint of `m` (`_Geometry`)."""
    index = {j.name: k for k, j in enumerate(m.joints)}
    k = len(m.joints)
    if not _file_form(m):
        point = np.array([np.asarray(j.at, dtype=float) for j in m.joints]).reshape(k, 3)
        frame = np.array([np.asarray(j.W_E0, dtype=float) for j in m.joints]).reshape(k, 3, 3)
        axis2 = np.array([np.zeros(3) if j.axis2 is None else np.asarray(j.axis2, dtype=float)
                          for j in m.joints]).reshape(k, 3)
        return _Geometry(point, frame, axis2, index)
    jt = m.joint_table
    st = m.initial
    R = quat_to_matrix(st.quaternion).reshape(-1, 3, 3)
    p, c = jt.parent, jt.child
    ground = p < 0
    R_p = np.where(ground[:, None, None], np.eye(3), R[p])
    x_p = np.where(ground[:, None], 0.0, st.position[p])
    on_child = st.position[c] + (R[c] @ jt.B_r_child[:, :, None])[:, :, 0]
    on_parent = x_p + (R_p @ jt.B_r_parent[:, :, None])[:, :, 0]
    child_particle = m.particle[c]
    point = np.where(child_particle[:, None], on_parent, on_child)
    both = child_particle & jt.particle_parent  # two particles: the file's point
    if both.any():
        point[both] = [np.asarray(m.joints[int(q)].at, dtype=float)
                       for q in np.flatnonzero(both)]
    frame = R_p @ jt.P_E3
    axis2 = (R[c] @ jt.C_axis2[:, :, None])[:, :, 0]
    return _Geometry(point, frame, axis2, index)


def _file_form(m: Model) -> bool:
    """Whether the model's initial state is not the file's pose (`mbody.load` assembled
    it: joint points per body, drivers), so that its joints' records, made at the file's
    pose, are not where the export writes them."""
    return m.file_state is not None or bool(m.joint_table.body_points.any())


@dataclass
class _Writer:
    """What `to_mjcf` accumulates: lines of the body tree, the keyframe, the notes."""

    model: Model
    scale: float
    geo: _Geometry
    lines: list[str] = field(default_factory=list)
    qpos: list[float] = field(default_factory=list)
    qvel: list[float] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    joint_names: set[str] = field(default_factory=set)
    sites: dict[str, list[str]] = field(default_factory=dict)  # body -> its site lines
    worst_velocity: float = 0.0
    native: dict[str, str] = field(default_factory=dict)  # joint -> the body holding it
    screws: list[tuple[Joint, str, str]] = field(default_factory=list)
    """Helical joints of the tree: (joint, its MuJoCo slide, its MuJoCo hinge)."""

    def name(self, wanted: str) -> str:
        """A joint name not used yet (MuJoCo wants them unique)."""
        out, k = wanted, 2
        while out in self.joint_names:
            out, k = f"{wanted}~{k}", k + 1
        self.joint_names.add(out)
        return out


def to_mjcf(model: Model, *, source: str | None = None) -> str:
    """The model as an MJCF document (MuJoCo's XML), at its initial state.

    Bodies nest along `spanning_tree`; each body frame is the mass centre with the body
    axes at the initial pose, so MuJoCo's ``qpos0`` is the file's pose. Gravity goes to
    ``<option>``, shapes to geoms that take no part in contacts, springs to spatial
    tendons, joints that close loops to ``<equality>`` constraints, the initial state to
    ``<keyframe><key name="initial">``. What MJCF cannot hold (point forces and couples,
    known reaction values) is listed in the header comment.

    Parameters
    ----------
    model : Model
    source : str, optional
        The file named in the header (default: the model's own file).

    Returns
    -------
    str
        The MJCF text.
    """
    geometry = _geometry(model)
    scale = _length_scale(model, geometry)
    w = _Writer(model, scale, geometry)
    tree = spanning_tree(model)
    for spring in range(len(model.springs.names)):
        _spring_sites(w, spring)
    for child in tree.children[cv.GROUND]:
        _body(w, tree, child, depth=2)
    equality = _equalities(w, tree.loops)
    tendons = _tendons(w)
    g = model.gravity
    out = [_header(w, tree, source), f"<mujoco model={quoteattr(model.name)}>",
           '  <compiler angle="radian" autolimits="true"/>',
           f'  <option gravity="{_vec(g)}"/>',
           "  <worldbody>", *("    " + s for s in w.sites.get(cv.GROUND, [])), *w.lines,
           "  </worldbody>"]
    out += _custom(w, tree) + equality + tendons
    out += ["  <keyframe>",
            f'    <key name="initial" time="0" qpos="{_vec(w.qpos)}" qvel="{_vec(w.qvel)}"/>',
            "  </keyframe>", "</mujoco>", ""]
    return "\n".join(out)


def write_mjcf(model: Model, path: str | os.PathLike[str], *,
               source: str | None = None) -> Path:
    """Write `to_mjcf(model)` to `path` atomically.

    Parameters
    ----------
    model : Model
    path : str or os.PathLike
        The ``.xml`` file to write (replaced whole, or left as it was on failure).
    source : str, optional
        The file named in the header (default: the model's own file).

    Returns
    -------
    Path
        `path`.
    """
    return write_atomic(path, to_mjcf(model, source=source))


# -- the body tree ----------------------------------------------------------------------


def _body(w: _Writer, tree: _Tree, name: str, depth: int) -> None:
    """Write body `name`, its joints, inertia, shape and sites, then its tree children."""
    m = w.model
    i = m.index[name]
    parent = tree.parent[name]
    x_c, q_c = m.initial.position[i], m.initial.quaternion[i]
    if parent == cv.GROUND:
        pos, quat = x_c, q_c
    else:
        p = m.index[parent]
        R_p = quat_to_matrix(m.initial.quaternion[p])
        pos = _snap(R_p.T @ (x_c - m.initial.position[p]), w.scale)
        quat = quat_mul(quat_conj(m.initial.quaternion[p]), q_c)
    pad = "  " * depth
    w.lines.append(f'{pad}<body name={quoteattr(name)} pos="{_vec(pos)}" quat="{_vec(quat)}">')
    inner = pad + "  "
    joint = tree.joint[name]
    if joint is None:
        _root_joints(w, name, inner)
    else:
        _tree_joint(w, joint, parent, name, inner)
    w.lines.append(inner + _inertial(m, i, w.scale))
    geom = _geom(m, i)
    if geom:
        w.lines.append(inner + geom)
    w.lines += [inner + s for s in w.sites.get(name, [])]
    for child in tree.children[name]:
        _body(w, tree, child, depth + 1)
    w.lines.append(f"{pad}</body>")


def _root_joints(w: _Writer, name: str, pad: str) -> None:
    """A body free of the tree's joints: a free joint (spatial), world slides and a hinge
    about z (planar); a particle gets the slides only (it has no orientation)."""
    m = w.model
    i = m.index[name]
    v = m.initial.velocity[i]
    planar = m.dimension == cv.PLANAR
    if not planar and not m.particle[i]:
        w.lines.append(f"{pad}<freejoint name={quoteattr(w.name(name))}/>")
        w.qpos += [*m.initial.position[i], *m.initial.quaternion[i]]
        w.qvel += [*v, *m.initial.omega[i]]
        return
    # the slide axes are written in the body's axes (MuJoCo's joint frame), so that they
    # are world x, y (z) whatever the body's initial attitude
    R = quat_to_matrix(m.initial.quaternion[i])
    for k, axis in enumerate("xyz"[:2 if planar else 3]):
        jn = w.name(f"{name}:{axis}")
        w.lines.append(f'{pad}<joint name={quoteattr(jn)} type="slide" pos="0 0 0" '
                       f'axis="{_vec(_snap(R.T[:, k], 1.0))}"/>')
        w.qpos.append(0.0)
        w.qvel.append(float(v[k]))
    if planar and not m.particle[i]:
        jn = w.name(f"{name}:theta")
        w.lines.append(f'{pad}<joint name={quoteattr(jn)} type="hinge" pos="0 0 0" '
                       f'axis="{_vec(_snap(R.T[:, 2], 1.0))}"/>')
        w.qpos.append(0.0)
        w.qvel.append(float(m.initial.omega[i, 2]))


def _tree_joint(w: _Writer, j: Joint, parent: str, child: str, pad: str) -> None:
    """The MuJoCo joint(s) of mbody joint `j`, in the tree child `child`, and their
    keyframe rates (least squares on the file's velocities: exact when they respect the
    joint)."""
    m = w.model
    c = m.index[child]
    R_c = quat_to_matrix(m.initial.quaternion[c])
    x_c = m.initial.position[c]
    k = w.geo.index[j.name]
    P = w.geo.point[k]
    B_P = _snap(R_c.T @ (P - x_c), w.scale)
    particle = bool(m.particle[c])
    if m.particle[c] and j.particle_joint == "pin":
        # a particle pinned at its own position moves with its parent: nested, no joint
        w.notes.append(f"joint {j.name!r} pins the particle {child!r} at its own position: "
                       "it moves with its parent (no MuJoCo joint)")
        return
    planar = m.dimension == cv.PLANAR
    jtype = joint_types.joint_type(m.dimension, j.type)
    parts = _parts(j, jtype, planar, child, w.geo.frame[k], w.geo.axis2[k])
    if not parts:  # fixed: welded by nesting
        return
    w.native[j.name] = child
    columns = []
    written = []
    for nm, kind, a in parts:
        jn = w.name(nm)
        written.append(jn)
        if kind == "ball":
            w.lines.append(f'{pad}<joint name={quoteattr(jn)} type="ball" pos="{_vec(B_P)}"/>')
            w.qpos += [1.0, 0.0, 0.0, 0.0]
            columns += [_column("hinge", R_c[:, k], P, x_c) for k in range(3)]
        else:
            w.lines.append(f'{pad}<joint name={quoteattr(jn)} type="{kind}" '
                           f'pos="{_vec(B_P)}" axis="{_vec(_snap(R_c.T @ a, 1.0))}"/>')
            w.qpos.append(0.0)
            columns.append(_column(kind, a, P, x_c))
    if any(comp.kind == SCREW for comp in jtype.components):  # coupled in <equality>
        w.screws.append((j, written[0], written[1]))
    w.qvel += _rates(w, j, parent, c, np.array(columns).T, particle)


_MJCF_KIND = {joint_types.ROTATION: "hinge", joint_types.TRANSLATION: "slide",
              joint_types.BALL: "ball"}


def _parts(j: Joint, jtype: joint_types.JointType, planar: bool, child: str,
           E: np.ndarray, axis2: np.ndarray) -> list[tuple[str, str, np.ndarray]]:
    """(name, MJCF joint type, world axis) of each MuJoCo joint that makes up `j`, in the
    order MuJoCo composes them: one per motion its type allows (mbody.joint_types), named
    ``<joint>:<part>`` when there are several; a screw's rotation is written as a slide
    and a hinge along one axis (their coupling is an equality, `_screw_equalities`).

    `E` is the joint frame (world, at the initial state) and `axis2` a universal joint's
    child axis. Written against the tree (`child` is `j`'s parent), the parts come in the
    reverse order, which is the inverse motion: a pin in a slot, a slide then a turn about
    the pin, is seen from the pin's body as a turn about the pin, then a slide along the
    slot (which turned with it)."""
    motions = list(jtype.motions)
    screw = any(c.kind == SCREW for c in jtype.components)
    if screw:  # the rotation and the advance it drags along
        motions = [joint_types.Motion("displacement", joint_types.TRANSLATION, 2,
                                      part="slide"),
                   joint_types.Motion("angle", joint_types.ROTATION, 2, part="turn")]
    out = []
    for mo in motions:
        if mo.what == joint_types.BALL:
            a = np.zeros(3)
        elif mo.on == "child":
            a = np.asarray(axis2, dtype=float)
        elif planar and mo.what == joint_types.ROTATION:
            a = np.array([0.0, 0.0, 1.0])  # a planar joint turns about world z
        else:
            a = E[:, mo.axis] if mo.on == "parent" and mo.axis >= 0 else E[:, 2]
        a = a / np.linalg.norm(a) if a.any() else a
        name = f"{j.name}:{mo.part}" if len(motions) > 1 else j.name
        out.append((name, _MJCF_KIND[mo.what], a))
    if j.child != child and any(mo.on == "child" for mo in motions):
        # a universal joint written against the tree (child -> parent): the axes swap roles
        out = [(out[0][0], "hinge", out[1][2]), (out[1][0], "hinge", out[0][2])]
    elif j.child != child and len(out) == 2 and float(np.linalg.norm(
            np.cross(out[0][2], out[1][2]))) > 1e-9:
        out.reverse()  # two motions that do not commute (a slot): the inverse order
    return out


def _column(kind: str, a: np.ndarray, P: np.ndarray, x_c: np.ndarray) -> np.ndarray:
    """(6,) what a unit joint rate gives the child: [ω (world), v of its mass centre]."""
    if kind == "slide":
        return np.concatenate((np.zeros(3), a))
    return np.concatenate((a, np.cross(a, x_c - P)))


def _rates(w: _Writer, j: Joint, parent: str, c: int, A: np.ndarray, particle: bool
           ) -> list[float]:
    """Joint rates q̇ with A q̇ = the child's motion relative to its tree parent."""
    m = w.model
    st = m.initial
    R_c = quat_to_matrix(st.quaternion[c])
    x_c = st.position[c]
    if parent == cv.GROUND:
        om_p, v_p = np.zeros(3), np.zeros(3)
    else:
        p = m.index[parent]
        om_p = quat_to_matrix(st.quaternion[p]) @ st.omega[p]
        v_p = st.velocity[p] + np.cross(om_p, x_c - st.position[p])
    rel = np.concatenate((R_c @ st.omega[c] - om_p, st.velocity[c] - v_p))
    if particle:  # a particle has no orientation to match: its translation only
        A, rel = A[3:], rel[3:]
    rates, *_ = np.linalg.lstsq(A, rel, rcond=None)
    miss = float(np.linalg.norm(A @ rates - rel))
    if miss > 1e-9 * max(1.0, float(np.linalg.norm(rel))):
        w.notes.append(f"the initial velocities break joint {j.name!r} by {miss:.3g} "
                       "(rad/s, m/s): the keyframe holds the nearest joint rates")
    return [float(x) for x in rates]


def _inertial(m: Model, i: int, scale: float) -> str:
    mass = float(m.mass[i])
    if m.particle[i]:
        d = PARTICLE_INERTIA * mass * scale**2
        return f'<inertial pos="0 0 0" mass="{_num(mass)}" diaginertia="{_vec([d] * 3)}"/>'
    J = np.asarray(m.J[i], dtype=float)
    if not np.any(J - np.diag(np.diag(J))):
        return (f'<inertial pos="0 0 0" mass="{_num(mass)}" '
                f'diaginertia="{_vec(np.diag(J))}"/>')
    full = (J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2])
    return f'<inertial pos="0 0 0" mass="{_num(mass)}" fullinertia="{_vec(full)}"/>'


def _geom(m: Model, i: int) -> str:
    """The body's shape as a geom in body axes; its inertia box when it has none
    (`mbody.model.drawn.inertia_box`: centred at G with the body's inertia, as the geom is
    read back as its shape; the pictures draw a bar through its points instead when it
    has two)."""
    body = m.bodies[m.body_names[i]]
    planar = m.dimension == cv.PLANAR
    rgba = _rgba(body.color)
    # shapes are for viewing only: contacts would add forces mbody does not have
    color = ' contype="0" conaffinity="0"' + (f' rgba="{rgba}"' if rgba else "")
    shape = body.shape
    if shape is None:  # the inertia box, not a bar: read back, a geom is the body's shape
        if body.particle:
            return ""
        box = inertia_box(m.dimension, body.mass, body.inertia)
        if planar:
            side = float(box.size[0])
            return f'<geom type="box" size="{_vec([side / 2, side / 2, side / 10])}"{color}/>'
        return (f'<geom type="box" size="{_vec(box.size / 2)}" '
                f'quat="{_vec(_matrix_quat(box.axes))}"{color}/>')
    kind, v = next(iter(shape.items()))
    if kind in ("box", "ellipsoid"):
        dims = [float(x) for x in v]
        if planar:
            dims.append(0.2 * min(dims))
        size = [d / 2 for d in dims] if kind == "box" else dims
        return f'<geom type="{kind}" size="{_vec(size)}"{color}/>'
    r = float(v["radius"])
    if kind == "sphere":
        return f'<geom type="sphere" size="{_num(r)}"{color}/>'
    length = float(v["length"]) if kind == "cylinder" else 0.1 * r if not planar else 0.2 * r
    return f'<geom type="cylinder" size="{_vec([r, length / 2])}"{color}/>'


# -- loops, springs, header -------------------------------------------------------------


def _equalities(w: _Writer, loops: list[Joint]) -> list[str]:
    """Loop-closing joints as equality constraints: revolute and spherical → connect at
    the joint point (a spatial revolute: a second connect one length scale along its
    axis, which holds the axis too), fixed → weld; others have no MuJoCo equality."""
    m = w.model
    lines = []
    soft = f'solimp="{LOOP_SOLIMP}"'
    for j in loops:
        c = m.index[j.child]
        R_c = quat_to_matrix(m.initial.quaternion[c])
        x_c = m.initial.position[c]
        k = w.geo.index[j.name]
        other = "" if j.parent == cv.GROUND else f" body2={quoteattr(j.parent)}"
        if j.particle_joint == "link":
            w.notes.append(f"joint {j.name!r} (a particle's link) closes a loop: MuJoCo has "
                           "no distance constraint, so it is left out")
            continue
        loop = joint_types.joint_type(m.dimension, j.type).mjcf_loop
        if loop == "connect":
            points = [w.geo.point[k]]
            if j.type == "revolute" and m.dimension == cv.SPATIAL:  # its axis: a 2nd point
                points.append(points[0] + w.scale * w.geo.frame[k][:, 2])
            for k, P in enumerate(points):
                nm = j.name if k == 0 else f"{j.name}:axis"
                lines.append(f"    <connect name={quoteattr(nm)} body1={quoteattr(j.child)}"
                             f'{other} anchor="{_vec(_snap(R_c.T @ (P - x_c), w.scale))}" {soft}/>')
        elif loop == "weld":
            lines.append(f"    <weld name={quoteattr(j.name)} body1={quoteattr(j.child)}"
                         f"{other} {soft}/>")
        else:
            w.notes.append(f"joint {j.name!r} ({j.type}) closes a loop: MuJoCo has no "
                           "equality constraint of that kind, so it is left out")
    screws = _screw_equalities(w)
    if not lines and not screws:
        return []
    what = " and ".join(x for x, there in (("Joints that close loops", lines),
                                           ("the couplings of screws", screws)) if there)
    return [f"  <!-- {what[0].upper()}{what[1:]}. MuJoCo enforces equality constraints softly",
            "       (a stiff spring-damper, solref/solimp), not exactly as mbody does:",
            "       accelerations agree only up to that softness. -->",
            "  <equality>", *lines, *screws, "  </equality>"]


def _screw_equalities(w: _Writer) -> list[str]:
    """Each helical joint's slide and hinge coupled by a joint equality, s = h θ with h =
    pitch/2π (MuJoCo: joint1 − its ref = Σ polycoef[k] (joint2 − its ref)^k).

    MuJoCo's softness is R/(A + R) of the constraint's acceleration, where A is the
    coupling's true inverse inertia and R = (1 − d)/d times MuJoCo's estimate of it, the
    sum of the two joints' own inverse weights, which leaves out the factor h on one of
    them. Written as the hinge following the slide (θ = s/h) when |h| < 1, A holds that
    estimate's larger term in full: the screw jack (models/screw_jack.yaml, 5 mm per turn)
    gives 1.4e-5, where s = h θ would give 0.96."""
    lines = []
    for j, slide, turn in w.screws:
        pitch = float(w.model.joint_table.pitch[w.geo.index[j.name]])
        h = pitch / (2.0 * math.pi)
        if 0.0 < abs(h) < 1.0:
            pair, coef = (turn, slide), 1.0 / h
        else:
            pair, coef = (slide, turn), h
        lines.append(f"    <joint name={quoteattr(j.name)} joint1={quoteattr(pair[0])} "
                     f'joint2={quoteattr(pair[1])} polycoef="0 {_num(coef)} 0 0 0" '
                     f'solimp="{LOOP_SOLIMP}"/>')
    return lines


def _custom(w: _Writer, tree: _Tree) -> list[str]:
    """The ``mbody:`` entries of ``<custom>`` (`mbody.io.interop.custom`): what the MJCF
    elements lose, one small entry each, so that the MJCF reader restores the model."""
    m = w.model
    d = 2 if m.dimension == cv.PLANAR else 3
    form = _file_form(m)
    out = [numeric("dimension", [d])]
    for i, name in enumerate(m.body_names):
        body: dict = {"inertia": 0} if m.particle[i] else {}
        if form:
            body.update(_file_pose(m, i, d))
        if body:
            out.append(text(f"body:{name}", body))
    for k, j in enumerate(m.joints):
        holder = w.native.get(j.name)
        pitch = float(m.joint_table.pitch[k])
        if holder is None:  # no MJCF element is exactly this joint: the whole joint
            entry: dict = {"type": j.type, "parent": j.parent, "child": j.child,
                           "at": _file_at(m, k, d)}
            if j.axis is not None:  # it sets the joint frame, so the reactions' axes
                entry["axis"] = _floats(np.asarray(j.axis)[:d])
            if j.axis2 is not None:
                entry["axis2"] = _floats(j.axis2)
            if j.type == "helical":
                entry["pitch"] = pitch
            out.append(text(f"joint:{j.name}", entry))
        else:
            lost: dict = {}
            if holder != j.child:  # written against the tree: its direction
                lost = {"parent": j.parent, "child": j.child}
            if form:  # the file's point and axes, at the file's pose
                lost["at"] = _file_at(m, k, d)
            if j.axis is not None and (form or j.type == "spherical" or (
                    j.type == "revolute" and d == 2)):
                # the axis sets the joint frame, hence the reaction components: a ball
                # has no axis, and a planar hinge turns about z whatever the file's axis
                lost["axis"] = _floats(np.asarray(j.axis)[:d])
            if form and j.axis2 is not None:
                lost["axis2"] = _floats(j.axis2)
            if j.type == "helical":  # 2π h would round it
                lost["pitch"] = pitch
            if lost:
                out.append(text(f"joint:{j.name}", lost))
    for ld in m.loads:
        out.append(text(f"load:{ld.name}", _load_entry(ld, d)))
    for label, value in m.known_reactions.items():
        if label not in m.known_expressions:
            out.append(numeric(f"reaction:{label}", [value]))
    out += [text(f"reaction:{label}", str(e)) for label, e in m.known_expressions.items()]
    drivers = m.drivers
    if drivers is not None:
        out += [text(f"driver:{name}", _driver_entry(m, k)) for k, name in
                enumerate(drivers.names)]
    # the file's order, which the body tree's nesting does not keep: the rows and columns
    # of the equations follow it
    out.append(text("order", {"bodies": list(m.body_names),
                              "joints": [j.name for j in m.joints]}))
    return ["  <!-- What MJCF cannot say, for mbody's reader (MuJoCo ignores it): see",
            "       the mbody documentation, interop, 'The mbody entries'. -->",
            "  <custom>", *("    " + s for s in out), "  </custom>"]


def _file_pose(m: Model, i: int, d: int) -> dict:
    """Body `i`'s state as the file writes it (the pose `mbody.load` assembled from):
    position, orientation (planar: angle), velocity, angular velocity (body axes)."""
    st = m.file_state if m.file_state is not None else m.initial
    q = st.quaternion[i]
    out: dict = {"position": _floats(st.position[i, :d])}
    if not m.particle[i]:
        if d == 2:
            out["angle"] = float(2.0 * math.atan2(q[3], q[0]))
        else:
            out["orientation"] = {"quaternion": _floats(q)}
    out["velocity"] = _floats(st.velocity[i, :d])
    if not m.particle[i]:
        out["angular_velocity"] = float(st.omega[i, 2]) if d == 2 else _floats(st.omega[i])
    return out


def _file_at(m: Model, k: int, d: int) -> list:
    """Joint `k`'s ``at`` as the file gives it: one world point at the file's pose, or
    ``[[parent point], [child point]]`` in each body's axes (world for ground)."""
    jt = m.joint_table
    if not jt.body_points[k]:
        return _floats(np.asarray(m.joints[k].at)[:d])
    child = jt.B_r_child[k]
    c = int(jt.child[k])
    if m.particle[c]:  # attached at the particle itself; the file's point says pin or link
        st = m.file_state if m.file_state is not None else m.initial
        child = np.asarray(m.joints[k].at, dtype=float) - st.position[c]
    return [_floats(jt.B_r_parent[k][:d]), _floats(child[:d])]


def _driver_entry(m: Model, k: int) -> dict:
    """Driver `k` as the file writes it, but its name: its joint and its law (or rate)."""
    drivers = m.drivers
    assert drivers is not None
    entry: dict = {"joint": m.joints[int(drivers.joint[k])].name}
    speed = drivers.speed[k] if drivers.speed else None
    if speed is not None:
        entry["speed"] = float(speed)
    else:
        key = "angle" if drivers.component[k] == "M" else "displacement"
        entry[key] = drivers.laws[k][0].text
    return entry


def _load_entry(ld, d: int) -> dict:
    """A load as the model file writes it (a spring: the tendon of the same name)."""
    if ld.type == "spring" or ld.vector is None:
        return {"type": "spring"}
    comps = [str(ld.expressions[k]) if k in ld.expressions else float(x)
             for k, x in enumerate(ld.vector)]
    entry: dict = {"type": ld.type, "body": ld.bodies[0]}
    if ld.type == "torque":
        entry["torque"] = comps[2] if d == 2 else comps
    else:
        entry["force"] = comps[:d]
        if ld.at and np.any(np.asarray(ld.at[0])):
            entry["at"] = _floats(np.asarray(ld.at[0])[:d])
    entry["frame"] = ld.frame
    return entry


def _floats(v) -> list[float]:
    return [float(x) for x in np.asarray(v, dtype=float).ravel()]


def _spring_sites(w: _Writer, k: int) -> None:
    """The two attachment points of spring `k` as sites in their bodies (world: ground)."""
    m = w.model
    sp = m.springs
    for end, (b, r) in enumerate(((sp.a[k], sp.r_a[k]), (sp.b[k], sp.r_b[k]))):
        owner = cv.GROUND if b < 0 else m.body_names[b]
        site = f"{sp.names[k]}:{'ab'[end]}"
        w.sites.setdefault(owner, []).append(f'<site name={quoteattr(site)} pos="{_vec(r)}"/>')


def _tendons(w: _Writer) -> list[str]:
    """Springs as spatial tendons: tension k (L − L0) + c L̇ between the two sites."""
    sp = w.model.springs
    lines = []
    for k, name in enumerate(sp.names):
        lines.append(f"    <spatial name={quoteattr(name)} stiffness="
                     f'"{_num(sp.stiffness[k])}" damping="{_num(sp.damping[k])}" '
                     f'springlength="{_num(sp.rest_length[k])}">')
        lines += [f"      <site site={quoteattr(f'{name}:{e}')}/>" for e in "ab"]
        lines.append("    </spatial>")
    return ["  <tendon>", *lines, "  </tendon>"] if lines else []


def _header(w: _Writer, tree: _Tree, source: str | None) -> str:
    """The comment at the top: where the file came from and what it leaves out."""
    m = w.model
    src = source if source is not None else m.file
    form = _file_form(m)
    drivers = m.drivers if m.drivers is not None and len(m.drivers) else None
    lost = ["the dimension", "loads", "known reactions", "fixed joints", "particles",
            "joint directions"]
    lost += ["screw pitches"] * bool(w.screws) + ["drivers"] * (drivers is not None)
    lost += ["the file's pose and joint points"] * form
    out = [f"Written by mbody {__version__} (mbody convert) from {src}.",
           f"Model {m.name!r}: {'planar' if m.dimension == cv.PLANAR else 'spatial'}, "
           f"{count(m.n, 'body', 'bodies')}, {count(len(m.joints), 'joint')}. Each MuJoCo "
           "body frame is the mbody body frame (mass centre, body axes) at the initial "
           "pose; the keyframe 'initial' is the "
           + ("assembled state." if form else "file's state."),
           f"What MJCF cannot say ({', '.join(lost)}) is in <custom> as mbody: entries, "
           "which MuJoCo ignores and mbody's reader restores.",
           ]
    if form:
        out.append("Assembled pose: the file gives joint points per body or drivers, so "
                   "mbody moves its bodies onto every joint and driver before it starts; "
                   "the bodies and joints are written there, and the file's own pose, "
                   "points and axes are in <custom> (mbody:body, mbody:joint), which mbody "
                   "reads back to assemble the same way.")
    if drivers is not None:
        out.append("Drivers (" + ", ".join(
            f"{n!r} on joint {m.joints[int(k)].name!r}" for n, k in zip(
                drivers.names, drivers.joint, strict=True))
            + "): MJCF has no motion prescribed in time, so MuJoCo moves the mechanism "
            "freely from the keyframe (its accelerations are those without the drivers); "
            "they are in <custom> for mbody (mbody:driver).")
    if w.screws:
        out.append("Helical joints (" + ", ".join(repr(j.name) for j, _, _ in w.screws)
                   + "): a slide and a hinge on the screw's axis, coupled by a joint "
                   "equality (advance = pitch/2pi x turn), which MuJoCo keeps softly (see "
                   "<equality>).")
    if m.dimension == cv.PLANAR:
        out.append("Planar model written in 3-D: bodies in the world x-y plane, joints "
                   "turning about world z or sliding in the plane.")
    point = [ld for ld in m.loads if ld.type in ("force", "torque")]
    if point:
        out.append("Not applied by MuJoCo (MJCF has no constant applied loads; apply them "
                   "at run time through MjData.xfrc_applied, a world force and torque "
                   "about the body's mass centre; mbody reads them back from <custom>):")
        for ld in point:
            out.append("  " + _describe_load(ld))
    if m.known_reactions or m.known_expressions:
        labels = sorted({*m.known_reactions, *m.known_expressions})
        out.append("Known reaction values of the file (" + ", ".join(labels) + "): in "
                   "<custom> for mbody; MuJoCo enforces every joint and computes all its "
                   "reactions, which agree with these values only where they are "
                   "consistent with the joint.")
    if any(m.particle):
        out.append(f"Particles (inertia 0) get principal moments {PARTICLE_INERTIA:g} m "
                   f"l^2 (l = {w.scale:.3g} m): MuJoCo refuses a moving body without "
                   "rotational inertia.")
    if tree.loops:
        out.append("Closed loops: the joints " + ", ".join(repr(j.name) for j in tree.loops)
                   + " close them and are written as equality constraints, which MuJoCo "
                   "keeps softly (see <equality>).")
    out += w.notes
    text = "\n".join(_wrap(line) for line in out)
    return "<!--\n" + text.replace("--", "- -") + "\n-->"


def _describe_load(ld) -> str:
    if ld.vector is None:
        return f"{ld.type} {ld.name!r}"
    comps = [str(ld.expressions[k]) if k in ld.expressions else _num(float(x))
             for k, x in enumerate(ld.vector)]
    where = ("" if ld.type == "torque" else
             f" at [{', '.join(_num(float(x)) for x in ld.at[0])}] (body axes)")
    return (f"{ld.type} {ld.name!r} on {ld.bodies[0]!r}: [{', '.join(comps)}] "
            f"({ld.frame} axes){where}")


def _wrap(line: str, width: int = 88) -> str:
    """`line` broken at spaces into lines of at most `width` characters (comment text)."""
    lead = line[:len(line) - len(line.lstrip(" "))]
    indent = lead + "  "
    out, cur = [], lead
    for word in line.split():
        if cur.strip() and len(cur) + 1 + len(word) > width:
            out.append(cur)
            cur = indent + word
        else:
            cur = f"{cur} {word}" if cur.strip() else cur + word
    out.append(cur)
    return "\n".join(out)


# -- numbers ----------------------------------------------------------------------------


def _length_scale(model: Model, geometry: _Geometry) -> float:
    """A typical length of the model (m): the largest distance from a mass centre to a
    joint point, else 1."""
    x = model.initial.position
    d = [float(np.linalg.norm(geometry.point[k] - x[model.index[b]]))
         for k, j in enumerate(model.joints) for b in (j.parent, j.child) if b != cv.GROUND]
    big = max(d, default=0.0)
    return big if big > 0 else 1.0


def _num(x: float) -> str:
    """Shortest text that reads back as the same double (0 for ±0)."""
    x = float(x)
    if x == 0.0:
        return "0"
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


def _snap(v: np.ndarray, size: float) -> np.ndarray:
    """`v` with the rounding noise of a frame change (|x| < 1e-14 `size`) made 0, for a
    readable file; the geometry moves by less than that."""
    return np.where(np.abs(v) < 1e-14 * size, 0.0, v)


def _vec(xs) -> str:
    return " ".join(_num(x) for x in np.asarray(xs, dtype=float).ravel())


def _matrix_quat(R: np.ndarray) -> np.ndarray:
    return np.asarray(matrix_to_quat(R[None]))[0]


def _rgba(color: str | None) -> str:
    """'#rrggbb' (or a colour name) -> 'r g b 1'; '' when there is none."""
    if not color:
        return ""
    if _HEX.fullmatch(color):
        rgb = [int(color[k:k + 2], 16) / 255 for k in (1, 3, 5)]
    else:
        from matplotlib.colors import to_rgb  # slow to import: only for a named colour

        try:
            rgb = list(to_rgb(color))
        except ValueError:
            return ""
    return " ".join(f"{c:.4g}" for c in rgb) + " 1"
