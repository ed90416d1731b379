"""A model as MuJoCo's MJCF: bodies nested along a spanning tree of the joint graph.

Each MuJoCo body frame is the mbody body frame at the initial pose (origin at the mass
centre, axes = body axes), so ``xipos`` is the mass centre, ``xmat`` is ``W_R_B`` and
every reference configuration (``qpos0``) is the file's initial pose. A joint of the
tree sits in its child body (``pos`` = the joint point in the child's axes); a joint
that closes a loop becomes an equality constraint, which MuJoCo enforces softly.

Joint types: revolute → hinge, prismatic → slide, cylindrical → slide + hinge on one
axis, spherical → ball, universal → two hinges in the child body (MuJoCo composes a
body's joints in order: the first axis stays fixed in the parent, the second turns with
the first and is fixed in the child, which is the universal joint exactly; no massless
intermediate body is needed, so the equations keep their bodies), fixed → no joint (the
child is welded by nesting). A body with no joint to the tree's root gets a free joint
(spatial), or slides along world x, y and a hinge about z (planar; slides only for a
particle). Planar models are written in 3-D: every planar joint turns about world z or
slides in the plane, so the motion stays planar.
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
from mbody.model.model import Joint, Model, count
from mbody.util.atomic import write_atomic
from mbody.util.spatial import (
    box_equivalent,
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
"""Impedance of the loop-closing equality constraints: MuJoCo's stiffest (its default,
0.9, lets a loop give by about 10 % of the force that holds it together)."""

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


@dataclass
class _Writer:
    """What `to_mjcf` accumulates: lines of the body tree, the keyframe, the notes."""

    model: Model
    scale: float
    lines: list[str] = field(default_factory=list)
    qpos: list[float] = field(default_factory=list)
    qvel: list[float] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    joint_names: set[str] = field(default_factory=set)
    sites: dict[str, list[str]] = field(default_factory=dict)  # body -> its site lines
    worst_velocity: float = 0.0
    native: dict[str, str] = field(default_factory=dict)  # joint -> the body holding it

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
    scale = _length_scale(model)
    w = _Writer(model, scale)
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
    P = np.asarray(j.at, dtype=float)
    B_P = _snap(R_c.T @ (P - x_c), w.scale)
    particle = bool(m.particle[c])
    if m.particle[c] and j.particle_joint == "pin":
        # a particle pinned at its own position moves with its parent: nested, no joint
        w.notes.append(f"joint {j.name!r} pins the particle {child!r} at its own position: "
                       "it moves with its parent (no MuJoCo joint)")
        return
    planar = m.dimension == cv.PLANAR
    jtype = joint_types.joint_type(m.dimension, j.type)
    parts = _parts(j, jtype, planar, child)
    if not parts:  # fixed: welded by nesting
        return
    w.native[j.name] = child
    columns = []
    for nm, kind, a in parts:
        jn = w.name(nm)
        if kind == "ball":
            w.lines.append(f'{pad}<joint name={quoteattr(jn)} type="ball" pos="{_vec(B_P)}"/>')
            w.qpos += [1.0, 0.0, 0.0, 0.0]
            columns += [_column("hinge", R_c[:, k], P, x_c) for k in range(3)]
        else:
            w.lines.append(f'{pad}<joint name={quoteattr(jn)} type="{kind}" '
                           f'pos="{_vec(B_P)}" axis="{_vec(_snap(R_c.T @ a, 1.0))}"/>')
            w.qpos.append(0.0)
            columns.append(_column(kind, a, P, x_c))
    w.qvel += _rates(w, j, parent, c, np.array(columns).T, particle)


_MJCF_KIND = {joint_types.ROTATION: "hinge", joint_types.TRANSLATION: "slide",
              joint_types.BALL: "ball"}


def _parts(j: Joint, jtype: joint_types.JointType, planar: bool, child: str
           ) -> list[tuple[str, str, np.ndarray]]:
    """(name, MJCF joint type, world axis) of each MuJoCo joint that makes up `j`: one per
    motion its type allows (mbody.joint_types), named ``<joint>:<part>`` when there are
    several; a screw's rotation is written as a hinge and a slide along one axis (their
    coupling is an equality, `_screws`)."""
    E = np.asarray(j.W_E0, dtype=float)
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
            a = np.asarray(j.axis2, dtype=float)
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
    """The body's shape as a geom in body axes (its equivalent box when it has none), as
    the drawings show it (`mbody.present.draw.outline`)."""
    body = m.bodies[m.body_names[i]]
    planar = m.dimension == cv.PLANAR
    rgba = _rgba(body.color)
    # shapes are for viewing only: contacts would add forces mbody does not have
    color = ' contype="0" conaffinity="0"' + (f' rgba="{rgba}"' if rgba else "")
    shape = body.shape
    if shape is None:
        if body.particle:
            return ""
        J = np.asarray(body.inertia, dtype=float)
        if planar:
            side = math.sqrt(6.0 * J[2, 2] / body.mass)
            return f'<geom type="box" size="{_vec([side / 2, side / 2, side / 10])}"{color}/>'
        moments, axes = np.linalg.eigh(J)
        if np.linalg.det(axes) < 0:
            axes[:, 2] *= -1.0
        edges = box_equivalent(moments, body.mass)
        return (f'<geom type="box" size="{_vec(edges / 2)}" quat="{_vec(_matrix_quat(axes))}"'
                f"{color}/>")
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
        other = "" if j.parent == cv.GROUND else f" body2={quoteattr(j.parent)}"
        if j.particle_joint == "link":
            w.notes.append(f"joint {j.name!r} (a particle's link) closes a loop: MuJoCo has "
                           "no distance constraint, so it is left out")
            continue
        loop = joint_types.joint_type(m.dimension, j.type).mjcf_loop
        if loop == "connect":
            points = [np.asarray(j.at, dtype=float)]
            if j.type == "revolute" and m.dimension == cv.SPATIAL:  # its axis: a 2nd point
                points.append(points[0] + w.scale * np.asarray(j.W_E0)[:, 2])
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
    if not lines:
        return []
    return ["  <!-- Joints that close loops. MuJoCo enforces equality constraints softly",
            "       (a stiff spring-damper, solref/solimp), not exactly as mbody does:",
            "       accelerations agree only up to that softness. -->",
            "  <equality>", *lines, "  </equality>"]


def _custom(w: _Writer, tree: _Tree) -> list[str]:
    """The ``mbody:`` entries of ``<custom>`` (`mbody.io.interop.custom`): what the MJCF
    elements lose, one small entry each, so that the MJCF reader restores the model."""
    m = w.model
    d = 2 if m.dimension == cv.PLANAR else 3
    out = [numeric("dimension", [d])]
    out += [text(f"body:{name}", {"inertia": 0})
            for i, name in enumerate(m.body_names) if m.particle[i]]
    for j in m.joints:
        holder = w.native.get(j.name)
        if holder is None:  # no MJCF element is exactly this joint: the whole joint
            entry: dict = {"type": j.type, "parent": j.parent, "child": j.child,
                           "at": _floats(j.at[:d])}
            if j.axis is not None:  # it sets the joint frame, so the reactions' axes
                entry["axis"] = _floats(np.asarray(j.axis)[:d])
            if j.axis2 is not None:
                entry["axis2"] = _floats(j.axis2)
            out.append(text(f"joint:{j.name}", entry))
        else:
            lost: dict = {}
            if holder != j.child:  # written against the tree: its direction
                lost = {"parent": j.parent, "child": j.child}
            if j.axis is not None and j.type in ("spherical", "revolute") and (
                    j.type == "spherical" or d == 2):
                # the axis sets the joint frame, hence the reaction components: a ball
                # has no axis, and a planar hinge turns about z whatever the file's axis
                lost["axis"] = _floats(np.asarray(j.axis)[:d])
            if lost:
                out.append(text(f"joint:{j.name}", lost))
    for ld in m.loads:
        out.append(text(f"load:{ld.name}", _load_entry(ld, d)))
    for label, value in m.known_reactions.items():
        if label not in m.known_expressions:
            out.append(numeric(f"reaction:{label}", [value]))
    out += [text(f"reaction:{label}", str(e)) for label, e in m.known_expressions.items()]
    return ["  <!-- What MJCF cannot say, for mbody's reader (MuJoCo ignores it): see",
            "       the mbody documentation, interop, 'The mbody entries'. -->",
            "  <custom>", *("    " + s for s in out), "  </custom>"]


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
    out = [f"Written by mbody {__version__} (mbody convert) from {src}.",
           f"Model {m.name!r}: {'planar' if m.dimension == cv.PLANAR else 'spatial'}, "
           f"{count(m.n, 'body', 'bodies')}, {count(len(m.joints), 'joint')}. Each MuJoCo "
           "body frame is the mbody body frame (mass centre, body axes) at the initial "
           "pose; the keyframe 'initial' is the file's state.",
           "What MJCF cannot say (the dimension, loads, known reactions, fixed joints, "
           "particles, joint directions) is in <custom> as mbody: entries, which MuJoCo "
           "ignores and mbody's reader restores.",
           ]
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


def _length_scale(model: Model) -> float:
    """A typical length of the model (m): the largest distance from a mass centre to a
    joint point, else 1."""
    x = model.initial.position
    d = [float(np.linalg.norm(np.asarray(j.at) - x[model.index[b]]))
         for j in model.joints for b in (j.parent, j.child) if b != cv.GROUND]
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
