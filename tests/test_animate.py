"""Animation: the scene's keyframes against closed-form motions, the offline page in a real
browser (pose after seeking, pixels on screen), the live viewer's loopback binding and
clean shutdown, and bad input."""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import psutil
import pytest

import mbody
from mbody.errors import MbodyError
from mbody.present.animate import (
    FILL,
    LiveViewer,
    build_scene,
    camera_fit,
    pack,
    page_html,
    unpack,
    write_page,
)
from mbody.simulate.trajectory import Trajectory

sys.path.insert(0, str(Path(__file__).parent))
import chromium  # noqa: E402

needs_browser = pytest.mark.skipif(not chromium.AVAILABLE, reason="no /usr/bin/chromium")
ROOT = Path(__file__).resolve().parent.parent

SPIN_YAML = """\
model: spinner
dimension: 3
bodies:
  - {name: brick, mass: 2, shape: {box: [0.4, 0.2, 0.1]}, color: red}
  - {name: rotor, mass: 1, shape: {cylinder: {radius: 0.1, length: 0.3}},
     position: [0, 0.5, 0], color: "#00ff00"}
loads:
  - {name: push, type: force, body: brick, force: [0, 0, 3], at: [0.2, 0, 0], frame: body}
"""
W = 3.0                                   # rad/s about the fixed axis N
N = np.array([1.0, 1.0, 2.0]) / math.sqrt(6.0)
V = 0.5                                   # m/s along world x


def spin_q(t):
    """Closed form: constant ω about a fixed axis, q = [cos(ωt/2), sin(ωt/2) N]."""
    t = np.asarray(t, dtype=float)
    return np.concatenate([np.cos(W * t / 2)[..., None], np.sin(W * t / 2)[..., None] * N], -1)


def rot(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@pytest.fixture(scope="module")
def spinner():
    model = mbody.loads(SPIN_YAML, "spinner.yaml")
    t = np.linspace(0.0, 2.0, 61)
    K = len(t)
    pos = np.zeros((K, 2, 3))
    pos[:, 0, 0] = V * t
    pos[:, 1, 1] = 0.5
    q = np.zeros((K, 2, 4))
    q[:, 0] = spin_q(t)
    q[:, 1, 0] = 1.0
    traj = Trajectory(t, pos, np.zeros_like(pos), q, np.zeros((K, 2, 3)), ("brick", "rotor"),
                      3, model_name="spinner", model_yaml=SPIN_YAML)
    return model, traj


PEND_L, PEND_A, PEND_W = 0.5, math.pi / 6, 3.0


@pytest.fixture(scope="module")
def pendulum():
    model = mbody.load(ROOT / "models" / "pendulum.yaml")
    t = np.linspace(0.0, 2.0, 81)
    th = PEND_A * np.cos(PEND_W * t)
    pos = np.stack([PEND_L * np.sin(th), -PEND_L * np.cos(th)], -1)[:, None, :]
    traj = Trajectory(t, pos, np.zeros_like(pos), th[:, None], np.zeros((len(t), 1)),
                      ("rod",), 2, model_name="physical-pendulum")
    return model, traj


def _animation(scene, path):
    anim = next(c for c in scene.commands if c["type"] == "set_animation")
    return {tr["name"]: tr for a in anim["animations"] if a["path"] == path
            for tr in a["clip"]["tracks"]}


# -- the scene (no browser) ---------------------------------------------------------------


def test_keyframes_are_the_trajectory(spinner):
    model, traj = spinner
    scene = build_scene(traj, model)
    tracks = _animation(scene, scene.paths["brick"])
    np.testing.assert_array_equal(tracks[".position"]["times"], traj.t - traj.t[0])
    P = np.reshape(tracks[".position"]["values"], (-1, 3))
    np.testing.assert_allclose(P[:, 0], V * traj.t, atol=1e-15)
    Q = np.reshape(tracks[".quaternion"]["values"], (-1, 4))  # three.js order x, y, z, w
    np.testing.assert_allclose(Q[:, [3, 0, 1, 2]], spin_q(traj.t), atol=1e-15)
    assert scene.duration == 2.0 and scene.frames == 61


def test_packed_keyframes_are_float32_arrays_of_the_motion(spinner):
    """The set_animation command goes out with every track as one Float32Array (msgpack
    ext 0x17) that decodes to the trajectory's numbers rounded to float32, not as
    per-number floats; the per-number path (typed_arrays=False) still gives float64."""
    model, traj = spinner
    scene = build_scene(traj, model, forces=True)
    cmd = next(c for c in scene.commands if c["type"] == "set_animation")
    data = pack(cmd)
    back = unpack(data)
    tracks = 0
    for sent, got in zip(cmd["animations"], back["animations"], strict=True):
        assert got["path"] == sent["path"]
        for a, b in zip(sent["clip"]["tracks"], got["clip"]["tracks"], strict=True):
            assert (b["name"], b["type"]) == (a["name"], a["type"])
            for key in ("times", "values"):
                assert isinstance(b[key], np.ndarray) and b[key].dtype == np.float32
                np.testing.assert_array_equal(b[key], np.float32(a[key]))
                tracks += 1
    assert tracks == 2 * (2 + 2 + 5)  # 2 bodies x 2 tracks, the arrow's 5 tracks
    brick = next(a for a in back["animations"] if a["path"] == scene.paths["brick"])
    P, Q = (tr["values"] for tr in brick["clip"]["tracks"])
    np.testing.assert_array_equal(P.reshape(-1, 3), np.float32(traj.position[:, 0]))
    np.testing.assert_array_equal(Q.reshape(-1, 4)[:, [3, 0, 1, 2]],
                                  np.float32(traj.orientation[:, 0]))
    np.testing.assert_array_equal(brick["clip"]["tracks"][0]["times"], np.float32(traj.t))
    # Each times array is one msgpack ext 8 (0xc7, its length, type 0x17): 4 bytes a number.
    assert 4 * traj.t.size < 256
    assert data.count(bytes([0xC7, 4 * traj.t.size, 0x17])) == 9
    old = unpack(pack(cmd, typed_arrays=False))
    a0 = old["animations"][0]["clip"]["tracks"][0]
    assert a0["values"] == cmd["animations"][0]["clip"]["tracks"][0]["values"].tolist()
    assert len(pack(cmd, typed_arrays=False)) > 1.8 * len(data)
    with pytest.raises(TypeError, match="int64"):
        pack({"type": "x", "values": np.arange(3)})


def test_the_package_keeps_its_public_names():
    """mbody.present.animate is a package of parts; its names and mbody.animate stay."""
    import mbody.present.animate as pkg

    for name in ("animate", "build_scene", "page_html", "write_page", "LiveViewer",
                 "resolve", "Scene", "ROOT", "HOST", "pack", "unpack"):
        assert name in pkg.__all__ and getattr(pkg, name) is not None, name
    assert callable(pkg.animate) and mbody.animate is pkg.animate
    assert pkg.build_scene.__module__ == "mbody.present.animate.scene"


def test_cylinder_axis_is_body_z(spinner):
    """meshcat's cylinder runs along its local y; the shape node must turn y onto z."""
    model, traj = spinner
    scene = build_scene(traj, model)
    cmd = next(c for c in scene.commands if c["type"] == "set_transform"
               and c["path"] == scene.paths["rotor"] + "/shape")
    T = np.reshape(cmd["matrix"], (4, 4)).T  # meshcat sends column-major
    np.testing.assert_allclose(T[:3, :3] @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    mesh = next(c for c in scene.commands if c["type"] == "set_object"
                and c["path"] == scene.paths["rotor"] + "/shape/mesh")
    geom = mesh["object"]["geometries"][0]
    assert (geom["height"], geom["radiusTop"]) == (0.3, 0.1)


def test_inertia_box_when_no_shape():
    """No shape: the uniform box with the body's inertia, along its principal axes."""
    model = mbody.load(ROOT / "models" / "seed_example_2.yaml")  # I = (2, 3, 4), m = 1
    traj = Trajectory(np.array([0.0, 1.0]), np.zeros((2, 1, 3)), np.zeros((2, 1, 3)),
                      np.tile([1.0, 0, 0, 0], (2, 1, 1)), np.zeros((2, 1, 3)), ("body",), 3)
    scene = build_scene(traj, model)
    mesh = next(c for c in scene.commands if c["type"] == "set_object"
                and c["path"].endswith("/shape/mesh"))
    a, b, c = mesh["object"]["geometries"][0]["width"], \
        mesh["object"]["geometries"][0]["height"], mesh["object"]["geometries"][0]["depth"]
    # I1 = m (b² + c²)/12 etc. for the drawn box
    np.testing.assert_allclose([(b * b + c * c) / 12, (a * a + c * c) / 12,
                                (a * a + b * b) / 12], [2, 3, 4], rtol=1e-12)


def test_force_arrow_tracks_follow_the_body(spinner):
    model, traj = spinner
    scene = build_scene(traj, model, forces=True)
    tracks = _animation(scene, scene.load_paths["push"])
    P = np.reshape(tracks[".position"]["values"], (-1, 3))
    Q = np.reshape(tracks[".quaternion"]["values"], (-1, 4))[:, [3, 0, 1, 2]]
    for k in (0, 17, 60):
        R = rot(spin_q(traj.t[k]))
        np.testing.assert_allclose(P[k], traj.position[k, 0] + R @ [0.2, 0, 0], atol=1e-12)
        np.testing.assert_allclose(rot(Q[k]) @ [0, 1, 0], R @ [0, 0, 1], atol=1e-12)


def test_reaction_arrows_show_the_solved_pin_force(tmp_path):
    """A simulated pendulum: the pin's arrow sits at the pin, points along the stored
    reaction R = (O.Fx, O.Fy) on the child at every frame, and its shaft length is
    proportional to |R|; a run without reactions is refused with a clear error."""
    model = mbody.load("models/pendulum.yaml")
    traj = mbody.simulate(model, t_end=0.5, fps=20)
    scene = build_scene(traj, model, reactions=True)
    path = scene.load_paths["O (force)"]
    tracks = _animation(scene, path)
    P = np.reshape(tracks[".position"]["values"], (-1, 3))
    Q = np.reshape(tracks[".quaternion"]["values"], (-1, 4))[:, [3, 0, 1, 2]]
    shaft = np.reshape(_animation(scene, path + "/shaft")[".scale"]["values"], (-1, 3))[:, 1]
    R = traj.reactions[:, [traj.reaction_labels.index("O.Fx"),
                           traj.reaction_labels.index("O.Fy")]]
    R3 = np.column_stack((R, np.zeros(len(R))))
    np.testing.assert_allclose(P, 0.0, atol=1e-9)  # the pin is at the origin
    for k in range(len(traj.t)):
        np.testing.assert_allclose(rot(Q[k]) @ [0, 1, 0], R3[k] / np.linalg.norm(R3[k]),
                                   atol=1e-9)
    # shaft = c |R| − head (a fixed head): its changes are proportional to |R|'s.
    mag = np.linalg.norm(R, axis=1)
    c = (shaft[-1] - shaft[0]) / (mag[-1] - mag[0])
    np.testing.assert_allclose(np.diff(shaft), c * np.diff(mag), rtol=1e-6, atol=1e-12)
    assert c > 0
    mesh = [c for c in scene.commands if c.get("type") == "set_object"
            and c["path"].endswith(path.strip("/") + "/shaft/geom/mesh")]
    assert mesh and mesh[0]["object"]["materials"][0]["color"] == 0xE8202A
    with pytest.raises(MbodyError, match="no joint reactions"):
        build_scene(mbody.simulate(mbody.load("models/seed_example_2.yaml"), t_end=0.1),
                    mbody.load("models/seed_example_2.yaml"), reactions=True)


def test_gravity_is_drawn_at_each_mass_centre_with_forces(spinner):
    """--forces draws m g at every G, pointing along g, as long as the largest applied
    force (the same scale and colour); no gravity, no gravity arrows."""
    model = mbody.load(ROOT / "models" / "double_pendulum.yaml")
    traj = double_pendulum_motion()
    scene = build_scene(traj, model, forces=True)
    assert sorted(scene.load_paths) == ["gravity (lower)", "gravity (upper)"]
    extent = 2.0 / np.reshape(next(c for c in scene.commands if c["path"] == "/meshcat/mbody"
                                   and c["type"] == "set_transform")["matrix"], (4, 4))[0, 0]
    for i, name in enumerate(("upper", "lower")):
        path = scene.load_paths[f"gravity ({name})"]
        tracks = _animation(scene, path)
        P = np.reshape(tracks[".position"]["values"], (-1, 3))
        Q = np.reshape(tracks[".quaternion"]["values"], (-1, 4))[:, [3, 0, 1, 2]]
        np.testing.assert_allclose(P[:, :2], traj.position[:, i], atol=1e-12)
        for k in (0, 20, 40):
            np.testing.assert_allclose(rot(Q[k]) @ [0, 1, 0], [0, -1, 0], atol=1e-12)
        head = np.reshape(_animation(scene, path + "/head")[".position"]["values"], (-1, 3))
        # equal masses: both at the full length 0.35 extent (shaft + head 0.06 extent)
        np.testing.assert_allclose(head[:, 1], 0.29 * extent, rtol=1e-12)
        mesh = [c for c in scene.commands if c.get("type") == "set_object"
                and c["path"].endswith(path.strip("/") + "/shaft/geom/mesh")]
        assert mesh[0]["object"]["materials"][0]["color"] == 0xFFD400
    assert "gravity (upper)" not in build_scene(traj, model).load_paths
    spin_model, spin_traj = spinner  # no gravity in the file: only the push
    assert list(build_scene(spin_traj, spin_model, forces=True).load_paths) == ["push"]


def test_camera_fit_puts_the_box_at_fill_with_equal_margins():
    """Projecting the box's corners from the fitted camera: every corner is inside FILL
    of the view, the binding dimension touches FILL on both sides, for any aspect."""
    rng = np.random.default_rng(3)
    lo, hi = -rng.uniform(0.2, 1.0, 3), rng.uniform(0.2, 1.0, 3)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])
    d = np.array([1, 0.8, 0.65]) / np.linalg.norm([1, 0.8, 0.65])
    fit = camera_fit(corners, d)
    tan = math.tan(math.radians(37.5))
    for aspect in (4 / 3, 800 / 457, 0.6):
        eye, target = fit.position(aspect), fit.target(aspect)
        back = (eye - target) / np.linalg.norm(eye - target)
        np.testing.assert_allclose(back, d, atol=1e-12)  # it looks along the direction
        right = np.cross([0, 0, 1], back)
        right /= np.linalg.norm(right)
        up = np.cross(back, right)
        rel = corners - eye
        depth = -rel @ back
        ndc = np.column_stack([rel @ right / (depth * aspect * tan), rel @ up / (depth * tan)])
        lo_n, hi_n = ndc.min(axis=0), ndc.max(axis=0)
        assert np.all(hi_n <= FILL + 1e-9) and np.all(lo_n >= -FILL - 1e-9)
        bind = int(np.argmax(hi_n - lo_n))
        np.testing.assert_allclose([lo_n[bind], hi_n[bind]], [-FILL, FILL], atol=1e-9)
        np.testing.assert_allclose(lo_n, -hi_n, atol=1e-9)  # centred in both


def test_a_push_into_the_body_ends_at_its_point(spinner):
    """Thrust at the bottom face pointing up: the arrow's tip touches the point."""
    model = mbody.loads(SPIN_YAML.replace("at: [0.2, 0, 0]", "at: [0, 0, -0.05]"))
    _, traj = spinner
    scene = build_scene(traj, model, forces=True)
    tracks = _animation(scene, scene.load_paths["push"])
    P = np.reshape(tracks[".position"]["values"], (-1, 3))
    head = _animation(scene, scene.load_paths["push"] + "/head")[".position"]["values"]
    shaft = np.reshape(head, (-1, 3))[:, 1]
    extent = 2.0 / np.reshape(next(c for c in scene.commands if c["path"] == "/meshcat/mbody"
                                   and c["type"] == "set_transform")["matrix"], (4, 4))[0, 0]
    length = shaft + 0.06 * extent  # shaft plus head
    for k in (0, 33):
        R = rot(spin_q(traj.t[k]))
        tip = P[k] + length[k] * (R @ [0, 0, 1])
        np.testing.assert_allclose(tip, traj.position[k, 0] + R @ [0, 0, -0.05], atol=1e-12)


def test_page_is_self_contained(spinner, tmp_path):
    model, traj = spinner
    out = write_page(traj, tmp_path / "run.html", model=model, forces=True)
    text = out.read_text(encoding="utf-8")
    links = set(re.findall(r"https?://[^\s\"'<>)]*", text))
    assert links == {"http://www.w3.org/1999/xhtml"}
    markup = re.sub(r"<script>.*?</script>", "", text, flags=re.S)  # the HTML outside scripts
    assert not re.search(r"\b(src|href)\s*=", markup) and "<link" not in markup
    assert "MeshCat.Viewer" in text and "<title>mbody: spinner</title>" in text
    assert [p.name for p in tmp_path.iterdir()] == ["run.html"]  # no temp file left


def test_bad_colour_and_body(spinner):
    model, traj = spinner
    with pytest.raises(MbodyError, match="'blurple' is not a colour"):  # refused as read
        build_scene(traj, mbody.loads(SPIN_YAML.replace("color: red", "color: blurple")))
    with pytest.raises(MbodyError, match="unknown body 'brik'.*did you mean 'brick'"):
        build_scene(traj, model, bodies=["brik"])
    other = mbody.loads(SPIN_YAML.replace("name: rotor", "name: wheel"))
    with pytest.raises(MbodyError, match="unknown body 'rotor'.*'spinner' has only"):
        build_scene(traj, other)
    with pytest.raises(MbodyError, match="give the model"):
        mbody.animate(traj, "/tmp/never.html")


# -- the page in a real browser -------------------------------------------------------------


@needs_browser
def test_browser_plays_the_spatial_motion(spinner, tmp_path):
    model, traj = spinner
    page = write_page(traj, tmp_path / "spin.html", model=model, forces=True)
    paths = build_scene(traj, model, forces=True)
    b, arrow = paths.paths["brick"], paths.load_paths["push"]
    t1, t2 = 1.2345, 0.31  # between keyframes: linear position and slerp are exact here
    r = chromium.probe(page, f"""
      var out = {{duration: viewer.animator.duration}};
      at({t1}); out.b1 = local("{b}"); out.a1 = local("{arrow}");
      out.red1 = dominant(0, 3, 90); out.s1 = screen("{b}");
      at({t2}); out.b2 = local("{b}"); out.red2 = dominant(0, 3, 90); out.s2 = screen("{b}");
      out.green = dominant(1, 3, 90); out.sg = screen("{paths.paths['rotor']}");
      return out;""")
    assert r["duration"] == pytest.approx(2.0)
    for key, t in (("b1", t1), ("b2", t2)):
        np.testing.assert_allclose(r[key]["p"], [V * t, 0, 0], atol=1e-6)
        q = np.array(r[key]["q"])[[3, 0, 1, 2]]
        assert min(np.abs(q - spin_q(t)).max(), np.abs(q + spin_q(t)).max()) < 1e-6
    # The arrow's foot is on the spinning body, 0.2 m from G; between keyframes it moves
    # along the chord, at most the sagitta 0.2 (1 − cos(ω Δt / 2)) from the arc.
    R = rot(spin_q(t1))
    sag = 0.2 * (1 - math.cos(W * (traj.t[1] - traj.t[0]) / 2))
    np.testing.assert_allclose(r["a1"]["p"], [V * t1, 0, 0] + R @ [0.2, 0, 0], atol=sag)
    # The red brick is on the canvas where its mass centre projects, at both times.
    for red, s in ((r["red1"], r["s1"]), (r["red2"], r["s2"])):
        assert red["n"] > 400, red
        assert math.dist(red["c"], s) < 0.05 * red["w"], (red, s)
    moved = np.subtract(r["red1"]["c"], r["red2"]["c"])
    np.testing.assert_allclose(moved, np.subtract(r["s1"], r["s2"]), atol=0.03 * 800)
    assert r["green"]["n"] > 300 and math.dist(r["green"]["c"], r["sg"]) < 40


@needs_browser
def test_browser_planar_is_upright_in_xy(pendulum, tmp_path):
    model, traj = pendulum
    page = write_page(traj, tmp_path / "pend.html", model=model)
    rod = build_scene(traj, model).paths["rod"]
    k = int(np.searchsorted(traj.t, 0.3))  # a keyframe where θ > 0
    r = chromium.probe(page, f"""
      at({traj.t[k]}); var o = local("{rod}");
      return {{rod: o, s: screen("{rod}"), origin: screen("/meshcat/mbody/origin"),
               orange: dominant(0, 1.6, 120)}};""")
    thk = PEND_A * math.cos(PEND_W * traj.t[k])
    np.testing.assert_allclose(r["rod"]["p"], [PEND_L * math.sin(thk),
                                               -PEND_L * math.cos(thk), 0], atol=1e-6)
    np.testing.assert_allclose(r["rod"]["q"], [0, 0, math.sin(thk / 2), math.cos(thk / 2)],
                               atol=1e-6)
    # Viewed from +z with y up: the hanging rod's centre is below and (θ > 0) right of
    # the pivot, and its pixels are around that point.
    assert thk > 0.3
    assert r["s"][1] > r["origin"][1] + 50 and r["s"][0] > r["origin"][0] + 5
    assert r["orange"]["n"] > 400 and math.dist(r["orange"]["c"], r["s"]) < 30


COVER = """
  viewer.scene.traverse(function (o) {
    if (o.type === "LineSegments" || o.type === "Line") o.visible = false; });
  node("/Grid").visible = false; viewer.set_property(["Background"], "visible", false);
  var gl = viewer.renderer.getContext(), w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  var px = new Uint8Array(4 * w * h), hit = new Uint8Array(w * h), N = FRAMES;
  for (var k = 0; k < N; k++) {  // every keyframe
    at(viewer.animator.duration * k / (N - 1));
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    for (var i = 0; i < w * h; i++)
      if (px[4*i+3] > 0 && (px[4*i] | px[4*i+1] | px[4*i+2]) > 8) hit[i] = 1;
  }
  var x0 = w, x1 = -1, y0 = h, y1 = -1;
  for (var i = 0; i < w * h; i++) if (hit[i]) { var x = i % w, y = Math.floor(i / w);
    x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); }
  return {w: w, h: h, box: [x0, y0, x1, y1]};
"""


def double_pendulum_motion():
    """Two 0.5 m rods of models/double_pendulum.yaml swinging (a kinematic motion)."""
    t = np.linspace(0.0, 2.0, 41)
    th1, th2 = 0.5 * np.cos(3 * t), 1.2 * np.sin(4 * t)
    A = 0.5 * np.stack([np.sin(th1), -np.cos(th1)], -1)
    pos = np.stack([A / 2, A + 0.25 * np.stack([np.sin(th2), -np.cos(th2)], -1)], 1)
    return Trajectory(t, pos, np.zeros_like(pos), np.stack([th1, th2], -1),
                      np.zeros((len(t), 2)), ("upper", "lower"), 2,
                      model_name="double-pendulum")


@needs_browser
@pytest.mark.parametrize("forces", [False, True])
def test_browser_the_motion_fills_the_view(forces, tmp_path):
    """The union of the model's pixels over the motion (grid, background and axes hidden)
    spans FILL = 85 % of the view's height (the binding dimension for a hanging double
    pendulum), centred, nothing cut off; gravity's arrows are kept in view too. Before
    the fit it spanned 29 % of the height."""
    model = mbody.load(ROOT / "models" / "double_pendulum.yaml")
    page = write_page(double_pendulum_motion(), tmp_path / "dp.html", model=model,
                      forces=forces)
    r = chromium.probe(page, COVER.replace("FRAMES", "41"), budget_ms=8000)
    x0, y0, x1, y1 = r["box"]
    w, h = r["w"], r["h"]
    assert (x1 - x0 + 1) / w < FILL < (y1 - y0 + 2) / h < FILL + 0.02, r
    assert abs((y0 + y1) / 2 - h / 2) < 0.01 * h and abs((x0 + x1) / 2 - w / 2) < 0.1 * w, r
    assert x0 > 0.02 * w and y0 > 0.02 * h and x1 < 0.98 * w and y1 < 0.98 * h, r


# -- the live viewer ---------------------------------------------------------------------


def _listening(pid):
    return [c.laddr for c in psutil.Process(pid).net_connections(kind="inet")
            if c.status == psutil.CONN_LISTEN]


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize("started_ignoring", [False, True])
def test_live_cli_binds_loopback_and_stops_on_ctrl_c(spinner, tmp_path, started_ignoring):
    """The live viewer listens on 127.0.0.1 only and Ctrl-C stops it cleanly, also when the
    command was started with SIGINT ignored (a shell's background job, nohup: Python then
    keeps ignoring it unless the command asks for it)."""
    model, traj = spinner
    run = traj.save(tmp_path / "run.npz")
    err = open(tmp_path / "stderr.txt", "w+")  # noqa: SIM115 - a file, not a pipe to fill up
    proc = subprocess.Popen([sys.executable, "-X", "faulthandler", "-m", "mbody.cli", "animate",
                             str(run), "--live"],
                            stdout=subprocess.PIPE, stderr=err, text=True, cwd=tmp_path,
                            preexec_fn=_ignore_sigint if started_ignoring else None)
    server = None
    try:
        line = proc.stdout.readline()
        assert "127.0.0.1 only" in line, line + (tmp_path / "stderr.txt").read_text()
        url = re.search(r"http://127\.0\.0\.1:(\d+)/static/", line)
        assert url, line
        (server,) = psutil.Process(proc.pid).children()
        addrs = _listening(server.pid)
        assert len(addrs) == 2  # the websocket/HTTP port and the ZMQ port
        assert {a.ip for a in addrs} == {"127.0.0.1"}
        assert int(url.group(1)) in {a.port for a in addrs}
        proc.send_signal(signal.SIGINT)
        try:
            code = proc.wait(15)
        except subprocess.TimeoutExpired:  # say where it hung: its stack, then its stderr
            proc.send_signal(signal.SIGABRT)  # faulthandler (-X) prints the stacks
            proc.wait(10)
            raise AssertionError("the viewer did not stop within 15 s of Ctrl-C:\n"
                                 + (tmp_path / "stderr.txt").read_text()[-4000:]) from None
        assert code == 0
        assert "viewer stopped" in (tmp_path / "stderr.txt").read_text()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdout.close()
        err.close()
    assert server is not None and not server.is_running()
    assert not psutil.Process().children(recursive=True)


def test_live_server_dies_with_a_killed_parent(tmp_path):
    """A SIGKILLed mbody cannot clean up; its server notices and exits by itself."""
    code = ("from mbody.present.animate import LiveViewer; v = LiveViewer(); "
            "print(v.pid, flush=True);"
            "import time; time.sleep(60)")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    server = psutil.Process(int(proc.stdout.readline()))
    proc.kill()
    proc.wait()
    proc.stdout.close()
    server.wait(10)  # psutil.TimeoutExpired if it outlives its parent
    assert not server.is_running()


@needs_browser
def test_live_viewer_shows_the_scene_to_a_browser(spinner, tmp_path):
    """A browser that connects after the scene was pushed is sent all of it."""
    from PIL import Image

    model, traj = spinner
    with LiveViewer() as viewer:
        pid = viewer.pid
        viewer.show(build_scene(traj, model))
        png = chromium.screenshot(viewer.url, tmp_path / "live.png")
        assert viewer.wait_for_browser(0.5) is False  # the browser has gone again
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    assert ((r > 90) & (r > 3 * g) & (r > 3 * b)).sum() > 300  # the red brick
    assert ((g > 90) & (g > 3 * r) & (g > 3 * b)).sum() > 200  # the green rotor
    assert not psutil.pid_exists(pid)


# -- command line --------------------------------------------------------------------------


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "mbody.cli", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=120)


def test_cli_writes_a_page_from_a_run_and_from_a_model(spinner, tmp_path):
    model, traj = spinner
    run = traj.save(tmp_path / "run.npz")
    p = _cli("animate", run, "-o", "out/a.html", "--forces", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "wrote out/a.html" in p.stdout and "2 bodies, 61 frames, 2 s" in p.stdout
    assert (tmp_path / "out" / "a.html").stat().st_size > 800_000  # the viewer is inlined
    p = _cli("animate", ROOT / "models" / "seed_example_2.yaml", "--t-end", 1, "--fps", 20,
             cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "wrote seed_example_2.html" in p.stdout and "21 frames, 1 s" in p.stdout


@pytest.mark.parametrize("args, message", [
    (["missing.npz"], "missing.npz: no such file"),
    (["wrong.npz"], "not an mbody trajectory"),
    (["run.npz", "--body", "brik"], "unknown body 'brik'"),
    (["run.npz", "--model", "other.yaml"], "unknown body 'rotor'"),
    (["run.npz", "--hold", "3"], "--hold only applies with --live"),
    (["run.npz", "--fps", "0"], "argument --fps: expected a number of frames per second "
     "above 0 up to 1000, got '0'"),
])
def test_cli_bad_input_exits_2(spinner, tmp_path, args, message):
    model, traj = spinner
    traj.save(tmp_path / "run.npz")
    np.savez(tmp_path / "wrong.npz", a=np.ones(3))
    (tmp_path / "other.yaml").write_text(SPIN_YAML.replace("name: rotor", "name: wheel"))
    p = _cli("animate", *args, cwd=tmp_path)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert message in p.stderr and "Traceback" not in p.stderr
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".html")]


def test_api_animate_model_and_trajectory(spinner, tmp_path):
    model, traj = spinner
    out = mbody.animate(traj, tmp_path / "a.html", model=model, bodies=["rotor"])
    assert out == tmp_path / "a.html" and out.stat().st_size > 800_000
    scene = build_scene(traj, model, bodies=["rotor"])
    assert list(scene.paths) == ["rotor"] and scene.title == "mbody: spinner"
    assert page_html(scene).count("<script>") == 2


def test_help_states_the_simulation_defaults_and_gravity():
    """`animate --help` gives --t-end's and --fps's defaults for a model, which are
    mbody.simulate's, and says --forces draws gravity."""
    import inspect

    from mbody.cli import animate as cli_animate

    sig = inspect.signature(mbody.simulate).parameters
    assert (sig["t_end"].default, sig["fps"].default) == (cli_animate.T_END, cli_animate.FPS)
    p = subprocess.run([sys.executable, "-m", "mbody.cli", "animate", "--help"],
                       capture_output=True, text=True, timeout=60)
    text = " ".join(p.stdout.split())
    assert f"when SOURCE is a model (default {sig['t_end'].default:g};" in text
    assert f"(default {sig['fps'].default:g};" in text
    assert "gravity (m g at each mass centre)" in text


def test_cli_says_when_the_frames_alias_a_spin_and_refuses_a_run_files_rate(tmp_path):
    """Review R7-16/17: the flywheel reaches 400 rad/s (63.7 rev/s), more than half a turn
    a frame at 60 fps; `simulate` warned of it, `animate` of the same run did not, and a
    run file's --fps was ignored silently."""
    flywheel = ROOT / "models" / "practice_2_flywheel.yaml"
    p = _cli("animate", flywheel, "-o", "f.html", cwd=tmp_path)
    assert p.returncode == 0 and "spin faster than 60 fps can show" in p.stderr, p.stderr
    p = _cli("animate", flywheel, "--fps", "130", "--t-end", "2", "-o", "g.html", cwd=tmp_path)
    assert p.returncode == 0 and "spin faster" not in p.stderr  # 130 fps shows 63.7 rev/s
    run = mbody.simulate(mbody.load(flywheel), 10.0, 60).save(tmp_path / "fw.npz")
    p = _cli("animate", run, "-o", "h.html", cwd=tmp_path)
    assert p.returncode == 0 and "spin faster" in p.stderr and "simulate the model again" \
        in p.stderr
    for flag in ("--fps", "--t-end"):
        p = _cli("animate", run, flag, "2", "-o", "i.html", cwd=tmp_path)
        assert p.returncode == 2 and f"{flag} does not apply to a run file" in p.stderr
        assert not (tmp_path / "i.html").exists()
