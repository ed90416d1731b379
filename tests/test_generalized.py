"""Generalized coordinates (`Assembly.generalized`): M_q q'' = f_q against independent
derivations.

- A double pendulum (rods with their mass centres off the middle, a spring and a couple)
  against SymPy's `LagrangesMethod` at random states: M_q and f_q to 1e-12 of their
  scale. Both are O(1) sums of a few products of the data (rounding ~1e-16 relative);
  1e-12 leaves room for the QR of the projection (condition ~10 at these states).
- Kinematic trees (hinge, slide, ball, free root) against MuJoCo's `mj_fullM`, the
  coordinates converted by the bodies' velocities: MuJoCo's qvel -> the mbody bodies'
  mass-centre and angular velocities (MuJoCo's Jacobians) -> q' = T⁺ v. For hinges and
  slides the conversion must be the identity (the same coordinates); 1e-12 relative as
  above (MuJoCo's CRBA and our projection round differently at 1e-16).
- Every shipped model: T q'' + a0 equals `solve()`'s accelerations (the reactions and
  the generalized equations are two solutions of one problem), to 1e-10 of their scale.
- Drivers: a driven slider-crank's motor torque from M q'' − f with q'' = f''(t) equals
  `solve()`'s driver effort.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.errors import MbodyError
from mbody.model import State

MODELS = sorted((Path(__file__).resolve().parent.parent / "models").glob("*.yaml"))

# -- the double pendulum, in mbody and in SymPy ------------------------------------------

DP = dict(m1=1.3, m2=0.8, I1=0.031, I2=0.017, L1=0.62, a1=0.27, a2=0.33, g=9.81,
          k=45.0, L0=0.4, c=0.0, tau=0.7, sx=0.3, sy=0.2)
"""Masses (kg), inertias about G (kg m^2), the upper rod's length O->A, the mass centres'
distances from their upper joints (m), gravity; a spring (k N/m, rest L0 m) from the
ground point (sx, sy) to the lower rod's mass centre; a couple tau (N m) on the lower rod."""


def dp_yaml(p=DP) -> str:
    return f"""
model: dp
dimension: 2
gravity: [0, {-p['g']!r}]
bodies:
  - {{name: upper, mass: {p['m1']!r}, inertia: {p['I1']!r}, position: [0, {-p['a1']!r}]}}
  - {{name: lower, mass: {p['m2']!r}, inertia: {p['I2']!r},
      position: [0, {-p['L1'] - p['a2']!r}]}}
loads:
  - {{name: k, type: spring, bodies: [ground, lower], at: [[{p['sx']!r}, {p['sy']!r}], [0, 0]],
      stiffness: {p['k']!r}, rest_length: {p['L0']!r}}}
  - {{name: tau, type: torque, body: lower, torque: {p['tau']!r}}}
joints:
  - {{name: O, type: revolute, parent: ground, child: upper, at: [[0, 0], [0, {p['a1']!r}]]}}
  - {{name: A, type: revolute, parent: upper, child: lower,
      at: [[0, {p['a1'] - p['L1']!r}], [0, {p['a2']!r}]]}}
"""


def dp_state(q, qd, p=DP) -> State:
    """The bodies at relative angles q (O.angle = the upper rod's angle from hanging,
    A.angle = the lower's relative to it) and rates qd, by hand."""
    f1, f2 = q[0], q[0] + q[1]
    w1, w2 = qd[0], qd[0] + qd[1]
    d1 = np.array([np.sin(f1), -np.cos(f1)])
    d2 = np.array([np.sin(f2), -np.cos(f2)])
    G1, A = p["a1"] * d1, p["L1"] * d1
    G2 = A + p["a2"] * d2
    perp = lambda r: np.array([-r[1], r[0]])  # noqa: E731 (z x r)
    v1 = w1 * perp(G1)
    v2 = w1 * perp(A) + w2 * perp(G2 - A)
    return State.planar(np.array([G1, G2]), np.array([f1, f2]), np.array([v1, v2]),
                        np.array([w1, w2]))


def sympy_double_pendulum(p=DP):
    """(M(q), forcing(q, q')) of the same pendulum by SymPy's LagrangesMethod, lambdified."""
    sm = pytest.importorskip("sympy")
    me = pytest.importorskip("sympy.physics.mechanics")
    q1, q2 = me.dynamicsymbols("q1 q2")
    u1, u2 = me.dynamicsymbols("q1 q2", 1)
    N = me.ReferenceFrame("N")
    B1 = N.orientnew("B1", "Axis", [q1, N.z])
    B2 = N.orientnew("B2", "Axis", [q1 + q2, N.z])
    O = me.Point("O")
    O.set_vel(N, 0)
    G1 = O.locatenew("G1", -p["a1"] * B1.y)
    J = O.locatenew("J", -p["L1"] * B1.y)
    G2 = J.locatenew("G2", -p["a2"] * B2.y)
    for pt, base, fr in ((G1, O, B1), (J, O, B1), (G2, J, B2)):
        pt.v2pt_theory(base, N, fr)
    b1 = me.RigidBody("b1", G1, B1, p["m1"], (me.inertia(B1, 0, 0, p["I1"]), G1))
    b2 = me.RigidBody("b2", G2, B2, p["m2"], (me.inertia(B2, 0, 0, p["I2"]), G2))
    L = me.Lagrangian(N, b1, b2)
    S = O.locatenew("S", p["sx"] * N.x + p["sy"] * N.y)
    r = G2.pos_from(S)
    length = sm.sqrt(r.dot(r))
    spring = -p["k"] * (length - p["L0"]) * r / length
    forces = [(G1, -p["m1"] * p["g"] * N.y), (G2, -p["m2"] * p["g"] * N.y + spring),
              (B2, p["tau"] * N.z)]
    lm = me.LagrangesMethod(L, [q1, q2], forcelist=forces, frame=N)
    lm.form_lagranges_equations()
    a, b, c, d = sm.symbols("a b c d")
    subs = {u1: c, u2: d, q1: a, q2: b}
    M = sm.lambdify((a, b, c, d), lm.mass_matrix.subs(subs), "numpy")
    F = sm.lambdify((a, b, c, d), me.msubs(lm.forcing, subs), "numpy")
    return M, F


def test_double_pendulum_against_sympy_at_random_states():
    model = mbody.loads(dp_yaml())
    M_ref, F_ref = sympy_double_pendulum()
    rng = np.random.default_rng(26)
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, 2)
        qd = rng.normal(scale=3.0, size=2)
        g = mbody.assemble(model, dp_state(q, qd)).generalized()
        assert g.coordinates == ["O.angle", "A.angle"]
        np.testing.assert_allclose(g.q, q, rtol=0, atol=1e-13)
        np.testing.assert_allclose(g.qdot, qd, rtol=0, atol=1e-12)
        M = np.array(M_ref(*q, *qd), dtype=float)
        F = np.array(F_ref(*q, *qd), dtype=float).ravel()
        assert np.abs(g.M - M).max() <= 1e-12 * np.abs(M).max()
        assert np.abs(g.f - F).max() <= 1e-12 * max(np.abs(F).max(), 1.0)
        assert np.allclose(g.M, g.M.T, rtol=0, atol=0)  # symmetric to the last bit


def test_absolute_angles_are_coordinates_too():
    """The same pendulum in the bodies' own angles (upper.theta, lower.theta): the
    transformation q = S p (q1 = p1, q2 = p2 − p1) gives M_p = Sᵀ M_q S, f_p = Sᵀ f_q."""
    model = mbody.loads(dp_yaml())
    state = dp_state([0.4, -0.9], [1.2, 0.5])
    asm = mbody.assemble(model, state)
    gq = asm.generalized()
    gp = asm.generalized(["upper.theta", "lower.theta"])
    S = np.array([[1.0, 0.0], [-1.0, 1.0]])
    np.testing.assert_allclose(gp.M, S.T @ gq.M @ S, rtol=0, atol=1e-14)
    np.testing.assert_allclose(gp.f, S.T @ gq.f, rtol=0, atol=1e-13)
    np.testing.assert_allclose(gp.q, [0.4, -0.5], atol=1e-14)


# -- MuJoCo -----------------------------------------------------------------------------

TREES = {
    "hinges and slides": ("""
<mujoco><option gravity="0 0 -9.81"/><worldbody>
  <body name="a" pos="0 0 1">
    <joint name="j1" type="hinge" axis="0 1 0"/>
    <inertial pos="0.1 0 -0.2" mass="1.3" diaginertia="0.02 0.03 0.04" quat="0.9 0.1 0.2 0.3"/>
    <body name="b" pos="0.05 0.1 -0.4">
      <joint name="j2" type="slide" axis="1 0 0.5"/>
      <inertial pos="0 0.1 -0.1" mass="0.7" diaginertia="0.01 0.02 0.015"/>
      <body name="c" pos="0 0 -0.3" euler="0.3 0.2 0.1">
        <joint name="j3" type="hinge" axis="0.2 1 0.1"/>
        <inertial pos="0.05 0.02 -0.2" mass="0.5" diaginertia="0.004 0.005 0.006"/>
      </body>
      <body name="d" pos="0.1 0 0">
        <joint name="j4" type="hinge" axis="1 0 0"/>
        <inertial pos="0.2 0 0" mass="0.4" diaginertia="0.002 0.003 0.004"/>
      </body>
    </body>
  </body></worldbody>
  <keyframe><key name="k" qpos="0.3 0.1 -0.9 1.7" qvel="1 -2 0.5 0.3"/></keyframe>
</mujoco>""", True),
    "ball and free root": ("""
<mujoco><option gravity="0 0 -9.81"/><worldbody>
  <body name="base" pos="0 0 1">
    <freejoint name="root"/>
    <inertial pos="0 0 0" mass="2.0" diaginertia="0.1 0.12 0.15"/>
    <body name="arm" pos="0.1 0 -0.1">
      <joint name="s" type="ball"/>
      <inertial pos="0.05 0.02 -0.2" mass="0.5" diaginertia="0.004 0.005 0.006"/>
      <body name="hand" pos="0 0 -0.4">
        <joint name="e" type="hinge" axis="0 1 0"/>
        <inertial pos="0 0 -0.1" mass="0.3" diaginertia="0.001 0.002 0.0025"/>
      </body>
    </body>
  </body></worldbody>
  <keyframe><key name="k" qpos="0.1 0.2 1.1 0.9 0.1 -0.2 0.3 0.8 0.3 -0.4 0.2 0.6"
    qvel="0.3 -0.2 0.1 1 -2 0.5 0.3 0.7 -1.1 0.4"/></keyframe>
</mujoco>""", False),
}


def full_mass(mujoco, mj, d, out) -> None:
    """mj_fullM across MuJoCo's versions: (m, dst, qM) before 3.3, (m, d, dst) since."""
    try:
        mujoco.mj_fullM(mj, d, out)
    except TypeError:
        mujoco.mj_fullM(mj, out, d.qM)


@pytest.mark.parametrize("name", list(TREES))
def test_trees_against_mujoco_full_mass_matrix(name, tmp_path):
    mujoco = pytest.importorskip("mujoco")
    xml, one_to_one = TREES[name]
    path = tmp_path / "tree.xml"
    path.write_text(xml)
    mj = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(mj)
    mujoco.mj_resetDataKeyframe(mj, d, 0)
    mujoco.mj_forward(mj, d)
    M_mj = np.zeros((mj.nv, mj.nv))
    full_mass(mujoco, mj, d, M_mj)
    model = mbody.load(path, keyframe="k")
    g = mbody.assemble(model).generalized()
    # the bodies' velocities per unit of each MuJoCo dof (mass centre, world; angular
    # velocity, mbody's body axes)
    state = model.initial
    V = np.zeros((6 * model.n, mj.nv))
    for i, body in enumerate(model.body_names):
        bid = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, body)
        np.testing.assert_allclose(state.position[i], d.xipos[bid], atol=1e-12)
        jp, jr = np.zeros((3, mj.nv)), np.zeros((3, mj.nv))
        mujoco.mj_jacBodyCom(mj, d, jp, jr, bid)
        V[6 * i:6 * i + 3] = jp
        V[6 * i + 3:6 * i + 6] = state.W_R_B[i].T @ jr
    S = np.linalg.pinv(g.T) @ V
    np.testing.assert_allclose(g.T @ S, V, rtol=0, atol=1e-12 * np.abs(V).max())
    if one_to_one:  # the same coordinates: hinge angles and slides, one for one
        np.testing.assert_allclose(S, np.eye(mj.nv), rtol=0, atol=1e-12)
    ours = S.T @ g.M @ S
    assert np.abs(ours - M_mj).max() <= 1e-12 * np.abs(M_mj).max()
    # and the rates of the state are MuJoCo's qvel, converted
    np.testing.assert_allclose(g.qdot, S @ d.qvel, rtol=0, atol=1e-12 * np.abs(d.qvel).max())


# -- consistency with solve() on every shipped model -------------------------------------


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_accelerations_equal_solve(path):
    model = mbody.load(path)
    asm = mbody.assemble(model)
    sol = asm.solve()
    g = asm.generalized()
    # a driver's coordinate is free here, its effort a generalized force: give it the
    # effort the solve found to hold the driver's law
    d = model.drivers
    efforts = {f"{n}.{c}": sol.reactions[f"{n}.{c}"]
               for n, c in zip(d.names, d.component, strict=True)} if d is not None else {}
    acc = g.body_accelerations(g.accelerations(efforts))
    scale = max(float(np.abs(sol.accelerations).max()), 1.0)
    assert np.abs(acc - sol.accelerations).max() <= 1e-10 * scale
    assert np.allclose(g.M, g.M.T, rtol=0, atol=0)
    assert np.linalg.eigvalsh(g.M).min() > 0
    assert len(g.coordinates) == g.coordinate_set.dof
    assert sum(g.forces.values()) == pytest.approx(g.f, abs=1e-12 * max(1, np.abs(g.f).max()))


def test_reactions_do_no_work_on_the_coordinates():
    """Tᵀ G = 0 for the held joints (why the reactions drop out)."""
    model = mbody.load(MODELS[0].parent / "fourbar_planar.yaml")
    asm = mbody.assemble(model)
    g = asm.generalized()
    G = asm.G.toarray()
    assert np.abs(g.T.T @ G).max() <= 1e-14 * np.abs(G).max() * np.abs(g.T).max()


# -- drivers ------------------------------------------------------------------------------

DRIVEN = """
model: driven-slider-crank
dimension: 2
gravity: [0, -9.81]
bodies:
  - {name: crank, mass: 0.4, inertia: 0.0003, position: [0.025, 0], angle: 0}
  - {name: rod, mass: 0.6, inertia: 0.0013, position: [0.13, 0], angle: 0}
  - {name: piston, mass: 0.5, inertia: 0.0004, position: [0.21, 0]}
loads:
  - {name: gas, type: force, body: piston, force: ["-300*cos(t)", 0]}
joints:
  - {name: O, type: revolute, parent: ground, child: crank, at: [0, 0]}
  - {name: A, type: revolute, parent: crank, child: rod, at: [0.05, 0]}
  - {name: B, type: revolute, parent: rod, child: piston, at: [0.21, 0]}
  - {name: P, type: prismatic, parent: ground, child: piston, at: [0.21, 0], axis: [1, 0]}
drivers:
  - {name: motor, joint: O, angle: "0.7 + 20*t + 3*t^2"}
"""


def test_driver_coordinate_carries_the_effort():
    model = mbody.loads(DRIVEN)
    state = mbody.kinematics(model, 0.3)
    asm = mbody.assemble(model, state)
    sol = asm.solve()
    g = asm.generalized()
    assert g.coordinates == ["O.angle"]
    assert g.efforts == {"motor.M": "O.angle"}
    t = 0.3
    np.testing.assert_allclose(g.q, [0.7 + 20 * t + 3 * t * t - 2 * np.pi], atol=1e-10)
    np.testing.assert_allclose(g.qdot, [20 + 6 * t], rtol=1e-12)
    effort = g.M[0, 0] * 6.0 - g.f[0]  # q'' = f'' = 6
    tau = sol.reactions["motor.M"]
    assert effort == pytest.approx(tau, rel=1e-10)
    np.testing.assert_allclose(g.accelerations({"motor.M": tau}), [6.0], rtol=1e-10)


def test_driver_held_when_its_coordinate_is_not_chosen():
    """With the piston's slide as the coordinate the motor is a constraint: there is no
    freedom left... so a driven mechanism has zero coordinates when the driver is held."""
    model = mbody.loads(DRIVEN)
    with pytest.raises(MbodyError, match="1 coordinate.* for 0 degree"):
        mbody.assemble(model).generalized(["P.displacement"])


def test_unknown_coordinate_has_a_did_you_mean():
    model = mbody.load(MODELS[0].parent / "double_pendulum.yaml")
    with pytest.raises(MbodyError, match="did you mean 'A.angle'"):
        mbody.assemble(model).generalized(["O.angle", "A.angel"])
    with pytest.raises(MbodyError, match="3 coordinate.* for 2 degree"):
        mbody.assemble(model).generalized(["O.angle", "A.angle", "upper.x"])
    with pytest.raises(MbodyError, match="does not add a motion"):
        mbody.assemble(model).generalized(["O.angle", "upper.theta"])


# -- symbolic -----------------------------------------------------------------------------


def test_double_pendulum_symbolic_equals_sympy_lagrangesmethod():
    """M(q) and f(q, q') in symbols equal SymPy's LagrangesMethod on the same pendulum,
    symbolically (the difference expands to 0), with the masses, inertias, g, the spring's
    k and L0 and the couple as symbols and the lengths the file's numbers, exactly."""
    sm = pytest.importorskip("sympy")
    me = pytest.importorskip("sympy.physics.mechanics")
    p = DP
    model = mbody.loads(dp_yaml())
    sym = mbody.assemble(model).generalized().symbolic()
    def R(x):  # the file's numbers as mbody holds them (the simplest rational near each)
        return sm.nsimplify(float(x), tolerance=1e-12 * max(abs(x), 1.0), rational=True)

    m1, m2, I1, I2, g, k, L0, tau = sm.symbols("m_upper m_lower I_upper I_lower g k_k L0_k "
                                               "M_tau")
    q1, q2 = me.dynamicsymbols("q1 q2")
    u1, u2 = me.dynamicsymbols("q1 q2", 1)
    N = me.ReferenceFrame("N")
    B1 = N.orientnew("B1", "Axis", [q1, N.z])
    B2 = N.orientnew("B2", "Axis", [q1 + q2, N.z])
    O = me.Point("O")
    O.set_vel(N, 0)
    G1 = O.locatenew("G1", -R(p["a1"]) * B1.y)  # the upper rod's joint point O at (0, a1)
    J = G1.locatenew("J", R(p["a1"] - p["L1"]) * B1.y)  # A at (0, a1 - L1) on it
    G2 = J.locatenew("G2", -R(p["a2"]) * B2.y)
    for pt, base, fr in ((G1, O, B1), (J, O, B1), (G2, J, B2)):
        pt.v2pt_theory(base, N, fr)
    bodies = (me.RigidBody("b1", G1, B1, m1, (me.inertia(B1, 0, 0, I1), G1)),
              me.RigidBody("b2", G2, B2, m2, (me.inertia(B2, 0, 0, I2), G2)))
    S = O.locatenew("S", R(p["sx"]) * N.x + R(p["sy"]) * N.y)
    r = G2.pos_from(S)
    length = sm.sqrt(r.dot(r))
    forces = [(G1, -m1 * g * N.y), (G2, -m2 * g * N.y - k * (length - L0) * r / length),
              (B2, tau * N.z)]
    lm = me.LagrangesMethod(me.Lagrangian(N, *bodies), [q1, q2], forcelist=forces, frame=N)
    lm.form_lagranges_equations()
    subs = {u1: sym.qdot[0], u2: sym.qdot[1], q1: sym.q[0], q2: sym.q[1]}

    def canonical(e):  # polynomial in cos and sin of each coordinate, sin² = 1 − cos²
        e = sm.expand(sm.expand_trig(e))
        return sm.expand(e.subs({sm.sin(x) ** 2: 1 - sm.cos(x) ** 2 for x in sym.q}))

    for mine, theirs in ((sym.M, lm.mass_matrix), (sym.f, lm.forcing)):
        theirs = me.msubs(theirs, subs)
        for a, b in zip(mine, theirs, strict=True):
            assert canonical(a - b) == 0
    # compact: each mass-matrix entry is a sum of terms with at most one cos or sin
    for entry in sym.M:
        for term in sm.Add.make_args(entry):
            assert len([f for f in sm.Mul.make_args(term) if isinstance(f, (sm.sin, sm.cos))]) <= 1
    assert sym.M[0, 1].has(sm.cos(sym.q[1]))  # cos(A.angle): the relative angle, compact
    # and they evaluate to the numeric equations at random states
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, qd = rng.uniform(-3, 3, 2), rng.normal(size=2)
        g_ = mbody.assemble(model, dp_state(q, qd)).generalized()
        M, f = sym.evaluate(q, qd)
        assert np.abs(M - g_.M).max() <= 1e-12 * np.abs(M).max()
        assert np.abs(f - g_.f).max() <= 1e-12 * max(np.abs(f).max(), 1.0)


def test_symbolic_refuses_a_closed_loop():
    pytest.importorskip("sympy")
    from mbody.equations.symbolic.lagrange import NotSymbolicError

    model = mbody.load(MODELS[0].parent / "fourbar_planar.yaml")
    with pytest.raises(NotSymbolicError, match="close a loop"):
        mbody.assemble(model).generalized().symbolic()


@pytest.mark.parametrize("name", ["double_pendulum", "heavy_top", "rotor_gyroscopic_bearings",
                                  "spinning_disc_bearings", "gyroscope_gimbals",
                                  "slider_crank", "fourbar_spatial", "flyball_governor",
                                  "helical_chain", "spring_mass_damper"])
def test_perturbed_evaluations_equal_whole_ones(name):
    """The linearisation's evaluations (the core moves the positions along T dq and keeps
    the joints' columns between a position's evaluations, recomputing only their velocity
    terms at new rates) equal whole evaluations at the moved state: f to the rounding of
    the terms it is made of."""
    from mbody.equations.generalized import evaluate, layout, state_with_velocities
    from mbody.equations.workspace import workspace
    from mbody.solve.configure import move
    from mbody.solve.linearize import free_coordinates

    model = mbody.load(Path(__file__).resolve().parent.parent / "models" / f"{name}.yaml")
    state = model.initial
    cs = free_coordinates(model)
    k = len(cs)
    g0 = evaluate(model, state, cs)
    rng = np.random.default_rng(len(name))
    # rows: positions and rates together, rates alone twice (the columns are reused)
    dq = 1e-2 * rng.normal(size=(4, k)) * cs.scales
    du = rng.normal(size=(4, k)) * np.maximum(np.abs(g0.qdot), 1.0)
    dq[2:] = 0.0
    P = np.ascontiguousarray(np.hstack((dq, du)))
    out = np.empty(4 * k)
    ws = workspace(model)
    ws.solver(cs.held).generalized_perturbed(float(state.t), ws.pack_state(state),
                                             cs.held.lam, cs.Iq, cs.cols, g0.qdot, P, out)
    f = out.reshape(4, k)
    assert layout(len(cs.cols), k)[-1] > 0
    for row in range(4):
        moved = move(model, state, g0.T @ dq[row])
        rates = g0.qdot + du[row]
        at = evaluate(model, moved, cs, qdot=rates)  # T and v_e there: the velocities
        moved = state_with_velocities(model, moved, at.T @ rates + at.v_e)
        ref = evaluate(model, moved, cs)  # a whole evaluation at that state
        scale = np.maximum(ref.f_scale, 1e-300)
        assert np.all(np.abs(f[row] - ref.f) <= 1e-11 * scale), (row, f[row], ref.f)
