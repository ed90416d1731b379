"""Driven mechanisms: a driver's effort, the kinematics that drivers impose, and static
equilibrium, each against a solution written out here from the mechanics (closed-form
position analysis, hand-written Newton-Euler rows, the energy method, Freudenstein's
equation) or an independent engine (MuJoCo's inverse dynamics)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

import mbody
from mbody.errors import ModelError
from mbody.solve.equilibrium import find_equilibrium

ROOT = Path(__file__).resolve().parent.parent
G0 = 9.81
R, L = 0.05, 0.16  # the shipped slider-crank's crank and rod
MC, MR, MP = 0.4, 0.6, 0.5
OMEGA = 1500 * 2 * math.pi / 60


def driven_slider_crank(extra: str = "") -> mbody.Model:
    """The shipped slider-crank without its loads, the crank driven at 1500 rpm."""
    text = (ROOT / "models" / "slider_crank.yaml").read_text()
    text = "\n".join(line for line in text.splitlines()
                     if "{name: gas" not in line and "{name: load" not in line)
    text += '\ndrivers:\n  - {name: motor, joint: O, speed: "1500 rpm"}\n' + extra
    return mbody.loads(text, "driven_slider_crank.yaml")


def slider_crank_kinematics(theta: float) -> dict[str, float]:
    """Closed-form position, velocity and acceleration analysis at crank angle θ, ω
    constant: the rod's angle φ = asin(−r sin θ / l), the piston's x."""
    s, c = math.sin(theta), math.cos(theta)
    phi = math.asin(-R * s / L)
    cp = math.cos(phi)
    phid = -R * c * OMEGA / (L * cp)
    phidd = (R * s * OMEGA ** 2 + L * math.sin(phi) * phid ** 2) / (L * cp)
    xb = R * c + L * cp
    xbd = -R * s * OMEGA - L * math.sin(phi) * phid
    xbdd = (-R * c * OMEGA ** 2 - L * cp * phid ** 2 - L * math.sin(phi) * phidd)
    return {"phi": phi, "phid": phid, "phidd": phidd, "xb": xb, "xbd": xbd, "xbdd": xbdd}


def hand_newton_euler(theta: float) -> dict[str, float]:
    """The 9 reaction and effort values at crank angle θ from the 9 Newton-Euler rows
    of the three bodies, written out here (uniform bars, mass centres at mid-length)."""
    k = slider_crank_kinematics(theta)
    s, c = math.sin(theta), math.cos(theta)
    phi = k["phi"]
    A = np.array([R * c, R * s])
    B = np.array([k["xb"], 0.0])
    Gc = A / 2
    Gr = (A + B) / 2
    # mass-centre accelerations (crank: centripetal only, ω constant)
    a_c = -OMEGA ** 2 * Gc
    a_A = -OMEGA ** 2 * A
    a_B = np.array([k["xbdd"], 0.0])
    a_r = (a_A + a_B) / 2
    I_c = MC * (0.05 ** 2 + 0.03 ** 2) / 12
    I_r = MR * (0.16 ** 2 + 0.02 ** 2) / 12
    # unknowns: O (2), A (2), B (2), P.Fy, P.Mz, motor torque; +R on the child
    rows, rhs = [], []
    def cross(r, f):  # z of r × f for a force f acting at r (relative to G)
        return r[0] * f[1] - r[1] * f[0]
    e = np.eye(2)
    # crank: O on it (+), A on it (−: the crank is A's parent), motor (+), gravity
    for i in range(2):
        row = np.zeros(9)
        row[i], row[2 + i] = 1.0, -1.0
        rows.append(row), rhs.append(MC * a_c[i] - MC * (-G0 if i == 1 else 0.0))
    row = np.zeros(9)
    for i in range(2):
        row[i] = cross(-Gc, e[i])
        row[2 + i] = -cross(A - Gc, e[i])
    row[8] = 1.0
    rows.append(row), rhs.append(0.0)  # I_c α = 0 (ω constant)
    # rod: A on it (+), B on it (−)
    for i in range(2):
        row = np.zeros(9)
        row[2 + i], row[4 + i] = 1.0, -1.0
        rows.append(row), rhs.append(MR * a_r[i] - MR * (-G0 if i == 1 else 0.0))
    row = np.zeros(9)
    for i in range(2):
        row[2 + i] = cross(A - Gr, e[i])
        row[4 + i] = -cross(B - Gr, e[i])
    rows.append(row), rhs.append(I_r * k["phidd"])
    # piston: B on it (+), the cylinder's Fy and Mz (+)
    for i in range(2):
        row = np.zeros(9)
        row[4 + i] = 1.0
        if i == 1:
            row[6] = 1.0
        rows.append(row), rhs.append(MP * a_B[i] - MP * (-G0 if i == 1 else 0.0))
    row = np.zeros(9)
    row[7] = 1.0
    rows.append(row), rhs.append(0.0)
    x = np.linalg.solve(np.array(rows), np.array(rhs))
    del I_c, phi
    return dict(zip(["O.Fx", "O.Fy", "A.Fx", "A.Fy", "B.Fx", "B.Fy", "P.Fy", "P.Mz",
                     "motor.M"], x.tolist(), strict=True))


def crank_angle(model: mbody.Model, state: mbody.State) -> float:
    q = state.quaternion[0]
    return 2.0 * math.atan2(q[3], q[0])


def test_a_driven_slider_crank_over_a_revolution():
    """At 36 crank angles: the kinematics the driver imposes equal the closed-form
    position analysis, every pin load and the motor torque equal the hand-written
    Newton-Euler rows, and the torque equals the energy method's τ ω = d(T + V)/dt."""
    model = driven_slider_crank()
    period = 2 * math.pi / OMEGA
    state = model.initial
    for k in range(36):
        t = k * period / 36
        state = mbody.kinematics(model, t, start=state)
        theta = crank_angle(model, state)
        assert math.remainder(theta - (math.pi / 4 + OMEGA * t), 2 * math.pi) == \
            pytest.approx(0.0, abs=1e-12)
        kin = slider_crank_kinematics(theta)
        assert state.position[2, 0] == pytest.approx(kin["xb"], abs=1e-12)
        assert state.velocity[2, 0] == pytest.approx(kin["xbd"], abs=1e-10 * OMEGA)
        sol = mbody.assemble(model, state).solve(axes="world")
        assert not sol.warnings  # the hand solution is in world axes: so are these
        hand = hand_newton_euler(theta)
        scale = max(abs(v) for v in hand.values())
        for label, value in hand.items():
            assert sol.reactions[label] == pytest.approx(value, abs=1e-9 * scale), label
        a = sol.accelerations.reshape(3, 3)
        v = np.concatenate((state.velocity[:, :2], state.omega[:, 2:]), axis=1)
        inertia = np.array([MC, MR, MP])[:, None] * np.array([1.0, 1.0, 0.0]) + \
            np.array([[0, 0, model.J[i, 2, 2]] for i in range(3)])
        dT = float(np.sum(inertia * v * a))
        dV = float(G0 * np.sum(np.array([MC, MR, MP]) * state.velocity[:, 1]))
        assert sol.reactions["motor.M"] * OMEGA == pytest.approx(dT + dV, rel=1e-9,
                                                                  abs=1e-9 * scale * OMEGA)


def test_the_motor_torque_at_the_dead_centre_is_the_weight_of_crank_and_rod():
    """Crank along the cylinder (θ = 0): T(θ) is even about it, so dT/dt = 0 there and
    the torque is dV/dθ = g r (m_crank + m_rod) / 2 (both mass centres at r sin θ / 2)."""
    model = driven_slider_crank()
    t = (2 * math.pi - math.pi / 4) / OMEGA  # the crank back at 0
    state = mbody.kinematics(model, t)
    assert crank_angle(model, state) == pytest.approx(0.0, abs=1e-12)
    sol = mbody.assemble(model, state).solve()
    assert sol.reactions["motor.M"] == pytest.approx(G0 * R * (MC + MR) / 2, rel=1e-9)


def fourbar(theta: float, off: float = 0.0, body_points: bool = False) -> str:
    """A planar four-bar: ground pivots O (0, 0) and D (d, 0), crank a, coupler b,
    rocker c, the crank driven to θ; the coupler's point of interest is 0.05 m off its
    line. `off` turns every body by that much (a file drawn a few degrees wrong: its
    joints must then be given per body)."""
    a, b, c, d = 0.1, 0.35, 0.25, 0.3
    Ax, Ay = a * math.cos(theta), a * math.sin(theta)
    psi = freudenstein(theta)
    Bx, By = d + c * math.cos(psi), c * math.sin(psi)
    cpl = math.atan2(By - Ay, Bx - Ax)

    def bar(name, x0, y0, x1, y1, mass):
        ang = math.atan2(y1 - y0, x1 - x0) + off
        return {"name": name, "mass": mass, "inertia": mass * 0.01,
                "position": [(x0 + x1) / 2, (y0 + y1) / 2], "angle": ang}
    bodies = [bar("crank", 0, 0, Ax, Ay, 0.3), bar("coupler", Ax, Ay, Bx, By, 0.8),
              bar("rocker", d, 0, Bx, By, 0.5)]
    if body_points:
        joints = [
            {"name": "O", "type": "revolute", "parent": "ground", "child": "crank",
             "at": [[0, 0], [-a / 2, 0]]},
            {"name": "A", "type": "revolute", "parent": "crank", "child": "coupler",
             "at": [[a / 2, 0], [-b / 2, 0]]},
            {"name": "B", "type": "revolute", "parent": "coupler", "child": "rocker",
             "at": [[b / 2, 0], [c / 2, 0]]},
            {"name": "D", "type": "revolute", "parent": "ground", "child": "rocker",
             "at": [[d, 0], [-c / 2, 0]]}]
    else:
        joints = [
            {"name": "O", "type": "revolute", "parent": "ground", "child": "crank",
             "at": [0, 0]},
            {"name": "A", "type": "revolute", "parent": "crank", "child": "coupler",
             "at": [Ax, Ay]},
            {"name": "B", "type": "revolute", "parent": "coupler", "child": "rocker",
             "at": [Bx, By]},
            {"name": "D", "type": "revolute", "parent": "ground", "child": "rocker",
             "at": [d, 0]}]
    del cpl
    doc = {"model": "fourbar", "dimension": 2, "bodies": bodies, "joints": joints,
           "drivers": [{"name": "motor", "joint": "O",
                        "angle": f"{theta!r} + 2*t"}]}
    return yaml.safe_dump(doc)


def freudenstein(theta: float) -> float:
    """The rocker's angle ψ for crank angle θ, from Freudenstein's equation
    K1 cos ψ − K2 cos θ + K3 = cos(θ − ψ), on the open branch."""
    a, b, c, d = 0.1, 0.35, 0.25, 0.3
    K1, K2, K3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    A = math.cos(theta) - K1 - K2 * math.cos(theta) + K3
    B = -2 * math.sin(theta)
    C = K1 - (K2 + 1) * math.cos(theta) + K3
    return 2 * math.atan2(-B + math.sqrt(B * B - 4 * A * C), 2 * A)


def coupler_point(model: mbody.Model, state: mbody.State) -> np.ndarray:
    """The coupler's point 0.05 m to the left of its line, at its middle."""
    k = model.index["coupler"]
    q = state.quaternion[k]
    ang = 2 * math.atan2(q[3], q[0])
    return state.position[k, :2] + 0.05 * np.array([-math.sin(ang), math.cos(ang)])


@pytest.mark.parametrize(("off", "body_points"), [(0.0, False), (math.radians(3), True)])
def test_a_four_bar_coupler_curve_equals_freudenstein(off, body_points):
    """The crank driven through a revolution from 0.3 rad: the coupler point's curve
    equals the closed-form position analysis to 1e-10 m, from the exact pose and from a
    pose 3 degrees off with joint points given on each body."""
    model = mbody.loads(fourbar(0.3, off, body_points))
    a, c, d = 0.1, 0.25, 0.3
    state = model.initial
    for k in range(60):
        t = k * math.pi / 60
        theta = 0.3 + 2 * t
        state = mbody.kinematics(model, t, start=state)
        Ax, Ay = a * math.cos(theta), a * math.sin(theta)
        psi = freudenstein(theta)
        Bx, By = d + c * math.cos(psi), c * math.sin(psi)
        mid = np.array([(Ax + Bx) / 2, (Ay + By) / 2])
        ang = math.atan2(By - Ay, Bx - Ax)
        want = mid + 0.05 * np.array([-math.sin(ang), math.cos(ang)])
        assert np.abs(coupler_point(model, state) - want).max() <= 1e-10


def test_an_open_chain_drivers_efforts_equal_mujocos_inverse_dynamics():
    """A double pendulum with both joints driven (q1(t), q2(t)): the drivers' torques
    equal MuJoCo's mj_inverse at the same q, q̇, q̈, to 1e-9 relative."""
    mujoco = pytest.importorskip("mujoco")
    l1, l2, m1, m2 = 0.7, 0.5, 1.3, 0.9
    law1, law2 = "0.4 + 0.6*sin(1.3*t)", "-0.2 + 0.9*sin(2.1*t + 0.5)"
    q1, q2 = 0.4, -0.2 + 0.9 * math.sin(0.5)
    # bodies as uniform rods hanging from their joints (angles from -y)
    def rod(name, x0, y0, ang, length, mass):
        return {"name": name, "mass": mass, "inertia": mass * length ** 2 / 12,
                "position": [x0 + length / 2 * math.sin(ang), y0 - length / 2 * math.cos(ang)],
                "angle": ang - math.pi / 2}
    A = (l1 * math.sin(q1), -l1 * math.cos(q1))
    doc = {"model": "driven-double", "dimension": 2, "gravity": [0, -G0],
           "bodies": [rod("upper", 0, 0, q1, l1, m1), rod("lower", A[0], A[1], q1 + q2, l2, m2)],
           "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "upper",
                       "at": [0, 0]},
                      {"name": "A", "type": "revolute", "parent": "upper", "child": "lower",
                       "at": list(A)}],
           "drivers": [{"name": "m1", "joint": "O", "angle": f"{law1} - pi/2"},
                       {"name": "m2", "joint": "A", "angle": law2}]}
    model = mbody.loads(yaml.safe_dump(doc))
    j1, j2 = m1 * l1 ** 2 / 12, m2 * l2 ** 2 / 12
    xml = f"""<mujoco><option gravity="0 -{G0} 0" integrator="RK4"/>
      <worldbody><body name="upper"><joint name="q1" type="hinge" axis="0 0 1"/>
        <inertial pos="0 -{l1 / 2} 0" mass="{m1}" diaginertia="{j1} {j1} {j1}"/>
        <body name="lower" pos="0 -{l1} 0"><joint name="q2" type="hinge" axis="0 0 1"/>
          <inertial pos="0 -{l2 / 2} 0" mass="{m2}" diaginertia="{j2} {j2} {j2}"/>
        </body></body></worldbody></mujoco>"""
    mm = mujoco.MjModel.from_xml_string(xml)
    md = mujoco.MjData(mm)
    from mbody.model.calculus import derivative
    from mbody.model.expressions import compile_expression
    laws = [compile_expression(law1), compile_expression(law2)]
    state = model.initial
    for t in (0.0, 0.37, 1.21, 2.9):
        state = mbody.kinematics(model, t, start=state)
        sol = mbody.assemble(model, state).solve()
        d1 = [derivative(f) for f in laws]
        d2 = [derivative(f) for f in d1]
        md.qpos[:] = [float(f(t)) for f in laws]
        md.qvel[:] = [float(f(t)) for f in d1]
        md.qacc[:] = [float(f(t)) for f in d2]
        mujoco.mj_inverse(mm, md)
        want = md.qfrc_inverse.copy()
        got = np.array([sol.reactions["m1.M"], sol.reactions["m2.M"]])
        assert np.abs(got - want).max() <= 1e-9 * np.abs(want).max()


def test_a_spring_loaded_pendulum_rests_where_the_closed_form_says():
    """A rod on a pin with a zero-length spring from its mass centre to a wall point at
    the pin's height a away: V = ½ k |x_G − P|² − m g l cos θ is least at tan θ = k a / m g,
    where the stiffness is k a l sin θ + m g l cos θ over I_O."""
    m, k, a, l, I_G = 2.0, 30.0, 1.2, 0.5, 0.1
    doc = {"model": "spring-pendulum", "dimension": 2, "gravity": [0, -G0],
           "bodies": [{"name": "rod", "mass": m, "inertia": I_G, "position": [0, -l]}],
           "loads": [{"name": "k", "type": "spring", "bodies": ["ground", "rod"],
                      "at": [[a, 0], [0, 0]], "stiffness": k, "rest_length": 0}],
           "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "rod",
                       "at": [0, 0]}]}
    model = mbody.loads(yaml.safe_dump(doc))
    found = find_equilibrium(model)
    assert found.found and found.stable
    x = found.state.position[0]
    theta = math.atan2(x[0], -x[1])
    want = math.atan(k * a / (m * G0))
    assert theta == pytest.approx(want, abs=1e-10)
    stiff = (k * a * l * math.sin(want) + m * G0 * l * math.cos(want)) / (I_G + m * l * l)
    assert found.stiffness[0] == pytest.approx(stiff, rel=1e-6)
    assert np.allclose(mbody.equilibrium(model).position, found.state.position)


def test_driver_errors_are_located():
    base = (ROOT / "models" / "slider_crank.yaml").read_text()
    for drivers, expected in (
            ("  - {name: m, joint: Q, speed: 1}", "no joint named 'Q'"),
            ("  - {name: m, joint: O, speed: 1, angle: 0.1}", "exactly one of"),
            ("  - {name: m, joint: P, angle: 0.1}", "cannot drive joint 'P'"),
            ("  - {name: m, joint: O, speed: '3 furlongs'}", "expected a rate"),
            ("  - {name: m, joint: O, speed: 1}\n  - {name: n, joint: O, angle: 't'}",
             "driven twice"),
            ("  - {name: m, joint: O, speed: 1}\n  - {name: n, joint: P, displacement: 't'}",
             "2 drivers for 1 degree(s) of freedom")):
        with pytest.raises(ModelError) as exc:
            mbody.loads(base + "drivers:\n" + drivers + "\n", "sc.yaml")
        assert expected in str(exc.value)
        assert all(i.line > 0 for i in exc.value.issues)


# -- a whole run (mbody.simulate.kinematic: one call of the compiled core) -----------------

def test_a_kinematic_run_of_the_driven_slider_crank_equals_the_hand_solution():
    """A revolution at 36 samples: every pin load and the motor torque (world axes)
    against the hand-written Newton-Euler rows, 1e-9 relative; the drivers' work equals
    the change of T + V (no other load); the motor torque equals the energy method's
    τ ω = dT/dt + dV/dt at each sample."""
    from mbody.simulate.kinematic import kinematic_run

    model = driven_slider_crank()
    period = 2 * math.pi / OMEGA
    traj = kinematic_run(model, period * 35 / 36, 36 / period, axes="world")
    assert len(traj) == 36
    labels = traj.reaction_labels
    for k in range(36):
        theta = float(traj.orientation[k, 0])
        hand = hand_newton_euler(theta)
        scale = max(abs(v) for v in hand.values())
        for label, value in hand.items():
            got = traj.reactions[k, labels.index(label)]
            assert got == pytest.approx(value, abs=1e-9 * scale), (k, label)
        kin = slider_crank_kinematics(theta)
        assert traj.position[k, 2, 0] == pytest.approx(kin["xb"], abs=1e-12)
    info = traj.info
    # no applied load: Q is gravity alone, and Q·v − m g·v is rounding
    power = float(np.abs(traj.series["driver_power"]).max())
    assert np.abs(traj.series["load_power"]).max() < 1e-13 * power
    # τ ω = d(T + V)/dt at every sample, from the solved accelerations: to rounding
    assert info["power_balance_residual"] < 1e-12
    # the work over the run by cubic quadrature (error O(h^4)): one sample a degree leaves
    # about (4 ω h)^4 / 180 = 1.3e-7 of it (the torque's fourth harmonic, h = 1 deg)
    fine = kinematic_run(model, period * 359 / 360, 360 / period)
    assert fine.info["energy_balance_residual"] < 1e-6


def test_a_kinematic_run_with_samples_far_apart_stores_each_angle_at_its_pose():
    """A quarter of a revolution between samples: the rod's stored angle is the closed
    form's at each sample (the Newton steps that close the loop turn the rod; its stored
    angle must follow them, not stay where the Taylor step left it)."""
    from mbody.simulate.kinematic import kinematic_run

    period = 2 * math.pi / OMEGA
    traj = kinematic_run(driven_slider_crank(), 2 * period, 4 / period)
    for k in range(len(traj)):
        phi = slider_crank_kinematics(float(traj.orientation[k, 0]))["phi"]
        assert traj.orientation[k, 1] == pytest.approx(phi, abs=1e-12), k


def test_a_kinematic_runs_coupler_curve_equals_freudenstein():
    """A named coupler point followed over half a revolution from a pose 3 degrees off
    (joint points per body): its world path equals the closed form to 1e-10 m."""
    from mbody.simulate.kinematic import kinematic_run

    model = mbody.loads(fourbar(0.3, math.radians(3), True))
    traj = kinematic_run(model, math.pi / 2, 120 / math.pi,
                         points={"P": ("coupler", [0.0, 0.05])})
    a, c, d = 0.1, 0.25, 0.3
    path = traj.series["point:P"]
    assert path.shape == (len(traj), 2)
    for k, t in enumerate(traj.t.tolist()):
        theta = 0.3 + 2 * t
        Ax, Ay = a * math.cos(theta), a * math.sin(theta)
        psi = freudenstein(theta)
        Bx, By = d + c * math.cos(psi), c * math.sin(psi)
        ang = math.atan2(By - Ay, Bx - Ax)
        want = np.array([(Ax + Bx) / 2, (Ay + By) / 2]) + \
            0.05 * np.array([-math.sin(ang), math.cos(ang)])
        assert np.abs(path[k] - want).max() <= 1e-10, k


def test_kinematic_run_points_in_the_command_lines_text_form_and_wrong_forms():
    """``{"P": "coupler:0,0.05"}`` (what --point writes after NAME=) follows the same
    point as ``{"P": ("coupler", [0, 0.05])}``; a list, an entry of another shape, a
    misspelt body or a count of coordinates that is not the model's is refused by name."""
    from mbody.simulate.kinematic import kinematic_run

    model = mbody.loads(fourbar(0.3))
    as_pair = kinematic_run(model, 0.5, 20, points={"P": ("coupler", [0.0, 0.05])})
    as_text = kinematic_run(model, 0.5, 20, points={"P": "coupler:0,0.05"})
    assert np.array_equal(as_text.series["point:P"], as_pair.series["point:P"])
    with pytest.raises(TypeError, match=r"^points must be a mapping name -> \(body"):
        kinematic_run(model, 0.5, 20, points=[("coupler", [0.0, 0.05])])
    with pytest.raises(TypeError, match=r"^points\['P'\] must be \(body, \[x, y"):
        kinematic_run(model, 0.5, 20, points={"P": ("coupler", 0.05)})
    for entry, said in [("coupler", "expected BODY:X,Y"), ("coupler:a,b", "not a list of numbers"),
                        ("couple:0,0.05", "did you mean 'coupler'?"),
                        ("coupler:0,0.05,1", "expected 2 finite coordinates")]:
        with pytest.raises(mbody.MbodyError, match=said):
            kinematic_run(model, 0.5, 20, points={"P": entry})


def test_a_kinematic_run_stops_at_a_dead_centre_with_the_distance_left():
    """The four-bar's rocker driven instead of its crank, at a constant rate: a rocker
    swings between two limits (where crank and coupler line up), so the run stops at
    the first sample past the upper one, naming the time and the driver's value."""
    from mbody.simulate.kinematic import kinematic_run
    from mbody.solve.kinematics import KinematicsError

    doc = yaml.safe_load(fourbar(0.3))
    psi0 = doc["bodies"][2]["angle"]
    # the rocker's angle over a crank revolution, from its value at the start (-1.546 rad)
    swing = max(freudenstein(th) for th in np.linspace(0, 2 * math.pi, 20001)) - \
        freudenstein(0.3)
    doc["drivers"] = [{"name": "rock", "joint": "D", "angle": f"{psi0!r} + t"}]
    model = mbody.loads(yaml.safe_dump(doc))
    with pytest.raises(KinematicsError, match=r"cannot all close at t = ([0-9.]+) s with "
                       r"rock = ") as err:
        kinematic_run(model, 2 * math.pi, 100)
    t_stop = float(err.value.args[0].split("t = ")[1].split(" s")[0])
    # the driver's angle there in degrees, as the rest of kinematics gives it (R7-14)
    rock = float(err.value.args[0].split("rock = ")[1].split(" deg")[0])
    assert rock == pytest.approx(math.degrees(psi0 + t_stop), rel=1e-5)
    # the first sample past the limit: within one sample (0.01 s) of it
    assert 0.0 < t_stop - swing <= 0.01 + 1e-9


def test_a_kinematic_runs_energy_check_counts_springs_and_dampers():
    """The arm on its pin driven to 0.5 sin 3t against a damped spring: the springs'
    elastic energy is in V and the damper's dissipation in the loads' work, so the
    drivers' power plus the loads' is d(T + V)/dt to rounding, and the damper's work over
    the run is −∫ c L′² dt (computed here from the run's own spring lengths)."""
    from mbody.simulate.kinematic import _cumulative, kinematic_run

    text = (ROOT / "models" / "spring_loaded_arm.yaml").read_text()
    text = text.replace("rest_length: 0}", "rest_length: 0.3, damping: 2}")
    text += 'drivers:\n  - {name: m, joint: O, angle: "0.5*sin(3*t)"}\n'
    model = mbody.loads(text)
    run = kinematic_run(model, 2.0, 500)
    assert run.info["power_balance_residual"] < 1e-12
    # the spring runs from the wall point (1.2, 0) to the rod's mass centre
    x = run.position[:, 0]
    L = np.linalg.norm(x - np.array([1.2, 0.0]), axis=1)
    Ld = np.gradient(L, run.t, edge_order=2)
    damper = float(_cumulative(-2.0 * Ld**2, run.t)[-1])
    # np.gradient's second-order differences at 500 per second: about 1e-5 relative
    assert run.info["load_work"] == pytest.approx(damper, rel=1e-4)
    assert run.info["driver_work"] + run.info["load_work"] == pytest.approx(
        run.info["energy_change"], rel=1e-9)


# -- mbody.simulate on driven models ------------------------------------------------------

def test_simulate_of_a_fully_driven_mechanism_is_its_kinematic_run():
    """No integration: the drivers fix the motion, so simulate returns the kinematic run
    (its samples, reactions and energy check), the same numbers as kinematic_run."""
    from mbody.simulate.kinematic import kinematic_run

    model = mbody.load(ROOT / "models" / "slider_crank_driven.yaml")
    run = mbody.simulate(model, 0.05, 1200)
    ref = kinematic_run(model, 0.05, 1200)
    assert run.info["kinematic"] and run.info["steps"] == 0
    np.testing.assert_array_equal(run.reactions, ref.reactions)
    assert run.info["power_balance_residual"] < 1e-12


def arm_angle(traj, body: int) -> tuple[np.ndarray, np.ndarray]:
    """An arm's angle θ from hanging (its mass centre seen from the hinge at (0, 0, 0.6))
    and its rate θ̇, from the run's positions and velocities."""
    r = traj.position[:, body] - np.array([0.0, 0.0, 0.6])
    v = traj.velocity[:, body]
    rho = np.hypot(r[:, 0], r[:, 1])
    rho_dot = (r[:, 0] * v[:, 0] + r[:, 1] * v[:, 1]) / rho
    theta = np.arctan2(rho, -r[:, 2])
    theta_dot = (rho_dot * -r[:, 2] - rho * -v[:, 2]) / (rho**2 + r[:, 2] ** 2)
    return theta, theta_dot


def test_a_partly_driven_flyball_governor_follows_its_closed_form():
    """The spindle driven at Ω = 2π rad/s, the arms free: each arm's angle obeys
    (I_t + m l²) θ̈ = Ω² sin θ cos θ (I_t + m l² − I_a) − m g l sin θ (integrated here
    by scipy at rtol 1e-12), and the motor's torque is the rate of the arms' angular
    momentum about the spindle, 2 × 2 Ω (I_t + m l² − I_a) sin θ cos θ θ̇."""
    from scipy.integrate import solve_ivp

    model = mbody.load(ROOT / "models" / "flyball_governor.yaml")
    run = mbody.simulate(model, 3.0, 100)
    assert not run.info.get("kinematic") and run.info["steps"] > 0
    m, l, W = 1.0, 0.25, 2 * math.pi
    I_t, I_a = float(model.J[1, 0, 0]), float(model.J[1, 2, 2])
    I_O = I_t + m * l * l

    def f(t, y):
        th, om = y
        return [om, (W**2 * math.sin(th) * math.cos(th) * (I_O - I_a)
                     - m * G0 * l * math.sin(th)) / I_O]

    ref = solve_ivp(f, (0.0, 3.0), [math.radians(30), 0.0], method="DOP853", rtol=1e-12,
                    atol=1e-14, t_eval=run.t)
    for body in (1, 2):
        theta, theta_dot = arm_angle(run, body)
        # DOP853 at rtol 1e-10 over 3 s (about 3 swings): the angle to 1e-7 rad
        assert np.abs(theta - ref.y[0]).max() < 1e-7
    theta, theta_dot = arm_angle(run, 1)
    torque = run.reactions[:, run.reaction_labels.index("motor.M")]
    expected = 4 * W * (I_O - I_a) * np.sin(theta) * np.cos(theta) * theta_dot
    assert np.abs(torque - expected).max() < 1e-9 * np.abs(expected).max()
    # the energy check: the motor's work is the change of T + V (no other load)
    assert run.info["power_balance_residual"] < 1e-12
    assert run.info["driver_work"] == pytest.approx(run.info["energy_change"], rel=1e-5)
    assert {"driver:motor", "driver_work"} <= set(run.series)
