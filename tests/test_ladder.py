"""Ladders of closed loops (`tools/bench_ladder.py`'s models): small ones solved right.

A ladder of N parallelogram loops (rungs pinned to the ground, couplers joining their
tips) has one degree of freedom: every rung turns through the same angle θ and the
couplers translate, like one compound pendulum. Here, on 3-loop ladders (planar, and
spatial with spherical coupler ends), the compiled and numpy paths must agree, the
accelerations must hold the joints (Gᵀ v̇ = γ) and equal that closed form, and a ladder
released from rest must swing as the pendulum does. Mid-size ladders must take the
banded path on both sides, never a dense factorisation.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.equations import plan as planmod
from mbody.simulate import state_derivative

pytest.importorskip("numba")
ROOT = Path(__file__).resolve().parent.parent
KINDS = ("planar", "spatial")


def _bench():
    name = "bench_ladder"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / "bench_ladder.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclasses look their module up while it loads
        spec.loader.exec_module(module)
    return sys.modules[name]


@pytest.fixture
def jit():
    """Switch paths inside a test: jit("on") / jit("off"); restored afterwards."""
    previous = planmod.JIT
    yield planmod.set_jit
    planmod.set_jit(previous)


def rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b))) / max(float(np.max(np.abs(b))), 1e-300)


def initial_y(model: mbody.Model) -> np.ndarray:
    """The state vector as `simulate` builds it: [x | q | v | ω | θ (planar)]."""
    s = model.initial
    theta = (2.0 * np.arctan2(s.quaternion[:, 3], s.quaternion[:, 0])
             if model.dimension == 2 else ())
    return np.concatenate((s.position.ravel(), s.quaternion.ravel(), s.velocity.ravel(),
                           s.omega.ravel(), theta))


@pytest.mark.parametrize("kind", KINDS)
def test_ladder_spec(kind):
    """3 loops: 7 bodies, 10 joints, and the unknown count the benchmark sizes by."""
    b = _bench()
    model = mbody.load(b.ladder_spec(3, kind))
    assert model.n == 7
    a, c = b.unknowns_per_loop(kind)
    assert len(model.reactions) == 3 * a + c
    sol = mbody.assemble(model).solve()
    assert not sol.broken_joints and not sol.redundant


@pytest.mark.parametrize("kind", KINDS)
def test_small_ladder_both_paths(jit, kind):
    b = _bench()
    model = mbody.load(b.ladder_spec(3, kind))
    state = model.initial
    jit("off")
    a = mbody.assemble(model, state).solve()
    jit("on")
    c = mbody.assemble(model, state).solve()
    f = state_derivative(model)  # the compiled core's, whatever the mode
    assert "compiled" not in a.method and c.method.endswith("compiled)")
    assert f.compiled
    # the two paths agree
    assert rel(c.accelerations, a.accelerations) <= 1e-10
    lam_a = np.array([a.reactions[r] for r in model.reactions])
    lam_c = np.array([c.reactions[r] for r in model.reactions])
    assert rel(lam_c, lam_a) <= 1e-10
    # simulate's right-hand side: at this state the joints hold, so Baumgarte's terms
    # vanish and its accelerations are the solve's
    y = initial_y(model)
    n = model.n
    d = f(0.0, y)[7 * n:13 * n].reshape(2, n, 3)
    acc = (np.stack((d[0, :, 0], d[0, :, 1], d[1, :, 2]), axis=1) if model.dimension == 2
           else np.concatenate((d[0], d[1]), axis=1)).ravel()
    assert rel(acc, a.accelerations) <= 1e-10
    # the accelerations hold the joints: Gᵀ v̇ = γ (γ ≠ 0: the rungs turn)
    asm = mbody.assemble(model, state)
    GT, gamma = asm.G.T.tocsr(), asm.jacobian().gamma
    assert np.max(np.abs(gamma)) > 0.1
    for sol in (a, c):
        scale = max(np.max(np.abs(gamma)),
                    np.max(abs(GT).sum(axis=1)) * np.max(np.abs(sol.accelerations)))
        assert np.max(np.abs(GT @ sol.accelerations - gamma)) <= 1e-9 * scale
    # and equal the compound pendulum's: equal rungs, translating couplers
    exact = b.closed_form_accelerations(3, kind)
    assert rel(a.accelerations, exact) <= 1e-10
    assert rel(c.accelerations, exact) <= 1e-10


def test_closed_form_is_a_pendulum():
    """The closed form's θ̈ at rest, by hand for equal masses: a check of `pendulum`."""
    b = _bench()
    inertia, stiffness = b.pendulum(3, "planar")
    mr, mc = b.masses(3)
    L = b.L
    assert inertia == pytest.approx(np.sum(mr) * L * L / 3 + np.sum(mc) * L * L, rel=1e-14)
    assert stiffness == pytest.approx(b.G0 * L * (np.sum(mr) / 2 + np.sum(mc)), rel=1e-14)
    acc = b.closed_form_accelerations(3, "planar", theta=0.4, omega=0.0).reshape(7, 3)
    assert np.allclose(acc[0::2, 2], -stiffness / inertia * np.sin(0.4), rtol=1e-14)
    assert np.all(acc[1::2, 2] == 0.0)  # couplers do not turn


@pytest.mark.parametrize("kind", KINDS)
def test_released_ladder_swings_as_one_pendulum(kind):
    b = _bench()
    model = mbody.load(b.ladder_spec(3, kind, omega0=0.0))
    traj = mbody.simulate(model, t_end=1.0, fps=20)
    x = traj.spatial()[0]
    pivots = np.arange(4) * b.D
    theta = np.arctan2(x[:, 0::2, 0] - pivots, -x[:, 0::2, 1])
    exact = b.pendulum_angle(3, kind, traj.t, b.THETA0)
    assert np.max(np.abs(theta - exact[:, None])) < 1e-7


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("target", [50, 100])
def test_mid_size_ladder_is_banded(jit, kind, target):
    """50 and 100 unknowns: the banded Cholesky of S on both paths, never a dense one."""
    b = _bench()
    n_loops = b.loops_for(kind, target)
    model = mbody.load(b.ladder_spec(n_loops, kind))
    assert len(model.reactions) > 48  # above mbody.solve.kkt.DENSE_LIMIT
    for mode in ("off", "on"):
        jit(mode)
        sol = mbody.assemble(model).solve()
        assert sol.method.startswith("banded Cholesky"), (mode, sol.method)
