"""`simulate(model, t_end, fps) -> Trajectory`: integrate the Newton-Euler equations

    ẋ = v,   q̇ = ½ q ⊗ (0, ω),   v̇ = a_G,   ω̇ = J⁻¹ (B_M − ω × J ω)     per body,

where (a_G, ω̇) = M⁻¹ (Q + G λ − b) come from the compiled core (`mbody.kernel`: the same
loads, gyroscopic terms and reaction columns as `assemble`), with the reactions not given
(in the file or as `known`) solved at every evaluation.

State: x (n, 3) world, q (n, 4) W_R_B quaternions [w, x, y, z], v (n, 3) world, ω (n, 3)
body axes, packed as blocks ``[x | q | v | ω]`` (13 n numbers; planar models add θ (n))
so that every block is a contiguous (n, k) view: the core's layout (kernel.h).

Quaternions: the exact flow keeps ‖q‖ = 1 (q̇ · q = 0), so q is integrated as it is; the
rotation used inside the derivative is built from q/‖q‖, and the quaternions stored at the
output samples are divided by their norms (the largest |‖q‖ − 1| before that is reported
as ``info['quaternion_norm_error']``). The integrator is never restarted, so the
renormalisation changes nothing but the stored samples.

How the run steps is `mbody.simulate.stepping`'s: DOP853 (the default) entirely in the
core, the other methods through scipy. Accelerations are pluggable: `dynamics(model,
state) -> (n, 6)` rows [a_G world, ω̇ body axes] replaces the core's (called from Python
at every evaluation).
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.conventions import check_axes
from mbody.equations.joints import joint_errors
from mbody.equations.workspace import Unknowns, workspace
from mbody.errors import (
    MbodyError,
    UnknownReactionsError,
    did_you_mean,
    option_name,
    option_setting,
    real_number,
)
from mbody.kernel import _core
from mbody.model.arguments import (
    KnownValues,
    checked_model,
    checked_state,
    known_values,
)
from mbody.model.expressions import Expression, first_nonfinite
from mbody.model.model import Model, State
from mbody.simulate.mechanism import (
    BAUMGARTE_RATE,
    STAGE_PIVOT_RTOL,
    JointProjection,
    conserved_figures,
    sample_figures,
)
from mbody.simulate.stepping import CORE, start
from mbody.simulate.trajectory import (
    Trajectory,
    appearance,
    last_sample_warning,
    model_text,
    model_values,
)
from mbody.solve.dynamics import Dynamics, StateDerivative, accelerations
from mbody.solve.kinematics import fully_driven

if TYPE_CHECKING:  # a TypeVar made at run time is 0.02 ms of every simulation's start
    from typing import TypeVar

    _T = TypeVar("_T")

METHODS = ("DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA")
"""The integrators: DOP853 is the compiled core's, the others scipy.integrate's (imported
when such a run starts)."""
DEFAULT_RTOL = 1e-10
DEFAULT_ATOL = 1e-12
DEFAULT_MAX_STEPS = 1_000_000
"""Step budget of a run. The heaviest shipped model needs about 9 300 steps for 10 s (the
slider-crank that ran away to 700 rad/s, 24 500): a hundred times that, yet a small
mechanism (a few microseconds per step) reaches it in seconds, a large one in minutes."""


def known_reaction_dynamics(model: Model, known: KnownValues | None = None
                            ) -> KnownReactionDynamics:
    """The default derivative: every reaction value known (file, then `known`), λ(t) applied.

    `known` values are numbers or expressions of t (text, see docs/expressions.md).
    Raises `UnknownReactionsError` when a reaction component has no value.
    """
    given = with_known(model, known)
    labels = model.reactions
    missing = [r for r in labels if r not in given.known_reactions]
    if missing:
        raise UnknownReactionsError(missing)
    base = np.array([given.known_reactions[r] for r in labels], dtype=float)
    varying = [(given.reaction_index[r], e) for r, e in given.known_expressions.items()
               if not e.constant]
    return KnownReactionDynamics(base, varying)


class KnownReactionDynamics:
    """f(model, state) -> (n, 6) accelerations with every reaction value given (a
    `mbody.solve.dynamics.Dynamics`): `base` (m,) the values in ``model.reactions``
    order, `expressions` [(index, expression of t)] those that vary in time."""

    def __init__(self, base: np.ndarray, expressions: list[tuple[int, Expression]]):
        self.base, self.expressions = base, expressions
        self.varying = bool(expressions)
        """Whether some reaction value varies in time."""

    def values_at(self, t: float) -> np.ndarray:
        """(m,) the reaction values at time t."""
        if not self.expressions:
            return self.base
        lam = self.base.copy()
        for i, e in self.expressions:  # one call per time-varying reaction, not per body
            lam[i] = e(t)
        return lam

    def reactions_at(self, t: np.ndarray) -> np.ndarray:
        """(K, m) reaction values at the sample times t (K,)."""
        out = np.broadcast_to(self.base, (len(t), len(self.base))).copy()
        for i, e in self.expressions:
            out[:, i] = e(t)
        return out

    def __call__(self, model: Model, state: State) -> np.ndarray:
        return accelerations(model, state,
                             self.values_at(state.t) if len(self.base) else None)


class _Progress:
    """tqdm bar over simulated time on stderr (a no-op when disabled)."""

    def __init__(self, enabled: bool, t_end: float, label: str):
        self.bar = None
        if enabled:
            from tqdm import tqdm  # type: ignore[import-untyped]  # tqdm ships no types

            self.bar = tqdm(total=t_end, unit="s", file=sys.stderr, desc=label, leave=True,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| t = {n:.3g} / "
                            "{total:.3g} s [{elapsed}<{remaining}]")
        self.t = 0.0

    def update(self, t: float) -> None:
        if self.bar is not None and t > self.t:
            self.bar.update(t - self.t)
            self.t = t

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def simulate(model: Model, t_end: float = 10.0, fps: float = 60, *,
             rtol: float = DEFAULT_RTOL, atol: float = DEFAULT_ATOL, method: str = "DOP853",
             known: Mapping[str, float | str] | None = None, progress: bool = False,
             dynamics: Dynamics | None = None, max_step: float = math.inf,
             initial: State | None = None, max_steps: int | None = DEFAULT_MAX_STEPS,
             max_wall: float | None = None, axes: str = "joint") -> Trajectory:
    """Integrate the motion from `initial` (default the model's state) to `t_end` seconds.

    Samples at t = k / fps for k = 0 .. ⌊t_end · fps⌋: the last sample is at t_end when
    t_end · fps is a whole number (to within rounding), else before it, and
    ``info["warnings"]`` then says where and which fps samples t_end. Reactions not given
    in the file or in `known` are solved for at every step, the joints held by
    projection (DOP853) or Baumgarte's terms (scipy's methods).

    Every argument is checked before any work: numbers must be numbers (not text, not
    bools; an `MbodyTypeError`, also a `TypeError`), in their ranges (`MbodyError`).

    Parameters
    ----------
    model : Model
        The model, from `load` or `loads` (a file's path is refused: read it with
        ``mbody.load(path)`` first, so that one model serves many runs).
    t_end : float
        End of the run (s), > 0.
    fps : float
        Samples per second of simulated time (1/s), > 0.
    rtol, atol : float
        The integrator's relative and absolute error tolerances per step (per state
        component); 0 < rtol < 1, atol > 0.
    method : str
        One of `METHODS` (DOP853: explicit Runge-Kutta of order 8 with a 7th-order
        interpolant, the compiled core's; RK45 and RK23 scipy's explicit ones; Radau, BDF
        and LSODA scipy's for stiff problems).
    known : mapping of str to float or str, optional
        Reaction values by label (N; N m), finite numbers or expressions of t (text, see
        docs/expressions.md), added to the file's (replacing its value of that label).
    progress : bool
        Show a progress bar over simulated time on stderr (tqdm).
    dynamics : Dynamics, optional
        Replaces the default accelerations: f(model, state) -> (n, 6) rows [a_G (world,
        m/s²), ω̇ (body axes, rad/s²)] (see `mbody.solve.dynamics.Dynamics`).
    max_step : float
        Longest integrator step (s), > 0; unbounded by default (``math.inf``).
    initial : State, optional
        The state to start from (default ``model.initial``); the run starts at t = 0. A
        `State` of the model's bodies with finite values (`mbody.model.arguments.
        checked_state`); for the state at given joint coordinates,
        `mbody.solve.configure.configure`.
    max_steps : int or None
        Budget of integrator steps (None: no limit).
    max_wall : float or None
        Budget of wall-clock seconds (None: no limit). A run that hits either budget
        stops with an `MbodyError` saying where and why.
    axes : {"joint", "world"}
        The axes of the stored reactions (`Trajectory.reactions`, ``reaction_labels``):
        each component along its joint frame (the default), or each joint's force and
        moment on its child along world x, y, z (``A.Fx, A.Fy...``, the drivers' efforts
        kept; `mbody.simulate.axes`). ``info["reaction_axes"]`` says which.

    Returns
    -------
    Trajectory
        The sampled motion, whose `info` holds the run facts and drift figures, and under
        ``info["warnings"]`` what looked wrong (a cost that exploded, a spin the frame
        rate aliases, samples too sparse for the drivers' motion to trust its peaks, a last
        sample short of t_end).

    Raises
    ------
    MbodyError
        An argument out of range or of the wrong type, an unknown method or reaction
        label, a state of another model, or a budget hit.
    """
    if not isinstance(model, Model):
        model = checked_model(model)
    t_end = real_number(t_end, "t_end", "a positive number of seconds")
    fps = real_number(fps, "fps", "a positive number of samples per second")
    if not (math.isfinite(t_end) and t_end > 0):
        raise MbodyError(f"t_end must be a positive number of seconds, got {t_end:g}")
    if not (math.isfinite(fps) and fps > 0):
        raise MbodyError(f"fps must be a positive number of samples per second, got {fps:g}")
    rtol = real_number(rtol, "rtol", "a number between 0 and 1 (relative tolerance)")
    atol = real_number(atol, "atol", "a positive number (absolute tolerance)")
    if not (0 < rtol < 1) or not (atol > 0):
        raise MbodyError(f"tolerances must satisfy 0 < rtol < 1 and atol > 0 "
                         f"(got rtol={rtol:g}, atol={atol:g})")
    max_step = real_number(max_step, "max_step", "a positive number of seconds (inf: no bound)")
    if not max_step > 0:  # NaN too
        raise MbodyError(f"max_step must be a positive number of seconds (inf: no bound), "
                         f"got {max_step:g}")
    check_axes(axes)
    if method not in METHODS:
        raise MbodyError(f"unknown integrator {method!r}; "
                         + (did_you_mean(method, METHODS) or f"one of {', '.join(METHODS)}"))
    if max_steps is not None and (isinstance(max_steps, bool) or not isinstance(
            max_steps, int | np.integer) or max_steps < 1):
        raise MbodyError(f"max_steps must be a positive whole number of steps or None, "
                         f"got {max_steps!r}")
    if max_wall is not None and not (isinstance(max_wall, int | float | np.number)
                                     and math.isfinite(max_wall) and max_wall > 0):
        raise MbodyError(f"max_wall must be a positive number of seconds or None, "
                         f"got {max_wall!r}")
    K = int(math.floor(t_end * fps + 1e-9)) + 1
    if K > 10_000_000:
        raise MbodyError(f"{K} output samples requested (t_end * fps); at most 10 million")
    if initial is not None:
        initial = checked_state(model, initial, "initial")
    given: KnownValues | None = None if known is None else known_values(model, known)
    plan = _prepared(model, given, dynamics, initial, method)
    if t_end not in plan.spans_checked:  # a span of the same model's runs, checked once
        _check_span(plan.varying, t_end)
        if len(plan.spans_checked) >= SPANS_KEPT:  # a sweep of t_end: kept bounded
            plan.spans_checked.clear()
        plan.spans_checked.add(t_end)
    if plan.driven:
        # the drivers fix the motion: each sample's kinematics then its reactions, no
        # integration. Imported here, as below: only some runs need these modules, and a
        # fresh process's first run pays for every module it imports (issue 24)
        from mbody.simulate.kinematic import kinematic_run

        return kinematic_run(with_known(model, given), t_end, fps, axes=axes)
    varying, mechanism, projecting = plan.varying, plan.mechanism, plan.projecting
    # no Baumgarte terms where the core projects, nor where no reaction is unknown
    rhs = state_derivative(model, given, dynamics, projected=projecting or not mechanism)
    run_model = rhs.model  # the model with `known`'s values in its known reactions
    y0, ratio = plan.y0, plan.ratio  # read only: each run steps its own copy
    n = model.n
    planar = model.dimension == cv.PLANAR
    size = len(y0)
    bar = _Progress(progress, t_end, model.name or "simulate")
    t_eval = _sample_times(model, K, fps, t_end)
    Y = np.empty((K, size))
    Y[0] = y0
    k, steps = 1, 0
    rate = _StepRate(t_end)
    wall = time.perf_counter()
    try:
        run = start(method, rhs, y0, t_end, rtol, atol, max_step, project=projecting,
                    filter_first=ratio < STAGE_PIVOT_RTOL)
        check_at = PREDICT_FROM
        first = None
        # the core notes where each step-rate window ends as it steps: no return to
        # Python at each one (scipy's runs come back after every step anyway). A wall-time
        # budget is checked in Python, so such a run still comes back at every window.
        marking = max_wall is None and run.mark_windows(rate.width)
        run.return_after(CHUNK_WALL)
        status = run.status
        while status == "running":
            limit = max(1, check_at - steps)
            if max_steps is not None:
                limit = min(limit, max(1, max_steps - steps))
            k, msg = run.advance(t_end if marking else min(rate.next, t_end), limit, t_eval,
                                 k, Y)
            steps, status = run.steps, run.status
            if status == "failed" or not math.isfinite(np.add.reduce(run.y)):
                from mbody.simulate.budget import blame_expression

                culprit = blame_expression(varying, run.t, run.t, run.step_size)
                raise MbodyError(
                    f"the integration stopped at t = {run.t:.6g} s: "
                    + (culprit or (msg or "the state is no longer finite")
                       + " (a body escaping to infinity, or tolerances too tight for "
                       "double precision?)"))
            if marking:
                rate.steps_at(run.marks())
            else:
                rate.step(run.t, steps)
            if progress:
                bar.update(run.t)
            if status == "running":
                if steps >= check_at:  # the whole run's cost, predicted from its start
                    check_at = 2 * steps
                    from mbody.simulate.budget import predict

                    predict(model, method, run.t, t_end, steps, rate, max_steps, max_wall,
                            time.perf_counter() - wall)
                if max_steps is not None and steps >= max_steps:
                    from mbody.simulate.budget import budget_message

                    raise MbodyError(budget_message(
                        f"the step budget: {steps} steps "
                        f"({option_setting('max_steps', max_steps)})",
                        run.t, t_end, steps, rate, f"at that rate the whole run needs "
                        f"about {steps * t_end / run.t:.2g} steps" if run.t > 0 else
                        "the steps do not advance the time",
                        f"raise {option_name('max_steps')}"))
                if max_wall is not None:
                    now = time.perf_counter()
                    if first is None:  # the pace is timed from here: no start-up costs
                        first = (run.t, now)
                    if now - wall > max_wall:
                        pace = ((now - first[1]) / (run.t - first[0]) if run.t > first[0]
                                else (now - wall) / run.t if run.t > 0 else math.inf)
                        from mbody.simulate.budget import budget_message

                        raise MbodyError(budget_message(
                            f"the wall-time budget: {now - wall:.3g} s "
                            f"({option_setting('max_wall', float(max_wall))})", run.t, t_end,
                            steps, rate, f"at that pace the rest of the run takes about "
                            f"{pace * (t_end - run.t):.2g} s more" if math.isfinite(pace)
                            else "no simulated time has passed yet",
                            f"raise {option_name('max_wall')}"))
    finally:
        bar.close()
    wall = time.perf_counter() - wall
    stepping_time = run.integration_time
    if stepping_time is None:  # scipy's: the loop's wall time
        stepping_time = wall

    # Y holds the stored samples from here: unit quaternions, and the planar angles set
    # to theirs (the projections turn q, not the angle carried beside it), in one pass
    q_err = _core.unit_samples(Y, n, planar)
    q = Y[:, 3 * n:7 * n].reshape(K, n, 4)
    x = Y[:, :3 * n].reshape(K, n, 3)
    v = Y[:, 7 * n:10 * n].reshape(K, n, 3)
    w = Y[:, 10 * n:13 * n].reshape(K, n, 3)

    labels = tuple(model.reactions)
    joint_info: dict = {}
    lengths = None
    if mechanism:
        assert rhs.unknowns is not None
        figures = sample_figures(run_model, rhs.unknowns, t_eval, Y,
                                 lengths=bool(len(model.springs.names)))
        assert figures.reactions is not None
        lam, lengths = figures.reactions, figures.lengths
        held = (PROJECTION_TEXT if projecting else
                f"Baumgarte, alpha = beta = {BAUMGARTE_RATE:g} 1/s (scipy's integrators "
                "keep their own history of the state, which a projection would break)")
        joint_info = {"joint_stabilisation": held,
                      "joint_position_drift": figures.position_drift,
                      "joint_velocity_drift": figures.velocity_drift,
                      "initial_joint_errors": _initial_joint_errors(model, initial, given),
                      "projection_evaluations": run.refreshed}
    elif dynamics is None and labels:
        lam = known_reaction_dynamics(model, given).reactions_at(t_eval)
    else:
        lam = np.zeros((K, 0))
    stored, values = labels, lam
    if axes == "world" and labels and lam.shape[1] == len(labels):
        from mbody.simulate.axes import world_series

        stored, values = world_series(run_model, t_eval, Y, lam)
    info = {
        "integrator": method, "rtol": rtol, "atol": atol, "t_end": t_end, "fps": fps,
        "samples": K, "steps": steps, "evaluations": run.nfev,
        "sampling_evaluations": run.sampling_evaluations, "step_rate": rate.figures(steps),
        "evaluation_path": "compiled" if rhs.compiled else "python",
        "wall_time_s": wall, "integration_time_s": stepping_time,
        "quaternion_norm_error": q_err,
        "quaternion_handling": "integrated as is; rotation built from q/|q|; output "
                               "samples divided by |q|",
        **joint_info, "reaction_axes": axes,
    }
    shapes, colors, text, values_set = _memo(
        model, ("carried",), lambda: (*appearance(model), model_text(model),
                                      tuple(map(tuple, model_values(model)))))
    if values_set:  # what Trajectory.model sets again on the text it carries
        info["model_values"] = [list(pair) for pair in values_set]
    pose: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] = (
        (x[..., :2], v[..., :2], Y[:, 13 * n:], w[..., 2]) if planar else (x, v, q, w))
    traj = Trajectory(
        t_eval, *pose, body_names=model.body_names, dimension=model.dimension,
        model_name=model.name, model_file=model.file, reaction_labels=stored,
        reactions=values, info=info, mass=np.array(model.mass), inertia=np.array(model.J),
        shapes=shapes, colors=colors, gravity=np.array(model.gravity),
        model_yaml=text)
    series, drift, spin_peak = _drift(run_model, t_eval, Y, dynamics is None,
                                      ideal_joints=mechanism, lengths=lengths)
    traj.series.update(series)  # run_model: `known` is among its reactions
    info.update(drift)
    if mechanism and run_model.drivers is not None and len(run_model.drivers.names):
        from mbody.simulate.kinematic import driven_figures

        assert rhs.unknowns is not None
        driven_figures(run_model, traj, Y, lam, rhs.unknowns)
    broken = info.get("initial_joint_errors")
    # a run with drivers has its samples' warning already (driven_figures: record_peaks)
    info["warnings"] = [w for w in (last_sample_warning(t_end, fps),
                                    _broken_start(broken, projecting) if broken else None,
                                    rate.warning(), _spin_warning(traj, spin_peak)) if w
                        ] + info.get("warnings", [])
    return traj


SPIN_WARNING = "spin faster than "
"""How the warning of a spin the frame rate aliases begins (`_spin_warning`): an animation
of the samples would show it turning slower or backwards."""
BROKEN_START = "the initial state breaks joint constraints: "
"""How the warning of a start off its joints begins (`_broken_start`)."""


def _broken_start(broken: list[str], projected: bool) -> str:
    """The warning of a run whose start breaks the joints `broken` (their errors as text,
    `joint_errors`), as its joints were held: by projection, or by Baumgarte's terms."""
    return (BROKEN_START + ", ".join(broken)
            + ("; the run starts from the nearest state that keeps them (projected), so "
               "energy and the motion are not those of the state as written" if projected
               else "; the stabilisation pulls the joints together, so energy and the "
               "early motion are not those of the model as written"))


PROJECTION_TEXT = ("coordinate projection after every step: positions by Gauss-Newton, "
                   "velocities mass-orthogonal")
CHUNK_WALL = 0.1
"""Seconds of wall time after which a compiled call comes back for the loop to look at its
budgets, progress and Ctrl-C: a steady pace whatever a step costs (a fixed count of steps
was either many round trips on a cheap model or seconds between looks on a dear one)."""

SPANS_KEPT = 64
"""Spans (t_end) whose check of the varying loads a model keeps before it starts over."""

PREDICT_FROM = 1000
"""Steps after which (and after twice, four times as many...) a run's total cost is
predicted from its rate so far."""
def _varying_expressions(model: Model, known: KnownValues | None
                         ) -> list[tuple[str, Expression]]:
    """(what it is, expression) for every load component and known reaction that varies
    in time, `known` included (compiled here, so a bad one is reported before any work)."""
    out = []
    for ld in model.loads:
        for k, e in sorted(ld.expressions.items()):
            comp = "" if model.dimension == cv.PLANAR and ld.type == "torque" else \
                f" {'xyz'[k]}"
            out.append((f"the load '{ld.name}' ({ld.type}{comp} on {ld.bodies[0]})", e))
    exprs = dict(model.known_expressions)
    for label, v in (known_values(model, known) if known else {}).items():
        if isinstance(v, Expression):
            exprs[label] = v
        else:
            exprs.pop(label, None)
    out += [(f"the known reaction {label}", e) for label, e in exprs.items()
            if not e.constant]
    return out


def _check_span(varying: list[tuple[str, Expression]], t_end: float) -> None:
    """Refuse, before any work, a run over a span where a load expression is not finite."""
    for what, e in varying:
        bad = first_nonfinite(e, t_end)
        if bad is not None:
            t = bad[0]
            raise MbodyError(
                f"{what} = \"{e.text}\" is not finite at t = {t:g} s ({bad[1]}), within the "
                f"simulated span 0 .. {t_end:g} s: the integration could not go past it. "
                + ("Change the expression (it is sampled every millisecond)." if t == 0 else
                   f"Change the expression, or simulate a shorter span ("
                   f"{option_name('t_end')} below {t:g})."))


class _StepRate:
    """Steps per simulated second, to catch a run whose cost explodes.

    The rate over the first part of the run (until t_end / `WINDOWS`) is the baseline; the
    rest is cut into windows of the same length, and a window whose rate exceeds `FACTOR`
    times the baseline (with at least `MIN_STEPS` steps in it, so that a few steps more
    on a cheap run say nothing) is kept for a warning.
    """

    WINDOWS, FACTOR, MIN_STEPS = 20, 20.0, 100

    def __init__(self, t_end: float):
        self.t_end, self.width = t_end, t_end / self.WINDOWS
        self.start: tuple[float, float] | None = None  # (t, steps per second) until t
        self.mark: tuple[float, float] = (0.0, 0)  # (t, steps) where the window began
        self.next = self.width
        self.slow: list[tuple[float, float, float]] = []  # (t0, t1, rate) windows
        self.peak = 0.0

    def step(self, t: float, steps: int) -> None:
        """The run is at t after `steps` steps: a window that ends there is counted."""
        self.steps_at(((t, steps),))

    def steps_at(self, marks: Iterable[Sequence[float]]) -> None:
        """The run passed each (t, steps) of `marks`, in time order (the core's notes
        where a window ends, `CoreRun.marks`): the windows ending there are counted."""
        # locals only in the loop: it runs for every window of every run, and is most of
        # a short run's time outside the integration (issue 24)
        start, (t0, n0), nxt, peak = self.start, self.mark, self.next, self.peak
        t_end, width, floor, least = self.t_end, self.width, math.floor, self.MIN_STEPS
        too_fast = math.inf if start is None else self.FACTOR * start[1]
        for t, steps in marks:
            if t < nxt and t < t_end:
                continue
            r = (steps - n0) / (t - t0)
            if start is None:
                start, too_fast = (t, r), self.FACTOR * r
            elif r > too_fast and steps - n0 >= least:
                self.slow.append((t0, t, r))
            if r > peak:
                peak = r
            t0, n0 = t, steps
            nxt = (floor(t / width) + 1) * width
        self.start, self.mark, self.next, self.peak = start, (t0, n0), nxt, peak

    def figures(self, steps: int) -> dict:
        """Steps per simulated second: over the first part, the busiest window, overall."""
        return {"start": float(self.start[1]) if self.start else None,
                "peak": float(self.peak), "overall": steps / self.t_end}

    def so_far(self, t: float, steps: int) -> str:
        """'N steps per simulated second so far (M over the first T s)'."""
        if t <= 0:
            return f"{steps} steps without simulated time passing"
        text = f"{steps / t:.4g} steps per simulated second so far"
        if self.start is not None:
            text += f" ({self.start[1]:.4g} over the first {self.start[0]:.3g} s"
            t0, n0 = self.mark
            if t > t0 and steps > n0:
                text += f", {(steps - n0) / (t - t0):.4g} since t = {t0:.3g} s"
            text += ")"
        return text

    def warning(self) -> str | None:
        if not self.slow or self.start is None:
            return None
        t0, t1, r = max(self.slow, key=lambda w: w[2])
        t_start, base = self.start
        return (f"the integration slowed down from t = {self.slow[0][0]:.3g} s: "
                f"{r:.4g} steps per simulated second at t = {t0:.3g} .. {t1:.3g} s, "
                f"{r / base:.0f} times the {base:.4g} per second over the first "
                f"{t_start:.3g} s. Something in the model speeds up or stiffens (a spin-up "
                "or runaway, a load that varies ever faster, a stiff spring): check the "
                "motion; a shorter --t-end, a looser --rtol (1e-8), or --method Radau "
                "for a stiff model cost less")


def _spin_warning(traj: Trajectory, peak: np.ndarray | None = None) -> str | None:
    """A body whose spin aliases the frame rate: |ω| / 2π > fps / 2 at a sample. `peak`:
    each body's largest |ω| (rad/s) when known (the core's, `conserved_figures`): the
    samples are then looked at only when a body is that fast."""
    fps = traj.info["fps"]
    if peak is not None:
        # the fastest body's test alone (division is monotonic); max() returns a NaN that
        # comes first, and a NaN is never fast: then each body is looked at below
        top = max(peak.tolist(), default=0.0)
        if top == top and not top / (2 * math.pi) > fps / 2:
            return None
    w = traj.angular_velocity
    if traj.n == 0 or not len(w):
        return None
    rate = np.abs(w) if traj.dimension == cv.PLANAR else np.linalg.norm(w, axis=2)
    at = rate.argmax(axis=0)  # (n,) the sample of each body's largest |ω|
    # one figure per body from here: Python floats (numpy's first stable argsort and
    # scalar formatting in a process cost a first run tens of microseconds)
    peaks = rate[at, range(traj.n)].tolist()  # (n,) rad/s
    fast = sorted((i for i, p in enumerate(peaks) if p / (2 * math.pi) > fps / 2),
                  key=lambda i: -peaks[i])  # fastest first; a tie keeps file order
    if not fast:
        return None
    times = traj.t[at].tolist()
    listed = ", ".join(f"{traj.body_names[i]} at up to {peaks[i]:.4g} rad/s "
                       f"({peaks[i] / (2 * math.pi):.3g} rev/s, at t = "
                       f"{times[i]:.3g} s)" for i in fast[:3])
    if len(fast) > 3:
        listed += f" and {len(fast) - 3} more bod{'y' if len(fast) == 4 else 'ies'}"
    need = math.ceil(2 * peaks[fast[0]] / (2 * math.pi))
    return (f"{SPIN_WARNING}{fps:g} fps can show: {listed}. A body turning more than "
            f"half a revolution between frames (|omega| / 2 pi > fps / 2 = {fps / 2:g} "
            f"rev/s) looks in an animation as if it turned slower or backwards; use "
            f"--fps {need} or more")


def state_derivative(model: Model, known: KnownValues | None = None,
                     dynamics: Dynamics | None = None, *, projected: bool | None = None
                     ) -> StateDerivative:
    """ẏ = f(t, y), what `simulate` integrates (`mbody.solve.dynamics.StateDerivative`): the
    compiled core's, with the reactions not given in the file or in `known` solved at every
    call (Baumgarte-stabilised, α = β = `BAUMGARTE_RATE`), or `dynamics` when given.
    `projected`: True leaves Baumgarte's terms out (a run that projects the state onto the
    joints, or whose model has no unknown reaction: `simulate` knows which); None leaves
    them out only for a model without unknown reactions. Its `model` is `model` with
    `known`'s values among its known reactions (numbers, or expressions of t that the core
    evaluates)."""
    if dynamics is not None:
        return StateDerivative(model, dynamics)
    run_model = with_known(model, known)
    if projected is None:
        projected = not _has_unknown_reactions(run_model, None)
    return StateDerivative(run_model, unknowns=workspace(run_model).file_unknowns,
                           rate=0.0 if projected else BAUMGARTE_RATE)


def with_known(model: Model, known: KnownValues | None) -> Model:
    """`model` with the reaction values `known` (label -> number, or expression of t as
    text) among its known reactions, replacing the file's value of a label; the same model
    when `known` is empty. Raises `MbodyError` for a label the model does not have, a
    value that is not a finite number or an expression (`known_values`)."""
    if not known:
        return model
    values: dict[str, float] = dict(model.known_reactions)
    exprs: dict[str, Expression] = dict(model.known_expressions)
    for label, v in known_values(model, known).items():
        exprs.pop(label, None)
        if isinstance(v, Expression):
            values[label] = v.value
            exprs[label] = v
        else:
            values[label] = v
    return dataclasses.replace(model, known_reactions=values, known_expressions=exprs)


def potential_energy(model: Model, traj: Trajectory, lengths: np.ndarray | None = None
                     ) -> np.ndarray:
    """V = −Σ m g·x + Σ ½ k (L − L0)²: (K,) gravity and spring potential, J; the springs'
    lengths L (K, s) as given, else from the compiled core at the trajectory's samples."""
    x, q, _, _ = traj.spatial()
    V = -((x @ model.gravity) @ model.mass)
    sp = model.springs
    if len(sp.names):
        if lengths is None:
            ws = workspace(model)
            K, n = len(traj.t), model.n
            Y = np.zeros((K, ws.state_size))
            Y[:, :3 * n] = x.reshape(K, -1)
            Y[:, 3 * n:7 * n] = q.reshape(K, -1)
            lengths = sample_figures(model, ws.file_unknowns, traj.t, Y, reactions=False,
                                     lengths=True).lengths
        V = V + 0.5 * np.sum(sp.stiffness * (lengths - sp.rest_length) ** 2, axis=1)
    return V


class _Prepared:
    """What a run needs before it steps, from its model and the arguments that change the
    equations (`known`, `dynamics`, `initial`, the method's family) alone (`_prepared`).
    Nothing in it refers to the model: kept in the model's workspace, it must not keep
    the model alive."""

    __slots__ = ("varying", "spans_checked", "driven", "mechanism", "projecting", "y0",
                 "ratio")

    def __init__(self, model: Model, given: KnownValues | None, dynamics: Dynamics | None,
                 initial: State | None, core: bool):
        self.varying = _varying_expressions(model, given)
        """(what, expression) of every load and known reaction varying in time."""
        self.spans_checked: set[float] = set()
        """The t_end whose span 0 .. t_end `_check_span` found them finite over."""
        self.driven = dynamics is None and initial is None and fully_driven(model)
        """The drivers fix the motion: a kinematic run, nothing below is made."""
        if self.driven:
            return
        run_model = with_known(model, given)
        self.mechanism = dynamics is None and _has_unknown_reactions(run_model, None)
        # the joints held by projecting the state after every step
        # (mbody.simulate.mechanism); scipy's integrators keep their own history of y, so
        # Baumgarte's terms hold them
        self.projecting = self.mechanism and core
        self.y0, self.ratio = _start(
            run_model, initial,
            workspace(run_model).file_unknowns if self.projecting else None)
        """The first state (core's layout; a copy is stepped) and its geometric ratio."""


def _prepared(model: Model, given: KnownValues | None, dynamics: Dynamics | None,
              initial: State | None, method: str) -> _Prepared:
    """`_Prepared` for this run: made once per model and method family for the model's
    own runs (nothing in `known`, no `dynamics`, no `initial`: a tolerance study, a
    benchmark, a sweep's repeats), else made for the run."""
    core = method in CORE
    if not given and dynamics is None and initial is None:
        return _memo(model, ("prepared", core),
                     lambda: _Prepared(model, None, None, None, core))
    return _Prepared(model, given, dynamics, initial, core)


def _memo(model: Model, key: tuple, make: Callable[[], _T]) -> _T:
    """What `make()` derives from `model` alone, made on a model's first run and kept in
    its workspace (`Workspace.memo`): a repeated run of one model (a tolerance study, a
    benchmark) does not redo it. Values are never changed by their users."""
    memo = workspace(model).memo
    key = (__name__, *key)
    value = memo.get(key, _NONE)
    if value is _NONE:
        value = memo[key] = make()
    return value  # type: ignore[return-value]  # each key's maker fixes its type


_NONE = object()
"""`_memo`'s mark of a key not made yet (a made value may be None)."""


def _start(model: Model, initial: State | None, projected: Unknowns | None
           ) -> tuple[np.ndarray, float]:
    """(y0, geometric ratio): a run's first state packed in the core's layout, moved onto
    the joints of the unknowns `projected` when given (their ratio there, else 1; see
    `JointProjection`). Made once per model from its own initial state (`initial` None),
    a fresh copy handed out."""
    def make() -> tuple[np.ndarray, float]:
        s0 = model.initial if initial is None else initial
        # Planar models also integrate θ itself (θ̇ = ω_z): the angle read back from a
        # quaternion is only known modulo 2π, and a fast wheel turns more than π per frame.
        theta0 = (2.0 * np.arctan2(s0.quaternion[:, 3], s0.quaternion[:, 0])
                  if model.dimension == cv.PLANAR else ())
        y0 = np.concatenate((s0.position.ravel(), s0.quaternion.ravel(),
                             s0.velocity.ravel(), s0.omega.ravel(), theta0))
        ratio = 1.0
        if projected is not None:  # the run starts on the joints
            _, _, ratio = JointProjection(model, projected)(y0, 0.0)
        return y0, ratio

    if initial is not None:
        return make()
    y0, ratio = _memo(model, ("start", None if projected is None else projected.key), make)
    return y0.copy(), ratio


def _sample_times(model: Model, K: int, fps: float, t_end: float) -> np.ndarray:
    """(K,) the output times k / fps, the last at most t_end (K allows t_end · fps to fall
    1e-9 short of k): a fresh array, the model's last run's copied when it asked for the
    same (the memo keeps one)."""
    last: dict[tuple[int, float, float], np.ndarray] = _memo(
        model, ("sample_times",), dict)
    t = last.get((K, fps, t_end))
    if t is None:
        t = np.arange(K, dtype=float)
        t /= fps
        np.minimum(t, t_end, out=t)
        last.clear()
        last[K, fps, t_end] = t
    return t.copy()


def _initial_joint_errors(model: Model, initial: State | None,
                          given: KnownValues | None) -> list[str]:
    """The joints the run's first state breaks, as text (`joint_errors`): `initial`'s, or
    the model's own initial state's (worked out once per model)."""
    if initial is not None:
        return joint_errors(model, initial)
    # the core's count first, where the run has made the solver it needs (a run with
    # `known` solves another set of unknowns): a file's pose on its joints, the usual
    # case, needs no description, and describing takes a first run tens of microseconds
    return list(_memo(model, ("initial_joint_errors",), lambda: tuple(
        joint_errors(model, model.initial)
        if given or workspace(model).breaks_joints(model.initial) else ())))


def _has_unknown_reactions(model: Model, known: Mapping[str, float | str] | None) -> bool:
    """Whether a reaction of `model` has no value in its file or in `known`."""
    given = model.known_reactions.keys() | model.known_expressions.keys() | (known or {}).keys()
    return not given.issuperset(model.reaction_table.labels)


def _named(names: list[str], most: int = 3) -> str:
    shown = ", ".join(names[:most])
    return shown + (f" and {len(names) - most} more" if len(names) > most else "")


def conservation(model: Model, default_dynamics: bool = True, ideal_joints: bool = False,
                 known: Mapping[str, float | str] | None = None) -> dict[str, str]:
    """What keeps each quantity from being conserved in this model: for ``energy``,
    ``momentum`` (linear) and ``angular_momentum``, the reasons ("" when it is conserved);
    ``angular_momentum_kind`` says about which point.

    Energy E = T + V (gravity, springs) is conserved when nothing else does work: no
    applied forces or torques (their potential is not in V), no dampers, no reaction
    values given (solved reactions of ideal joints do no work), mbody's own dynamics.
    Linear momentum Σ m v: no external force (gravity, applied forces, springs or joints
    to ground; a couple and forces between bodies leave it). Angular momentum: about the
    world origin when nothing external acts; with uniform gravity as the only external
    load, about the mass centres (each body's spin, when nothing joins the bodies) or
    about the system's mass centre (gravity has no moment about it). `ideal_joints`: the
    unknown reactions are solved (a mechanism); `known`: reaction values given besides the
    file's."""
    sp = model.springs
    forces = model.forces
    loads = list(forces.names)
    pushes = [nm for nm, c in zip(forces.names, forces.couple.tolist(), strict=True)
              if not c]
    springs = list(sp.names)
    grounded_springs = [nm for nm, a, b in zip(sp.names, sp.a.tolist(), sp.b.tolist(),
                                               strict=True) if a < 0 or b < 0]
    dampers = [nm for nm, c in zip(sp.names, sp.damping.tolist(), strict=True) if c > 0]
    jt = model.joint_table  # the joints the core holds, without a record made per joint
    grounded_joints = [nm for nm, p in zip(jt.names, jt.parent.tolist(), strict=True) if p < 0]
    gravity = any(np.asarray(model.gravity).tolist())
    own = [] if default_dynamics else ["the dynamics are the caller's"]

    energy = list(own)
    if loads:
        energy.append(f"applied loads do work: {_named(loads)}")
    if dampers:
        energy.append(f"dampers dissipate: {_named(dampers)}")
    drivers = list(model.drivers.names) if model.drivers is not None else []
    if drivers and ideal_joints:  # a driver's effort does work on its moving joint
        energy.append(f"drivers do work: {_named(drivers)}")
    given = list(model.known_reactions) if ideal_joints else list(model.reactions)
    given += [k for k in known or {} if k not in given]
    if given:  # solved reactions of ideal joints do no work (Gᵀ v = 0); given ones may
        energy.append(f"given reaction values act as loads: {_named(given)}")

    external = list(own)
    if gravity:
        external.append("gravity")
    if pushes:
        external.append(f"applied forces: {_named(pushes)}")
    if grounded_springs:
        external.append(f"springs to ground: {_named(grounded_springs)}")
    if grounded_joints:
        external.append(f"joints to ground: {_named(grounded_joints)}")

    moments = [r for r in external if r != "gravity"]
    couples = [nm for nm in loads if nm not in pushes]
    if couples:
        moments.append(f"applied couples: {_named(couples)}")
    turning: list[str] = []
    if not moments and not gravity:
        kind = "total, about the world origin"
    elif not moments and not springs and not model.joints:
        kind = "spin, about the mass centres"
    elif not moments:
        kind = "total, about the system's mass centre"
    else:
        kind = "total, about the world origin"
        turning = (["gravity"] if gravity else []) + moments
    return {"energy": "; ".join(energy), "momentum": "; ".join(external),
            "angular_momentum": "; ".join(turning), "angular_momentum_kind": kind}


def _drift(model: Model, t: np.ndarray, Y: np.ndarray, default_dynamics: bool, *,
           ideal_joints: bool = False, known: Mapping[str, float | str] | None = None,
           lengths: np.ndarray | None = None
           ) -> tuple[dict[str, np.ndarray], dict, np.ndarray]:
    """Energy, linear and angular momentum at the samples Y (K, state size: the core's
    layout, as stored) at the times t: their series, largest relative change, and whether
    the model conserves them (`conservation`, with its reasons when not).

    Energy E = T + V; its change is relative to max(|E(0)|, max T). Linear momentum
    p = Σ m v and angular momentum H = Σ (r × m v + W_R_B J ω) (r and v from the world
    origin, or from the system's mass centre; spin only: Σ W_R_B J ω): relative to the
    largest sum of their terms' magnitudes. All in one call of the compiled core
    (`mbody.simulate.mechanism.conserved_figures`). `lengths`: the springs' lengths at the
    samples (K, s), when the run has them (else the core computes them). Also returns
    each body's largest |ω| over the samples (n,), from the same pass."""
    why, about = (_memo(model, ("conservation", default_dynamics, ideal_joints),
                        lambda: _conserved(model, default_dynamics, ideal_joints))
                  if not known else _conserved(model, default_dynamics, ideal_joints, known))
    if len(model.springs.names) and lengths is None:
        lengths = sample_figures(model, workspace(model).file_unknowns, t, Y,
                                 reactions=False, lengths=True).lengths
    kind = why["angular_momentum_kind"]
    c = conserved_figures(model, Y, about, lengths)
    T, V, H = c.kinetic_energy, c.potential_energy, c.angular_momentum
    E = T + V
    series = {"kinetic_energy": T, "potential_energy": V, "energy": E, "angular_momentum": H}
    return series, {
        "energy_conserved": not why["energy"], "energy_drift": c.energy_drift,
        "energy_initial": float(E[0]), "energy_not_conserved": why["energy"],
        "momentum_conserved": not why["momentum"], "momentum_drift": c.momentum_drift,
        "momentum_initial": c.momentum_initial.tolist(),
        "momentum_not_conserved": why["momentum"],
        "angular_momentum_conserved": not why["angular_momentum"],
        "angular_momentum_kind": kind,
        "angular_momentum_drift": c.angular_momentum_drift,
        "angular_momentum_initial": H[0].tolist(),
        "angular_momentum_not_conserved": why["angular_momentum"],
    }, c.spin_peak


def _conserved(model: Model, default_dynamics: bool, ideal_joints: bool,
               known: Mapping[str, float | str] | None = None) -> tuple[dict, str]:
    """(`conservation`'s reasons, the point its angular momentum is taken about: a key of
    `mbody.simulate.mechanism.ANGULAR_MOMENTUM_ABOUT`)."""
    why = conservation(model, default_dynamics, ideal_joints, known)
    kind = why["angular_momentum_kind"]
    return why, ("spins" if kind.startswith("spin") else
                 "mass centre" if kind.endswith("system's mass centre") else "world origin")


def conserved_lines(info: Mapping) -> list[tuple[str, str]]:
    """(quantity, what the run says of it) for energy, linear and angular momentum: the
    relative drift where the model conserves it, else "not conserved here (reason)"; for
    the summary and the notebook's table (runs saved before the reasons were kept say
    "not conserved here" alone)."""
    out = []
    for key, what, unit in (("energy", "energy T + V", "J"),
                            ("momentum", "linear momentum", "kg m/s"),
                            ("angular_momentum", "angular momentum", "kg m^2/s")):
        if f"{key}_drift" not in info:
            continue
        if key == "angular_momentum":
            what += f" ({info.get('angular_momentum_kind', 'about the world origin')})"
        if info.get(f"{key}_conserved"):
            first = info.get(f"{key}_initial")
            start = (f"E(0) = {first:.6g} J" if key == "energy" else
                     f"|{'p' if key == 'momentum' else 'H'}(0)| = "
                     f"{float(np.linalg.norm(first)):.6g} {unit}") if first is not None else ""
            out.append((what, (start + ", " if start else "")
                        + f"relative drift {info[f'{key}_drift']:.2e}"))
        else:
            reason = info.get(f"{key}_not_conserved", "")
            out.append((what, "not conserved here" + (f" ({reason})" if reason else "")))
    return out


def summary(traj: Trajectory, path: str | os.PathLike[str] | None = None) -> str:
    """The run in a few lines: integrator, cost, and drift of the conserved quantities;
    a run with drivers adds their peaks and energy check; a kinematic run (a fully driven
    mechanism) has its own (`mbody.simulate.kinematic.summary`)."""
    i = traj.info
    if i.get("kinematic"):
        from mbody.simulate.kinematic import summary as kinematic_summary

        return kinematic_summary(traj, None if path is None else str(path))
    lines = [
        f"simulated {traj.model_name!r}: {traj.n} bod{'y' if traj.n == 1 else 'ies'}, "
        f"t = 0 .. {i['t_end']:g} s, {i['samples']} samples at {i['fps']:g} fps",
        f"integrator {i['integrator']} (rtol {i['rtol']:g}, atol {i['atol']:g}): "
        f"{i['steps']} steps, {i['evaluations']} evaluations"
        + (f" ({i['sampling_evaluations']} of them for the samples)"
           if i.get("sampling_evaluations") else "")
        + f", {i['wall_time_s']:.3g} s",
    ]
    # a drift figure only for what the model conserves: the relative change of anything
    # else (a motor's work, gravity's moment) is physics, not an error
    lines.extend(f"{what}: {said}" for what, said in conserved_lines(i))
    if i["energy_conserved"] and i["energy_drift"] > 1e-6:
        lines.append(f"warning: energy should be conserved but drifted {i['energy_drift']:.1e}"
                     " (relative); check the initial state and the tolerances")
    if "joint_stabilisation" in i:
        lines.append(f"joints: reactions solved at every step ({i['joint_stabilisation']}); "
                     f"largest joint error |phi| {i['joint_position_drift']:.1e}, "
                     f"|G^T v| {i['joint_velocity_drift']:.1e}")
        broken = i.get("initial_joint_errors") or []
        if broken and not any(w.startswith(BROKEN_START) for w in i.get("warnings", ())):
            # a run saved before the warning was among info["warnings"]
            lines.append("warning: " + _broken_start(
                broken, i["joint_stabilisation"] == PROJECTION_TEXT))
    if traj.dimension == cv.SPATIAL:
        lines.append(f"quaternion norm error before renormalising: "
                     f"{i['quaternion_norm_error']:.1e}")
    if i.get("reaction_axes") == "world" and np.asarray(traj.reactions).size and \
            not i.get("peaks"):
        lines.append("reactions stored in world axes: each joint's force and moment on its "
                     "child along world x, y, z")
    if i.get("peaks") or "driver_work" in i:  # a run with drivers: their lines
        from mbody.simulate.kinematic import driven_lines

        lines.extend(driven_lines(traj))
    lines.extend(f"warning: {w}" for w in i.get("warnings", ()))
    if path is not None:
        lines.append(f"wrote {path}")
    return "\n".join(lines)
