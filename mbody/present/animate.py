"""Animate a `Trajectory` in meshcat: a self-contained HTML page, or the live viewer.

Body i is drawn at its pose at every sample k,

    W_x(t_k) = W_r_G,i(t_k) + W_R_B,i(t_k) B_x      (every point B_x of its shape)

as keyframes (position and quaternion tracks, times t_k − t_0 in seconds) that the
viewer interpolates (linearly for positions, slerp for rotations). Planar bodies live in
the x-y plane and turn about z. Applied forces and couples (`forces=True`) are arrows:
a cylinder shaft and a cone head, placed at the point of application, pointing along
W_f, with length proportional to |W_f| (couples: along the moment vector, at G).

This is the only module that imports meshcat (0.3.2). Its Python side breaks under
numpy 2 unless it is given float64 arrays and Python scalars, so every number handed to
it is converted first (`tolist()`, `float`, float64 4x4 matrices).
"""

from __future__ import annotations

import base64
import contextlib
import html
import math
import os
import selectors
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import mbody
from mbody import conventions as cv
from mbody.equations.joints import reaction_columns
from mbody.equations.loads import applied_loads
from mbody.equations.spatial import box_equivalent, matvec, planar_quat, quat_to_matrix
from mbody.errors import MbodyError, did_you_mean
from mbody.io.atomic import write_atomic
from mbody.model.model import Model
from mbody.model.model import load as load_model
from mbody.simulate.trajectory import Trajectory

ROOT = "/meshcat/mbody"
"""Scene path of the model's frame; bodies are at ROOT/bodies/<name>."""
PALETTE = ("#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#bcbd22",
           "#17becf", "#7f7f7f", "#1f77b4")
"""Default body colours (matplotlib's tab10 without its red, which marks joint reactions
as on the free-body diagrams; blue last: the background is blue)."""
FORCE_COLOR, COUPLE_COLOR = "#ffd400", "#ff00ff"
REACTION_COLOR, REACTION_COUPLE_COLOR = "#e8202a", "#8b0a14"
"""Joint reactions: the red of the free-body diagrams' reaction arrows, a darker red for
couples, and thinner arrows than applied loads."""
SCENE_SIZE = 2.0
"""The motion's bounding box is scaled to about this size (m) in the viewer, so that the
viewer's fixed camera range (near 0.01, far 100) and lights suit any model."""
CAMERA_DISTANCE = 3.4


def _meshcat():
    """meshcat's geometry module (imports are slow and warn about zmq: do it on demand)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "zmq.eventloop.ioloop is deprecated",
                                DeprecationWarning)
        import meshcat.geometry

    return meshcat


# -- the scene --------------------------------------------------------------------------


@dataclass(frozen=True)
class Scene:
    """Lowered meshcat commands (dicts, in order) that build and animate the motion.

    paths: body name -> scene path of its animated node (local pose = W_r_G, W_R_B).
    duration: seconds of animation (t_end − t_0); t0: the trajectory's first time.
    """

    commands: list[dict[str, Any]]
    paths: dict[str, str]
    duration: float
    t0: float
    frames: int
    title: str
    load_paths: dict[str, str] = field(default_factory=dict)


def _rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _homogeneous(R: np.ndarray | None = None, p: Sequence[float] | None = None,
                 scale: float = 1.0) -> np.ndarray:
    T = np.eye(4, dtype=np.float64)
    if R is not None:
        T[:3, :3] = R
    T[:3, :3] *= scale
    if p is not None:
        T[:3, 3] = p
    return T


def _color(value: str | None, i: int) -> int:
    """A colour name or '#rrggbb' -> 0xRRGGBB (meshcat wants a Python int)."""
    from matplotlib.colors import to_hex

    text = value if value is not None else PALETTE[i % len(PALETTE)]
    try:
        return int(to_hex(text)[1:], 16)
    except ValueError:
        raise MbodyError(f"{text!r} is not a colour: give a name such as 'orange' or "
                         "'#rrggbb'") from None


def _shape(g, body, dimension: int) -> tuple[Any, np.ndarray, np.ndarray]:
    """meshcat geometry of a body, its fixed transform in body axes, its half-extents.

    meshcat's cylinder axis is its local +y (three.js); turning it by +90° about x puts it
    along body z, the axis the model format gives cylinders and discs.
    """
    to_z = _homogeneous(_rot_x(math.pi / 2))
    eye = np.eye(4)
    shape = body.shape
    if shape is None:  # the uniform box with the body's inertia, along its principal axes
        if dimension == cv.PLANAR:
            side = math.sqrt(6.0 * body.I_G / body.mass)
            return g.Box([side, side, 0.2 * side]), eye, np.array([side, side, 0.2 * side]) / 2
        moments, axes = np.linalg.eigh(np.asarray(body.inertia, dtype=np.float64))
        if np.linalg.det(axes) < 0:
            axes[:, 2] *= -1.0
        edges = box_equivalent(moments, body.mass)
        half = np.abs(axes) @ (edges / 2)
        return g.Box([float(e) for e in edges]), _homogeneous(axes), half
    kind, v = next(iter(shape.items()))
    if kind == "box":
        dims = [float(x) for x in v]
        if dimension == cv.PLANAR:
            dims.append(0.2 * min(dims))
        return g.Box(dims), eye, np.array(dims) / 2
    if kind == "ellipsoid":
        radii = [float(x) for x in v]
        if dimension == cv.PLANAR:
            radii.append(0.2 * min(radii))
        return g.Ellipsoid(np.array(radii, dtype=np.float64)), eye, np.array(radii)
    r = float(v["radius"])
    if kind == "sphere":
        return g.Sphere(r), eye, np.full(3, r)
    length = float(v["length"]) if kind == "cylinder" else 0.1 * r if dimension == 3 else 0.2 * r
    return g.Cylinder(length, r), to_z, np.array([r, r, length / 2])


def _internal(traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """(K, n, 3) positions and (K, n, 4) quaternions [w, x, y, z], planar ones lifted."""
    if traj.dimension == cv.PLANAR:
        K, n = traj.orientation.shape
        pos = np.zeros((K, n, 3))
        pos[..., :2] = traj.position
        return pos, planar_quat(traj.orientation)
    return np.asarray(traj.position, dtype=np.float64), np.asarray(traj.orientation,
                                                                    dtype=np.float64)


def _xyzw(q: np.ndarray) -> np.ndarray:
    """[w, x, y, z] -> three.js order [x, y, z, w]."""
    return np.concatenate([q[..., 1:], q[..., :1]], axis=-1)


def _track(name: str, kind: str, times: list[float], values: np.ndarray) -> dict[str, Any]:
    # three.js KeyframeTrack JSON with flat `times`/`values` (the compact form its
    # parser accepts); the clip's fps is 1, so times are seconds.
    return {"name": "." + name, "type": kind, "times": times,
            "values": np.asarray(values, dtype=np.float64).ravel().tolist()}


def _y_to(d: np.ndarray) -> np.ndarray:
    """(..., 3) unit vectors -> quaternions [w, x, y, z] turning +y onto them."""
    w = 1.0 + d[..., 1]
    q = np.stack([w, d[..., 2], np.zeros_like(w), -d[..., 0]], axis=-1)
    flip = w < 1e-9  # d = −y: half a turn about x
    q[flip] = [0.0, 1.0, 0.0, 0.0]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _round_up(x: float) -> float:
    """The smallest of 1, 2, 5 times a power of ten that is >= x (> 0)."""
    p = 10.0 ** math.floor(math.log10(x))
    return next(m * p for m in (1.0, 2.0, 5.0, 10.0) if m * p >= x * (1 - 1e-12))


def _path_name(name: str) -> str:
    return name.replace("/", "_") or "_"


def build_scene(traj: Trajectory, model: Model, *, forces: bool = False,
                bodies: Iterable[str] | None = None, reactions: bool = False) -> Scene:
    """The meshcat commands that draw `model`'s bodies moving along `traj`.

    traj: positions (K, n, d) world, orientations (K, n, 4) w-first or (K, n) angles.
    model: supplies each body's shape (or inertia-equivalent box), colour and loads.
    bodies: draw only these (default: all).
    """
    traj_names = list(traj.body_names)
    _check_match(traj, model)
    shown = list(traj_names if bodies is None else bodies)
    for name in shown:
        if name not in traj_names:
            hint = did_you_mean(name, traj_names)
            raise MbodyError(f"unknown body {name!r}: the trajectory has "
                             f"{', '.join(traj_names)}" + (f" ({hint})" if hint else ""))
    if len(traj.t) < 1:
        raise MbodyError("the trajectory has no samples")
    t = np.asarray(traj.t, dtype=np.float64)
    if np.any(np.diff(t) <= 0):
        raise MbodyError("the trajectory's times do not increase")

    mc = _meshcat()
    g = mc.geometry
    cmds: list[dict[str, Any]] = []

    def set_object(path: str, obj) -> None:
        cmds.append(mc.commands.SetObject(obj, path=_mpath(mc, path)).lower())

    def mesh(path: str, geom, color: int, opacity: float = 1.0) -> None:
        mat = g.MeshLambertMaterial(color=int(color), opacity=float(opacity),
                                    transparent=opacity < 1.0)
        cmds.append(mc.commands.SetObject(geom, mat, path=_mpath(mc, path)).lower())

    def set_transform(path: str, T: np.ndarray) -> None:
        cmds.append({"type": "set_transform", "path": path,
                     "matrix": np.asarray(T, dtype=np.float64).T.ravel().tolist()})

    def set_property(path: str, key: str, value: Any) -> None:
        cmds.append({"type": "set_property", "path": path, "property": key, "value": value})

    pos, quat = _internal(traj)
    idx = [traj_names.index(nm) for nm in shown]
    times = (t - t[0]).tolist()
    duration = float(t[-1] - t[0])

    # Geometry first: its size sets the scene's scale.
    geoms = []
    for nm in shown:
        body = model.bodies[nm]
        geom, T_shape, half = _shape(g, body, traj.dimension)
        geoms.append((nm, geom, T_shape, half, _color(body.color, body.index)))
    reach = max(float(np.linalg.norm(h)) for *_, h, _ in geoms)
    P = pos[:, idx, :].reshape(-1, 3)
    lo, hi = P.min(axis=0) - reach, P.max(axis=0) + reach
    extent = float(np.max(hi - lo))
    centre = (lo + hi) / 2
    s = SCENE_SIZE / extent

    # The model frame: centred, scaled to SCENE_SIZE; planar x-y plane stood upright
    # (model y up on screen, the camera on model +z).
    R_view = _rot_x(math.pi / 2) if traj.dimension == cv.PLANAR else np.eye(3)
    W_root = _homogeneous(R_view, -s * R_view @ centre, s)
    set_transform(ROOT, W_root)

    # Ground grid in the model's x-y plane: below the motion (spatial), behind the
    # bodies (planar). meshcat's grid is 40 cells of 0.5; cells of a round size (1, 2 or
    # 5 times a power of ten) make it 3 to 7.5 times the motion's size. (A much larger
    # grid, reaching far behind the camera, loses its near lines in software WebGL.)
    cell = _round_up(3.0 * extent / 40)
    gz = lo[2] if traj.dimension == cv.SPATIAL else -max(h[2] for *_, h, _ in geoms) - 1e-3
    gc = [round(centre[0] / cell) * cell, round(centre[1] / cell) * cell, gz]
    set_transform("/Grid", W_root @ _homogeneous(None, gc, cell / 0.5))
    set_property("/Axes", "visible", False)
    set_object(f"{ROOT}/origin", g.triad(float(0.15 * extent)))

    # Camera in meshcat's y-up camera frame: (x, y, z)_world = (x, -z, y)_camera.
    d = np.array([0.0, -1.0, 0.0]) if traj.dimension == cv.PLANAR else np.array([1, .8, .65])
    d = CAMERA_DISTANCE * d / np.linalg.norm(d)
    set_property("/Cameras/default/rotated/<object>", "position",
                 [float(d[0]), float(d[2]), float(-d[1])])

    paths: dict[str, str] = {}
    animations = []
    for (nm, geom, T_shape, half, color), i in zip(geoms, idx, strict=True):
        path = f"{ROOT}/bodies/{_path_name(nm)}"
        paths[nm] = path
        set_transform(f"{path}/shape", T_shape)
        mesh(f"{path}/shape/mesh", geom, color)
        set_object(f"{path}/axes", g.triad(float(1.3 * np.max(half))))
        animations.append(_animation(path, [
            _track("position", "vector3", times, pos[:, i, :]),
            _track("quaternion", "quaternion", times, _xyzw(quat[:, i, :]))]))

    load_paths: dict[str, str] = {}
    if forces:
        arrows, load_paths = _arrows(traj, model, pos, quat, set(idx), times, extent,
                                     set_transform, mesh)
        animations.extend(arrows)
    if reactions:
        arrows, reaction_paths = _reaction_arrows(traj, model, times, extent, set_transform,
                                                  mesh)
        animations.extend(arrows)
        load_paths.update(reaction_paths)

    cmds.append({"type": "set_animation", "path": "", "animations": animations,
                 "options": {"play": True, "repetitions": math.inf}})
    title = f"mbody: {model.name or traj.model_name or 'motion'}"
    return Scene(cmds, paths, duration, float(t[0]), len(t), title, load_paths)


def _mpath(mc, path: str):
    return mc.path.Path(tuple(p for p in path.split("/") if p))


def _animation(path: str, tracks: list[dict[str, Any]]) -> dict[str, Any]:
    return {"path": path, "clip": {"fps": 1, "name": "default", "tracks": tracks}}


def _arrows(traj: Trajectory, model: Model, pos: np.ndarray, quat: np.ndarray, shown: set,
            times: list[float], extent: float, set_transform, mesh):
    """Arrows for applied forces (at their points) and couples (at G), per frame.

    Each arrow node turns +y onto the load's direction; its shaft is scaled along y to
    length L − head and its head sits at the shaft's end, so the head keeps its shape.
    A force that pushes into its body (f · r < 0, r from G to the point) is drawn ending
    at its point, so that it stays outside the body; others start at their point.
    L = L_max |f| / max|f| over the run (forces and couples scaled separately).
    """

    mc = _meshcat()
    g = mc.geometry
    K = len(times)
    W_f, W_p, W_m = [], [], []
    for k in range(K):  # one vectorised evaluation per frame (loads may depend on t)
        c = applied_loads(model, traj.state(k)).contributions
        on = c.body >= 0  # spring ends on ground are not drawn
        R = quat_to_matrix(quat[k, np.where(on, c.body, 0)])
        W_f.append(c.W_f)
        W_p.append(pos[k, np.where(on, c.body, 0)] + matvec(R, c.B_r))
        W_m.append(matvec(R, c.B_m))
        couple, body, names = c.couple, c.body, c.names
    if not K or not len(body):
        return [], {}
    W_f, W_p, W_m = np.array(W_f), np.array(W_p), np.array(W_m)
    vec = np.where(couple[None, :, None], W_m, W_f)
    at = np.where(couple[None, :, None], pos[:, np.maximum(body, 0)], W_p)
    size = np.linalg.norm(vec, axis=-1)  # (K, k)
    L_max, head, radius = 0.35 * extent, 0.06 * extent, 0.012 * extent
    out, paths = [], {}
    for group in (False, True):
        sel = (couple == group) & (body >= 0) & np.isin(body, list(shown))
        top = size[:, sel].max() if sel.any() else 0.0
        scale = L_max / top if top > 0 else 0.0
        color = int((COUPLE_COLOR if group else FORCE_COLOR)[1:], 16)
        for j in np.flatnonzero(sel):
            path = f"{ROOT}/loads/{j}_{_path_name(names[j])}"
            paths.setdefault(names[j], path)
            lever = None if group else at[:, j] - pos[:, body[j]]
            out += _arrow(g, path, at[:, j], vec[:, j], size[:, j] * scale, color,
                          (head, radius), times, set_transform, mesh, lever)
    return out, paths


def _arrow(g, path: str, at: np.ndarray, vec: np.ndarray, L: np.ndarray, color: int,
           dims: tuple[float, float], times: list[float], set_transform, mesh,
           lever: np.ndarray | None = None) -> list[dict[str, Any]]:
    """One arrow's nodes and tracks: (K, 3) foot `at`, direction of `vec`, length L (K,).

    With `lever` (K, 3) (point minus mass centre), a push into the body is drawn with its
    tip at the point instead of its foot, so that it stays outside the body.
    """
    head, radius = dims
    K = len(times)
    size = np.linalg.norm(vec, axis=-1)
    d = np.divide(vec, size[:, None], out=np.zeros((K, 3)), where=size[:, None] > 0)
    d[size == 0] = [0.0, 1.0, 0.0]
    set_transform(f"{path}/shaft/geom", _homogeneous(p=[0.0, 0.5, 0.0]))
    mesh(f"{path}/shaft/geom/mesh", g.Cylinder(1.0, radius), color)
    set_transform(f"{path}/head/geom", _homogeneous(p=[0.0, head / 2, 0.0]))
    mesh(f"{path}/head/geom/mesh",
         g.Cylinder(head, radiusTop=0.0, radiusBottom=2.5 * radius), color)
    shaft = np.maximum(L - head, 0.0)
    at = np.array(at, dtype=np.float64)
    if lever is not None:
        tol = 1e-9 * size * np.linalg.norm(lever, axis=-1)  # f ⊥ r is not inward
        inward = np.einsum("ij,ij->i", vec, lever) < -tol
        at[inward] -= (shaft + head)[inward, None] * d[inward]
    shown_k = (size > 0).astype(np.float64)
    ones, zeros = np.ones(K), np.zeros(K)
    return [
        _animation(path, [
            _track("position", "vector3", times, at),
            _track("quaternion", "quaternion", times, _xyzw(_y_to(d))),
            _track("scale", "vector3", times, np.stack([shown_k] * 3, axis=-1))]),
        _animation(f"{path}/shaft", [
            _track("scale", "vector3", times, np.stack([ones, shaft, ones], axis=-1))]),
        _animation(f"{path}/head", [
            _track("position", "vector3", times, np.stack([zeros, shaft, zeros], -1))])]


def _reaction_arrows(traj: Trajectory, model: Model, times: list[float], extent: float,
                     set_transform, mesh):
    """Each joint's net reaction on its child, per frame: the force at the joint point
    (R = Σ λ_k e_k over its force components) and its couple (Σ over moment components),
    dashed-red style of the diagrams (REACTION_COLOR, thinner). The parent gets −R."""

    if not len(traj.reaction_labels) or traj.reactions.shape[1] == 0:
        raise MbodyError("this run holds no joint reactions to draw (a model without "
                         "joints, or a run saved before reactions were stored)")
    mc = _meshcat()
    g = mc.geometry
    K, J = len(times), len(model.joints)
    t = model.reaction_table
    order = [traj.reaction_labels.index(r) for r in model.reactions]
    F, C, P = np.zeros((K, J, 3)), np.zeros((K, J, 3)), np.zeros((K, J, 3))
    for k in range(K):  # one vectorised evaluation per frame
        cols = reaction_columns(model, traj.state(k))
        w = traj.reactions[k, order][:, None] * cols.W_e
        for comp_is_moment, acc in ((False, F), (True, C)):
            sel = cols.is_moment == comp_is_moment
            for c in range(3):
                acc[k, :, c] = np.bincount(t.joint[sel], w[sel, c], minlength=J)
        P[k] = cols.joint_W_P
    L_max, head, radius = 0.35 * extent, 0.05 * extent, 0.008 * extent
    out, paths = [], {}
    for vec, color, kind in ((F, REACTION_COLOR, "force"), (C, REACTION_COUPLE_COLOR, "couple")):
        size = np.linalg.norm(vec, axis=-1)
        top = float(size.max()) if size.size else 0.0
        if top <= 0:
            continue
        for jn, joint in enumerate(model.joints):
            if not np.any(size[:, jn] > 1e-12 * top):
                continue
            path = f"{ROOT}/reactions/{_path_name(joint.name)}_{kind}"
            paths[f"{joint.name} ({kind})"] = path
            out += _arrow(g, path, P[:, jn], vec[:, jn], size[:, jn] * L_max / top,
                          int(color[1:], 16), (head, radius), times, set_transform, mesh)
    return out, paths


def _check_match(traj: Trajectory, model: Model) -> None:
    if traj.dimension != model.dimension:
        raise MbodyError(f"the trajectory is {'planar' if traj.dimension == 2 else 'spatial'}"
                         f" but model {model.name!r} is "
                         f"{'planar' if model.dimension == 2 else 'spatial'}")
    for nm in traj.body_names:
        if nm not in model.bodies:
            hint = did_you_mean(nm, model.body_names)
            raise MbodyError(f"unknown body {nm!r}: the trajectory names it but model "
                             f"{model.name!r} has only {', '.join(model.body_names)}"
                             + (f" ({hint})" if hint else ""))


# -- the offline page -------------------------------------------------------------------

_PAGE = """<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ margin: 0; overflow: hidden; font: 14px sans-serif; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
#mbody-bar {{ position: absolute; left: 0; right: 0; bottom: 0; display: flex; gap: 8px;
  align-items: center; padding: 6px 10px; background: rgba(0, 0, 0, 0.55); color: #fff; }}
#mbody-bar button {{ min-width: 4.5em; }}
#mbody-time {{ flex: 1; }}
#mbody-clock {{ min-width: 11em; font-variant-numeric: tabular-nums; }}
</style></head>
<body><div id="meshcat-pane"></div>
<div id="mbody-bar"><button id="mbody-play" type="button">pause</button>
<input id="mbody-time" type="range" min="0" max="{duration}" step="any" value="0">
<span id="mbody-clock"></span><span>{caption}</span></div>
<script>{js}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
[{blobs}].forEach(function (s) {{
  var b = atob(s), a = new Uint8Array(b.length);
  for (var i = 0; i < b.length; i++) a[i] = b.charCodeAt(i);
  viewer.handle_command_bytearray(a);
}});
(function () {{
  var anim = viewer.animator, t0 = {t0}, duration = {duration};
  var play = document.getElementById("mbody-play");
  var slider = document.getElementById("mbody-time");
  var clock = document.getElementById("mbody-clock");
  function toggle() {{ if (anim.playing) anim.pause(); else anim.play(); }}
  play.onclick = toggle;
  document.addEventListener("keydown", function (e) {{
    if (e.code === "Space") {{ e.preventDefault(); toggle(); }} }});
  slider.oninput = function () {{
    var t = +slider.value; anim.pause(); anim.seek(t); anim.display_progress(t); }};
  function show() {{
    var t = anim.time;
    if (document.activeElement !== slider) slider.value = t;
    clock.textContent = "t = " + (t0 + t).toFixed(3) + " s of " + (t0 + duration).toFixed(3);
    play.textContent = anim.playing ? "pause" : "play";
    requestAnimationFrame(show);
  }}
  show();
}})();
window.mbody_ready = true;
</script>
{extra}</body></html>
"""


def page_html(scene: Scene, *, extra_js: str = "") -> str:
    """A self-contained page: meshcat's viewer inlined, the commands replayed in order.

    Nothing is fetched: no server, no external links. `extra_js` is appended as a last
    <script> (tests use it to probe the page).
    """
    import umsgpack

    mc = _meshcat()
    js = (Path(mc.viewer_assets_path()) / "dist" / "main.min.js").read_text(encoding="utf-8")
    if "</script" in js.lower():  # would end the inline <script> early
        raise MbodyError("meshcat's viewer script cannot be inlined (it contains </script>)")
    blobs = ",".join(f'"{base64.b64encode(umsgpack.packb(c)).decode("ascii")}"'
                     for c in scene.commands)
    extra = f"<script>\n{extra_js}\n</script>\n" if extra_js else ""
    caption = html.escape(f"{scene.title.removeprefix('mbody: ')} · {scene.frames} frames")
    return _PAGE.format(title=html.escape(scene.title), duration=repr(scene.duration),
                        t0=repr(scene.t0), caption=caption, js=js, blobs=blobs, extra=extra)


def write_page(traj: Trajectory, out: str | os.PathLike[str], *, model: Model,
               forces: bool = False, bodies: Iterable[str] | None = None,
               extra_js: str = "", reactions: bool = False) -> Path:
    """Write the offline animation page for `traj` to `out` (atomically); return its path."""
    scene = build_scene(traj, model, forces=forces, bodies=bodies, reactions=reactions)
    return write_atomic(out, page_html(scene, extra_js=extra_js))


# -- the live viewer --------------------------------------------------------------------

HOST = "127.0.0.1"


def _serve(parent_pid: int) -> None:  # pragma: no cover - runs in the server process
    """meshcat's ZMQ/websocket bridge, listening on 127.0.0.1 only.

    meshcat 0.3.2 calls ``app.listen(port)``, which binds every interface; the app's
    `listen` is wrapped to pass the loopback address. The server stops when its parent
    goes away (so a killed mbody leaves nothing behind) and ignores Ctrl-C, which the
    parent handles by terminating it.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        import tornado.ioloop
        from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class LoopbackBridge(ZMQWebSocketBridge):
        def make_app(self):
            app = super().make_app()
            listen = app.listen
            app.listen = lambda port, **kw: listen(port, address=HOST, **kw)
            return app

    bridge = LoopbackBridge(host=HOST)
    print(f"zmq_url={bridge.zmq_url}")
    print(f"web_url={bridge.web_url}", flush=True)

    def orphaned() -> None:
        if os.getppid() != parent_pid:
            tornado.ioloop.IOLoop.current().stop()

    tornado.ioloop.PeriodicCallback(orphaned, 500).start()
    bridge.run()


class LiveViewer:
    """meshcat's live viewer on 127.0.0.1, in its own server process; a context manager.

        with LiveViewer() as v:
            print(v.url); v.show(scene)        # browsers that connect later get the scene

    `close()` terminates and reaps the server, closes its pipes and the ZMQ socket.
    """

    def __init__(self, *, timeout: float = 15.0):
        import zmq

        self._stderr = tempfile.TemporaryFile()  # noqa: SIM115 - closed in close()
        self.proc: subprocess.Popen | None = subprocess.Popen(
            [sys.executable, "-u", "-c",
             f"from mbody.animate import _serve; _serve({os.getpid()})"],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=self._stderr)
        self._ctx = zmq.Context()
        self._sock = None
        self.timeout = timeout
        try:
            urls = self._read_urls(timeout)
            self.zmq_url, self.url = urls["zmq_url"], urls["web_url"]
            self._connect()
        except BaseException:
            self.close()
            raise

    @property
    def pid(self) -> int | None:
        return self.proc.pid if self.proc else None

    def _read_urls(self, timeout: float) -> dict[str, str]:
        assert self.proc is not None and self.proc.stdout is not None
        out, urls = b"", {}
        deadline = time.monotonic() + timeout
        with selectors.DefaultSelector() as sel:
            sel.register(self.proc.stdout, selectors.EVENT_READ)
            while "web_url" not in urls:
                left = deadline - time.monotonic()
                if left <= 0 or not sel.select(left):
                    raise MbodyError(f"the meshcat server did not start within {timeout:g} s"
                                     + self._server_log())
                chunk = os.read(self.proc.stdout.fileno(), 4096)
                if not chunk:
                    raise MbodyError("the meshcat server exited while starting"
                                     + self._server_log())
                out += chunk
                for line in out.decode("utf-8", "replace").split("\n")[:-1]:  # whole lines
                    key, sep, value = line.partition("=")
                    if sep and key in ("zmq_url", "web_url"):
                        urls[key] = value.strip()
        return urls

    def _server_log(self) -> str:
        self._stderr.seek(0)
        text = self._stderr.read().decode("utf-8", "replace").strip()
        return f": {text.splitlines()[-1]}" if text else ""

    def _connect(self) -> None:
        import zmq

        if self._sock is not None:
            self._sock.close(linger=0)
        self._sock = self._ctx.socket(zmq.REQ)
        self._sock.setsockopt(zmq.LINGER, 0)
        self._sock.setsockopt(zmq.SNDTIMEO, int(self.timeout * 1000))
        self._sock.connect(self.zmq_url)

    def _request(self, frames: list[bytes], timeout: float | None = None) -> bytes | None:
        """One REQ/REP exchange; None on timeout (the socket is then replaced: a REQ
        socket that missed its reply cannot send again)."""
        import zmq

        if self._sock is None:
            raise MbodyError("the live viewer is closed")
        self._sock.send_multipart(frames)
        wait = self.timeout if timeout is None else timeout
        if self._sock.poll(int(wait * 1000), zmq.POLLIN):
            return self._sock.recv()
        self._connect()
        return None

    def send(self, command: dict[str, Any]) -> None:
        """Send one lowered meshcat command (as built by `build_scene`)."""
        import umsgpack

        reply = self._request([command["type"].encode(), command["path"].encode(),
                               umsgpack.packb(command)])
        if reply is None:
            raise MbodyError(f"the meshcat server did not answer within {self.timeout:g} s")

    def show(self, scene: Scene) -> None:
        """Push a whole scene (objects, transforms and the animation)."""
        for command in scene.commands:
            self.send(command)

    def wait_for_browser(self, timeout: float = 10.0) -> bool:
        """True once a browser is connected (False after `timeout` s)."""
        return self._request([b"wait"], timeout) is not None

    def close(self) -> None:
        """Stop the server and release everything; safe to call twice. (meshcat 0.3.2's
        own `Visualizer.close()` raises, and its server would outlive a killed parent.)"""
        if self._sock is not None:
            self._sock.close(linger=0)
            self._sock = None
        if self._ctx is not None:
            self._ctx.term()
            self._ctx = None
        if self.proc is not None:
            proc, self.proc = self.proc, None
            proc.terminate()
            try:
                proc.wait(5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(5)
            if proc.stdout:
                proc.stdout.close()
        if not self._stderr.closed:
            self._stderr.close()

    def __enter__(self) -> LiveViewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()


# -- the entry point --------------------------------------------------------------------


def resolve(source, model: Model | str | os.PathLike[str] | None = None, *,
            t_end: float | None = None, fps: float | None = None
            ) -> tuple[Trajectory, Model]:
    """(trajectory, model) from a Trajectory, a Model, or a path to a model or run file.

    A model is simulated first (`mbody.simulate` with its defaults unless `t_end`/`fps`
    are given); a trajectory's model comes from `model`, else from the file it names.
    """

    if isinstance(model, (str, os.PathLike)):
        model = load_model(model)
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if not path.is_file():
            raise MbodyError(f"{path}: no such file")
        if _is_npz(path):
            source = _load_trajectory(path)
            if model is None:
                model = _model_of(source, path)
        else:
            source = load_model(path)
    if isinstance(source, Model):
        model = source
        source = _simulate(source, t_end, fps)
    if not isinstance(source, Trajectory):
        raise MbodyError(f"cannot animate a {type(source).__name__}: give a Trajectory, a "
                         "Model, or the path of a model (.yaml) or run (.npz) file")
    if model is None:
        raise MbodyError("give the model the trajectory was computed from (model=...)")
    return source, model


def _is_npz(path: Path) -> bool:
    with open(path, "rb") as fh:
        return fh.read(4) == b"PK\x03\x04" or path.suffix == ".npz"


def _load_trajectory(path: Path) -> Trajectory:
    return Trajectory.load(path)  # TrajectoryFileError (an MbodyError) names the problem


def _model_of(traj: Trajectory, path: Path) -> Model:
    """The run's model: from the YAML text it carries, else from the file it names."""

    if getattr(traj, "model_yaml", ""):
        return traj.model()
    if not traj.model_file:
        raise MbodyError(f"{path} does not say which model it came from: pass --model MODEL")
    for where in (Path(traj.model_file), path.parent / traj.model_file):
        if where.is_file():
            return load_model(where)
    raise MbodyError(f"{path} was computed from {traj.model_file}, which is not found: "
                     "pass --model MODEL")


def _simulate(model: Model, t_end: float | None, fps: float | None) -> Trajectory:

    sim = getattr(mbody, "simulate", None)
    if sim is None:
        raise MbodyError("this mbody cannot simulate yet: animate a saved trajectory")
    kw = {k: v for k, v in (("t_end", t_end), ("fps", fps)) if v is not None}
    return sim(model, **kw)


def animate(source, out: str | os.PathLike[str] | None = "run.html", *,
            model: Model | str | os.PathLike[str] | None = None, forces: bool = False,
            live: bool = False, t_end: float | None = None, fps: float | None = None,
            bodies: Iterable[str] | None = None, reactions: bool = False) -> Path | LiveViewer:
    """Animate a motion: write a self-contained page, or (live=True) open the live viewer.

    source: a `Trajectory` (then give `model`), a `Model` (simulated first, `t_end`/`fps`
    passed to `mbody.simulate`), or a path to a model (.yaml) or run (.npz) file.
    Returns the page's path; with live=True, a running `LiveViewer` instead (no page is
    written; show its `url` in a browser and `close()` it when done).
    """
    traj, mdl = resolve(source, model, t_end=t_end, fps=fps)
    scene = build_scene(traj, mdl, forces=forces, bodies=bodies, reactions=reactions)
    if not live:
        if out is None:
            raise MbodyError("give out= (the page to write) or live=True")
        return write_atomic(out, page_html(scene))
    viewer = LiveViewer()
    try:
        viewer.show(scene)
    except BaseException:
        viewer.close()
        raise
    return viewer
