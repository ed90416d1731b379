"""The two joint types added through the registry alone (mbody/joint_types/slot.py and
helical.py), each against an independent solution: the pin in a slot against a Lagrange
solution derived by hand; the helical joint against a screw jack's closed form and
against Pinocchio's helical joint (JointModelHelicalUnaligned) on a two-link chain."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

import mbody
from mbody.util.spatial import quat_to_matrix

G0 = 9.81


def euler_to_matrix(angles: np.ndarray) -> np.ndarray:
    """R = Rz(a) Ry(b) Rx(c): a turned frame, written out here."""
    a, b, c = angles
    Rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    Ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    Rx = np.array([[1, 0, 0], [0, math.cos(c), -math.sin(c)], [0, math.sin(c), math.cos(c)]])
    return Rz @ Ry @ Rx


def slot_pendulum(s: float, theta: float, sdot: float, thetadot: float,
                  m: float = 2.0, inertia: float = 0.15, a: float = 0.4) -> mbody.Model:
    """A rod whose pin, a body point (a, 0) from its mass centre, slides in a horizontal
    slot (world x) through the origin, the rod turning freely; gravity −y. Coordinates:
    s, the pin's position along the slot; θ, the rod's angle."""
    c, sn = math.cos(theta), math.sin(theta)
    x = [s - a * c, -a * sn]
    v = [sdot + a * sn * thetadot, -a * c * thetadot]
    doc = {"model": "slot-pendulum", "dimension": 2, "gravity": [0, -G0],
           "bodies": [{"name": "rod", "mass": m, "inertia": inertia, "position": x,
                       "angle": theta, "velocity": v, "angular_velocity": thetadot}],
           "joints": [{"name": "S", "type": "slot", "parent": "ground", "child": "rod",
                       "at": [s, 0.0], "axis": [1, 0]}]}
    return mbody.loads(yaml.safe_dump(doc))


@pytest.mark.parametrize("state", [(0.1, 0.3, 0.0, 0.0), (-0.2, 1.1, 0.7, -2.0),
                                   (0.0, -0.6, -1.3, 3.5)])
def test_pin_in_slot_equals_its_lagrange_solution(state):
    """L = ½ m |ẋ_G|² + ½ I θ̇² + m g a sin θ with x_G = (s − a cos θ, −a sin θ) gives
    m (s̈ + a sin θ θ̈ + a cos θ θ̇²) = 0 and m a sin θ s̈ + (m a² + I) θ̈ = m g a cos θ."""
    s, th, sd, thd = state
    m, inertia, a = 2.0, 0.15, 0.4
    model = slot_pendulum(s, th, sd, thd, m, inertia, a)
    sol = mbody.assemble(model).solve()
    A = np.array([[m, m * a * math.sin(th)], [m * a * math.sin(th), m * a * a + inertia]])
    rhs = np.array([-m * a * math.cos(th) * thd ** 2, m * G0 * a * math.cos(th)])
    sdd, thdd = np.linalg.solve(A, rhs)
    want = [sdd + a * math.cos(th) * thd ** 2 + a * math.sin(th) * thdd,
            a * math.sin(th) * thd ** 2 - a * math.cos(th) * thdd, thdd]
    np.testing.assert_allclose(sol.accelerations, want, rtol=1e-12, atol=1e-12)
    # the slot holds the pin vertically: the only vertical force besides the weight
    assert sol.reactions["S.Fy"] == pytest.approx(m * (want[1] + G0), rel=1e-12, abs=1e-12)
    assert model.reactions == ["S.Fy"] and not sol.warnings


@pytest.mark.parametrize("pitch", [0.005, -0.012])
def test_screw_jack_closed_form(pitch):
    """A nut (mass m, J about the screw) turned by a torque τ on a fixed vertical screw,
    under gravity: z = h θ with h = pitch/2π, so (m h² + J) θ̈ = τ − m g h; the screw
    pushes the nut with Wz = m (z̈ + g) and turns it back by −h Wz."""
    m, J, tau = 50.0, 0.02, 3.0
    h = pitch / (2 * math.pi)
    doc = {"model": "jack", "dimension": 3, "gravity": [0, 0, -G0],
           "bodies": [{"name": "nut", "mass": m, "inertia": [0.03, 0.03, J],
                       "position": [0, 0, 0.2], "angular_velocity": [0, 0, 4.0],
                       "velocity": [0, 0, 4.0 * h]}],
           "loads": [{"name": "turn", "type": "torque", "body": "nut", "torque": [0, 0, tau]}],
           "joints": [{"name": "H", "type": "helical", "parent": "ground", "child": "nut",
                       "at": [0, 0, 0.2], "axis": [0, 0, 1], "pitch": pitch}]}
    sol = mbody.assemble(mbody.loads(yaml.safe_dump(doc))).solve()
    thdd = (tau - m * G0 * h) / (m * h * h + J)
    acc = dict(zip(sol.coordinates, sol.accelerations, strict=True))
    assert acc["nut.w3"] == pytest.approx(thdd, rel=1e-12)
    assert acc["nut.z"] == pytest.approx(h * thdd, rel=1e-12)
    for k in ("nut.x", "nut.y", "nut.w1", "nut.w2"):
        assert abs(acc[k]) <= 1e-12 * abs(thdd)
    assert sol.reactions["H.Wz"] == pytest.approx(m * (h * thdd + G0), rel=1e-12)


def test_helical_chain_equals_pinocchio():
    """Ground —helical (turned axis, pitch 0.07 m per turn)→ link 1 —revolute→ link 2,
    both links off their joints and turned, at a random configuration and speed: the
    mass centres' accelerations (world) and the angular accelerations (body axes) equal
    Pinocchio's forward dynamics (ABA) with its helical joint."""
    pin = pytest.importorskip("pinocchio")
    rng = np.random.default_rng(7)
    pitch = 0.07
    a1 = rng.normal(size=3)
    a1 /= np.linalg.norm(a1)
    a2 = rng.normal(size=3)
    a2 /= np.linalg.norm(a2)
    P1, P2 = np.array([0.1, -0.2, 0.3]), np.array([0.5, 0.1, 0.2])  # joints, world, q = 0
    masses = (1.3, 0.7)
    coms = (np.array([0.3, 0.05, 0.1]), np.array([0.7, 0.3, 0.1]))  # world, q = 0
    R = (euler_to_matrix(rng.uniform(-1, 1, 3)), euler_to_matrix(rng.uniform(-1, 1, 3)))
    J = (np.diag([0.02, 0.05, 0.06]), np.diag([0.01, 0.03, 0.035]))
    # Pinocchio: joint frames with world axes, at the joints' points
    pm = pin.Model()
    pm.gravity.linear = np.array([0.0, 0.0, -G0])
    j1 = pm.addJoint(0, pin.JointModelHelicalUnaligned(a1, pitch / (2 * math.pi)),
                     pin.SE3(np.eye(3), P1), "H")
    j2 = pm.addJoint(j1, pin.JointModelRevoluteUnaligned(a2), pin.SE3(np.eye(3), P2 - P1),
                     "A")
    frames = []
    for j, P, c, m, Rb, Jb in ((j1, P1, coms[0], masses[0], R[0], J[0]),
                               (j2, P2, coms[1], masses[1], R[1], J[1])):
        pm.appendBodyToJoint(j, pin.Inertia(m, c - P, Rb @ Jb @ Rb.T), pin.SE3.Identity())
        frames.append(pm.addFrame(pin.Frame(f"com{j}", j, 0, pin.SE3(Rb, c - P),
                                            pin.FrameType.OP_FRAME)))
    pd = pm.createData()
    q, v = rng.uniform(-1.5, 1.5, 2), rng.uniform(-2, 2, 2)
    qdd = pin.aba(pm, pd, q, v, np.zeros(2))
    pin.forwardKinematics(pm, pd, q, v, qdd)
    pin.updateFramePlacements(pm, pd)
    pose, twist, accel = [], [], []
    for f in frames:
        pose.append(pd.oMf[f])
        twist.append(pin.getFrameVelocity(pm, pd, f, pin.LOCAL_WORLD_ALIGNED))
        accel.append(pin.getFrameClassicalAcceleration(pm, pd, f, pin.LOCAL_WORLD_ALIGNED))
    # mbody: the same model written at q = 0, then evaluated at Pinocchio's state
    def quat(Rm):
        w = math.sqrt(max(0.0, 1.0 + np.trace(Rm))) / 2.0
        return [float(w), float((Rm[2, 1] - Rm[1, 2]) / (4 * w)),
                float((Rm[0, 2] - Rm[2, 0]) / (4 * w)), float((Rm[1, 0] - Rm[0, 1]) / (4 * w))]
    doc = {"model": "helical-chain", "dimension": 3, "gravity": [0, 0, -G0],
           "bodies": [{"name": f"l{i + 1}", "mass": masses[i],
                       "inertia": [float(x) for x in np.diag(J[i])],
                       "position": coms[i].tolist(),
                       "orientation": {"quaternion": quat(R[i])}} for i in range(2)],
           "joints": [{"name": "H", "type": "helical", "parent": "ground", "child": "l1",
                       "at": P1.tolist(), "axis": a1.tolist(), "pitch": pitch},
                      {"name": "A", "type": "revolute", "parent": "l1", "child": "l2",
                       "at": P2.tolist(), "axis": a2.tolist()}]}
    model = mbody.loads(yaml.safe_dump(doc))
    state = model.initial.replace(
        position=np.array([p.translation for p in pose]),
        quaternion=np.array([quat(p.rotation) for p in pose]),
        velocity=np.array([tw.linear for tw in twist]),
        omega=np.array([p.rotation.T @ tw.angular for p, tw in zip(pose, twist, strict=True)]))
    sol = mbody.assemble(model, state).solve()
    assert not sol.broken_joints  # Pinocchio's state keeps both joints
    got = sol.accelerations.reshape(2, 6)
    for i in range(2):
        Rw = quat_to_matrix(state.quaternion[i])
        np.testing.assert_allclose(got[i, :3], accel[i].linear, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(got[i, 3:], Rw.T @ accel[i].angular, rtol=1e-9, atol=1e-9)
