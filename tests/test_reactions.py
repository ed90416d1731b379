"""Joint reactions solved with the accelerations: closed forms, hand derivations, and the
kinematic identities behind the constrained solve (Gᵀv = φ̇, Gᵀv̇ = γ)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from randmodels import planar_model, spatial_model
from scipy.spatial.transform import Rotation

import mbody
from mbody.equations.constraints import phi
from mbody.model import State

G0 = 9.81
ROOT = Path(__file__).resolve().parent.parent


def pendulum(theta: float, theta_dot: float, dimension: int, L: float = 1.2, m: float = 2.0,
             I_G: float = 0.3) -> dict:
    """A body pinned at the origin, mass centre at distance L/2 below the pin when θ = 0."""
    d = L / 2
    r = np.array([d * np.sin(theta), -d * np.cos(theta)])
    v = theta_dot * np.array([-r[1], r[0]])
    if dimension == 2:
        body = {"name": "rod", "mass": m, "inertia": I_G, "position": r.tolist(),
                "angle": theta, "velocity": v.tolist(), "angular_velocity": theta_dot}
        joint = {"name": "O", "type": "revolute", "parent": "ground", "child": "rod",
                 "at": [0, 0]}
        g = [0, -G0]
    else:
        body = {"name": "rod", "mass": m, "inertia": [I_G / 2, I_G, I_G],
                "position": [*r.tolist(), 0.0],
                "orientation": {"euler": [theta, 0, 0], "sequence": "ZYX"},
                "velocity": [*v.tolist(), 0.0], "angular_velocity": [0, 0, theta_dot]}
        joint = {"name": "O", "type": "revolute", "parent": "ground", "child": "rod",
                 "at": [0, 0, 0], "axis": [0, 0, 1]}
        g = [0, -G0, 0]
    return {"model": "pendulum", "dimension": dimension, "gravity": g, "bodies": [body],
            "joints": [joint]}


@settings(max_examples=30, deadline=None)
@given(theta=st.floats(-3.1, 3.1), theta_dot=st.floats(-8, 8), dimension=st.sampled_from([2, 3]))
def test_pendulum_pivot_reaction_any_angle_and_speed(theta, theta_dot, dimension):
    """α = −m g d sin θ / (I_G + m d²); R = m a_G − m g with a_G = α ẑ × r − θ̇² r."""
    m, I_G, L = 2.0, 0.3, 1.2
    d = L / 2
    sol = mbody.assemble(mbody.load(pendulum(theta, theta_dot, dimension))).solve()
    alpha = -m * G0 * d * np.sin(theta) / (I_G + m * d * d)
    r = np.array([d * np.sin(theta), -d * np.cos(theta)])
    a_G = alpha * np.array([-r[1], r[0]]) - theta_dot**2 * r
    R = m * a_G - m * np.array([0, -G0])
    acc = sol.as_dict()
    ang = "rod.theta" if dimension == 2 else "rod.w3"
    assert acc[ang] == pytest.approx(alpha, rel=1e-12, abs=1e-12)
    assert [acc["rod.x"], acc["rod.y"]] == pytest.approx(a_G, rel=1e-12, abs=1e-11)
    assert [sol.reactions["O.Fx"], sol.reactions["O.Fy"]] == pytest.approx(R, rel=1e-12,
                                                                          abs=1e-10)
    if dimension == 3:  # a plane motion about a principal axis needs no out-of-plane load
        for c in ("Fz", "Mx", "My"):
            assert sol.reactions[f"O.{c}"] == pytest.approx(0.0, abs=1e-10)
    assert sol.residual < 1e-14


def heavy_top(theta: float, omega3: float, *, m=1.5, A=0.02, C=0.035, l=0.1):
    """A symmetric top on a spherical joint at the origin in steady precession.

    With A_O = A + m l² (about the pivot), steady precession at tilt θ needs
    A_O cos θ Ω² − C ω₃ Ω + m g l = 0 (slow root). Returns (model dict, Ω, state facts).
    """
    A_O = A + m * l * l
    disc = (C * omega3) ** 2 - 4 * A_O * np.cos(theta) * m * G0 * l
    Omega = (C * omega3 - np.sqrt(disc)) / (2 * A_O * np.cos(theta))
    e3 = np.array([np.sin(theta), 0.0, np.cos(theta)])
    R = np.column_stack(([np.cos(theta), 0.0, -np.sin(theta)], [0.0, 1.0, 0.0], e3))
    z = np.array([0.0, 0.0, 1.0])
    psi_dot = omega3 - Omega * np.cos(theta)
    w_W = Omega * z + psi_dot * e3
    r = l * e3
    model = {"model": "heavy-top", "dimension": 3, "gravity": [0, 0, -G0],
             "bodies": [{"name": "top", "mass": m, "inertia": [A, A, C],
                         "position": r.tolist(),
                         "orientation": {"matrix": R.tolist()},
                         "velocity": np.cross(w_W, r).tolist(),
                         "angular_velocity": (R.T @ w_W).tolist()}],
             "joints": [{"name": "O", "type": "spherical", "parent": "ground",
                         "child": "top", "at": [0, 0, 0]}]}
    return model, Omega, R, w_W, r


@pytest.mark.parametrize("theta, omega3", [(0.3, 120.0), (0.8, 200.0), (1.2, 90.0)])
def test_heavy_top_steady_precession(theta, omega3):
    """In steady precession ω̇ = Ω ẑ × ω (world), a_G = Ω ẑ × (Ω ẑ × r), R = m a_G − m g."""
    m = 1.5
    model, Omega, R, w_W, r = heavy_top(theta, omega3, m=m)
    sol = mbody.assemble(mbody.load(model)).solve()
    z = np.array([0.0, 0.0, 1.0])
    acc = sol.accelerations
    a_G = np.cross(Omega * z, np.cross(Omega * z, r))
    assert acc[:3] == pytest.approx(a_G, abs=1e-9)
    assert acc[3:] == pytest.approx(R.T @ np.cross(Omega * z, w_W), rel=1e-9, abs=1e-9)
    reac = [sol.reactions[f"O.F{c}"] for c in "xyz"]
    assert reac == pytest.approx(m * a_G - m * np.array([0, 0, -G0]), rel=1e-9, abs=1e-9)


def test_heavy_top_precession_rate_holds_in_simulation():
    """Simulated from the steady state, the tilt stays put and the axis turns at Ω."""
    theta, omega3 = 0.5, 150.0
    model, Omega, *_ = heavy_top(theta, omega3)
    traj = mbody.simulate(mbody.load(model), t_end=0.5, fps=100)
    e3 = traj.position[:, 0, :] / np.linalg.norm(traj.position[:, 0, :], axis=1)[:, None]
    assert np.arccos(e3[:, 2]) == pytest.approx(np.full(len(e3), theta), abs=1e-6)
    azimuth = np.unwrap(np.arctan2(e3[:, 1], e3[:, 0]))
    assert azimuth[-1] - azimuth[0] == pytest.approx(Omega * 0.5, rel=1e-6)


def _advance(state: State, h: float) -> State:
    """The state after time h at constant v (world) and ω (body axes): v̇ = 0."""
    rot = Rotation.from_quat(state.quaternion, scalar_first=True)
    step = Rotation.from_rotvec(state.omega * h)
    return state.replace(position=state.position + h * state.velocity,
                         quaternion=(rot * step).as_quat(scalar_first=True))


def _jointed(seed: int, dim: int):
    """A random model with every joint type of `dim`, its initial state, and that state's
    velocities stacked in the model's coordinates (planar: rows x, y, θ)."""
    spec = (spatial_model(seed, n=4, n_joints=6, known=False) if dim == 3
            else planar_model(seed, n=4, n_joints=5, known=False))
    model = mbody.load(spec)
    s0 = model.initial
    sel = np.arange(6) if dim == 3 else np.array([0, 1, 5])
    return model, s0, np.concatenate((s0.velocity, s0.omega), axis=1)[:, sel].ravel()


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("dim", [2, 3])
def test_gamma_is_minus_gdot_transpose_v(seed, dim):
    """d/dt (Gᵀ v) along a path with v̇ = 0 equals −γ (central differences, h = 1e-5)."""
    model, s0, v = _jointed(seed, dim)
    jac = mbody.assemble(model, s0).jacobian()
    h = 1e-5

    def gtv(state):
        return mbody.assemble(model, state).G.T @ v

    deriv = (gtv(_advance(s0, h)) - gtv(_advance(s0, -h))) / (2 * h)
    assert deriv == pytest.approx(-jac.gamma, rel=1e-6, abs=1e-6)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("dim", [2, 3])
def test_phi_rate_is_g_transpose_v(seed, dim):
    """At the assembled pose φ = 0 and dφ/dt = Gᵀ v for every joint type."""
    model, s0, v = _jointed(seed, dim)
    assert phi(model, s0) == pytest.approx(0.0, abs=1e-12)
    h = 1e-6
    rate = (phi(model, _advance(s0, h)) - phi(model, _advance(s0, -h))) / (2 * h)
    assert rate == pytest.approx(mbody.assemble(model, s0).G.T @ v, rel=1e-6, abs=1e-7)


@pytest.mark.parametrize("seed", range(4))
def test_constrained_solution_satisfies_both_block_rows(seed):
    """M v̇ + b = Q + G λ and Gᵀ v̇ = γ hold for the solved (v̇, λ); third law per joint."""
    spec = spatial_model(seed, n=5, n_joints=4, known=False,
                         joint_types=("revolute", "spherical", "universal", "cylindrical"))
    rng = np.random.default_rng(seed)
    for k, j in enumerate(spec["joints"]):  # a tree: joint k holds body k+1 to an earlier one
        j["child"] = f"b{k + 1}"
        j["parent"] = str(rng.choice(["ground"] + [f"b{i}" for i in range(k + 1)]))
    model = mbody.load(spec)
    asm = mbody.assemble(model)
    sol = asm.solve()
    lam = np.array([sol.reactions[r] for r in asm.reactions])
    a = sol.accelerations
    assert asm.M @ a + asm.b == pytest.approx(asm.Q + asm.G @ lam, rel=1e-9, abs=1e-9)
    assert asm.G.T @ a == pytest.approx(asm.jacobian().gamma, rel=1e-9, abs=1e-9)
    assert sol.residual < 1e-13
    assert not sol.not_unique and sol.redundant == 0
    # The random velocities break the joints, and the solution says so by name.
    assert sol.broken_joints and all("G^T v" in b for b in sol.broken_joints[:-1])
    assert sol.broken_joints[-1] == "8 more"  # 16 components broken, 8 described
    assert [w for w in sol.warnings if "breaks" in w] == sol.warnings


def test_inconsistent_redundant_constraints_are_reported():
    """Two joints between the same bodies, velocities that break them: no exact solution
    exists; the least-squares answer comes with a warning, never silently."""
    spec = spatial_model(0, n=5, n_joints=4, known=False,
                         joint_types=("revolute", "spherical", "universal", "cylindrical"))
    sol = mbody.assemble(mbody.load(spec)).solve()
    assert sol.not_unique
    assert sol.residual > 1e-6
    assert any("inconsistent" in w for w in sol.warnings)


def slider_crank_model(theta, omega, r=0.1, L=0.3, m=(0.5, 1.2, 0.8), I=(5e-4, 9e-3)):
    """Crank OA (pin at O), rod AB, slider B on a horizontal guide; gravity −y."""
    A = r * np.array([np.cos(theta), np.sin(theta)])
    phi_ = np.arcsin(-A[1] / L)  # rod angle, slider on y = 0
    B = A + L * np.array([np.cos(phi_), np.sin(phi_)])
    # Velocities: crank ω; rod ω₂ from the slider staying on y = 0.
    vA = omega * np.array([-A[1], A[0]])
    w2 = -vA[1] / (L * np.cos(phi_))
    vB = vA + w2 * np.array([-(B - A)[1], (B - A)[0]])
    g1, g2 = A / 2, (A + B) / 2
    v1 = omega * np.array([-g1[1], g1[0]])
    v2 = vA + w2 * np.array([-(g2 - A)[1], (g2 - A)[0]])
    spec = {"model": "slider-crank", "dimension": 2, "gravity": [0, -G0],
            "bodies": [
                {"name": "crank", "mass": m[0], "inertia": I[0], "position": g1.tolist(),
                 "angle": theta, "velocity": v1.tolist(), "angular_velocity": omega},
                {"name": "rod", "mass": m[1], "inertia": I[1], "position": g2.tolist(),
                 "angle": phi_, "velocity": v2.tolist(), "angular_velocity": w2},
                {"name": "slider", "mass": m[2], "inertia": 1e-4, "position": B.tolist(),
                 "velocity": vB.tolist()}],
            "loads": [{"name": "P", "type": "force", "body": "slider", "force": [-40.0, 0]}],
            "joints": [
                {"name": "O", "type": "revolute", "parent": "ground", "child": "crank",
                 "at": [0, 0]},
                {"name": "A", "type": "revolute", "parent": "crank", "child": "rod",
                 "at": A.tolist()},
                {"name": "B", "type": "revolute", "parent": "rod", "child": "slider",
                 "at": B.tolist()},
                {"name": "S", "type": "prismatic", "parent": "ground", "child": "slider",
                 "at": B.tolist(), "axis": [1, 0]}]}
    return spec, dict(A=A, B=B, g1=g1, g2=g2, w2=w2, phi=phi_)


@pytest.mark.parametrize("theta, omega", [(0.7, 0.0), (2.0, 15.0), (-1.0, -30.0)])
def test_slider_crank_pin_forces_by_hand(theta, omega):
    """Each body's Newton-Euler pair written by hand from its free-body diagram, with the
    kinematic relations a_A = α₁ ẑ×A − ω²A etc., solved as one linear system."""
    m, I = (0.5, 1.2, 0.8), (5e-4, 9e-3)
    spec, k = slider_crank_model(theta, omega, m=m, I=I)
    A, B, g1, g2, w2 = k["A"], k["B"], k["g1"], k["g2"], k["w2"]

    def perp(u):
        return np.array([-u[1], u[0]])

    def cross2(u, f):
        return u[0] * f[1] - u[1] * f[0]

    # Unknowns x = [α1, α2, aB, Ox, Oy, Ax, Ay, Bx, By, N, Ms]  (forces on the child)
    # Accelerations of mass centres in terms of α1, α2 (plus velocity terms):
    #   a_g1 = α1 ẑ×g1 − ω² g1;  a_A = α1 ẑ×A − ω² A
    #   a_g2 = a_A + α2 ẑ×(g2−A) − ω2² (g2−A);  a_B = a_A + α2 ẑ×(B−A) − ω2² (B−A)
    # and the slider keeps a_B,y = 0, α3 = 0.
    rows, rhs = [], []
    g = np.array([0, -G0])

    def lin(alpha1=(0, 0), alpha2=(0, 0), const=(0, 0)):
        return np.array(alpha1), np.array(alpha2), np.array(const)

    aG1 = lin(perp(g1), (0, 0), -omega**2 * g1)
    aA = lin(perp(A), (0, 0), -omega**2 * A)
    aG2 = lin(aA[0], perp(g2 - A), aA[2] - w2**2 * (g2 - A))
    aBk = lin(aA[0], perp(B - A), aA[2] - w2**2 * (B - A))
    for comp in (0, 1):
        # crank: m1 a_g1 = O + (−A) + m1 g
        row = np.zeros(11)
        row[0], row[1] = m[0] * aG1[0][comp], m[0] * aG1[1][comp]
        row[3 + comp] -= 1.0
        row[5 + comp] += 1.0
        rows.append(row)
        rhs.append(m[0] * g[comp] - m[0] * aG1[2][comp])
        # rod: m2 a_g2 = A + (−B) + m2 g
        row = np.zeros(11)
        row[0], row[1] = m[1] * aG2[0][comp], m[1] * aG2[1][comp]
        row[5 + comp] -= 1.0
        row[7 + comp] += 1.0
        rows.append(row)
        rhs.append(m[1] * g[comp] - m[1] * aG2[2][comp])
    # slider: m3 aB_x = Bx − 40 ; m3·0 = By + N + m3 g_y ; 0 = Ms (no rotation, moments at B)
    row = np.zeros(11)
    row[2], row[7] = m[2], -1.0
    rows.append(row)
    rhs.append(-40.0)
    row = np.zeros(11)
    row[8], row[9] = 1.0, 1.0
    rows.append(row)
    rhs.append(-m[2] * g[1])
    row = np.zeros(11)
    row[10] = 1.0
    rows.append(row)
    rhs.append(0.0)
    # crank Euler about g1: I1 α1 = (O−g1)×O + (A−g1)×(−A)
    row = np.zeros(11)
    row[0] = I[0]
    row[3], row[4] = -cross2(-g1, [1, 0]), -cross2(-g1, [0, 1])
    row[5], row[6] = cross2(A - g1, [1, 0]), cross2(A - g1, [0, 1])
    rows.append(row)
    rhs.append(0.0)
    # rod Euler about g2: I2 α2 = (A−g2)×A + (B−g2)×(−B)
    row = np.zeros(11)
    row[1] = I[1]
    row[5], row[6] = -cross2(A - g2, [1, 0]), -cross2(A - g2, [0, 1])
    row[7], row[8] = cross2(B - g2, [1, 0]), cross2(B - g2, [0, 1])
    rows.append(row)
    rhs.append(0.0)
    # kinematics: aB_x (unknown) equals the chain's; aB_y = 0
    row = np.zeros(11)
    row[0], row[1], row[2] = aBk[0][0], aBk[1][0], -1.0
    rows.append(row)
    rhs.append(-aBk[2][0])
    row = np.zeros(11)
    row[0], row[1] = aBk[0][1], aBk[1][1]
    rows.append(row)
    rhs.append(-aBk[2][1])
    x = np.linalg.solve(np.array(rows), np.array(rhs))

    sol = mbody.assemble(mbody.load(spec)).solve()
    acc = sol.as_dict()
    assert acc["crank.theta"] == pytest.approx(x[0], rel=1e-9, abs=1e-9)
    assert acc["rod.theta"] == pytest.approx(x[1], rel=1e-9, abs=1e-9)
    assert acc["slider.x"] == pytest.approx(x[2], rel=1e-9, abs=1e-9)
    got = [sol.reactions[k] for k in ("O.Fx", "O.Fy", "A.Fx", "A.Fy", "B.Fx", "B.Fy",
                                      "S.Fy", "S.Mz")]
    assert got == pytest.approx(x[3:], rel=1e-9, abs=1e-9)


def fourbar(dimension: int) -> dict:
    """A planar four-bar (ground link 0.4 m), written planar or with spatial revolutes."""
    O, A, B, C = (np.array(p, float) for p in ([0, 0], [0.1, 0.2], [0.42, 0.28], [0.4, 0]))
    links = [("crank", O, A), ("coupler", A, B), ("rocker", C, B)]
    bodies = []
    for name, p, q in links:
        L = float(np.linalg.norm(q - p))
        ang = float(np.arctan2(*(q - p)[::-1]))
        g = ((p + q) / 2).tolist()
        if dimension == 2:
            bodies.append({"name": name, "mass": 1.0, "inertia": L * L / 12, "position": g,
                           "angle": ang})
        else:
            bodies.append({"name": name, "mass": 1.0, "inertia": [1e-4, L * L / 12, L * L / 12],
                           "position": [*g, 0.0],
                           "orientation": {"euler": [ang, 0, 0], "sequence": "ZYX"}})
    pins = [("O", "ground", "crank", O), ("A", "crank", "coupler", A),
            ("B", "coupler", "rocker", B), ("C", "ground", "rocker", C)]
    joints = []
    for name, par, ch, p in pins:
        j = {"name": name, "type": "revolute", "parent": par, "child": ch,
             "at": p.tolist() if dimension == 2 else [*p.tolist(), 0.0]}
        if dimension == 3:
            j["axis"] = [0, 0, 1]
        joints.append(j)
    g = [0, -G0] if dimension == 2 else [0, -G0, 0]
    return {"model": f"fourbar-{dimension}d", "dimension": dimension, "gravity": g,
            "bodies": bodies, "joints": joints,
            "loads": [{"name": "drive", "type": "torque", "body": "crank",
                       "torque": 2.0 if dimension == 2 else [0, 0, 2.0]}]}


def test_redundant_fourbar_minimum_norm_and_named():
    """The spatial four-bar has 20 reaction components but 18 − 1 = 17 independent
    constraints... its in-plane motion equals the planar four-bar's, the reactions that
    are not unique are named, and the minimum-norm solution is returned."""
    planar = mbody.assemble(mbody.load(fourbar(2))).solve()
    asm3 = mbody.assemble(mbody.load(fourbar(3)))
    spatial = asm3.solve()
    p, s = planar.as_dict(), spatial.as_dict()
    for body in ("crank", "coupler", "rocker"):
        assert s[f"{body}.x"] == pytest.approx(p[f"{body}.x"], rel=1e-9, abs=1e-9)
        assert s[f"{body}.y"] == pytest.approx(p[f"{body}.y"], rel=1e-9, abs=1e-9)
        assert s[f"{body}.w3"] == pytest.approx(p[f"{body}.theta"], rel=1e-9, abs=1e-9)
        assert s[f"{body}.z"] == pytest.approx(0.0, abs=1e-9)
    assert spatial.not_unique, "redundant constraints must be reported"
    assert spatial.warnings and "not unique" in spatial.warnings[0]
    # The in-plane pin forces are unique and agree with the planar model.
    for pin in "OABC":
        for c in ("Fx", "Fy"):
            assert spatial.reactions[f"{pin}.{c}"] == pytest.approx(
                planar.reactions[f"{pin}.{c}"], rel=1e-8, abs=1e-8)
    assert all(lab.split(".")[1] in ("Fz", "Mx", "My") for lab in spatial.not_unique)
    # Minimum norm: no other solution of the same system has a smaller norm.
    lam = np.array([spatial.reactions[r] for r in asm3.reactions])
    G = asm3.G.toarray()
    null = np.linalg.svd(G)[2][np.linalg.matrix_rank(G):]
    assert np.abs(null @ lam).max() < 1e-8


OMEGA = np.array([0.3, -0.2, 0.1])
"""The hanging chain turns as one rigid body about its top pin (a state its joints allow)."""


def chain(n: int, L: float = 0.1) -> dict:
    bodies, joints = [], []
    for i in range(n):
        x = np.array([0.0, 0.0, -L * (i + 0.5)])
        bodies.append({"name": f"l{i}", "mass": 1.0, "inertia": [1e-3, 1e-3, 2e-4],
                       "position": x.tolist(), "angular_velocity": OMEGA.tolist(),
                       "velocity": np.cross(OMEGA, x).tolist()})  # turning as one rigid body
        joints.append({"name": f"j{i}", "type": "spherical",
                       "parent": "ground" if i == 0 else f"l{i - 1}", "child": f"l{i}",
                       "at": [0.0, 0.0, -L * i]})
    return {"model": f"chain-{n}", "dimension": 3, "gravity": [0, 0, -G0], "bodies": bodies,
            "joints": joints}


@pytest.mark.parametrize("n", [5, 400, 2000])
def test_long_chain_backward_error_and_statics(n):
    """At rest (ω along the links' own axes aside), a hanging chain's pin j carries the
    weight of the links below it; large solves are judged by backward error."""
    turning = mbody.assemble(mbody.load(chain(n))).solve()
    assert turning.residual <= 1e-12 and not turning.broken_joints
    spec = chain(n)
    for b in spec["bodies"]:
        b["angular_velocity"] = b["velocity"] = [0.0, 0.0, 0.0]
    sol = mbody.assemble(mbody.load(spec)).solve(condition=True)
    assert sol.residual <= 1e-12 and not sol.broken_joints
    assert sol.condition is not None and sol.condition > 1
    Fz = np.array([sol.reactions[f"j{i}.Fz"] for i in range(n)])
    assert Fz == pytest.approx(G0 * (n - np.arange(n)), rel=1e-9)
    assert np.abs(sol.accelerations).max() < 1e-9 * n


@pytest.mark.parametrize("seed", [0, 1])
def test_large_random_trees_solve_their_equations(seed):
    """A random tree of 120 bodies with full inertia tensors and every joint type (over
    300 unknowns, a banded Schur complement): the solve satisfies M v̇ + b = Q + G λ and
    Gᵀ v̇ = γ, with the sparse matrices the assembly gives, to rounding."""
    types = ("revolute", "prismatic", "cylindrical", "universal", "spherical", "fixed")
    spec = spatial_model(seed, n=120, n_joints=119, n_forces=40, n_torques=10,
                         n_springs=5, known=False, joint_types=types)
    rng = np.random.default_rng(seed)
    for k, j in enumerate(spec["joints"]):  # a tree
        j["child"] = f"b{k + 1}"
        j["parent"] = str(rng.choice(["ground"] + [f"b{i}" for i in range(max(0, k - 3),
                                                                          k + 1)]))
    model = mbody.load(spec)
    assert model.minv6 is None  # full inertia tensors: the non-diagonal M⁻¹ branch
    asm = mbody.assemble(model)
    sol = asm.solve()
    assert sol.method.startswith("banded Cholesky") and len(sol.solved) > 300
    lam = np.array([sol.reactions[r] for r in model.reactions])
    a = sol.accelerations
    newton = asm.M @ a + asm.b - asm.Q - asm.G @ lam
    scale = (abs(asm.M) @ np.abs(a) + np.abs(asm.b) + np.abs(asm.Q)
             + abs(asm.G) @ np.abs(lam)).max()
    assert np.abs(newton).max() <= 1e-12 * scale
    held = asm.G.T @ a - asm.jacobian().gamma
    assert np.abs(held).max() <= 1e-12 * (abs(asm.G.T) @ np.abs(a)).max()
    assert sol.residual < 1e-14


def _estimated(asm: mbody.Assembly, monkeypatch) -> float:
    """The condition of S through the sparse estimate, whatever the size."""
    from mbody.equations import assemble as assemble_module

    with monkeypatch.context() as m:
        m.setattr(assemble_module, "DENSE_CONDITION", 0)
        sol = mbody.assemble(asm.model, asm.state).solve(condition=True)
    assert sol.condition is not None
    return sol.condition


@pytest.mark.parametrize("spec", [
    *(spatial_model(seed, n=4, n_joints=4, known=False) for seed in range(3)),
    *(planar_model(seed, n=4, n_joints=3, known=False) for seed in range(3)),
    ROOT / "models" / "point_pendulum.yaml", ROOT / "models" / "spherical_pendulum.yaml",
    ROOT / "models" / "slider_crank.yaml", chain(12)], ids=lambda s: getattr(s, "stem", None))
def test_the_condition_estimate_is_the_exact_figure_of_small_systems(spec, monkeypatch):
    """Above `DENSE_CONDITION` unknowns the 1-norm condition of S = G_Uᵀ M⁻¹ G_U is
    estimated with M⁻¹ made block by block (particles among the bodies too): Hager and
    Higham's estimator gives a lower bound of each norm, in practice within a factor of 3
    and usually exact, so against the dense figure it is at most it and not below a third
    (9 for the two norms' product)."""
    asm = mbody.assemble(mbody.load(spec))
    exact = asm.solve(condition=True).condition
    assert exact is not None
    if math.isinf(exact):  # redundant constraints: both say singular
        assert math.isinf(_estimated(asm, monkeypatch))
        return
    estimate = _estimated(asm, monkeypatch)
    assert exact / 9 <= estimate <= exact * (1 + 1e-9)


def test_the_mass_inverse_inverts_each_bodys_block():
    from mbody.equations.assemble import mass_inverse, mass_matrix

    for spec in (spatial_model(4, n=5), planar_model(4, n=5),
                 ROOT / "models" / "point_pendulum.yaml"):
        model = mbody.load(spec)
        rows = model.rows
        product = (mass_inverse(model).tocsr()[rows][:, rows] @ mass_matrix(model)).toarray()
        assert product == pytest.approx(np.eye(len(rows)), abs=1e-12)
