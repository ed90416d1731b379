"""tools/bench_small.py compares mbody with MuJoCo models it builds from mbody's models: this
keeps those equivalents honest, without timing anything.

For every tree model (no loop, so MuJoCo's answer is exact, not softened by equality
constraints) the MuJoCo equivalent must put every mass centre and body frame where mbody
does, move them as mbody does, and give the same accelerations (a_G and ω̇, world axes)
to 1e-8 relative: at the model's initial state, and at a second state reached by turning
every joint (so that the velocity-product terms a state at rest hides are compared too).
The triple pendulum shipped for the benchmark is also checked against Lagrange's
equations, written out here by hand.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.model import State

mujoco = pytest.importorskip("mujoco")

ROOT = Path(__file__).resolve().parent.parent
RTOL = 1e-8


def _bench():
    name = "bench_small"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / "bench_small.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclasses look their module up while it loads
        spec.loader.exec_module(module)
    return sys.modules[name]


bench = _bench()
TREES = ["pendulum.yaml", "double_pendulum.yaml", "triple_pendulum.yaml", "heavy_top.yaml",
         "gyroscope_gimbals.yaml"]
LOOPS = ["slider_crank.yaml", "fourbar_planar.yaml", "fourbar_spatial.yaml"]


def test_every_benchmark_system_is_a_shipped_model():
    files = {f for _, f in bench.SYSTEMS}
    assert set(TREES) | set(LOOPS) == files
    for f in files:
        assert (ROOT / "models" / f).is_file()


@pytest.mark.parametrize("file", TREES)
def test_tree_equivalent_agrees_at_the_initial_state(file: str):
    model = bench.load(file)
    eq = bench.mujoco_equivalent(model)
    assert eq.loops == [] and len(eq.tree) == len(model.joints)
    c = bench.check_equivalent(model, eq)
    assert c.exact
    assert c.pose < 1e-12, "mass centres or body axes misplaced"
    assert c.velocity < 1e-12 * max(1.0, float(np.abs(model.initial.omega).max()))
    assert c.acc < RTOL, f"accelerations differ by {c.acc:.1e} relative"
    if file != "gyroscope_gimbals.yaml":  # the conversion (planar chains, the top)
        assert c.qacc < RTOL


def _state_from_mujoco(m, d, eq) -> State:
    """mbody's State of the bodies MuJoCo has moved (body frames are mass-centre frames)."""
    ids = eq.body_ids
    vel = np.zeros((len(ids), 6))
    for i, b in enumerate(ids):
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, int(b), vel[i], 0)
    R = d.xmat[ids].reshape(-1, 3, 3)
    omega = np.einsum("nji,nj->ni", R, vel[:, :3])  # world -> body axes
    return State(d.xpos[ids].copy(), d.xquat[ids].copy(), vel[:, 3:].copy(), omega)


@pytest.mark.parametrize("file", TREES)
def test_tree_equivalent_agrees_at_a_moved_state(file: str):
    model = bench.load(file)
    eq = bench.mujoco_equivalent(model)
    m, d = eq.make()
    rng = np.random.default_rng(3)
    for j in range(m.njnt):
        a, v = m.jnt_qposadr[j], m.jnt_dofadr[j]
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL:
            q = np.array([1.0, *rng.normal(scale=0.3, size=3)])
            d.qpos[a:a + 4] = q / np.linalg.norm(q)
            d.qvel[v:v + 3] += rng.normal(size=3)
        else:
            d.qpos[a] = rng.uniform(-0.8, 0.8)
            d.qvel[v] += rng.normal()
    mujoco.mj_forward(m, d)
    state = _state_from_mujoco(m, d, eq)
    if model.dimension == 2:  # rounding out of the plane would only add noise
        state = State(state.position * [1, 1, 0], state.quaternion * [1, 0, 0, 1],
                      state.velocity * [1, 1, 0], state.omega * [0, 0, 1])
    ours = bench.mbody_accelerations(model, state)
    assert np.abs(ours).max() > 1e-3  # the state moves something
    diff = bench.relative_difference(ours, bench.mujoco_accelerations(m, d, eq))
    assert diff < RTOL, f"accelerations differ by {diff:.1e} relative"


@pytest.mark.parametrize("file", LOOPS)
def test_loop_equivalents_are_close(file: str):
    """MuJoCo's loop closures are soft (the benchmark compares only time there), but the
    model must be the same mechanism: accelerations within 1e-3 relative."""
    model = bench.load(file)
    eq = bench.mujoco_equivalent(model)
    assert len(eq.loops) == 1
    c = bench.check_equivalent(model, eq)
    assert c.pose < 1e-12 and c.velocity < 1e-9
    assert c.acc < 1e-3


def test_state_vector_is_the_one_simulate_integrates():
    """initial_y builds the block layout [x | q | v | ω | θ] that simulate starts from."""
    model = bench.load("double_pendulum.yaml")
    y = bench.initial_y(model)
    n = model.n
    s = model.initial
    np.testing.assert_array_equal(y[:3 * n], s.position.ravel())
    np.testing.assert_array_equal(y[3 * n:7 * n], s.quaternion.ravel())
    np.testing.assert_allclose(y[13 * n:], np.radians([30, 45]), rtol=1e-14)
    traj = mbody.simulate(model, t_end=0.05, fps=20)
    np.testing.assert_allclose(traj.spatial()[0][0], s.position)


def test_time_to_reach_interpolates_log_log():
    pts = [(1.0, 1e-2), (10.0, 1e-6)]
    t, bound = bench.time_to_reach(pts, 1e-4)
    assert bound == "" and t == pytest.approx(10 ** 0.5)
    assert bench.time_to_reach(pts, 1e-1) == (1.0, "≤")
    t, _ = bench.time_to_reach(pts, 1e-9)
    assert np.isnan(t)
    assert bench.time_to_reach([(1.0, np.inf), (2.0, 1e-5)], 1e-4) == (2.0, "≤")


def test_triple_pendulum_matches_lagrange():
    """Three equal rods (m = 1 kg, L = 0.5 m) at 30, 45, 60 deg, released from rest."""
    model = bench.load("triple_pendulum.yaml")
    acc = mbody.assemble(model).solve().accelerations
    m, L, g = 1.0, 0.5, 9.81
    p = np.radians([30.0, 45.0, 60.0])
    c = np.cos(p[:, None] - p[None, :])
    M = m * L * L * np.array([[7 / 3, 1.5 * c[0, 1], 0.5 * c[0, 2]],
                              [1.5 * c[0, 1], 4 / 3, 0.5 * c[1, 2]],
                              [0.5 * c[0, 2], 0.5 * c[1, 2], 1 / 3]])
    Q = -m * g * L * np.array([2.5 * np.sin(p[0]), 1.5 * np.sin(p[1]), 0.5 * np.sin(p[2])])
    phidd = np.linalg.solve(M, Q)
    np.testing.assert_allclose(acc[2::3], phidd, rtol=1e-10)
    np.testing.assert_allclose(phidd, [-3.49525, -8.88525, -8.07292], rtol=1e-5)  # comment
