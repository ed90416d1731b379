"""The compiled DOP853 steps (`mbody.stepping`) are scipy's steps: the same step sizes,
the same number of evaluations, the same motion to rounding, on the shipped mechanisms
(constant and time-varying loads, planar and spatial, open and closed chains)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.simulate import stepping

MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.mark.parametrize("name", ["double_pendulum", "slider_crank", "fourbar_spatial",
                                  "gyroscope_gimbals", "heavy_top", "spring_mass_damper"])
def test_compiled_steps_equal_scipys(name, monkeypatch):
    model = mbody.load(MODELS / f"{name}.yaml")
    runs = {}
    for on in (True, False):
        monkeypatch.setattr(stepping, "COMPILED_STEPS", on)
        runs[on] = mbody.simulate(model, 1.0, 50)
    fast, slow = runs[True], runs[False]
    assert fast.info["evaluation_path"] == "compiled"
    assert fast.info["steps"] == slow.info["steps"]
    assert fast.info["evaluations"] == slow.info["evaluations"]
    scale = 1.0 + float(np.max(np.abs(slow.position)))
    np.testing.assert_allclose(fast.position, slow.position, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(fast.velocity, slow.velocity, rtol=0,
                               atol=1e-9 * (1.0 + float(np.max(np.abs(slow.velocity)))))


def test_compiled_steps_are_taken(monkeypatch):
    """The compiled run really is what steps the run (so the test above compares two
    different paths): its step counter, read through the kernel's Python entry."""
    from mbody.equations.plan import compiled

    c = compiled()
    taken = []
    kernel = c.rk_run

    def counted(*args):
        kernel(*args)
        taken.append(args[-1][c.RUN_STEPS])

    monkeypatch.setattr(c, "rk_run", counted)
    traj = mbody.simulate(mbody.load(MODELS / "double_pendulum.yaml"), 0.5, 10)
    assert sum(taken) == traj.info["steps"] > 0


EXPRESSIONS = ["-4000*exp(-200*t)", "50*sin(2*t) - cos(t)/3", "2^-t", "t^0.5", "(t - 3)^2",
               "1/(t - 1)", "log(t - 2)", "sqrt(t - 2)", "(-8)^(1/3)*t", "abs(-t)^2.5",
               "tan(pi*t)", "-(t)", "exp(1000*t)", "0^(t - 1)", "log(t)"]


@pytest.mark.parametrize("text", EXPRESSIONS)
def test_compiled_load_programs_equal_the_expressions(text):
    """`compiled.set_loads` (the loads inside a compiled step) gives the numbers numpy
    gives, inf and nan included, at times around the awkward ones."""
    from mbody.equations.plan import compiled

    from mbody.model.expressions import ExpressionTable, compile_expression

    e = compile_expression(text)
    table = ExpressionTable.build([(0, 1, e), (1, 2, e)])
    base = np.arange(6.0).reshape(2, 3)
    out = np.empty_like(base)
    for t in (0.0, 0.3, 1.0, 2.0, 2.5, 3.0, 10.0):
        compiled().set_loads(base, *table.program, t, out)
        expected = table.apply(base, np.array([t]))[0]
        np.testing.assert_allclose(out, expected, rtol=1e-15, atol=0, equal_nan=True)


def test_a_state_that_is_not_finite_stops_the_compiled_run():
    """A nan error norm shrinks the step as scipy does (Python's max(0.2, nan) is 0.2)
    until it is too small: the run reports that instead of looping on a nan step."""
    import scipy.integrate
    from mbody.equations.plan import compiled

    from mbody.simulate import state_derivative

    c = compiled()
    model = mbody.load(MODELS / "torque_free_asymmetric.yaml")  # a free body: no solve
    rhs = state_derivative(model, None, None)
    assert rhs.compiled
    s0 = model.initial
    y = np.concatenate((s0.position.ravel(), s0.quaternion.ravel(), s0.velocity.ravel(),
                        s0.omega.ravel()))
    y[7] = np.nan  # a velocity
    f = rhs(0.0, y)
    solver = scipy.integrate.DOP853(lambda t, z: z, 0.0, np.zeros(3), 1.0)
    K = np.empty((solver.n_stages + 1, len(y)))
    run = np.zeros(9)
    run[c.RUN_H] = 1e-3
    c.rk_run(rhs._F, rhs._I, rhs._Iu, *model.plan.load_program, rhs.unknowns.lam, 0.0,
             False, solver.A, solver.B, solver.C, solver.E3, solver.E5, 1e-10, 1e-12, np.inf,
             1.0, 1.0, 100, False, 1e-2, 1e-14, y, f, K, np.empty_like(y), run)
    assert run[c.RUN_STATUS] == 1.0 and run[c.RUN_STEPS] == 0
