"""The compiled core's DOP853 (mbody/kernel/src/dop853.c) against its definition and
against scipy.integrate.DOP853 (public API only: the constructor, step(), t, t_old, y,
nfev, status, dense_output()).

Step for step: the accepted step a step-size proposal leads to is decided by an error
estimate that cancels terms 1e5 to 1e11 times larger than itself, so two correct
implementations that merely sum the stages in another order (scipy: BLAS; the core: in
stage order, as mbody's compiled path did) propose steps that differ far above rounding
(1e-7 relative at rtol 1e-10), and after a borderline rejection the two whole runs take
different steps. The comparison is therefore made step by step from the same start:
every step of the core's run is taken again by a fresh scipy solver from the same (t, y)
with the same first step; the two must accept or reject alike, land on the same time,
the same state and dense output to rounding, and propose the same next step to within
the rounding sensitivity of the error estimate (derived from the step's own stages).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from ode_systems import (
    ARENSTORF_MU,
    ARENSTORF_PERIOD,
    ARENSTORF_Y0,
    SYSTEMS,
    oscillator,
    van_der_pol,
)
from scipy.integrate import DOP853 as ScipyDOP853

from mbody.kernel import _core
from mbody.kernel.dop853 import DOP853

EPS = np.finfo(float).eps
STAGE_EVALS = 12  # evaluations per attempted step


def tableau():
    t = _core.dop853_tableau()
    return {k: np.array(v).reshape(-1, 16) if k in ("a", "d") else np.array(v)
            for k, v in t.items()}


# -- the coefficients ---------------------------------------------------------------------
def test_tableau_equals_scipys_numbers():
    """Written from HNW's published tableau, the numbers are scipy's to the last bit
    (both round the same decimal digits: no arithmetic is involved)."""
    t = tableau()
    assert np.array_equal(t["c"][:12], ScipyDOP853.C)
    assert np.array_equal(t["c"][13:], ScipyDOP853.C_EXTRA)
    assert np.array_equal(t["a"][:12, :12], ScipyDOP853.A)
    assert np.array_equal(t["a"][13:], ScipyDOP853.A_EXTRA)
    assert np.array_equal(t["b"], ScipyDOP853.B)
    assert np.array_equal(t["e5"], ScipyDOP853.E5)
    assert np.array_equal(t["e3"], ScipyDOP853.E3)
    assert np.array_equal(t["d"], ScipyDOP853.D)


def test_tableau_order_conditions():
    """Consistency (row sums of A = c), the quadrature conditions of order 8 for b,
    and the embedded estimators: e5 of order 5 and e3 of order 3 vanish on the
    quadrature conditions up to their orders (they are differences of two solutions)."""
    t = tableau()
    a, c, b = t["a"], t["c"], t["b"]
    rows = [s for s in range(16) if s != 12]  # row 12 is y_new (the weights b)
    np.testing.assert_allclose(a[rows].sum(axis=1), c[rows], rtol=0, atol=1e-14)
    c12 = c[:12]
    for k in range(1, 9):  # sum b c^(k-1) = 1/k
        assert abs(b @ c12 ** (k - 1) - 1.0 / k) < 1e-14
    assert abs(b @ c12 ** 8 - 1.0 / 9) > 1e-6  # and no more: order 8 exactly
    c13 = c[:13]
    for k in range(1, 6):
        assert abs(t["e5"] @ c13 ** (k - 1)) < 1e-13
    for k in range(1, 4):
        assert abs(t["e3"] @ c13 ** (k - 1)) < 1e-13


# -- the built-in systems ------------------------------------------------------------------
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_built_in_systems_equal_the_python_ones(name):
    """The core's test systems compute what the Python functions here compute (so that
    the benchmark compares the same problem)."""
    fun, params, y0, _, _ = SYSTEMS[name]
    rng = np.random.default_rng(1)
    for _ in range(20):
        y = np.asarray(y0) + rng.normal(size=len(y0))
        out = np.empty(len(y0))
        _core.dop853_system(_core.__dict__[f"DOP_SYSTEM_{name.upper()}"],
                            np.array(params, dtype=float), 0.0, y, out)
        np.testing.assert_allclose(out, fun(0.0, y), rtol=4 * EPS, atol=0)


# -- step for step against scipy -----------------------------------------------------------
def jacobian_size(fun, t: float, y: np.ndarray) -> np.ndarray:
    """|df/dy| at (t, y) by central differences (for error bounds: twice its size)."""
    n = len(y)
    out = np.empty((n, n))
    for k in range(n):
        d = np.zeros(n)
        d[k] = 1e-6 * (1.0 + abs(y[k]))
        out[:, k] = (fun(t, y + d) - fun(t, y - d)) / (2 * d[k])
    return 2 * np.abs(out)


def proposal_sensitivity(solver: DOP853, fun, rtol: float, atol) -> float:
    """Relative change of the next step's proposal that rounding can cause, from the
    step's own stages K (u = 16 eps, the bound on a sum of up to 16 terms):
    the stage states z_s = y + h sum_l a_sl K_l are rounded by dz_s <= u (|y| + |h|
    sum_l |a_sl| |K_l|), which reaches K_s as dK_s <= u |K_s| + |J| dz_s; the estimate
    r_i = (sum_j e_j K_ji) / sc_i then moves by dr_i <= sum_j |e_j| (u |K_ji| + dK_ji) /
    sc_i. ln err moves by at most 1.5 dn5/n5 + 0.5 dn3/n3 (n = sum r^2), the proposal
    by 1/8 of that."""
    n, t = solver.n, tableau()
    K = solver.work[_core.DOP_W_K * n:(_core.DOP_W_K + 13) * n].reshape(13, n)
    y, h = solver.y_start, solver.step_size
    u = 16 * EPS
    weights = np.vstack((t["a"][:12, :13], np.append(t["b"], 0.0)))  # stages 0..12
    dz = u * (np.abs(y) + abs(h) * (np.abs(weights) @ np.abs(K)))
    dK = u * np.abs(K) + dz @ jacobian_size(fun, solver.step_start, y).T
    dK[0] = 0.0  # f(t, y): the same evaluation in both
    sc = atol + np.maximum(np.abs(y), np.abs(solver.y)) * rtol
    rel = []
    for e in (t["e5"], t["e3"]):
        r = (e @ K) / sc
        bound = (np.abs(e) @ (u * np.abs(K) + dK)) / sc
        rel.append(float(np.sum(2 * np.abs(r) * bound + bound ** 2) / max(r @ r, 1e-300)))
    return (1.5 * rel[0] + 0.5 * rel[1]) / 8 + 4 * EPS


def rounding_scale(solver: DOP853, rows: int, weights: np.ndarray) -> np.ndarray:
    """|y_start| + |y| + |h| sum_j w_j |K_j|: the size of the terms a state or dense output
    of the last step sums (the bound on its rounding, divided by eps)."""
    n = solver.n
    K = solver.work[_core.DOP_W_K * n:(_core.DOP_W_K + rows) * n].reshape(rows, n)
    return (np.abs(solver.y_start) + np.abs(solver.y)
            + abs(solver.step_size) * (weights[:rows] @ np.abs(K)))


def assert_within(difference: np.ndarray, bound: np.ndarray) -> None:
    bad = np.abs(difference) > bound
    assert not bad.any(), \
        f"{np.abs(difference)[bad]} above {np.broadcast_to(bound, bad.shape)[bad]}"


def synced_steps(fun, y0, t0, t_bound, *, rtol, atol, max_step=math.inf):
    """Every step of the core's run taken again by scipy from the same start (module
    docstring). Returns (steps, rejected steps, proposals compared)."""
    t = tableau()
    b_weights = np.concatenate((np.abs(t["b"]), np.zeros(4)))
    d_weights = b_weights + np.abs(t["d"]).sum(axis=0)
    mine = DOP853(fun, t0, y0, t_bound, rtol=rtol, atol=atol, max_step=max_step)
    ref0 = ScipyDOP853(fun, t0, np.array(y0, dtype=float), t_bound, rtol=rtol, atol=atol,
                       max_step=max_step)
    assert mine.nfev == ref0.nfev == 2
    steps = rejected_steps = compared = 0
    while mine.status == "running":
        t_start, y_start, h_start = mine.t, mine.y.copy(), mine.next_step
        rejected, nfev = mine.rejected, mine.nfev
        mine.step()
        steps += 1
        attempts = 1 + mine.rejected - rejected
        assert mine.nfev - nfev == STAGE_EVALS * attempts
        remaining = abs(t_bound - t_start)  # scipy refuses a longer first step
        ref = ScipyDOP853(fun, t_start, y_start, t_bound, rtol=rtol, atol=atol,
                          max_step=max_step, first_step=min(h_start, remaining))
        ref.step()
        if attempts > 1:  # scipy rejects the same first attempt, then takes mine again
            rejected_steps += 1
            assert ref.nfev - 1 >= 2 * STAGE_EVALS
            ref = ScipyDOP853(fun, t_start, y_start, t_bound, rtol=rtol, atol=atol,
                              max_step=max_step, first_step=abs(mine.step_size))
            ref.step()
        assert ref.nfev - 1 == STAGE_EVALS, "scipy rejected a step the core accepted"
        assert ref.status == mine.status
        assert ref.t == pytest.approx(mine.t, rel=1e-14, abs=1e-300)
        scale = rounding_scale(mine, 12, b_weights)
        assert_within(ref.y - mine.y, 256 * EPS * scale)
        inside = mine.step_start + mine.step_size * np.array([0.0, 0.13, 0.5, 0.87, 1.0])
        dense = mine.dense(inside)  # (samples, n)
        scale = rounding_scale(mine, 16, d_weights)
        assert_within(ref.dense_output()(inside).T - dense, 256 * EPS * scale)
        if ref.status == "running":  # scipy's proposal: its next step, when accepted
            nfev = ref.nfev
            ref.step()
            if ref.nfev - nfev == STAGE_EVALS and ref.t != t_bound:
                h_ref = abs(ref.t - ref.t_old)
                if attempts > 1:  # no growth right after a rejection (scipy's had none)
                    h_ref = min(h_ref, abs(mine.step_size))
                h_mine = min(mine.next_step, max_step)
                tol = proposal_sensitivity(mine, fun, rtol, atol)
                assert abs(h_ref - h_mine) <= tol * h_mine, (steps, h_ref, h_mine, tol)
                compared += 1
    return steps, rejected_steps, compared


@pytest.mark.parametrize("rtol", [1e-3, 1e-7, 1e-11])
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_steps_equal_scipys(name, rtol):
    fun, _, y0, t0, t_bound = SYSTEMS[name]
    steps, rejected, compared = synced_steps(fun, y0, t0, t_bound, rtol=rtol,
                                             atol=rtol * 1e-3)
    assert steps >= 10
    # the proposals really were compared (not where scipy's next step was rejected, which
    # hides its proposal, nor at the end)
    assert compared >= 0.5 * steps


def test_steps_equal_scipys_backwards_with_vector_atol_and_max_step():
    """Integration towards an earlier time, per-component atol, a step bound."""
    fun, _, y0, _, _ = SYSTEMS["arenstorf"]
    atol = np.array([1e-9, 1e-9, 1e-7, 1e-7])
    steps, _, compared = synced_steps(fun, y0, 0.0, -6.0, rtol=1e-8, atol=atol,
                                      max_step=0.05)
    assert steps >= 120  # 6 s at 0.05 s at most
    assert compared >= 0.5 * steps
    steps, rejected, _ = synced_steps(van_der_pol, [2.0, 0.0], 3.0, -3.0, rtol=1e-6,
                                      atol=np.array([1e-8, 1e-6]))
    assert steps >= 10


def test_some_steps_are_rejected():
    """The comparisons above cover rejected attempts too (van der Pol's fast phases)."""
    total = sum(synced_steps(van_der_pol, [2.0, 0.0], 0.0, 12.0, rtol=r, atol=r * 1e-3)[1]
                for r in (1e-3, 1e-7))
    assert total >= 1


@pytest.mark.parametrize("name", list(SYSTEMS))
@pytest.mark.parametrize("rtol", [1e-3, 1e-6, 1e-10])
def test_initial_step_is_scipys(name, rtol):
    """HNW's initial step (II.4): scipy's first step, when scipy accepts it at once."""
    fun, _, y0, t0, t_bound = SYSTEMS[name]
    mine = DOP853(fun, t0, y0, t_bound, rtol=rtol, atol=rtol * 1e-3)
    ref = ScipyDOP853(fun, t0, np.array(y0, dtype=float), t_bound, rtol=rtol,
                      atol=rtol * 1e-3)
    ref.step()
    assert ref.nfev == 2 + STAGE_EVALS  # accepted at once: its size is the initial step
    assert ref.t - t0 == pytest.approx(mine.next_step, rel=1e-14)


def test_initial_step_limits():
    """HNW's fall-backs and the bounds: a state and slope of zero take 1e-6 (h0 = 1e-6,
    h1 = max(1e-6, 1e-3 h0)); the step never exceeds max_step nor the interval."""
    assert DOP853(oscillator, 0.0, [0.0, 0.0], 10.0).next_step == 1e-6
    free = DOP853(oscillator, 0.0, [1.0, 0.0], 10.0).next_step
    assert DOP853(oscillator, 0.0, [1.0, 0.0], 10.0, max_step=free / 3).next_step == free / 3
    assert DOP853(oscillator, 0.0, [1.0, 0.0], free / 5).next_step == free / 5
    assert DOP853(oscillator, 0.0, [1.0, 0.0], 10.0, first_step=0.25).next_step == 0.25
    # y' = -1e-7 y: |y'| / sc = 1e-4 suggests h0 = 0.01 |y| / |y'| = 100, yet on [0, 1]
    # the Euler probe stays inside the interval, and the step is the interval
    times = []

    def slow(t, y):
        times.append(t)
        return -1e-7 * y

    assert DOP853(slow, 0.0, [1.0], 1.0).next_step == 1.0
    assert len(times) == 2 and max(times) <= 1.0


def test_minimal_step_failure():
    """y' = y^2, y(0) = 1 blows up at t = 1: the run fails with scipy's message where
    the step falls below 10 ulps of t, at scipy's time after as many evaluations."""
    def fun(t, y):
        return y * y

    for rtol in (1e-3, 1e-8):
        mine = DOP853(fun, 0.0, [1.0], 2.0, rtol=rtol, atol=rtol)
        ref = ScipyDOP853(fun, 0.0, np.array([1.0]), 2.0, rtol=rtol, atol=rtol)
        while mine.status == "running":
            message = mine.step()
        while ref.status == "running":
            ref_message = ref.step()
        assert mine.status == ref.status == "failed"
        assert message == ref_message
        assert mine.nfev == ref.nfev
        assert abs(mine.t - 1.0) < 1e-5 and mine.t == pytest.approx(ref.t, rel=1e-12)
        assert mine.next_step < 10 * 2 * EPS * abs(mine.t)


# -- accuracy against closed forms ---------------------------------------------------------
def test_order_eight_with_fixed_steps():
    """With steps held at h (max_step = first step = h, tolerances so loose that no step
    is rejected), the error of the oscillator after one period falls as h^8, and the
    dense output at mid-step as well (its local error is O(h^8))."""
    T = 2 * math.pi
    hs, errors, dense_errors = [], [], []
    for m in (6, 8, 12, 16):
        h = T / m
        s = DOP853("oscillator", 0.0, [1.0, 0.0], T, rtol=0.5, atol=0.5, max_step=h,
                   first_step=h, params=[1.0])
        worst = 0.0
        while s.status == "running":
            s.step()
            mid = s.step_start + 0.5 * s.step_size
            worst = max(worst, float(np.max(np.abs(s.dense(mid)
                                                   - [math.cos(mid), -math.sin(mid)]))))
        assert s.rejected == 0 and s.steps in (m, m + 1)
        hs.append(h)
        errors.append(float(np.max(np.abs(s.y - [1.0, 0.0]))))
        dense_errors.append(worst)
    assert 7.6 < np.polyfit(np.log(hs), np.log(errors), 1)[0] < 8.4
    assert 7.6 < np.polyfit(np.log(hs), np.log(dense_errors), 1)[0] < 8.4


def test_error_proportional_to_tolerance():
    """Adaptive steps: the error after ten periods of the oscillator falls in proportion
    to the tolerance (slope 1 in log-log; DOP853 controls the error per step with local
    extrapolation)."""
    tols = np.array([1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10])
    errors = []
    for r in tols:
        s = DOP853("oscillator", 0.0, [1.0, 0.0], 20 * math.pi, rtol=r, atol=r,
                   params=[1.0])
        assert s.run(max_steps=10**6) == "finished"
        errors.append(float(np.max(np.abs(s.y - [1.0, 0.0]))))
    assert 0.9 < np.polyfit(np.log(tols), np.log(errors), 1)[0] < 1.1
    assert max(e / r for e, r in zip(errors, tols, strict=True)) < 100


def test_arenstorf_orbit_closes():
    """The periodic orbit returns to its start after one period (HNW I, II.0)."""
    s = DOP853("arenstorf", 0.0, ARENSTORF_Y0, ARENSTORF_PERIOD, rtol=1e-11, atol=1e-11,
               params=[ARENSTORF_MU])
    assert s.run(max_steps=10**6) == "finished"
    assert np.max(np.abs(s.y - ARENSTORF_Y0)) < 1e-6


# -- the run's interface -------------------------------------------------------------------
def test_runs_in_chunks_equal_one_run():
    """run(t_stop, max_steps) stops after the first step that reaches t_stop, or after
    max_steps steps, and goes on from there as if never stopped: the same arithmetic,
    so the same numbers to the bit."""
    whole = DOP853("van_der_pol", 0.0, [2.0, 0.0], 10.0, rtol=1e-8, atol=1e-10,
                   params=[5.0])
    times = []
    while whole.status == "running":
        whole.step()
        times.append(whole.t)
    parts = DOP853("van_der_pol", 0.0, [2.0, 0.0], 10.0, rtol=1e-8, atol=1e-10,
                   params=[5.0])
    reached = []
    for t_stop in np.arange(1, 11):
        steps = parts.steps
        parts.run(t_stop, max_steps=7)
        assert parts.steps - steps <= 7
        assert parts.t >= t_stop or parts.steps - steps == 7
        assert parts.step_start < t_stop or parts.steps - steps == 0
        reached.append(parts.t)
        while parts.t < t_stop:
            parts.run(t_stop, max_steps=7)
    assert parts.status == "finished" and parts.t == 10.0
    assert parts.steps == len(times) and parts.nfev == whole.nfev
    np.testing.assert_array_equal(parts.y, whole.y)
    assert set(reached) <= set(times)


def test_dense_output_ends_on_the_step():
    s = DOP853("pendulum", 0.0, [2.5, 0.0], 5.0, rtol=1e-9, atol=1e-12, params=[9.81])
    with pytest.raises(RuntimeError, match="no step"):
        s.dense(0.0)
    s.run(2.0)
    nfev = s.nfev
    ends = s.dense([s.step_start, s.t])
    assert s.nfev == nfev + 3  # the three extra stages, once per step
    s.dense(0.5 * (s.step_start + s.t))
    assert s.nfev == nfev + 3
    assert_within(ends[0] - s.y_start, 4 * EPS * np.abs(s.y_start))
    assert_within(ends[1] - s.y, 64 * EPS * (np.abs(s.y) + np.abs(s.y_start)))


def test_python_exception_stops_the_run():
    calls = []

    def fun(t, y):
        calls.append(t)
        if len(calls) > 30:
            raise ValueError("boom")
        return -y

    s = DOP853(fun, 0.0, [1.0], 10.0)
    with pytest.raises(ValueError, match="boom"):
        s.run(max_steps=100)
    assert s.status == "stopped"
    assert s.state[_core.DOP_CODE] == _core.DOP_PY_ERROR


# -- projection, stage projection and the error filter -------------------------------------
G, L = np.array([0.0, -9.81]), 1.0


def cartesian_pendulum(t, y):
    """A particle held at distance L from the origin (index-1 form): a = g - lam r,
    lam = (r . g + |v|^2) / |r|^2."""
    r, v = y[:2], y[2:]
    lam = (r @ G + v @ v) / (r @ r)
    return np.concatenate((v, G - lam * r))


def onto_circle(y):
    """y moved onto |r| = L, r . v = 0 in place; the size of the move."""
    before = y.copy()
    r = y[:2] * (L / math.hypot(y[0], y[1]))
    u = r / L
    y[:2] = r
    y[2:] -= (y[2:] @ u) * u
    return float(np.max(np.abs(y - before)))


def test_projection_after_each_step():
    """After every accepted step the state is on the circle to rounding; the next step
    starts from a fresh derivative exactly when the move exceeded refresh * atol, else
    from the derivative at the step's unprojected end (k_13)."""
    atol, refresh = 1e-10, 1e-2
    moves = []

    def project(t, y):
        moves.append(onto_circle(y))
        return moves[-1], 0.0

    y0 = [math.sin(2.0), -math.cos(2.0), 0.0, 0.0]
    s = DOP853(cartesian_pendulum, 0.0, y0, 3.0, rtol=1e-7, atol=atol, project=project,
               refresh=refresh)
    n = s.n
    while s.status == "running":
        steps = s.steps
        refreshed = s.refreshed
        s.step()
        assert s.steps == steps + 1
        assert abs(math.hypot(s.y[0], s.y[1]) - L) < 4 * EPS
        assert abs(s.y[:2] @ s.y[2:]) < 64 * EPS * (1 + np.abs(s.y[2:]).max())
        fresh = s.refreshed - refreshed
        assert fresh == (moves[-1] > refresh * atol)
        k13 = s.work[(_core.DOP_W_K + 12) * n:(_core.DOP_W_K + 13) * n]
        np.testing.assert_array_equal(s.f, cartesian_pendulum(s.t, s.y) if fresh else k13)
    assert 0 < s.refreshed < s.steps
    assert s.nfev == 2 + STAGE_EVALS * (s.steps + s.rejected) + s.refreshed


def test_dense_output_after_a_projection():
    """The dense output of a step whose end was projected runs from y_start to the
    projected y, with the slopes the steps start from: k_1 at the start, and at the end
    the fresh derivative at the projected state (an artificial move of 1 % of the
    velocity, far above refresh), not k_13 at the unprojected end."""
    def project(t, y):
        move = 0.01 * float(np.max(np.abs(y[2:])))
        y[2:] *= 0.99
        return move, 0.0

    y0 = [math.sin(2.0), -math.cos(2.0), 3 * math.cos(2.0), 3 * math.sin(2.0)]
    s = DOP853(cartesian_pendulum, 0.0, y0, 3.0, rtol=1e-9, atol=1e-12, project=project,
               refresh=1e-2)
    n, d = s.n, 1e-4
    for _ in range(30):
        s.step()
        h = s.step_size
        k1 = s.work[_core.DOP_W_K * n:(_core.DOP_W_K + 1) * n].copy()
        k13 = s.work[(_core.DOP_W_K + 12) * n:(_core.DOP_W_K + 13) * n].copy()
        p = s.dense(s.step_start + h * np.array([0.0, d, 2 * d, 1 - 2 * d, 1 - d, 1.0]))
        start = (-3 * p[0] + 4 * p[1] - p[2]) / (2 * d * h)  # second-order differences
        end = (3 * p[5] - 4 * p[4] + p[3]) / (2 * d * h)
        # their error: d^2 / 3 max|p'''| / h, p of degree 7 in s whose coefficients are
        # sums of the dense rows (|p'''| <= 210 their sum); rounding: 8 eps |y| / (d h)
        rows = s.work[_core.DOP_W_DENSE * n:(_core.DOP_W_DENSE + 7) * n].reshape(7, n)
        tol = (d * d / 3 * 210 * np.abs(rows).sum(axis=0) / abs(h)
               + 8 * EPS * np.abs(s.y).max() / (d * abs(h)))
        assert_within(start - k1, tol)
        assert_within(end - s.f, tol)
        assert np.all(np.abs(s.f - k13)[:2] > 10 * tol[:2])  # the slopes it tells apart


def test_filtered_steps():
    """A projection that asks for filtered steps: every evaluation of those steps (and
    of their dense output) is made at the stage callback's projection of a copy, the
    two error estimates pass through the tangent callback, and each step is followed by
    a fresh derivative (the projection here reports no move: only the filtering asks
    for it); the flags say which steps were filtered."""
    calls = {"stage": 0, "tangent": 0}
    filter_from = 5

    def project(t, y):
        onto_circle(y)
        return 0.0, float(s_steps() + 1 >= filter_from)

    def stage(t, y):
        calls["stage"] += 1
        onto_circle(y)

    def tangent(t, y, e):
        calls["tangent"] += 1

    y0 = [math.sin(2.0), -math.cos(2.0), 0.0, 0.0]
    s = DOP853(cartesian_pendulum, 0.0, y0, 3.0, rtol=1e-7, atol=1e-10, project=project,
               stage=stage, tangent=tangent, refresh=1e-2)

    def s_steps():
        return s.steps

    for k in range(1, 12):
        nfev, attempts = s.nfev, s.rejected
        before = dict(calls)
        refreshed = s.refreshed
        s.step()
        attempts = 1 + s.rejected - attempts
        filtered = k >= filter_from
        assert s.state[_core.DOP_FILTER] == filtered
        assert s.state[_core.DOP_FILTER_NEXT] == (k + 1 >= filter_from)
        if filtered:
            assert calls["stage"] - before["stage"] == s.nfev - nfev
            assert calls["tangent"] - before["tangent"] == 2 * attempts
            assert s.refreshed == refreshed + 1
            s.dense(s.t)
            assert calls["stage"] - before["stage"] == s.nfev - nfev
        else:
            assert calls == before
            assert s.refreshed == refreshed


def test_error_filter_drives_the_step_size():
    """An error filter that removes all of the estimate: every step is accepted and the
    next one is fac_max = 10 times longer (up to max_step)."""
    def project(t, y):
        return 0.0, 1.0

    def tangent(t, y, e):
        e[:] = 0.0

    s = DOP853(oscillator, 0.0, [1.0, 0.0], 100.0, rtol=1e-10, atol=1e-12,
               project=project, tangent=tangent, filter_first=True, first_step=1e-6,
               max_step=1.0)
    sizes = []
    for _ in range(5):
        s.step()
        sizes.append(s.step_size)
    np.testing.assert_allclose(sizes, [1e-6, 1e-5, 1e-4, 1e-3, 1e-2], rtol=1e-12)
    assert s.rejected == 0
