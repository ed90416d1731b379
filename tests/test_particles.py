"""Particles (point masses, `inertia: 0`): translation rows only, joints that hold their
position (a pin) or their distance (a rigid link, reaction T), the exact pendulum
motions, both evaluation paths equal, labels and exports, and the validation errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipj, ellipk

import mbody
from mbody.model import State

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
GRAVITY = 9.81


def both(model, state=None):
    """The solution at the state (one compiled core: once the numpy and the numba path,
    held equal here; today's results are tests/test_golden.py)."""
    return (mbody.assemble(model, state).solve(),)


def rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))


# -- planar point pendulum: the exact elliptic solution --------------------------------------
def pendulum_exact(t: np.ndarray, theta0: float, L: float) -> np.ndarray:
    """θ(t) released from rest at θ0 (from the downward vertical):
    sin(θ/2) = k sn(K(k) − ω0 t | k²), k = sin(θ0/2), ω0 = √(g/L) (at t = 0 sn(K) = 1)."""
    k = np.sin(theta0 / 2)
    sn = ellipj(ellipk(k * k) - np.sqrt(GRAVITY / L) * t, k * k)[0]
    return 2 * np.arcsin(k * sn)


def test_point_pendulum_matches_the_elliptic_solution():
    model = mbody.load(MODELS / "point_pendulum.yaml")
    traj = mbody.simulate(model, 10.0, 100, rtol=1e-12, atol=1e-12)
    th = pendulum_exact(traj.t, np.radians(30), 1.0)
    exact = np.stack((np.sin(th), -np.cos(th)), axis=1)
    err = np.abs(traj.position[:, 0, :2] - exact).max()
    assert err < 1e-9, err
    # a particle never turns: no spurious rotation, and no extra steps for it
    assert np.all(traj.angular_velocity == 0.0) and np.all(traj.orientation == 0.0)


def test_point_pendulum_default_tolerances_need_no_more_steps_than_the_exact_ode():
    """A particle costs the integrator nothing beyond its motion (a tiny inertia used to
    make the problem stiff): at the default tolerances the steps are within 5 % of DOP853's
    on the exact Cartesian equations a = g + λ r, λ = −(r·g + |v|²)/|r|², in mbody's own
    state layout. (A rigid bob of inertia 1e-3 kg m² is another pendulum, with another
    period, and is no yardstick: 134 steps against the particle's 141.)"""
    import scipy.integrate

    from mbody.simulate import DEFAULT_ATOL, DEFAULT_RTOL

    point = mbody.load(MODELS / "point_pendulum.yaml")
    a = mbody.simulate(point, 10.0, 30)
    s0 = point.initial
    theta0 = 2.0 * np.arctan2(s0.quaternion[:, 3], s0.quaternion[:, 0])
    y0 = np.concatenate((s0.position.ravel(), s0.quaternion.ravel(), s0.velocity.ravel(),
                         s0.omega.ravel(), theta0))
    g = np.array([0.0, -GRAVITY, 0.0])

    def f(t, y):
        r, v = y[:3], y[7:10]  # the pivot O is at the origin
        d = np.zeros_like(y)
        d[:3] = v
        d[7:10] = g - (r @ g + v @ v) / (r @ r) * r
        return d

    solver = scipy.integrate.DOP853(f, 0.0, y0, 10.0, rtol=DEFAULT_RTOL, atol=DEFAULT_ATOL)
    ideal = 0
    while solver.status == "running":
        solver.step()
        ideal += 1
    assert a.info["steps"] <= 1.05 * ideal, (a.info["steps"], ideal)


@pytest.mark.parametrize("theta, rate", [(0.7, 1.3), (-2.5, -0.4), (0.0, 3.0)])
def test_tension_is_m_g_cos_plus_m_L_thetadot_squared(theta, rate):
    model = mbody.load(MODELS / "point_pendulum.yaml")
    L, m = 1.0, 1.0
    pos = L * np.array([[np.sin(theta), -np.cos(theta)]])
    vel = L * rate * np.array([[np.cos(theta), np.sin(theta)]])
    state = State.planar(pos, np.zeros(1), vel, np.zeros(1))
    exact = m * (GRAVITY * np.cos(theta) + L * rate ** 2)
    for sol in both(model, state):
        assert abs(sol.reactions["O.T"] - exact) <= 1e-12 * abs(exact)
        # a = −g sinθ along the path + centripetal L θ̇² toward the pivot
        a = (-GRAVITY * np.sin(theta) * np.array([np.cos(theta), np.sin(theta)])
             + L * rate ** 2 * np.array([-np.sin(theta), np.cos(theta)]))
        np.testing.assert_allclose(sol.accelerations, a, rtol=0, atol=1e-12 * 20)


# -- spatial spherical pendulum: energy and vertical angular momentum --------------------------
def test_spherical_pendulum_conserves_energy_and_vertical_angular_momentum():
    model = mbody.load(MODELS / "spherical_pendulum.yaml")
    traj = mbody.simulate(model, 10.0, 100, rtol=1e-12, atol=1e-12)
    x, v = traj.position[:, 0], traj.velocity[:, 0]
    Hz = x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]
    E = 0.5 * np.einsum("ij,ij->i", v, v) + GRAVITY * x[:, 2]
    assert np.abs(Hz / Hz[0] - 1).max() < 1e-9
    assert np.abs(E / E[0] - 1).max() < 1e-9
    assert np.abs(np.linalg.norm(x, axis=1) - 1.0).max() < 1e-9
    assert traj.info["energy_drift"] < 1e-9
    # the bob really swings around (not a plane pendulum): more than a full turn of azimuth
    phi = np.unwrap(np.arctan2(x[:, 1], x[:, 0]))
    assert phi[-1] - phi[0] > 2 * np.pi
    assert np.all(traj.angular_velocity == 0.0)


def test_spherical_pendulum_start():
    model = mbody.load(MODELS / "spherical_pendulum.yaml")
    assert model.coordinates == ["bob.x", "bob.y", "bob.z"] and model.reactions == ["O.T"]
    sol = mbody.assemble(model).solve()
    c = np.sqrt(0.5)
    T = GRAVITY * c + 1.5 ** 2
    assert sol.reactions["O.T"] == pytest.approx(T, rel=1e-12)
    np.testing.assert_allclose(sol.accelerations, [-T * c, 0, T * c - GRAVITY], atol=1e-12)


# -- pins, links, particle parents; the two paths ---------------------------------------------
ROD = """
model: rod-and-bob
dimension: 2
gravity: [0, -9.81]
bodies:
  - {name: rod, mass: 3.0, inertia: 0.25, position: [0.5, 0]}
  - {name: bob, mass: 2.0, inertia: 0, position: [1.0, 0]}
joints:
  - {name: A, type: revolute, parent: ground, child: rod, at: [0, 0]}
  - {name: B, type: revolute, parent: PARENT, child: CHILD, at: [1.0, 0]}
"""


@pytest.mark.parametrize("swap", [False, True])
def test_particle_pinned_to_the_end_of_a_rod(swap):
    """A horizontal rod (M 3 kg, l 1 m, I_G 0.25) pinned at one end, a 2 kg particle pinned
    at the other, released from rest: one rigid pendulum with I_O = I_G + M (l/2)² + m l²,
    α = −(M l/2 + m l) g / I_O; the pin's force on the bob is m (a − g), a = (0, α l)."""
    text = ROD.replace("PARENT", "bob" if swap else "rod").replace("CHILD",
                                                                    "rod" if swap else "bob")
    model = mbody.loads(text)
    assert model.reactions == ["A.Fx", "A.Fy", "B.Fx", "B.Fy"]
    assert model.coordinates == ["rod.x", "rod.y", "rod.theta", "bob.x", "bob.y"]
    asm = mbody.assemble(model)
    assert asm.M.shape == (5, 5) and asm.G.shape == (5, 4) and asm.Q.shape == (5,)
    np.testing.assert_array_equal(asm.M.toarray(), np.diag([3, 3, 0.25, 2, 2]))
    M_, m, l = 3.0, 2.0, 1.0
    alpha = -(M_ * l / 2 + m * l) * GRAVITY / (0.25 + M_ * (l / 2) ** 2 + m * l ** 2)
    on_bob = np.array([0.0, m * (alpha * l + GRAVITY)])
    sign = -1.0 if swap else 1.0  # +R acts on the child
    for sol in both(model):
        np.testing.assert_allclose(sol.accelerations,
                                   [0, alpha * l / 2, alpha, 0, alpha * l], atol=1e-12)
        np.testing.assert_allclose([sol.reactions["B.Fx"], sol.reactions["B.Fy"]],
                                   sign * on_bob, atol=1e-12)


DOUBLE = """
model: double-point-pendulum
dimension: 2
gravity: [0, -9.81]
bodies:
  - {name: m1, mass: 1.0, inertia: 0, position: [0.6, -0.8], velocity: [0.8, 0.6]}
  - {name: m2, mass: 0.5, inertia: 0, position: [1.6, -0.8], velocity: [0.8, -0.4]}
joints:
  - {name: A, type: revolute, parent: ground, child: m1, at: [0, 0]}
  - {name: B, type: revolute, parent: m1, child: m2, at: [0.6, -0.8]}
"""

SPATIAL_LINK = """
model: bob-on-a-turning-arm
dimension: 3
gravity: [0, 0, -9.81]
bodies:
  - {name: arm, mass: 2.0, inertia: [0.1, 0.2, 0.25], position: [0.3, 0, 0],
     angular_velocity: [0, 0, 1.5], velocity: [0, 0.45, 0]}
  - {name: bob, mass: 0.5, inertia: [[0, 0, 0], [0, 0, 0], [0, 0, 0]],
     position: [0.6, 0.4, 0], velocity: [-0.6, 0.9, 0.4]}
  - {name: ball, mass: 0.3, inertia: 0, position: [0.6, 0.4, -0.5], velocity: [-0.3, 0.9, 0.4]}
joints:
  - {name: A, type: revolute, parent: ground, child: arm, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: B, type: revolute, parent: arm, child: bob, at: [0.6, 0, 0], axis: [1, 0, 0]}
  - {name: C, type: spherical, parent: bob, child: ball, at: [0.6, 0.4, 0]}
"""


def test_link_components():
    m = mbody.loads(DOUBLE)
    assert m.reactions == ["A.T", "B.T"] and m.coordinates == ["m1.x", "m1.y", "m2.x", "m2.y"]
    s = mbody.loads(SPATIAL_LINK)
    assert s.reactions == ["A.Fx", "A.Fy", "A.Fz", "A.Mx", "A.My", "B.T", "B.Fz", "C.T"]
    assert s.coordinates[6:] == ["bob.x", "bob.y", "bob.z", "ball.x", "ball.y", "ball.z"]


@pytest.mark.parametrize("text", [DOUBLE, SPATIAL_LINK], ids=["double", "spatial_link"])
def test_links_solve_cleanly_along_a_run(text):
    model = mbody.loads(text)
    rng = np.random.default_rng(3)
    states = [model.initial]
    for _ in range(3):  # move off the initial state along a short simulation
        traj = mbody.simulate(model, rng.uniform(0.05, 0.5), 50)
        states.append(traj.state(len(traj.t) - 1))
    for state in states:
        (a,) = both(model, state)
        assert np.all(np.isfinite(a.accelerations)) and not a.warnings


@pytest.mark.parametrize("text", [DOUBLE, SPATIAL_LINK], ids=["double", "spatial_link"])
def test_links_conserve_energy_and_keep_their_lengths(text):
    """γ of a link is right (else energy drifts and the lengths creep): a double point
    pendulum (a particle as a parent) and a bob on a revolute link carried by a turning
    arm (a rotating parent) with a ball on a string below it."""
    model = mbody.loads(text)
    traj = mbody.simulate(model, 5.0, 50, rtol=1e-11, atol=1e-12)
    assert traj.info["energy_drift"] < 1e-8, traj.info["energy_drift"]
    assert traj.info["joint_position_drift"] < 1e-8
    if text is SPATIAL_LINK:
        assert np.all(traj.angular_velocity[:, 1:] == 0.0)  # the particles never turn


# -- validation ---------------------------------------------------------------------------------
BAD = {
    "torque": ("loads:\n  - {name: twist, type: torque, body: bob, torque: 1.0}\n",
               "a torque cannot act on the particle 'bob'", "loads[0].type"),
    "offset force": ("loads:\n  - {name: push, type: force, body: bob, force: [1, 0], "
                     "at: [0.1, 0]}\n", "acts at the particle", "loads[0].at"),
    "prismatic": ("  - {name: P, type: prismatic, parent: ground, child: bob, at: [0, 0], "
                  "axis: [1, 0]}\n", "a prismatic joint cannot connect the particle 'bob'",
                  "joints[1].type"),
}
BASE = """model: bad
dimension: 2
gravity: [0, -9.81]
bodies:
  - name: bob
    mass: 1.0
    inertia: 0
    position: [0.5, -0.8660254037844386]
joints:
  - {name: O, type: revolute, parent: ground, child: bob, at: [0, 0]}
"""


def run_cli(*args) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "MBODY_DEBUG"}
    return subprocess.run([sys.executable, "-m", "mbody.cli", *map(str, args)], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=300)


def _bad_text(case: str) -> str:
    extra = BAD[case][0]
    return BASE + extra if extra.startswith("  -") else BASE + extra


@pytest.mark.parametrize("case", sorted(BAD))
def test_forbidden_particle_inputs(tmp_path, case):
    path = tmp_path / "bad.yaml"
    path.write_text(_bad_text(case))
    with pytest.raises(mbody.ModelError) as err:
        mbody.load(path)
    (issue,) = err.value.issues
    _, words, key = BAD[case]
    assert words in issue.message and issue.key == key
    assert f"{path}:{issue.line}:{issue.column}: " in str(err.value)
    p = run_cli("check", path)
    assert p.returncode != 0 and "Traceback" not in p.stderr + p.stdout
    assert p.stderr.startswith("mbody: ") and f"bad.yaml:{issue.line}:{issue.column}" in p.stderr


def test_particle_has_no_angular_velocity_or_angle(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(BASE.replace("    inertia: 0\n", "    inertia: 0\n    angular_velocity: 2\n"
                                 "    angle: 10 deg\n"))
    with pytest.raises(mbody.ModelError) as err:
        mbody.load(path)
    keys = sorted(i.key for i in err.value.issues)
    assert keys == ["bodies[0].angle", "bodies[0].angular_velocity"]
    assert all("particle" in i.message and i.line > 0 and i.column > 0
               for i in err.value.issues)
    p = run_cli("check", path)
    assert p.returncode != 0 and "Traceback" not in p.stderr
    # zero is fine
    mbody.loads(BASE.replace("    inertia: 0\n", "    inertia: 0\n    angular_velocity: 0\n"))


def test_two_particles_need_the_joint_point_at_one_of_them():
    text = DOUBLE.replace("at: [0.6, -0.8]}", "at: [1.0, -0.8]}")
    with pytest.raises(mbody.ModelError, match="must be at one of them"):
        mbody.loads(text)


def test_spatial_particle_inertia_forms():
    for form in ("0", "[0, 0, 0]", "[[0, 0, 0], [0, 0, 0], [0, 0, 0]]"):
        m = mbody.loads(f"dimension: 3\nbodies:\n  - {{name: p, mass: 2, inertia: {form}}}\n")
        assert m.coordinates == ["p.x", "p.y", "p.z"] and m.bodies["p"].particle


# -- the command line on the shipped models ------------------------------------------------------
@pytest.mark.parametrize("name", ["point_pendulum", "spherical_pendulum"])
def test_cli_on_particle_models(tmp_path, name):
    path = MODELS / f"{name}.yaml"
    p = run_cli("solve", path, "--json")
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert list(out["reactions"]) == ["O.T"] and out["reactions"]["O.T"] > 0
    assert all(not c.endswith(("theta", "w1", "w2", "w3")) for c in out["coordinates"])
    run = tmp_path / "run.npz"
    p = run_cli("simulate", path, "--t-end", "2", "-o", run)
    assert p.returncode == 0, p.stderr
    assert run.exists()
    p = run_cli("fbd", path, "-o", tmp_path / "fbd")
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "fbd" / "fbd_bob.svg").exists()
    for suffix in (".npz", ".json", ".mat"):
        out_file = tmp_path / f"eqs{suffix}"
        p = run_cli("export", path, "-o", out_file)
        assert p.returncode == 0, p.stderr
        assert out_file.exists()
    p = run_cli("assemble", path, "--latex")
    assert p.returncode == 0 and "a particle: no rotational inertia" in p.stdout, p.stderr


@pytest.mark.parametrize("name", ["point_pendulum", "spherical_pendulum"])
def test_export_of_a_particle_model_round_trips_and_solves(tmp_path, name):
    from mbody.io.export import load_export, write_export

    model = mbody.load(MODELS / f"{name}.yaml")
    asm = mbody.assemble(model)
    path = tmp_path / "eqs.npz"
    write_export(asm, path)
    exp = load_export(path)
    assert exp.coordinates == model.coordinates
    sol = exp.solve()
    np.testing.assert_allclose(sol.accelerations, asm.solve().accelerations, atol=1e-12)


def test_a_known_reaction_a_link_does_not_have_is_a_clean_error(tmp_path):
    """A link to a particle has T only: `reactions: {O.Fz: ...}` was a KeyError (fuzz
    mutation 1023); it is a validation error naming the link's components."""
    path = tmp_path / "m.yaml"
    path.write_text("model: sp\ndimension: 3\ngravity: [0, 0, -9.81]\nbodies:\n"
                    "  - {name: bob, mass: 1.0, inertia: 0, position: [1, 0, 0]}\n"
                    "joints: [{name: O, type: spherical, parent: ground, child: bob, "
                    "at: [0, 0, 0]}]\nreactions:\n  O.Fz: 2.0\n")
    with pytest.raises(mbody.ModelError) as e:
        mbody.load(path)
    assert "no reaction component 'O.Fz'" in str(e.value) and "O.T" in str(e.value)
    assert ":8:3:" in str(e.value)  # the line of O.Fz under reactions:
