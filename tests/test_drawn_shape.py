"""The box a body without a shape is drawn as (`mbody.model.drawn`): a bar through its
joint and load points when it has two, else its inertia box; the same in the free-body
diagram (its outline and joint points), the animation (meshcat's box and its transform),
and the MJCF export's geom (the inertia box, read back as the body's shape)."""

from __future__ import annotations

import math
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest

import mbody
from mbody.io.interop.mjcf_write import to_mjcf
from mbody.model.drawn import BAR_WIDTH, DrawnBox, body_box, drawn_box, load_points
from mbody.present.animate.scene import build_scene
from mbody.present.draw import fbd_scene
from mbody.present.draw.scene import Disc, Poly
from mbody.simulate.trajectory import Trajectory

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(__file__).resolve().parent / "data"

SLIDER_CRANK = (DATA / "review_slider_crank.yaml").read_text(encoding="utf-8")
"""The course review's model (R4, F12): a 0.3 m rod (I_G = 0.015, so its inertia square
is 0.21 m wide) pinned at ±0.15 m, which fell outside the square."""


def inside(box: DrawnBox, points: np.ndarray, d: int) -> np.ndarray:
    """How far each point lies inside the box along each of its axes (>= 0: inside)."""
    local = (np.asarray(points, dtype=float) - box.centre) @ box.axes
    return box.size / 2 - np.abs(local[:, :d])


def test_the_review_rod_is_a_bar_through_its_pins():
    model = mbody.loads(SLIDER_CRANK)
    i = model.body_names.index("rod")
    points = load_points(model, i)
    np.testing.assert_allclose(points[:, :2], [[-0.15, 0.0], [0.15, 0.0]])
    box = body_box(model, i)
    assert box.bar
    # along the pins' line: their distance and half a width past each; a tenth as wide
    np.testing.assert_allclose(box.size, [0.3 * (1 + BAR_WIDTH), 0.3 * BAR_WIDTH],
                               rtol=1e-12)
    np.testing.assert_allclose(np.abs(box.axes[:, 0]), [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(box.centre, 0.0, atol=1e-15)
    assert np.all(inside(box, points, 2) > 0)
    # the old square, the same I_G: a = sqrt(6 I / m) = 0.212 m, the pins outside it
    assert math.sqrt(6 * 0.015 / 2) / 2 < 0.15


def test_the_diagram_outline_holds_every_joint_point_it_draws():
    """In the picture's scene: the rod's outline is the bar, and every joint point drawn
    (a `joint-point` disc) is inside it; the piston (all its points at G) keeps the
    square with its I_G."""
    asm = mbody.assemble(mbody.loads(SLIDER_CRANK))
    for name, bar in (("rod", True), ("crank", True), ("piston", False)):
        items = next(p for p in fbd_scene(asm.bodies[name]).panels if p.gid == "drawing").items
        hull = next(it for it in items if isinstance(it, Poly) and it.gid == "body-outline").xy
        pins = [it.center for it in items if isinstance(it, Disc) and it.gid == "joint-point"]
        edges = np.roll(hull, -1, axis=0) - hull
        keep = np.linalg.norm(edges, axis=1) > 1e-12  # a vertex repeated by the hull
        hull, edges = hull[keep], edges[keep]

        def cross(a, b):
            return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]

        # a convex polygon: a point is inside when it is on the same side of every edge
        turn = np.sign(cross(edges[0], edges[1]))
        for p in pins:
            assert np.all(turn * cross(edges, p - hull) > 0), (name, p)
        side = np.linalg.norm(edges, axis=1)
        if bar:
            assert side.max() / side.min() == pytest.approx(1 / BAR_WIDTH + 1, rel=1e-6)
        else:
            assert not pins  # both joints at G: drawn as points at G, not discs
            np.testing.assert_allclose(side, math.sqrt(6 * 0.001 / 0.5), rtol=1e-9)


def test_a_bar_reaches_past_g_and_every_point_off_its_line():
    """A bell crank: three pins not on one line and G off the line of the farthest two.
    The bar lies along that line, and is wide enough for the third pin and G."""
    P = np.array([[0.2, 0.0, 0.0], [-0.1, 0.0, 0.0], [0.0, 0.12, 0.0]])
    box = drawn_box(2, 1.0, np.diag([0.0, 0.0, 0.01]), P - [0.0, 0.05, 0.0])
    width = BAR_WIDTH * 0.3
    assert box.bar
    np.testing.assert_allclose(box.size, [0.3 + width, 0.12 + width], rtol=1e-12)
    pts = np.vstack((P - [0.0, 0.05, 0.0], np.zeros(3)))
    np.testing.assert_allclose(inside(box, pts, 2).min(), width / 2, rtol=1e-12)


def test_spatial_bar_and_fewer_points_keep_the_inertia_box():
    """A spatial rod with ball joints at its ends and a load point beside it: a bar along
    the ends, across toward the load point; a body with one point keeps its inertia box."""
    P = np.array([[0.0, 0.0, -0.25], [0.0, 0.0, 0.25], [0.03, 0.0, 0.1]])
    J = np.diag([0.02, 0.02, 0.001])
    box = drawn_box(3, 1.0, J, P)
    assert box.bar and np.allclose(box.axes.T @ box.axes, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(np.abs(box.axes[:, 0]), [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(np.abs(box.axes[:, 1]), [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(box.size, [0.55, 0.03 + 0.05, 0.05], rtol=1e-12)
    assert np.all(inside(box, np.vstack((P, np.zeros(3))), 3) >= 0.025 - 1e-15)

    one = drawn_box(3, 1.0, J, P[:1])
    assert not one.bar
    a, b, c = one.size  # the uniform box with those moments: I1 = m (b² + c²) / 12 ...
    np.testing.assert_allclose(np.sort([(b * b + c * c) / 12, (a * a + c * c) / 12,
                                        (a * a + b * b) / 12]), [0.001, 0.02, 0.02])
    same = drawn_box(3, 1.0, J, np.zeros((3, 3)))  # loads at G alone: one point
    assert not same.bar


def test_the_shipped_spring_loaded_arm_rod_is_a_bar_from_g_to_its_pin():
    model = mbody.load(ROOT / "models" / "spring_loaded_arm.yaml")
    box = body_box(model, 0)
    assert box.bar  # the spring at G and the pin 0.5 m from it
    np.testing.assert_allclose(box.size, [0.55, 0.05], rtol=1e-12)
    np.testing.assert_allclose(box.centre, [0, 0.25, 0], atol=1e-12)


def test_the_animation_draws_the_same_bar():
    """meshcat's box for the shapeless rod: the bar's edges (with the planar thickness,
    a fifth of its width) and its transform from the body's frame: the bar's axes and
    centre."""
    model = mbody.load(ROOT / "models" / "spring_loaded_arm.yaml")
    traj = Trajectory(np.array([0.0, 1.0]), np.zeros((2, 1, 2)), np.zeros((2, 1, 2)),
                      np.zeros((2, 1)), np.zeros((2, 1)), ("rod",), 2)
    scene = build_scene(traj, model)
    path = scene.paths["rod"]
    mesh = next(c for c in scene.commands if c["type"] == "set_object"
                and c["path"] == path + "/shape/mesh")
    geom = mesh["object"]["geometries"][0]
    box = body_box(model, 0)
    np.testing.assert_allclose([geom["width"], geom["height"], geom["depth"]],
                               [*box.size, 0.2 * box.size.min()], rtol=1e-12)
    T = np.reshape(next(c for c in scene.commands if c["type"] == "set_transform"
                        and c["path"] == path + "/shape")["matrix"], (4, 4)).T
    np.testing.assert_allclose(T[:3, :3], box.axes, atol=1e-15)
    np.testing.assert_allclose(T[:3, 3], [0, 0.25, 0], atol=1e-12)


def test_the_mjcf_geom_stays_the_inertia_box():
    """Read back, a geom is the body's shape, centred at G: the export keeps the box with
    the body's inertia (documented in mbody.model.drawn)."""
    root = ElementTree.fromstring(to_mjcf(mbody.loads(SLIDER_CRANK)))
    rod = next(b for b in root.iter("body") if b.get("name") == "rod")
    geom = rod.find("geom")
    assert geom is not None and geom.get("pos") is None
    side = math.sqrt(6 * 0.015 / 2)
    np.testing.assert_allclose([float(x) for x in geom.get("size", "").split()],
                               [side / 2, side / 2, side / 10], rtol=1e-12)
