"""How a simulation steps (`mbody.simulate.stepping`): the compiled core's DOP853 on the
core's right-hand side takes scipy's DOP853's steps on the shipped models (scipy driven
through its public API only, step by step); with the projection bound in C
(mbody/kernel/src/mechanism.c) it takes the steps the same callbacks written in Python
take, near singular positions (filtered steps) too; and a run calls no Python per step."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate
from mechanism_reference import Callbacks

import mbody
from mbody.equations.workspace import workspace
from mbody.kernel.dop853 import DOP853
from mbody.simulate import simulation, state_derivative
from mbody.simulate.mechanism import STAGE_PIVOT_RTOL, JointProjection
from mbody.simulate.simulation import _has_unknown_reactions
from mbody.simulate.stepping import CoreRun
from mbody.solve.dynamics import StateDerivative

MODELS = Path(__file__).resolve().parents[1] / "models"
SIX = ["double_pendulum", "slider_crank", "fourbar_spatial", "gyroscope_gimbals",
       "heavy_top", "spring_mass_damper"]


def initial_state(model: mbody.Model) -> np.ndarray:
    s = model.initial
    theta = (2.0 * np.arctan2(s.quaternion[:, 3], s.quaternion[:, 0])
             if model.dimension == 2 else ())
    return np.concatenate((s.position.ravel(), s.quaternion.ravel(), s.velocity.ravel(),
                           s.omega.ravel(), theta))


@pytest.mark.parametrize("name", SIX)
def test_core_steps_equal_scipys(name):
    """The core's right-hand side (mechanisms Baumgarte-stabilised, no projection: scipy's
    DOP853 cannot be projected without writing into it) under the core's DOP853 and
    under scipy's, driven through its public API (step(), dense_output()): the same
    steps, the same evaluations, the same motion at the samples to rounding. (Step for
    step from the same start, on plain ODEs: tests/test_dop853.py; a mechanism's
    constrained solve amplifies the stages' rounding too much for its bounds.)"""
    model = mbody.load(MODELS / f"{name}.yaml")
    rhs = state_derivative(model)
    y0 = initial_state(model)
    t_eval = np.arange(51) / 50.0
    ours = CoreRun(rhs, y0, 1.0, 1e-10, 1e-12, math.inf)
    mine = np.empty((len(t_eval), len(y0)))
    mine[0] = y0
    k = 1
    while ours.status == "running":
        k, why = ours.advance(1.0, 100, t_eval, k, mine)
        assert why is None
    ref = scipy.integrate.DOP853(rhs, 0.0, y0.copy(), 1.0, rtol=1e-10, atol=1e-12)
    theirs = np.empty_like(mine)
    theirs[0] = y0
    j, steps = 1, 0
    while ref.status == "running":
        assert ref.step() is None
        steps += 1
        i = int(np.searchsorted(t_eval, ref.t, side="right"))
        if i > j:
            theirs[j:i] = ref.dense_output()(t_eval[j:i]).T
            j = i
    assert k == j == len(t_eval)
    assert (ours.steps, ours.nfev) == (steps, ref.nfev)
    scale = 1.0 + float(np.max(np.abs(theirs)))
    np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-9 * scale)


def test_a_run_steps_as_its_problem_does():
    """`CoreRun` (a simulation's) with the core's right-hand side bound in C takes the
    steps of the same DOP853 calling that right-hand side from Python."""
    model = mbody.load(MODELS / "double_pendulum.yaml")
    rhs = state_derivative(model)
    y0 = initial_state(model)
    ours = CoreRun(rhs, y0, 1.0, 1e-10, 1e-12, math.inf)
    ref = DOP853(rhs, 0.0, y0, 1.0, rtol=1e-10, atol=1e-12)
    while ref.status == "running":
        ref.run(max_steps=1)
        ours.solver.run(max_steps=1)
        assert ours.t == ref.t
        np.testing.assert_array_equal(ours.y, ref.y)
    assert ours.status == "finished" and (ours.steps, ours.nfev) == (ref.steps, ref.nfev)


def _projected_runs(model: mbody.Model, t_end: float, rtol: float, atol: float):
    """(the core's run with its C callbacks, the run with the Python ones), both from the
    projected initial state."""
    rhs = state_derivative(model)
    assert _has_unknown_reactions(rhs.model, None)
    rhs.rate = 0.0
    y0 = initial_state(model)
    _, _, ratio = JointProjection(rhs.model, rhs.unknowns)(y0, 0.0)
    first = ratio < STAGE_PIVOT_RTOL
    ours = CoreRun(rhs, y0, t_end, rtol, atol, math.inf, project=True, filter_first=first)
    ref = Callbacks(rhs.model, rhs.unknowns).dop853(y0, t_end, rtol, atol, filter_first=first)
    return ours, ref


def _step_for_step(ours: CoreRun, ref, scale: float) -> int:
    steps = 0
    while ref.status == "running":
        ref.run(max_steps=1)
        ours.solver.run(max_steps=1)
        steps += 1
        assert ours.t == pytest.approx(ref.t, rel=1e-12, abs=1e-15)
        np.testing.assert_allclose(ours.y, ref.y, rtol=0, atol=1e-11 * scale)
    assert ours.status == ref.status == "finished"
    assert ours.steps == ref.steps == steps
    assert (ours.nfev, ours.refreshed) == (ref.nfev, ref.refreshed)
    return steps


@pytest.mark.parametrize("name", ["double_pendulum", "slider_crank", "fourbar_spatial",
                                  "gyroscope_gimbals", "heavy_top", "triple_pendulum"])
def test_projection_in_c_equals_the_python_callbacks(name):
    model = mbody.load(MODELS / f"{name}.yaml")
    ours, ref = _projected_runs(model, 1.0, 1e-10, 1e-12)
    _step_for_step(ours, ref, 1.0 + float(np.max(np.abs(ref.y))))


def test_filtered_steps_in_c_equal_the_python_callbacks():
    """The four-bar chain through its first flat position: the stage projection and the
    error along the joints (filtered steps) bound in C step as their Python versions."""
    from fourbar_chain import FourbarChain

    chain = FourbarChain(crank=0.25, spacing=0.5, width=0.03125)
    model = mbody.loads(chain.yaml(0.3, 0.0))
    ours, ref = _projected_runs(model, 0.6, 1e-10, 1e-12)
    filtered = 0
    while ref.status == "running":
        _step_for_step_once(ours, ref)
        filtered += int(ref.state[mbody.kernel._core.DOP_FILTER])
    # the crossing was stepped through filtered steps, so that the comparison covers them
    # (how many depends on rounding at the flat position: 3 with OpenBLAS's SkylakeX
    # kernels, 2 with its Haswell ones; each is compared above, value for value)
    assert filtered >= 1
    assert ours.steps == ref.steps and ours.nfev == ref.nfev


def _step_for_step_once(ours: CoreRun, ref) -> None:
    ref.run(max_steps=1)
    ours.solver.run(max_steps=1)
    assert ours.t == pytest.approx(ref.t, rel=1e-12, abs=1e-15)
    np.testing.assert_allclose(ours.y, ref.y, rtol=0, atol=1e-11)


def test_a_dop853_run_calls_no_python_per_step(monkeypatch):
    """The right-hand side, the projection and the sampling of a mechanism's DOP853 run
    are the core's: `StateDerivative.__call__` is never called (it would be per
    evaluation), and the samples are those of the steps."""
    calls = []
    call = StateDerivative.__call__

    def counted(self, t, y):
        calls.append(t)
        return call(self, t, y)

    monkeypatch.setattr(StateDerivative, "__call__", counted)
    traj = mbody.simulate(mbody.load(MODELS / "slider_crank.yaml"), 0.5, 60)
    assert traj.info["steps"] > 50 and traj.info["evaluation_path"] == "compiled"
    assert calls == []
    # a `dynamics` given in Python is called from the same loop, once per evaluation
    model = mbody.load(MODELS / "torque_free_asymmetric.yaml")
    traj = mbody.simulate(model, 0.5, 60,
                          dynamics=lambda m, s: mbody.solve.dynamics.accelerations(m, s))
    assert len(calls) == traj.info["evaluations"] > 0
    assert traj.info["evaluation_path"] == "python"


def test_a_state_that_is_not_finite_stops_the_run():
    """A nan error norm shrinks the step as scipy does (Python's max(0.2, nan) is 0.2)
    until it is too small: the run reports that instead of looping on a nan step."""
    model = mbody.load(MODELS / "torque_free_asymmetric.yaml")  # a free body: no solve
    rhs = state_derivative(model)
    y = initial_state(model)
    y[7] = np.nan  # a velocity
    run = CoreRun(rhs, y, 1.0, 1e-10, 1e-12, math.inf)
    Y = np.zeros((2, len(y)))
    k, why = run.advance(1.0, 100, np.array([0.0, 1.0]), 1, Y)
    assert run.status == "failed" and run.steps == 0 and k == 1
    assert why == "Required step size is less than spacing between numbers."


EXPRESSIONS = ["-4000*exp(-200*t)", "50*sin(2*t) - cos(t)/3", "2^-t", "t^0.5", "(t - 3)^2",
               "1/(t - 1)", "abs(-t)^2.5", "tan(pi*t)", "-(t)", "exp(1000*t)"]
"""Loads a model file accepts (finite at t = 0); those out of their domain from t = 0
(log(t), sqrt(t - 2) ...) are compared at the expression level in tests/test_kernel.py."""


@pytest.mark.parametrize("text", EXPRESSIONS)
def test_the_cores_load_values_equal_the_expressions(text):
    """The loads inside a run (the core evaluates each expression of t at every stage)
    are the numbers numpy gives, inf and nan included, at times around the awkward ones."""
    model = mbody.loads(f"""
dimension: 3
bodies: [{{name: b, mass: 1, inertia: [1, 1, 1]}}]
loads:
  - {{name: f, type: force, body: b, force: ["{text}", 2, "{text}"]}}
  - {{name: c, type: torque, body: b, torque: [0, "{text}", 1]}}
""")
    core = workspace(model).core
    out = np.empty((core.k, 3))
    with np.errstate(all="ignore"):
        for t in (0.0, 0.3, 1.0, 2.0, 2.5, 3.0, 10.0):
            core.loads_at(t, out)
            np.testing.assert_allclose(out, model.forces.vector_at(t), rtol=1e-15, atol=0,
                                       equal_nan=True)


PIN = {
    "model": "pin", "dimension": 3, "gravity": [0, -9.81, 0],
    "bodies": [{"name": "rod", "mass": 1.2, "inertia": [0.01, 0.1, 0.1],
                "position": [0.5, 0, 0]}],
    "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "rod",
                "at": [0, 0, 0], "axis": [0, 0, 1]}],
}


def test_a_driven_joint_is_followed_by_the_run():
    """A time-dependent constraint (a law f(t) on the pin's turn, as drivers will add):
    the run in C with its projection follows it with nothing else added. The rod,
    released at rest while the law asks for f'(0) = 1 rad/s, is projected onto the law
    at t = 0 (Gᵀ v = f'), then turns as f(t) = 0.5 sin 2t: its angle, rate and mass
    centre are the closed form's at every sample, φ − f and Gᵀ v − f' at rounding."""
    from mbody.equations.pack import Component, pack_model, pack_unknowns
    from mbody.kernel import _core
    from mbody.model.expressions import compile_expression
    from mbody.simulate.mechanism import ITERATIONS, STAGE_ITERATIONS
    from mbody.simulate.stepping import REFRESH_ATOL

    model = mbody.load(PIN)
    law = tuple(compile_expression(e) for e in ("0.5*sin(2*t)", "cos(2*t)", "-2*sin(2*t)"))
    extra = (Component(0, _core.KIND_TURN, 2, law=law),)
    core = _core.Model(*pack_model(model, extra), False)
    m = core.m
    U = np.arange(m)  # the pin's five components and the driven turn
    solver = _core.Unknowns(core, pack_unknowns(model, U, extra))
    y0 = initial_state(model)
    info = np.empty(_core.PROJECT_INFO)
    solver.project(0.0, y0, ITERATIONS, STAGE_PIVOT_RTOL, False, info)
    assert y0[12] == pytest.approx(1.0, abs=1e-12)  # ω_z = f'(0)
    params = np.zeros(_core.MECH_PARAMS + m)
    params[_core.MECH_ROBUST] = STAGE_PIVOT_RTOL
    params[_core.MECH_ITERS], params[_core.MECH_STAGE_ITERS] = ITERATIONS, STAGE_ITERATIONS
    run = DOP853(solver, 0.0, y0, 3.0, rtol=1e-10, atol=1e-12, params=params, project=True,
                 stage=True, tangent=True, refresh=REFRESH_ATOL)
    t = np.arange(61) / 20.0
    Y = np.empty((len(t), len(y0)))
    Y[0], k = y0, 1
    while run.status == "running":
        k = run.sampled(3.0, 200, t, k, Y, project_samples=True)
    assert run.status == "finished" and k == len(t)
    f = 0.5 * np.sin(2 * t)
    angle = 2 * np.arctan2(Y[:, 6], Y[:, 3])  # about z: q = [cos f/2, 0, 0, sin f/2]
    np.testing.assert_allclose(angle, f, atol=1e-9)
    np.testing.assert_allclose(Y[:, 12], np.cos(2 * t), atol=1e-9)
    np.testing.assert_allclose(Y[:, :2], 0.5 * np.stack((np.cos(f), np.sin(f)), axis=1),
                               atol=1e-9)
    drift = np.zeros(2)
    _core.samples(solver, np.zeros(m), t, Y, None, None, drift)
    assert drift[0] <= 1e-13 and drift[1] <= 1e-12


def test_a_call_comes_back_after_its_wall_time_with_the_same_steps():
    """`return_after`: a call of the core comes back after the first step that ends past
    its wall time (here at once: one step a call), and the run is the same, sample for
    sample, as one whole call (the steps do not depend on where the calls end)."""
    model = mbody.load(MODELS / "double_pendulum.yaml")
    rhs = state_derivative(model)
    y0 = initial_state(model)
    t_eval = np.arange(21) / 20.0
    runs = []
    for seconds in (0.0, 1e-12):
        run = CoreRun(rhs, y0, 1.0, 1e-10, 1e-12, math.inf)
        run.return_after(seconds)
        Y = np.empty((len(t_eval), len(y0)))
        Y[0] = y0
        k, calls = 1, 0
        while run.status == "running":
            k, why = run.advance(1.0, 10_000, t_eval, k, Y)
            assert why is None
            calls += 1
        runs.append((calls, run.steps, Y))
    (calls_once, steps, whole), (calls_each, steps_each, stepwise) = runs
    assert calls_once == 1 and steps > 20
    assert (calls_each, steps_each) == (steps, steps)  # one step per call
    assert np.array_equal(whole, stepwise)


def test_simulate_is_the_same_however_often_it_comes_back(monkeypatch):
    """`simulate`'s loop looks at its budgets between calls of the core timed by
    `CHUNK_WALL`; a call that came back after every step gives the same trajectory."""
    model = mbody.load(MODELS / "slider_crank.yaml")
    whole = mbody.simulate(model, 0.5, 40)
    monkeypatch.setattr(simulation, "CHUNK_WALL", 1e-12)
    stepwise = mbody.simulate(model, 0.5, 40)
    assert whole.info["steps"] == stepwise.info["steps"] > 40
    for a, b in ((whole.position, stepwise.position), (whole.velocity, stepwise.velocity),
                 (whole.reactions, stepwise.reactions)):
        assert np.array_equal(a, b)
