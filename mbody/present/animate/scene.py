"""The scene: meshcat commands that draw each body and move it along a `Trajectory`.

Body i is drawn at its pose at every sample k,

    W_x(t_k) = W_r_G,i(t_k) + W_R_B,i(t_k) B_x      (every point B_x of its shape)

as keyframes (position and quaternion tracks, times t_k − t_0 in seconds) that the
viewer interpolates (linearly for positions, slerp for rotations). Planar bodies live in
the x-y plane and turn about z. Applied forces and couples (`forces=True`) are arrows:
a cylinder shaft and a cone head, placed at the point of application, pointing along
W_f, with length proportional to |W_f| (couples: along the moment vector, at G).

meshcat 0.3.2's Python side breaks under numpy 2 unless it is given float64 arrays and
Python scalars, so every number handed to it is converted first (`float`, float64 4x4
matrices). Keyframe tracks bypass it: they are float64 numpy arrays in the commands,
sent as Float32Arrays (`mbody.present.animate.wire`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody.equations.joints import reaction_columns
from mbody.equations.loads import applied_loads
from mbody.errors import MbodyError, did_you_mean
from mbody.model.drawn import body_box
from mbody.model.model import Body, Model
from mbody.present.animate.wire import load_meshcat
from mbody.simulate.trajectory import Trajectory
from mbody.util.colours import colour_hex, colour_hint
from mbody.util.spatial import matvec, planar_quat, quat_to_matrix

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
FOV = 75.0
"""meshcat's camera: a perspective camera with this vertical field of view (degrees)."""
FILL, ASPECT = 0.85, 4 / 3
"""The motion's bounding box fills FILL of the view's width or height, whichever binds;
the live viewer's camera assumes a view ASPECT (width / height) wide, the offline page
refits it to its window (`CameraFit.js`)."""
CAMERA = "/Cameras/default/rotated/<object>"


@dataclass(frozen=True)
class Scene:
    """Lowered meshcat commands (dicts, in order) that build and animate the motion.

    commands: each a dict as meshcat's viewer reads it; keyframe `times` and `values`
    are flat float64 numpy arrays (packed as Float32Arrays by `wire.pack`).
    paths: body name -> scene path of its animated node (local pose = W_r_G, W_R_B).
    duration: seconds of animation (t_end − t_0); t0: the trajectory's first time.
    load_paths: load (or 'joint (force)', 'joint (couple)') name -> its arrow's path.
    """

    commands: list[dict[str, Any]]
    paths: dict[str, str]
    duration: float
    t0: float
    frames: int
    title: str
    load_paths: dict[str, str] = field(default_factory=dict)
    camera: CameraFit | None = None


@dataclass(frozen=True)
class CameraFit:
    """Where the camera must be for the motion's bounding box to fill the view.

    basis: (3, 3) rows right, up, back (unit vectors, meshcat world axes, z up); the
    camera looks along −back with up as its up. points: (8, 3) the box's corners in
    those axes (x right, y up, z towards the camera), scene units, about the scene's
    origin.

    With t = tan(fov / 2) FILL, a corner (x, y, z) is in view of a camera at (c_x, c_y,
    z = D) when |x − c_x| <= (D − z) a t and |y − c_y| <= (D − z) t, a the aspect. Each
    pair of bounds is tight at D = (A + B) / (2 a t), c_x = (A − B) / 2 with
    A = max(x + a t z), B = max(−x + a t z) (likewise for y). The larger D wins; then
    each offset is the one that centres the corners' projections (x − c_x) / (D − z): in
    perspective a box's near corners look larger, so the camera aims off its centre.
    """

    basis: np.ndarray
    points: np.ndarray
    fov: float = FOV
    fill: float = FILL

    def solve(self, aspect: float) -> tuple[float, float, float]:
        """(c_x, c_y, D): the camera's sideways and upward offset and its distance, for a
        view `aspect` (width / height) wide."""
        tan = self.fill * math.tan(math.radians(self.fov) / 2)
        x, y, z = self.points.T
        D = 0.0
        for u, k in ((x, aspect * tan), (y, tan)):
            D = max(D, (float(np.max(u + k * z)) + float(np.max(-u + k * z))) / (2 * k))
        return _centre(x, D - z), _centre(y, D - z), D

    def target(self, aspect: float) -> np.ndarray:
        """The orbit target (meshcat world) for a view `aspect` wide."""
        cx, cy, _ = self.solve(aspect)
        return cx * self.basis[0] + cy * self.basis[1]

    def position(self, aspect: float) -> np.ndarray:
        """The camera's position (meshcat world) for a view `aspect` wide."""
        cx, cy, D = self.solve(aspect)
        return cx * self.basis[0] + cy * self.basis[1] + D * self.basis[2]

    def shifted(self, offset: np.ndarray) -> CameraFit:
        """The same fit with the scene moved by `offset` (meshcat world)."""
        return CameraFit(self.basis, self.points + self.basis @ offset, self.fov, self.fill)

    def js(self) -> str:
        """JavaScript: a function `fit(viewer)` that aims the camera for the viewer's own
        aspect (`solve`, in the page's window)."""
        pts = [[round(float(v), 6) for v in p] for p in self.points]
        basis = [[float(v) for v in row] for row in self.basis]
        return (
            "function fit(viewer) {\n"
            f"  var pts = {pts}, B = {basis};\n"
            f"  var t = {self.fill!r} * Math.tan({math.radians(self.fov) / 2!r});\n"
            "  function reach(i, k) { var A = -Infinity, C = -Infinity;\n"
            "    pts.forEach(function (p) { A = Math.max(A, p[i] + k * p[2]);\n"
            "      C = Math.max(C, -p[i] + k * p[2]); });\n"
            "    return (A + C) / (2 * k); }\n"
            "  function centre(i, D) { var lo = Infinity, hi = -Infinity;\n"
            "    pts.forEach(function (p) { lo = Math.min(lo, p[i]); hi = Math.max(hi, p[i]); });\n"
            "    for (var n = 0; n < 60; n++) {\n"
            "      var c = (lo + hi) / 2, a = -Infinity, b = Infinity;\n"
            "      pts.forEach(function (p) { var q = (p[i] - c) / (D - p[2]);\n"
            "        a = Math.max(a, q); b = Math.min(b, q); });\n"
            "      if (a + b > 0) lo = c; else hi = c; }\n"
            "    return (lo + hi) / 2; }\n"
            "  var D = Math.max(reach(0, viewer.camera.aspect * t), reach(1, t));\n"
            "  var cx = centre(0, D), cy = centre(1, D), w = [0, 1, 2].map(function (i) {\n"
            "    return cx * B[0][i] + cy * B[1][i]; });\n"
            "  // meshcat's camera frame is y up: (x, y, z)_world = (x, -z, y)_camera\n"
            "  viewer.controls.target.set(w[0], w[2], -w[1]);\n"
            "  viewer.camera.position.set(w[0] + D * B[2][0], w[2] + D * B[2][2],"
            " -w[1] - D * B[2][1]);\n"
            "  viewer.controls.update(); viewer.set_dirty();\n"
            "}\n")


def _centre(u: np.ndarray, e: np.ndarray) -> float:
    """The offset c for which the projections (u − c) / e (e > 0) are centred on 0:
    max + min of them falls as c grows, from >= 0 at min(u) to <= 0 at max(u)."""
    lo, hi = float(np.min(u)), float(np.max(u))
    for _ in range(60):
        c = (lo + hi) / 2
        q = (u - c) / e
        lo, hi = (c, hi) if q.max() + q.min() > 0 else (lo, c)
    return (lo + hi) / 2


def camera_fit(corners: np.ndarray, direction: np.ndarray) -> CameraFit:
    """The camera fit for box `corners` (8, 3), seen from unit `direction` (z up).

    Parameters
    ----------
    corners : (8, 3) array
        The bounding box's corners in meshcat world axes.
    direction : (3,) array
        Unit vector from the target to the camera; the camera's up is world +z, as
        meshcat's orbit controls keep it.

    Returns
    -------
    CameraFit
    """
    back = np.asarray(direction, dtype=np.float64)
    right = np.cross([0.0, 0.0, 1.0], back)
    right /= np.linalg.norm(right)
    basis = np.stack([right, np.cross(back, right), back])
    return CameraFit(basis, np.asarray(corners, dtype=np.float64) @ basis.T)


def _box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(8, 3) corners of the box [lo, hi]."""
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                     for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=np.float64)


def _motion_box(pos: np.ndarray, quat: np.ndarray, extents: Sequence[_Extent]
                ) -> tuple[np.ndarray, np.ndarray]:
    """The world box holding every body's shape at every sample: (lo, hi), each (3,).

    pos (K, n, 3), quat (K, n, 4) w-first; extents: the n bodies' shapes.
    """
    R = quat_to_matrix(quat)
    reach = np.stack([e.reach(R[:, i]) for i, e in enumerate(extents)], axis=1)
    return (pos - reach).min(axis=(0, 1)), (pos + reach).max(axis=(0, 1))


class _Commands:
    """The command list being built, with meshcat's lowering for objects."""

    def __init__(self, mc: ModuleType):
        self.mc = mc
        self.g = mc.geometry
        self.list: list[dict[str, Any]] = []
        self.bounds: list[tuple[np.ndarray, np.ndarray]] = []  # (lo, hi) of each arrow

    def set_object(self, path: str, obj: Any) -> None:
        self.list.append(self.mc.commands.SetObject(obj, path=self._path(path)).lower())

    def mesh(self, path: str, geom: Any, color: int, opacity: float = 1.0) -> None:
        mat = self.g.MeshLambertMaterial(color=int(color), opacity=float(opacity),
                                         transparent=opacity < 1.0)
        self.list.append(self.mc.commands.SetObject(geom, mat, path=self._path(path)).lower())

    def set_transform(self, path: str, T: np.ndarray) -> None:
        # column-major, as three.js Matrix4.fromArray reads it
        self.list.append({"type": "set_transform", "path": path,
                          "matrix": np.asarray(T, dtype=np.float64).T.ravel().tolist()})

    def set_property(self, path: str, key: str, value: Any) -> None:
        self.list.append({"type": "set_property", "path": path, "property": key,
                          "value": value})

    def _path(self, path: str) -> Any:
        return self.mc.path.Path(tuple(p for p in path.split("/") if p))


def _rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _homogeneous(R: np.ndarray | None = None, p: Sequence[float] | np.ndarray | None = None,
                 scale: float = 1.0) -> np.ndarray:
    T = np.eye(4, dtype=np.float64)
    if R is not None:
        T[:3, :3] = R
    T[:3, :3] *= scale
    if p is not None:
        T[:3, 3] = p
    return T


def _color(value: str | None, i: int) -> int:
    """A colour name or '#rrggbb' -> 0xRRGGBB (meshcat wants a Python int). A model's
    colour was checked when it was read; a run file's is checked here."""
    text = value if value is not None else PALETTE[i % len(PALETTE)]
    rgb = colour_hex(text)
    if rgb is None:
        raise MbodyError(f"{text!r} is not a colour: {colour_hint(text)}")
    return int(rgb[1:], 16)


@dataclass(frozen=True)
class _Extent:
    """A shape for bounding: kind ('box', 'ellipsoid' or 'cylinder' along its z), the
    rotation from its own axes to body axes, its half-extents (radii; for a cylinder
    [r, r, length / 2]) in its own axes, and its centre from the mass centre (body axes:
    a bar through a body's points, `mbody.model.drawn`, need not be centred at G)."""

    kind: str
    axes: np.ndarray
    half: np.ndarray
    centre: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def body_half(self) -> np.ndarray:
        """Half-extents of a box in body axes, centred at G, that holds the shape."""
        return np.abs(self.axes) @ self.half + np.abs(self.centre)

    def reach(self, R: np.ndarray) -> np.ndarray:
        """(K, 3) half-extents along world axes, about the mass centre, of the shape
        turned by R (K, 3, 3), exact for each kind about its own centre: a box spans
        |R| h, an ellipsoid sqrt(Σ_j (R_ij r_j)²), a cylinder of axis a spans
        r sqrt(1 − a_i²) + (length / 2) |a_i|; plus how far R puts that centre from G."""
        Rs = R @ self.axes
        off = np.abs(R @ self.centre)
        if self.kind == "box":
            return np.abs(Rs) @ self.half + off
        if self.kind == "ellipsoid":
            return np.sqrt((Rs * Rs) @ (self.half * self.half)) + off
        a = Rs[..., 2]
        return (self.half[0] * np.sqrt(np.clip(1.0 - a * a, 0.0, None))
                + self.half[2] * np.abs(a)) + off


def _shape(g: ModuleType, model: Model, body: Body, dimension: int
           ) -> tuple[Any, np.ndarray, _Extent]:
    """meshcat geometry of a body, its fixed transform in body axes, its extent.

    meshcat's cylinder axis is its local +y (three.js); turning it by +90° about x puts it
    along body z, the axis the model format gives cylinders and discs.
    """
    to_z = _homogeneous(_rot_x(math.pi / 2))
    eye, I3 = np.eye(4), np.eye(3)
    shape = body.shape
    if shape is None:  # a bar through its points, or the box with its inertia
        box = body_box(model, body.index)
        dims = [float(e) for e in box.size]
        if dimension == cv.PLANAR:
            dims.append(0.2 * min(dims))
        return (g.Box(dims), _homogeneous(box.axes, box.centre),
                _Extent("box", box.axes, np.array(dims) / 2, box.centre))
    kind, v = next(iter(shape.items()))
    if kind == "box":
        dims = [float(x) for x in v]
        if dimension == cv.PLANAR:
            dims.append(0.2 * min(dims))
        return g.Box(dims), eye, _Extent("box", I3, np.array(dims) / 2)
    if kind == "ellipsoid":
        radii = [float(x) for x in v]
        if dimension == cv.PLANAR:
            radii.append(0.2 * min(radii))
        return (g.Ellipsoid(np.array(radii, dtype=np.float64)), eye,
                _Extent("ellipsoid", I3, np.array(radii)))
    r = float(v["radius"])
    if kind == "sphere":
        return g.Sphere(r), eye, _Extent("ellipsoid", I3, np.full(3, r))
    length = float(v["length"]) if kind == "cylinder" else 0.1 * r if dimension == 3 else 0.2 * r
    return g.Cylinder(length, r), to_z, _Extent("cylinder", I3, np.array([r, r, length / 2]))


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


def _track(name: str, kind: str, times: np.ndarray, values: np.ndarray) -> dict[str, Any]:
    # three.js KeyframeTrack JSON with flat `times`/`values` (the compact form its
    # parser accepts); the clip's fps is 1, so times are seconds.
    return {"name": "." + name, "type": kind, "times": times,
            "values": np.ascontiguousarray(values, dtype=np.float64).reshape(-1)}


def _animation(path: str, tracks: list[dict[str, Any]]) -> dict[str, Any]:
    return {"path": path, "clip": {"fps": 1, "name": "default", "tracks": tracks}}


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

    Parameters
    ----------
    traj : Trajectory
        Positions (K, n, d) world, orientations (K, n, 4) w-first or (K, n) angles.
    model : Model
        Supplies each body's shape (or inertia-equivalent box), colour and loads.
    forces : bool
        Draw applied forces and couples as arrows.
    bodies : iterable of str, optional
        Draw only these (default: all).
    reactions : bool
        Draw each joint's reaction force and couple on its child.

    Returns
    -------
    Scene
        The commands in order, with each body's scene path.
    """
    traj_names = list(traj.body_names)
    index = {nm: i for i, nm in enumerate(traj_names)}
    _check_match(traj, model)
    shown = list(traj_names if bodies is None else bodies)
    for name in shown:
        if name not in index:
            hint = did_you_mean(name, traj_names)
            raise MbodyError(f"unknown body {name!r}: the trajectory has "
                             f"{', '.join(traj_names)}" + (f" ({hint})" if hint else ""))
    traj.need_samples()
    t = np.asarray(traj.t, dtype=np.float64)
    if np.any(np.diff(t) <= 0):
        raise MbodyError("the trajectory's times do not increase")

    out = _Commands(load_meshcat())
    g = out.g
    pos, quat = _internal(traj)
    idx = [index[nm] for nm in shown]
    times = t - t[0]
    times.setflags(write=False)  # one array shared by every track
    duration = float(t[-1] - t[0])

    # Geometry first: its size sets the scene's scale.
    geoms, extents = [], []
    for nm in shown:
        body = model.bodies[nm]
        geom, T_shape, ext = _shape(g, model, body, traj.dimension)
        extents.append(ext)
        geoms.append((nm, geom, T_shape, ext.body_half(), _color(body.color, body.index)))
    lo, hi = _motion_box(pos[:, idx], quat[:, idx], extents)
    extent = float(np.max(hi - lo))
    mark = len(out.list)  # the model frame, grid and camera go here once all is drawn

    # Every shown body's keyframes at once, body-major, so each track is a view.
    P_all = np.ascontiguousarray(pos[:, idx, :].transpose(1, 0, 2))
    Q_all = np.ascontiguousarray(_xyzw(quat[:, idx, :]).transpose(1, 0, 2))
    paths: dict[str, str] = {}
    animations = []
    for j, (nm, geom, T_shape, half, color) in enumerate(geoms):
        path = f"{ROOT}/bodies/{_path_name(nm)}"
        paths[nm] = path
        out.set_transform(f"{path}/shape", T_shape)
        out.mesh(f"{path}/shape/mesh", geom, color)
        out.set_object(f"{path}/axes", g.triad(float(1.3 * np.max(half))))
        animations.append(_animation(path, [
            _track("position", "vector3", times, P_all[j]),
            _track("quaternion", "quaternion", times, Q_all[j])]))

    load_paths: dict[str, str] = {}
    if forces:
        arrows, load_paths = _arrows(traj, model, pos, quat, set(idx), times, extent, out)
        animations.extend(arrows)
    if reactions:
        arrows, reaction_paths = _reaction_arrows(traj, model, times, extent, out)
        animations.extend(arrows)
        load_paths.update(reaction_paths)


    # Fit the view to everything drawn: the bodies' box, with the arrows' reach.
    if out.bounds:
        lo = np.minimum(lo, np.min([b[0] for b in out.bounds], axis=0))
        hi = np.maximum(hi, np.max([b[1] for b in out.bounds], axis=0))
    rest, out.list = out.list[mark:], out.list[:mark]
    camera = _view(out, traj.dimension, lo, hi, extent,
                   -max(h[2] for *_, h, _ in geoms) - 1e-3)
    out.list += rest

    out.list.append({"type": "set_animation", "path": "", "animations": animations,
                     "options": {"play": True, "repetitions": math.inf}})
    title = f"mbody: {model.name or traj.model_name or 'motion'}"
    return Scene(out.list, paths, duration, float(t[0]), len(t), title, load_paths,
                 camera)


def _view(out: _Commands, dimension: int, lo: np.ndarray, hi: np.ndarray,
          extent: float, behind: float) -> CameraFit:
    """The model frame's transform, the grid and the camera for the box [lo, hi] (model
    axes) of all that is drawn; `extent` sets the scale (the bodies' motion), `behind`
    the planar grid's z."""
    centre = (lo + hi) / 2
    s = SCENE_SIZE / extent
    # The model frame: scaled to SCENE_SIZE, the planar x-y plane stood upright (model y
    # up on screen, the camera on model +z), and placed so that the orbit target, which
    # meshcat keeps at the origin, is where the camera fit aims (off the box's centre:
    # in perspective its near corners look larger).
    R_view = _rot_x(math.pi / 2) if dimension == cv.PLANAR else np.eye(3)
    d = np.array([0.0, -1.0, 0.0]) if dimension == cv.PLANAR else np.array([1, .8, .65])
    camera = camera_fit(s * (_box_corners(lo, hi) - centre) @ R_view.T, d / np.linalg.norm(d))
    aim = camera.target(ASPECT)
    camera = camera.shifted(-aim)
    W_root = _homogeneous(R_view, -s * R_view @ centre - aim, s)
    out.set_transform(ROOT, W_root)

    # Ground grid in the model's x-y plane: below the motion (spatial), behind the
    # bodies (planar). meshcat's grid is 40 cells of 0.5; cells of a round size (1, 2 or
    # 5 times a power of ten) make it 3 to 7.5 times the motion's size. (A much larger
    # grid, reaching far behind the camera, loses its near lines in software WebGL.)
    cell = _round_up(3.0 * extent / 40)
    gz = lo[2] if dimension == cv.SPATIAL else behind
    gc = [round(centre[0] / cell) * cell, round(centre[1] / cell) * cell, gz]
    out.set_transform("/Grid", W_root @ _homogeneous(None, gc, cell / 0.5))
    out.set_property("/Axes", "visible", False)
    out.set_object(f"{ROOT}/origin", out.g.triad(float(0.15 * extent)))

    # The camera along a fixed direction, at the distance where the box fills FILL of
    # the view (the page refits it to its window's aspect).
    p_cam = camera.position(ASPECT)
    # meshcat's camera sits in a y-up frame: (x, y, z)_world = (x, -z, y)_camera.
    out.set_property(CAMERA, "position", [float(p_cam[0]), float(p_cam[2]), float(-p_cam[1])])
    return camera


def _arrows(traj: Trajectory, model: Model, pos: np.ndarray, quat: np.ndarray,
            shown: set[int], times: np.ndarray, extent: float, out: _Commands
            ) -> tuple[list[dict[str, Any]], dict[str, str]]:
    """Arrows for applied forces (at their points), gravity (m g at G) and couples (at
    G), per frame.

    Each arrow node turns +y onto the load's direction; its shaft is scaled along y to
    length L − head and its head sits at the shaft's end, so the head keeps its shape.
    A force that pushes into its body (f · r < 0, r from G to the point) is drawn ending
    at its point, so that it stays outside the body; others start at their point.
    L = L_max |f| / max|f| over the run (forces and couples scaled separately).
    """
    K = len(times)
    f_list, p_list, m_list = [], [], []
    for k in range(K):  # one vectorised evaluation per frame (loads may depend on t)
        c = applied_loads(model, traj.state(k)).contributions
        on = c.body >= 0  # spring ends on ground are not drawn
        R = quat_to_matrix(quat[k, np.where(on, c.body, 0)])
        f_list.append(c.W_f)
        p_list.append(pos[k, np.where(on, c.body, 0)] + matvec(R, c.B_r))
        m_list.append(matvec(R, c.B_m))
        couple, body, names = c.couple, c.body, c.names
    W_f, W_p, W_m = np.array(f_list), np.array(p_list), np.array(m_list)
    vec = np.where(couple[None, :, None], W_m, W_f)
    at = np.where(couple[None, :, None], pos[:, np.maximum(body, 0)], W_p)
    names = tuple(names)
    # Gravity, m g at each mass centre: the free-body diagrams' weight, drawn and scaled
    # as the other forces are.
    weight = model.mass[:, None] * np.asarray(model.gravity, dtype=np.float64)[None, :]
    heavy = np.flatnonzero(np.linalg.norm(weight, axis=1) > 0)
    if len(heavy):
        where = [list(traj.body_names).index(model.body_names[i]) for i in heavy]
        vec = np.concatenate([vec, np.broadcast_to(weight[heavy], (K, len(heavy), 3))], 1)
        at = np.concatenate([at, pos[:, where]], axis=1)
        body = np.concatenate([body, where])
        couple = np.concatenate([couple, np.zeros(len(heavy), dtype=bool)])
        names += tuple(f"gravity ({model.body_names[i]})" for i in heavy)
    if not K or not len(body):
        return [], {}
    size = np.linalg.norm(vec, axis=-1)  # (K, k)
    L_max, head, radius = 0.35 * extent, 0.06 * extent, 0.012 * extent
    anims: list[dict[str, Any]] = []
    paths: dict[str, str] = {}
    for group in (False, True):
        sel = (couple == group) & (body >= 0) & np.isin(body, list(shown))
        top = size[:, sel].max() if sel.any() else 0.0
        scale = L_max / top if top > 0 else 0.0
        color = int((COUPLE_COLOR if group else FORCE_COLOR)[1:], 16)
        for j in np.flatnonzero(sel):
            path = f"{ROOT}/loads/{j}_{_path_name(names[j])}"
            paths.setdefault(names[j], path)
            lever = None if group else at[:, j] - pos[:, body[j]]
            anims += _arrow(out, path, at[:, j], vec[:, j], size[:, j] * scale, color,
                            (head, radius), times, lever)
    return anims, paths


def _arrow(out: _Commands, path: str, at: np.ndarray, vec: np.ndarray, L: np.ndarray,
           color: int, dims: tuple[float, float], times: np.ndarray,
           lever: np.ndarray | None = None) -> list[dict[str, Any]]:
    """One arrow's nodes and tracks: (K, 3) foot `at`, direction of `vec`, length L (K,).

    With `lever` (K, 3) (point minus mass centre), a push into the body is drawn with its
    tip at the point instead of its foot, so that it stays outside the body.
    """
    g = out.g
    head, radius = dims
    K = len(times)
    size = np.linalg.norm(vec, axis=-1)
    d = np.divide(vec, size[:, None], out=np.zeros((K, 3)), where=size[:, None] > 0)
    d[size == 0] = [0.0, 1.0, 0.0]
    out.set_transform(f"{path}/shaft/geom", _homogeneous(p=[0.0, 0.5, 0.0]))
    out.mesh(f"{path}/shaft/geom/mesh", g.Cylinder(1.0, radius), color)
    out.set_transform(f"{path}/head/geom", _homogeneous(p=[0.0, head / 2, 0.0]))
    out.mesh(f"{path}/head/geom/mesh",
             g.Cylinder(head, radiusTop=0.0, radiusBottom=2.5 * radius), color)
    shaft = np.maximum(L - head, 0.0)
    at = np.array(at, dtype=np.float64)
    if lever is not None:
        tol = 1e-9 * size * np.linalg.norm(lever, axis=-1)  # f ⊥ r is not inward
        inward = np.einsum("ij,ij->i", vec, lever) < -tol
        at[inward] -= (shaft + head)[inward, None] * d[inward]
    shown_k = (size > 0).astype(np.float64)
    if shown_k.any():
        ends = np.concatenate([at, at + (shaft + head)[:, None] * d])[np.tile(size > 0, 2)]
        out.bounds.append((ends.min(axis=0), ends.max(axis=0)))
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


def _reaction_arrows(traj: Trajectory, model: Model, times: np.ndarray, extent: float,
                     out: _Commands) -> tuple[list[dict[str, Any]], dict[str, str]]:
    """Each joint's net reaction on its child, per frame: the force at the joint point
    (R = Σ λ_k e_k over its force components) and its couple (Σ over moment components),
    dashed-red style of the diagrams (REACTION_COLOR, thinner). The parent gets −R."""
    if not len(traj.reaction_labels) or traj.reactions.shape[1] == 0:
        raise MbodyError("this run holds no joint reactions to draw (a model without "
                         "joints, or a run saved before reactions were stored)")
    K, J = len(times), len(model.joints)
    t = model.reaction_table
    column = {r: i for i, r in enumerate(traj.reaction_labels)}
    order = [column[r] for r in model.reactions]
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
    anims: list[dict[str, Any]] = []
    paths: dict[str, str] = {}
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
            anims += _arrow(out, path, P[:, jn], vec[:, jn], size[:, jn] * L_max / top,
                            int(color[1:], 16), (head, radius), times)
    return anims, paths


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
