"""The linearisation (`mbody.linearize`) against closed forms and hand derivations.

Tolerances come from the linearisation's own error bounds: K and D carry entry-wise
bounds (K_error, D_error: the Richardson estimate and the rounding of f). For an undamped
mode φ of the symmetric pencil (K, M), first-order perturbation theory gives
δ(ω²) = φᵀ δK φ / φᵀ M φ, so |δω| ≤ |φ|ᵀ |δK| |φ| / (2 ω φᵀ M φ). The tests assert that
bound is below the issue's tolerance and the error below the bound.

- A double pendulum hanging: its two natural frequencies against the closed form
  det(K − ω² M) = 0, to 1e-10.
- A body spinning about each principal axis (I = 2, 3, 4, the course's body): the
  eigenvalues ±λ, λ² = Ω²(I_a − I_i)(I_j − I_a)/(I_i I_j), to 1e-10 (f is quadratic in
  the rates: the differences are exact but for rounding); `stable` False exactly for the
  intermediate axis; the same with the inertia given as a full tensor whose principal
  axes are turned.
- A closed four-bar with gravity and a spring: its one frequency about a stable
  equilibrium against a hand derivation (loop closure, velocity and acceleration
  coefficients by hand, V''/I_eq), and without the constraint forces' geometric
  stiffness it is far off.
- A gyroscope in gimbals precessing steadily: the nutation's eigenvalues against SymPy's
  Lagrange equations differentiated symbolically, the precession and spin left out.
- A spring-mass-damper's ω and ζ, and a state that is not steady is said to be so.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_generalized import DP, dp_yaml

import mbody
from mbody.solve.configure import configure
from mbody.solve.equilibrium import equilibrium
from mbody.solve.linearize import linearize


def frequency_bounds(lin) -> np.ndarray:
    """Per oscillation (undamped, simple), the largest error on its natural frequency the
    linearisation's bounds allow (rad/s): |φ|ᵀ |δK| |φ| / (2 ω φᵀ M φ)."""
    out = []
    for mode in lin.oscillations:
        phi = mode.shape.real
        out.append(np.abs(phi) @ np.abs(lin.K_error) @ np.abs(phi)
                   / (phi @ lin.M @ phi) / (2 * mode.frequency))
    return np.array(out)


# -- the double pendulum -------------------------------------------------------------------


def test_double_pendulum_frequencies_against_the_closed_form():
    p = dict(DP, k=0.0, tau=0.0)
    model = mbody.loads(dp_yaml(p))
    lin = linearize(model, configure(model, [0.0, 0.0]))
    assert lin.steady and lin.stable
    m1, m2, I1, I2, L1, a1, a2, g = (p[k] for k in ("m1", "m2", "I1", "I2", "L1", "a1", "a2",
                                                    "g"))
    # absolute angles: M = [[I1 + m1 a1² + m2 L1², m2 L1 a2], [., I2 + m2 a2²]],
    # K = diag((m1 a1 + m2 L1) g, m2 a2 g); det(K − ω² M) = 0
    M = np.array([[I1 + m1 * a1**2 + m2 * L1**2, m2 * L1 * a2], [m2 * L1 * a2, I2 + m2 * a2**2]])
    K = np.diag([(m1 * a1 + m2 * L1) * g, m2 * a2 * g])
    A, B, C = np.linalg.det(M), -(M[0, 0] * K[1, 1] + M[1, 1] * K[0, 0]), K[0, 0] * K[1, 1]
    disc = np.sqrt(B * B - 4 * A * C)
    omega = np.sqrt(np.array([(-B - disc) / (2 * A), (-B + disc) / (2 * A)]))
    bound = frequency_bounds(lin)
    assert np.all(bound <= 1e-10 * omega)
    np.testing.assert_allclose(lin.frequencies, omega, rtol=1e-10)
    assert np.all(np.abs(lin.frequencies - omega) <= bound + 1e-13 * omega)
    np.testing.assert_allclose(lin.frequencies_hz, omega / (2 * np.pi), rtol=1e-10)
    np.testing.assert_allclose(lin.damping_ratios, 0.0, atol=1e-12)
    # the mode shapes solve (K − ω² M) φ = 0 in the relative coordinates
    for mode in lin.oscillations:
        phi = mode.shape.real
        r = (lin.K - mode.frequency**2 * lin.M) @ phi
        assert np.abs(r).max() <= 1e-9 * np.abs(lin.K).max()
        assert np.abs(phi).max() == pytest.approx(1.0)


def test_gravity_is_all_geometric_stiffness():
    """Gravity is constant in the bodies' coordinates: the loads' own stiffness is 0 and
    the whole K is the constraint forces' geometric stiffness. A linearisation that drops
    λ ∂Gᵀ/∂q (Exudyn's K on a pendulum in redundant coordinates) finds frequencies
    [0, 0]."""
    model = mbody.loads(dp_yaml(dict(DP, k=0.0, tau=0.0)))
    lin = linearize(model, configure(model, [0.0, 0.0]))
    assert np.abs(lin.K - lin.K_geometric).max() <= 1e-9 * np.abs(lin.K).max()
    without = np.linalg.eigvals(np.linalg.solve(lin.M, lin.K - lin.K_geometric))
    assert np.abs(without).max() <= 1e-8 * lin.frequencies.max() ** 2


# -- steady spin ------------------------------------------------------------------------------

I_COURSE = (2.0, 3.0, 4.0)


def spinning(J: np.ndarray, omega_body, gravity: bool = False) -> mbody.Model:
    rows = ", ".join("[" + ", ".join(repr(float(x)) for x in r) + "]" for r in J)
    w = ", ".join(repr(float(x)) for x in omega_body)
    g = "gravity: [0, 0, -9.81]\n" if gravity else ""
    return mbody.loads(f"""
model: spin
dimension: 3
{g}bodies:
  - {{name: body, mass: 1.5, inertia: [{rows}], angular_velocity: [{w}]}}
""")


def turned(seed: int) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.random(random_state=seed).as_matrix()


@pytest.mark.parametrize("frame", ["principal", "turned"])
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_steady_spin_about_a_principal_axis(axis, frame):
    I = np.array(I_COURSE)
    R = np.eye(3) if frame == "principal" else turned(7 + axis)
    J = R @ np.diag(I) @ R.T  # body axes: the principal axes are R's columns
    Omega = 2.3
    model = spinning(J, Omega * R[:, axis])
    lin = mbody.linearize(model)
    assert lin.steady
    assert set(lin.left_out) == {"body.w1", "body.w2", "body.w3"}  # the orientation
    i, j = [k for k in range(3) if k != axis]
    lam2 = Omega**2 * (I[axis] - I[i]) * (I[j] - I[axis]) / (I[i] * I[j])
    w = lin.eigenvalues
    big = w[np.abs(w) > 1e-6]
    assert len(big) == 2
    # ±λ: real for the intermediate axis (λ² > 0), imaginary otherwise
    expected = np.sqrt(complex(lam2))
    np.testing.assert_allclose(np.sort_complex(big), np.sort_complex([expected, -expected]),
                               rtol=0, atol=1e-10 * abs(expected))
    assert abs(big[0] ** 2 - lam2) <= 1e-10 * abs(lam2)
    assert lin.stable is (axis != 1)
    kinds = sorted(m.kind for m in lin.modes if m.kind != "neutral")
    assert kinds == (["decay", "growth"] if axis == 1 else ["oscillation"])
    # the rest are the free motion's and the spin's zeros
    assert np.abs(w[np.abs(w) <= 1e-6]).max() <= lin.tolerance


def test_spin_about_a_non_principal_axis_is_not_steady():
    model = spinning(np.diag(I_COURSE), [1.0, 1.0, 0.0])
    lin = mbody.linearize(model)
    assert not lin.steady and lin.stable is None
    assert "not an equilibrium or a steady motion" in lin.warnings[0]
    # the spin's components are quasi-velocities: their rate is one prime, not two
    assert "body.w" in lin.warnings[0] and "' = " in lin.warnings[0]
    assert "'' = " not in lin.warnings[0]


def test_a_moving_pendulum_names_its_angle_acceleration_with_two_primes():
    lin = mbody.linearize(mbody.load("models/double_pendulum.yaml"))
    assert any(".angle'' = " in w for w in lin.warnings)


# -- a closed four-bar ------------------------------------------------------------------------

FB = dict(a=0.10, b=0.30, c=0.25, d=0.30, m=(0.118, 0.353, 0.294), g=9.81,
          k=60.0, L0=0.12, S=(0.15, 0.35), u=0.1)
"""Crank a (O2 at the origin), coupler b, rocker c (O4 at (d, 0)), uniform bars of masses
m, gravity −y; a spring (k N/m, rest L0 m) from the ground point S to the coupler point
at u m from A along it."""


def fb_angles(q: float):
    """Loop closure by hand: the coupler and rocker angles (θ3, θ4) at crank angle q
    (the open branch), and their first and second derivatives by q."""
    a, b, c, d = FB["a"], FB["b"], FB["c"], FB["d"]
    A = a * np.array([np.cos(q), np.sin(q)])
    O4 = np.array([d, 0.0])
    e = O4 - A
    L = np.linalg.norm(e)
    # B on both circles, the branch with B above the line A-O4
    x = (b * b - c * c + L * L) / (2 * L)
    h = np.sqrt(b * b - x * x)
    u = e / L
    B = A + x * u + h * np.array([-u[1], u[0]])
    t3 = np.arctan2(*(B - A)[::-1])
    t4 = np.arctan2(*(B - O4)[::-1])
    # velocity: a e(q) + b e(t3) − c e(t4) = d x̂, differentiated: J [t3', t4'] = −a e'(q)
    def ep(t):
        return np.array([-np.sin(t), np.cos(t)])

    J = np.column_stack((b * ep(t3), -c * ep(t4)))
    w3, w4 = np.linalg.solve(J, -a * ep(q))
    # acceleration: J [t3'', t4''] = a e(q) + b e(t3) t3'^2 − c e(t4) t4'^2
    def ee(t):
        return np.array([np.cos(t), np.sin(t)])

    al3, al4 = np.linalg.solve(J, a * ee(q) + b * ee(t3) * w3**2 - c * ee(t4) * w4**2)
    return (t3, t4), (w3, w4), (al3, al4)


def fb_hand(q: float):
    """V'(q), V''(q) and I_eq(q) of the four-bar by hand."""
    a, b, c = FB["a"], FB["b"], FB["c"]
    m1, m2, m3 = FB["m"]
    g = FB["g"]
    (t3, t4), (w3, w4), (al3, al4) = fb_angles(q)

    def e(t):
        return np.array([np.cos(t), np.sin(t)])

    def ep(t):
        return np.array([-np.sin(t), np.cos(t)])

    # mass centres and their first and second derivatives by q
    G1p, G1pp = a / 2 * ep(q), -a / 2 * e(q)
    A, Ap, App = a * e(q), a * ep(q), -a * e(q)
    G2p = Ap + b / 2 * ep(t3) * w3
    G2pp = App + b / 2 * (ep(t3) * al3 - e(t3) * w3**2)
    G3p = c / 2 * ep(t4) * w4
    G3pp = c / 2 * (ep(t4) * al4 - e(t4) * w4**2)
    Vp = g * (m1 * G1p[1] + m2 * G2p[1] + m3 * G3p[1])
    Vpp = g * (m1 * G1pp[1] + m2 * G2pp[1] + m3 * G3pp[1])
    P = A + FB["u"] * e(t3)
    Pp = Ap + FB["u"] * ep(t3) * w3
    Ppp = App + FB["u"] * (ep(t3) * al3 - e(t3) * w3**2)
    r = P - np.array(FB["S"])
    Ls = np.linalg.norm(r)
    Lp = r @ Pp / Ls
    Lpp = (Pp @ Pp + r @ Ppp - Lp**2) / Ls
    Vp += FB["k"] * (Ls - FB["L0"]) * Lp
    Vpp += FB["k"] * (Lp**2 + (Ls - FB["L0"]) * Lpp)
    I = [m * L * L / 12 for m, L in zip(FB["m"], (a, b, c), strict=True)]
    Ieq = (m1 * G1p @ G1p + I[0] + m2 * G2p @ G2p + I[1] * w3**2 + m3 * G3p @ G3p
           + I[2] * w4**2)
    return Vp, Vpp, Ieq


def fb_model(q: float) -> mbody.Model:
    a, b, c, d = FB["a"], FB["b"], FB["c"], FB["d"]
    (t3, t4), _, _ = fb_angles(q)

    def e(t):
        return np.array([np.cos(t), np.sin(t)])

    A = a * e(q)
    B = A + b * e(t3)
    G = [a / 2 * e(q), A + b / 2 * e(t3), np.array([d, 0.0]) + c / 2 * e(t4)]
    v = lambda x: "[" + ", ".join(repr(float(t)) for t in x) + "]"  # noqa: E731
    bodies = []
    for name, G_, t, m, L in zip(("crank", "coupler", "rocker"), G, (q, t3, t4), FB["m"],
                                 (a, b, c), strict=True):
        bodies.append(f"  - {{name: {name}, mass: {m!r}, inertia: {m * L * L / 12!r}, "
                      f"position: {v(G_)}, angle: {float(t)!r}}}")
    return mbody.loads(f"""
model: fourbar-spring
dimension: 2
gravity: [0, {-FB['g']!r}]
bodies:
{chr(10).join(bodies)}
loads:
  - {{name: k, type: spring, bodies: [ground, coupler],
      at: [{v(FB['S'])}, [{FB['u'] - b / 2!r}, 0]],
      stiffness: {FB['k']!r}, rest_length: {FB['L0']!r}}}
joints:
  - {{name: O2, type: revolute, parent: ground, child: crank, at: [0, 0]}}
  - {{name: A, type: revolute, parent: crank, child: coupler, at: {v(A)}}}
  - {{name: B, type: revolute, parent: coupler, child: rocker, at: {v(B)}}}
  - {{name: O4, type: revolute, parent: ground, child: rocker, at: [{d!r}, 0]}}
""")


def test_fourbar_frequency_against_a_hand_derivation():
    # the equilibrium by Newton on the hand derivation's V'(q)
    q = 1.2
    for _ in range(50):
        Vp, Vpp, _ = fb_hand(q)
        step = Vp / Vpp
        q -= step
        if abs(step) < 1e-15:
            break
    Vp, Vpp, Ieq = fb_hand(q)
    assert abs(Vp) < 1e-12 and Vpp > 0  # a stable equilibrium
    omega = np.sqrt(Vpp / Ieq)
    model = fb_model(q)
    lin = linearize(model)
    assert lin.coordinates == ["O2.angle"]
    assert lin.steady and lin.stable
    np.testing.assert_allclose(lin.generalized.q, [q], atol=1e-12)
    np.testing.assert_allclose(lin.M, [[Ieq]], rtol=1e-12)
    bound = frequency_bounds(lin)[0]
    assert bound <= 1e-9 * omega
    assert abs(lin.frequencies[0] - omega) <= bound + 1e-12 * omega
    # mbody's own finder lands on the same equilibrium from the file's neighbourhood
    found = equilibrium(fb_model(q + 0.2))
    assert mbody.assemble(fb_model(q + 0.2), found).generalized().q[0] == pytest.approx(q,
                                                                                        abs=1e-7)
    # the geometric stiffness matters: without it (the spring's own stiffness only) the
    # frequency is far off
    K_loads = lin.K - lin.K_geometric
    without = np.sqrt(K_loads[0, 0] / Ieq) if K_loads[0, 0] > 0 else 0.0
    assert abs(without - omega) > 0.1 * omega
    assert abs(lin.K_geometric[0, 0]) > 0.1 * lin.K[0, 0]


# -- a gyroscope precessing steadily ----------------------------------------------------------

GY = dict(Io=(0.004, 0.003, 0.006), Ii=(0.002, 0.0015, 0.0025), A=0.0004, C=0.0007, m=0.5,
          l=0.06, g=9.81)
"""Outer gimbal (yaw about world z), inner gimbal (pitch about the outer's x), rotor
(spin about the inner's y): principal inertias of the gimbals in their axes, the rotor's
(A, C, A) with C about its spin axis; the rotor's mass m at l along its axis; the
gimbals' mass centres at the pivot."""


def gyro_model() -> mbody.Model:
    p = GY
    return mbody.loads(f"""
model: gyroscope
dimension: 3
gravity: [0, 0, {-p['g']!r}]
bodies:
  - {{name: outer, mass: 0.3, inertia: {list(p['Io'])}}}
  - {{name: inner, mass: 0.2, inertia: {list(p['Ii'])}}}
  - {{name: rotor, mass: {p['m']!r}, inertia: [{p['A']!r}, {p['C']!r}, {p['A']!r}],
      position: [0, {p['l']!r}, 0]}}
joints:
  - {{name: yaw, type: revolute, parent: ground, child: outer, at: [0, 0, 0], axis: [0, 0, 1]}}
  - {{name: pitch, type: revolute, parent: outer, child: inner, at: [0, 0, 0], axis: [1, 0, 0]}}
  - {{name: spin, type: revolute, parent: inner, child: rotor, at: [0, 0, 0], axis: [0, 1, 0]}}
""")


def gyro_sympy():
    """(f(q, q'), M(q), K = −∂f/∂q, D = −∂f/∂q') of the same gyroscope, SymPy."""
    sm = pytest.importorskip("sympy")
    me = pytest.importorskip("sympy.physics.mechanics")
    p = GY
    q = me.dynamicsymbols("psi theta phi")
    u = me.dynamicsymbols("psi theta phi", 1)
    N = me.ReferenceFrame("N")
    O = N.orientnew("O", "Axis", [q[0], N.z])
    In = O.orientnew("In", "Axis", [q[1], O.x])
    R = In.orientnew("R", "Axis", [q[2], In.y])
    P0 = me.Point("P0")
    P0.set_vel(N, 0)
    Go = P0.locatenew("Go", 0)
    Gi = P0.locatenew("Gi", 0)
    Gr = P0.locatenew("Gr", p["l"] * In.y)
    for pt in (Go, Gi):
        pt.set_vel(N, 0)
    Gr.v2pt_theory(P0, N, In)
    bodies = [me.RigidBody("o", Go, O, 0.3, (me.inertia(O, *p["Io"]), Go)),
              me.RigidBody("i", Gi, In, 0.2, (me.inertia(In, *p["Ii"]), Gi)),
              me.RigidBody("r", Gr, R, p["m"], (me.inertia(R, p["A"], p["C"], p["A"]), Gr))]
    L = me.Lagrangian(N, *bodies)
    lm = me.LagrangesMethod(L, q, forcelist=[(Gr, -p["m"] * p["g"] * N.z)], frame=N)
    lm.form_lagranges_equations()
    x = sm.symbols("x0:6")
    subs = dict(zip([*u, *q], [x[3], x[4], x[5], x[0], x[1], x[2]], strict=True))
    f = me.msubs(lm.forcing, subs)
    M = me.msubs(lm.mass_matrix, subs)
    K = -f.jacobian(x[:3])
    D = -f.jacobian(x[3:])
    return [sm.lambdify(x, e, "numpy") for e in (f, M, K, D)]


def test_gyroscope_precessing_steadily():
    f, M, K, D = gyro_sympy()
    theta, spin = 0.35, 150.0
    # the precession rate that balances the pitch equation: f_theta is quadratic in it
    rates = np.array([-1.0, 0.0, 1.0])
    vals = [float(np.asarray(f(0, theta, 0, r, 0, spin), float).ravel()[1]) for r in rates]
    coef = np.polyfit(rates, vals, 2)
    roots = np.roots(coef)
    Omega = float(roots[np.argmin(np.abs(roots))].real)  # the slow precession
    x = (0.4, theta, 1.1, Omega, 0.0, spin)
    ref_f = np.asarray(f(*x), float).ravel()
    assert np.abs(ref_f).max() < 1e-12 * GY["m"] * GY["g"] * GY["l"]
    Mr, Kr, Dr = (np.asarray(F(*x), float) for F in (M, K, D))
    A = np.block([[np.zeros((3, 3)), np.eye(3)],
                  [-np.linalg.solve(Mr, Kr), -np.linalg.solve(Mr, Dr)]])
    ref = np.linalg.eigvals(A)
    ref = ref[np.abs(ref) > 1e-6 * np.abs(ref).max()]
    model = gyro_model()
    state = configure(model, {"yaw.angle": 0.4, "pitch.angle": theta, "spin.angle": 1.1},
                      {"yaw.angle": Omega, "spin.angle": spin})
    lin = linearize(model, state)
    assert lin.steady, lin.warnings
    assert set(lin.left_out) == {"yaw.angle", "spin.angle"}
    ours = lin.eigenvalues[np.abs(lin.eigenvalues) > 1e-6 * np.abs(lin.eigenvalues).max()]
    assert len(ours) == len(ref) == 2  # the nutation: ±i ω
    np.testing.assert_allclose(np.sort_complex(ours), np.sort_complex(ref), rtol=1e-9)
    np.testing.assert_allclose(lin.M, Mr, rtol=0, atol=1e-13 * np.abs(Mr).max())
    assert lin.stable
    assert lin.frequencies[0] == pytest.approx(abs(ref[0]), rel=1e-9)


# -- damping, and states that are not steady -------------------------------------------------


def test_spring_mass_damper():
    """2 kg on 800 N/m and 8 N s/m: ω = 20 rad/s, ζ = c / (2 √(k m)) = 0.1, about the
    static equilibrium the finder gives (the spring stretched by m g / k)."""
    model = mbody.load("models/spring_mass_damper.yaml")
    state = equilibrium(model)
    lin = linearize(model, state)
    assert lin.steady and lin.stable
    vertical = [m for m in lin.oscillations if abs(m.shape[1]) == 1.0]
    assert len(vertical) == 1
    assert vertical[0].frequency == pytest.approx(20.0, rel=1e-10)
    assert vertical[0].damping_ratio == pytest.approx(0.1, rel=1e-10)
    assert state.position[0, 1] == pytest.approx(-0.55 - 2 * 9.81 / 800, rel=1e-12)


def test_a_moving_pendulum_is_not_steady():
    model = mbody.load("models/double_pendulum.yaml")
    lin = mbody.linearize(model)
    assert not lin.steady and lin.stable is None
    assert any("not an equilibrium" in w for w in lin.warnings)


def test_an_inverted_pendulum_is_unstable():
    model = mbody.load("models/pendulum.yaml")
    up = equilibrium(model, start=configure(model, {"O.angle": 3.0}))
    lin = linearize(model, up)
    assert lin.steady and lin.stable is False
    assert [m.kind for m in lin.modes] == ["decay", "growth"] or \
        sorted(m.kind for m in lin.modes) == ["decay", "growth"]


def test_a_mode_played_follows_its_shape():
    """`animate --mode`'s motion: the coordinates of every frame are q0 + a Re(φ e^{λt})
    (to the 1e-12 of the Newton steps onto them), the rates their derivative."""
    from mbody.simulate.modes import mode_trajectory

    model = mbody.load("models/double_pendulum.yaml")
    lin = linearize(model, equilibrium(model))
    traj = mode_trajectory(lin, 2, periods=1, fps=30)
    mode, a = lin.modes[1], traj.info["amplitude"]
    q0 = lin.generalized.q
    for i in range(0, len(traj.t), 4):
        g = mbody.assemble(model, traj.state(i)).generalized()
        z = a * mode.shape * np.exp(mode.eigenvalue * traj.t[i])
        np.testing.assert_allclose(g.q, q0 + z.real, rtol=0, atol=1e-12)
        np.testing.assert_allclose(g.qdot, (mode.eigenvalue * z).real, rtol=0, atol=1e-12)
    assert traj.info["kind"] == "oscillation"
    assert abs(traj.t[-1] - mode.period) <= 1 / 30  # one period, at 30 frames a second
