"""What a sweep computes for each case, a chunk of cases at a time: the runs and their
output columns.

- ``solve``: one solve at each case's initial state; columns ``acceleration:<coordinate>``
  and ``reaction:<label>``.
- ``kinematics``: the kinematic analysis at instants from 0 to T, each from the previous
  one, then a solve at each (a driven mechanism's kinetostatics); columns
  ``final:<coordinate>`` and ``peak:<label>``. The instants are ``mbody kinematics``'s
  by default (`instants`: one a degree of the first driver, at each case's own rate,
  when it turns at a constant rate, else 100 a second; and T), `fps` a second as
  ``mbody kinematics --fps`` samples (and T), or `steps` of them evenly spaced.
- ``simulate``: `mbody.simulate` to T, `fps` samples a second; the same columns.
- ``modes``: the natural frequencies about the initial state (or, with `equilibrium`,
  about the static equilibrium nearest it), and what ``mbody modes`` says with them;
  columns ``frequency:<k>``, ``growth:<k>``, ``steady`` and ``stable``
  (`mbody.sweep.modes`), and with `equilibrium` the equilibrium's position coordinates
  ``equilibrium:<coordinate>``.

``final:`` is the last instant's position coordinate (planar ``x``, ``y`` in m and
``theta`` in rad, in (−π, π]; spatial ``x``, ``y``, ``z`` and the attitude's quaternion
``qw``, ``qx``, ``qy``, ``qz``); ``peak:`` the largest magnitude over the instants of a
reaction component or a driver's effort (joint-frame components, N or N m).

A chunk's cases are evaluated together: their values packed by one `Family` (each value
read once), their solves and kinematic analyses in single calls of the compiled core
(`mbody.solve.batch.Evaluator`). A fully driven mechanism's motion depends on its joints,
drivers and start only (not on masses, loads or gravity): cases that differ only there
share one kinematic analysis. A case that fails is a row with its message; an
unexpected failure of a chunk is retried case by case, so that only the failing case
says so.
"""

from __future__ import annotations

import hashlib
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody.equations.solution import singular_mass_error
from mbody.errors import MbodyError, g_text, option_name, option_setting, options_named
from mbody.kernel import _core
from mbody.model.model import Model, State, from_source
from mbody.model.source import Source
from mbody.simulate.kinematic import default_fps, revolution
from mbody.simulate.peaks import PEAK_SAMPLES, samples_a_turn, sparse_text, steady_turning
from mbody.simulate.simulation import simulate
from mbody.simulate.trajectory import last_sample_warning, sample_times
from mbody.solve.batch import Evaluator, closed
from mbody.solve.family import Case, Family
from mbody.solve.kinematics import kinematics as kinematics_at
from mbody.solve.kinematics import require_fully_driven
from mbody.sweep import modes
from mbody.sweep.grid import Grid
from mbody.sweep.limits import LIMITS
from mbody.util.formatting import number

RUNS = ("solve", "kinematics", "simulate", "modes")
"""What ``--run`` names."""
SIMULATE_FPS = 60.0
"""A ``simulate`` run's samples a second without `Settings.fps`: `mbody.simulate`'s
default (a test keeps them equal)."""
APPLIES = {"t_end": ("kinematics", "simulate"), "revolutions": ("kinematics", "simulate"),
           "steps": ("kinematics",), "fps": ("kinematics", "simulate")}
"""The runs that use each setting (`check_run` refuses it with another run; and
``equilibrium``, ``modes`` only, in words of its own), ..."""
USE = {"t_end": "the end of each case's run", "revolutions": "the end of each case's run",
       "steps": "its instants, evenly spaced", "fps": "samples per second"}
"""... and what it is to them."""
SOLVE_BLOCK = 50_000
"""Most states solved in one call of the core (a block's arrays stay a few tens of MB)."""


@dataclass(frozen=True)
class Settings:
    """How each case is run.

    Parameters
    ----------
    run : str
        One of `RUNS`.
    t_end : float or None
        The run's end (s), for ``kinematics`` and ``simulate``.
    revolutions : float or None
        Or the end as turns of the first driver that turns (``--t-end "1 rev"``): the
        time it takes at its rate at t = 0, in each case.
    steps : int or None
        The ``kinematics`` run's instants, from 0 to the end (both included), evenly
        spaced; None: `fps`, or as ``mbody kinematics`` samples each case (`instants`).
    fps : float or None
        Samples per second: the ``simulate`` run's (None: `SIMULATE_FPS`, as
        `frame_rate` says), or the ``kinematics`` run's, as ``mbody kinematics --fps``
        samples (None: `steps`, or its default sampling).
    equilibrium : bool
        The ``modes`` run about the static equilibrium nearest each case's initial pose
        (``mbody modes --equilibrium``), not about the initial state.
    """

    run: str = "solve"
    t_end: float | None = None
    revolutions: float | None = None
    steps: int | None = None
    fps: float | None = None
    equilibrium: bool = False

    @property
    def frame_rate(self) -> float:
        """The ``simulate`` run's samples per second (`fps`, or `SIMULATE_FPS`)."""
        return self.fps if self.fps is not None else SIMULATE_FPS


@dataclass(frozen=True)
class Job:
    """Everything a process needs to evaluate cases of one sweep: the model's source
    (with its fixed values), the grid and the settings; `key` names the sweep (a process
    keeps what it built for it)."""

    source: Source
    grid: Grid
    settings: Settings
    key: str
    names: dict[str, str] = field(default_factory=dict)
    """How the caller names the arguments (`mbody.errors.option_names`: the command's
    flags, or {} from Python): a case's error reads the same on every worker."""


@dataclass
class Rows:
    """A chunk's results: case indices, the output columns (float, NaN where a case
    failed), each case's error or None, and the seconds its evaluation took."""

    indices: list[int]
    outputs: np.ndarray
    errors: list[str | None]
    seconds: float = 0.0
    worker: str = ""
    cpu: float = 0.0
    """The processor seconds the evaluation took (`seconds` is wall-clock: on a shared
    machine, also other programs' time)."""
    sparse: int = 0
    """Cases whose ``peak:`` columns come from fewer than `PEAK_SAMPLES` samples a
    revolution of a driver turning at a steady rate (`sampling`)."""
    sparsest: Sparsest | None = None
    """The chunk's case with the fewest samples a revolution, when it has fewer than
    `PEAK_SAMPLES`."""


@dataclass(frozen=True, order=True)
class Sparsest:
    """A case sampled fewer than `PEAK_SAMPLES` times a revolution of a driver turning
    at a steady rate: that many samples (first: the fewest compare lowest), the case, the
    driver's name, its rate (rad/s) and the case's run (s)."""

    per_turn: float
    case: int
    driver: str
    rate: float
    span: float = 0.0


def final_labels(model: Model) -> list[str]:
    """The ``final:`` columns' coordinates (module doc)."""
    if model.dimension == cv.PLANAR:
        return cv.coordinate_labels(list(model.body_names), model.dimension)
    return [f"{b}.{c}" for b in model.body_names
            for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]


def final_values(model: Model, Y: np.ndarray) -> np.ndarray:
    """(K, len(final_labels)) the position coordinates of packed states Y (K, >= 7 n)."""
    n = model.n
    x = Y[:, :3 * n].reshape(-1, n, 3)
    q = Y[:, 3 * n:7 * n].reshape(-1, n, 4)
    if model.dimension == cv.PLANAR:
        theta = 2.0 * np.arctan2(q[..., 3], q[..., 0])
        theta = np.where(theta > np.pi, theta - 2 * np.pi, theta)
        theta = np.where(theta <= -np.pi, theta + 2 * np.pi, theta)
        return np.concatenate((x[..., :2], theta[..., None]), axis=2).reshape(len(Y), -1)
    return np.concatenate((x, q), axis=2).reshape(len(Y), -1)


def pose_values(model: Model, state: State) -> np.ndarray:
    """(len(final_labels),) the position coordinates of one state."""
    Y = np.concatenate((state.position.ravel(), state.quaternion.ravel()))[None]
    return final_values(model, Y)[0]


def columns(model: Model, settings: Settings) -> list[str]:
    """The output columns of a run of `model` (module doc)."""
    if settings.run == "solve":
        return ([f"acceleration:{c}" for c in model.coordinates]
                + [f"reaction:{r}" for r in model.reactions])
    if settings.run == "modes":
        return (modes.columns(model)
                + ([f"{modes.POSE}{c}" for c in final_labels(model)]
                   if settings.equilibrium else []))
    return ([f"final:{c}" for c in final_labels(model)]
            + [f"peak:{r}" for r in model.reactions])


def turning_driver(model: Model) -> int:
    """The index of the first driver that turns (its rate sets ``--t-end N rev``)."""
    drivers = model.drivers
    for i, comp in enumerate(drivers.component if drivers is not None else ()):
        if comp == "M":
            return i
    raise MbodyError(f"an end in turns ({turns_end('N')}) needs a driver that turns a joint "
                     "(an angle or a speed about an axis); this model has none: give the time "
                     f"in seconds ({option_name('t_end', 'SECONDS', 'SECONDS')})")


def _an_end() -> str:
    """The arguments that give a run its end, as the caller names them."""
    seconds, turns = option_name("t_end"), option_name("revolutions")
    if seconds == turns:  # the command line's one --t-end takes both
        return f"{seconds} (seconds, or '1 rev')"
    return f"{seconds} (seconds) or {turns} (turns)"


def turns_end(n: str) -> str:
    """An end of `n` turns as the caller gives it: ``--t-end 'N rev'`` on the command
    line, ``revolutions=N`` in Python (`mbody.errors.option_name`)."""
    flag = option_name("revolutions")
    return f"{flag} '{n} rev'" if flag != "revolutions" else f"revolutions={n}"


_RUN_IS = {"solve": "is one solve of each case at its initial state",
           "modes": "linearises each case at one state",
           "simulate": "is sampled at {fps} (default {default:g})"}
"""What each run does, where a setting it does not use is refused (`check_run`)."""


def check_run(settings: Settings) -> None:
    """Refuse a run that is not one of `RUNS`, and a setting the run does not use
    (`APPLIES`), naming the setting, the runs it goes with and what the run does; and
    both ways of giving a ``kinematics`` run's instants. Needs no model: made before the
    model file is read."""
    run = settings.run
    if run not in RUNS:
        raise MbodyError(f"unknown run {run!r}; expected one of {', '.join(RUNS)}")
    if settings.equilibrium and run != "modes":
        raise MbodyError(f"{option_name('equilibrium', 'True')} goes with "
                         f"{option_setting('run', 'modes')} (it linearises each case about "
                         f"its static equilibrium); the {run} run starts from each "
                         "case's initial state")
    # every setting the run does not use, in one message (not the first alone)
    unused = [keyword for keyword, value in (
        ("t_end", settings.t_end), ("revolutions", settings.revolutions),
        ("steps", settings.steps), ("fps", settings.fps))
        if value is not None and run not in APPLIES[keyword]]
    if unused:
        does = _RUN_IS[run].format(fps=option_name("fps"), default=SIMULATE_FPS)
        named: dict[str, str] = {}  # t_end and revolutions are one --t-end on the command line
        for k in unused:
            named.setdefault(option_name(k), k)
        goes = [f"{name} goes with "
                f"{' or '.join(option_setting('run', r) for r in APPLIES[k])} ({USE[k]})"
                for name, k in named.items()]
        raise MbodyError(f"{'; '.join(goes)}; the {run} run {does}")
    if run == "kinematics" and settings.steps is not None and settings.fps is not None:
        steps, fps = option_name("steps"), option_name("fps")
        raise MbodyError(f"{steps} and {fps}: give the kinematics run's instants one way, "
                         f"{option_name('steps', 'K', 'K')} (K evenly spaced from 0 to the "
                         f"end) or {option_name('fps', 'F', 'F')} (F a second, as mbody "
                         "kinematics --fps samples)")


def check_settings(model: Model, settings: Settings) -> None:
    """Refuse settings the model cannot run, before any case is (`check_run` first)."""
    check_run(settings)
    if settings.run in ("kinematics", "simulate"):
        if settings.t_end is None and settings.revolutions is None:
            raise MbodyError(f"the {settings.run} run needs {_an_end()}")
        if settings.revolutions is not None:
            turning_driver(model)
    if settings.run == "kinematics" and settings.steps is not None and settings.steps < 2:
        raise MbodyError(f"{option_name('steps')}: expected at least 2 instants, got "
                         f"{settings.steps}")
    if settings.run == "kinematics":  # as `mbody kinematics` refuses it (--run simulate)
        require_fully_driven(model)


# -- a process's sweep: the model, its family, its evaluator, built once ---------------

@dataclass
class Context:
    """What one process builds once per sweep (`context`)."""

    job: Job
    model: Model
    family: Family
    evaluator: Evaluator
    width: int
    driver: int = -1
    kin_from: int = 0
    """Where the entries of F that a fully driven motion depends on start (joints,
    components, expression numbers: after gravity, bodies, loads and springs)."""
    cache: dict[str, Any] = field(default_factory=dict)
    turns_steadily: bool = False
    """The first driver turns at a constant rate (`revolution`): a ``kinematics`` run
    without `Settings.steps` samples each case `SAMPLES_A_TURN` times a revolution of it,
    at the case's own rate (its values set the rate, not the law's form)."""
    turning: list[int] = field(default_factory=list)
    """The drivers that turn at a steady rate (in the model as read; a case's values set
    their rates, not their laws' form), whose samples a revolution `sampling` checks, for
    the runs that report peaks."""


_CONTEXTS: dict[str, Context] = {}
_KEEP = 2


def context(job: Job) -> Context:
    """This process's `Context` of `job`, built on first use."""
    ctx = _CONTEXTS.get(job.key)
    if ctx is None:
        model = from_source(job.source)
        cols = columns(model, job.settings)
        n, k, s = model.n, len(model.forces.names), len(model.springs.names)
        driver = turning_driver(model) if job.settings.revolutions is not None else -1
        ctx = Context(job, model, Family(model, job.grid.paths), Evaluator(model), len(cols),
                      driver, 3 + _core.BODY_W * n + _core.LOAD_W * k + _core.SPRING_W * s,
                      turning=_steady_turning(model, job.settings),
                      turns_steadily=revolution(model) is not None)
        while len(_CONTEXTS) >= _KEEP:
            _CONTEXTS.pop(next(iter(_CONTEXTS)))
        _CONTEXTS[job.key] = ctx
    return ctx


def run_chunk(job: Job, indices: Sequence[int]) -> Rows:
    """Evaluate cases `indices` of `job` (what a worker runs), its errors naming the
    arguments as the caller does (`Job.names`), wherever it runs."""
    with options_named(job.names):
        return _run_chunk(job, indices)


def _run_chunk(job: Job, indices: Sequence[int]) -> Rows:
    import os
    import socket

    begin, cpu = time.perf_counter(), time.process_time()
    ctx = context(job)
    indices = [int(i) for i in indices]
    values = [job.grid.values(i) for i in indices]
    cases: list[Case | None]
    try:
        made = ctx.family.cases(values)
        outputs, errors = _evaluate(ctx, values, made)
        cases = list(made)
    except Exception:  # a bug in one case must not lose the others: each on its own
        outputs = np.full((len(values), ctx.width), np.nan)
        errors, cases = [], []
        for k, v in enumerate(values):
            case = None
            try:
                (case,) = ctx.family.cases([v])
                out, err = _evaluate(ctx, [v], [case])
                outputs[k], e = out[0], err[0]
            except Exception as exc:  # noqa: BLE001 - reported in the case's row
                e = f"internal error (a bug in mbody; please report it): " \
                    f"{type(exc).__name__}: {exc}"
            errors.append(e)
            cases.append(case)
    for k, e in enumerate(errors):
        if e is not None:
            outputs[k] = np.nan
    sparse, sparsest = sampling(ctx, indices, cases, errors)
    return Rows(indices, outputs, errors, time.perf_counter() - begin,
                f"{socket.gethostname()}:{os.getpid()}", time.process_time() - cpu,
                sparse, sparsest)


def _evaluate(ctx: Context, values: list[dict[str, Any]], cases: list[Case]
              ) -> tuple[np.ndarray, list]:
    """(outputs, errors) of the cases with `values` (`cases`: the family's of them)."""
    run = ctx.job.settings.run
    if run == "solve":
        return _solve(ctx, values, cases)
    if run == "kinematics":
        return _kinematics(ctx, values, cases)
    if run == "simulate":
        return _per_model(ctx, values, cases, _simulate)
    return _per_model(ctx, values, cases, _modes)


# -- whether the peaks are sampled closely enough ---------------------------------------

def _steady_turning(model: Model, settings: Settings) -> list[int]:
    """`Context.turning`: checked over the run's span (one second for a span in turns)."""
    if settings.run not in ("kinematics", "simulate"):
        return []
    span = settings.t_end if settings.t_end is not None else 1.0
    return steady_turning(model, np.linspace(0.0, span, 11))


def sampling(ctx: Context, indices: Sequence[int], cases: Sequence[Case | None],
             errors: Sequence[str | None]) -> tuple[int, Sparsest | None]:
    """(how many of the cases that ran have fewer than `PEAK_SAMPLES` samples a
    revolution of a driver turning at a steady rate, the one with the fewest): a
    ``kinematics`` run has (steps - 1) / T samples a second, or its default's
    (`per_second`), a ``simulate`` run fps; each driver's rate is the case's at t = 0."""
    s = ctx.job.settings
    drivers = ctx.model.drivers
    if not ctx.turning or drivers is None:
        return 0, None
    count, sparsest = 0, None
    for index, case, error in zip(indices, cases, errors, strict=True):
        if error is not None or case is None or case.extras is None:
            continue
        span = _end(ctx, case)
        per_second = s.frame_rate if s.run == "simulate" else _per_second(ctx, case, span)
        fewest = None
        for d in ctx.turning:
            rate = float(case.extras[d])
            if rate == 0.0 or not math.isfinite(rate):
                continue
            here = Sparsest(samples_a_turn(per_second, rate), index, drivers.names[d], rate,
                            span)
            if here.per_turn < PEAK_SAMPLES * (1.0 - 1e-9):
                fewest = here if fewest is None else min(fewest, here)
        if fewest is not None:
            count += 1
            sparsest = fewest if sparsest is None else min(sparsest, fewest)
    return count, sparsest


def sampling_warning(settings: Settings, grid: Grid, count: int, ran: int,
                     sparsest: Sparsest | None) -> str | None:
    """The warning of a sweep whose `count` of `ran` cases have fewer than `PEAK_SAMPLES`
    samples a revolution (`sampling`): the sparsest case, how low its peaks can read, and
    the --steps (kinematics) or --fps (simulate, or kinematics with --fps) that gives
    every case enough."""
    if not count or sparsest is None:
        return None
    text = sparse_text(sparsest.driver, sparsest.rate, sparsest.per_turn,
                       f"case {sparsest.case} ({grid.shown(sparsest.case)}) has")
    if settings.run == "kinematics" and settings.fps is None:  # its turns in that run
        turns = sparsest.span * abs(sparsest.rate) / (2.0 * math.pi)
        need = option_setting("steps", math.ceil(PEAK_SAMPLES * turns * (1.0 - 1e-12)) + 1)
    else:
        turns_a_second = abs(sparsest.rate) / (2.0 * math.pi)
        need = option_setting("fps", math.ceil(PEAK_SAMPLES * turns_a_second * (1.0 - 1e-12)))
    sine = 100.0 * (1.0 - math.cos(math.pi / PEAK_SAMPLES))
    return (f"{text}. {count} of the {ran} cases run have fewer than {PEAK_SAMPLES} samples a "
            f"revolution: their peak: columns can read low. Use {need} or more "
            f"({PEAK_SAMPLES} samples a revolution in every case: a sine's peak within "
            f"{sine:.2g} %)")


# -- solve -------------------------------------------------------------------------------

def _solve(ctx: Context, values: list[dict[str, Any]], cases: list[Case]
           ) -> tuple[np.ndarray, list]:
    out = np.full((len(values), ctx.width), np.nan)
    errors: list[str | None] = [c.error for c in cases]
    for ev, ks, F in _groups(ctx, cases):
        rows = None if F is None else np.arange(len(ks))
        Y, ok = ev.assemble(np.stack([cases[k].start for k in ks]), F, rows)  # type: ignore
        res = ev.solve(np.zeros(len(ks)), Y, F, rows)
        for j, k in enumerate(ks):
            if not ok[j]:
                errors[k] = _load_error(ctx, values[k])
                continue
            errors[k] = _singular(ev, res[j]) or errors[k]
            acc = res[j, :ev.N] if ev.plan.rows is None else res[j, :ev.N][ev.plan.rows]
            out[k] = np.concatenate((acc, res[j, ev.o_lam:ev.o_lam + ev.m]))
    return out, errors


def _groups(ctx: Context, cases: list[Case]
            ) -> list[tuple[Evaluator, list[int], np.ndarray | None]]:
    """(evaluator, the cases it evaluates, their F rows or None): the family's structure
    for the shared cases, and each case of a structure of its own by itself."""
    out: list[tuple[Evaluator, list[int], np.ndarray | None]] = []
    shared = [k for k, c in enumerate(cases) if c.shared]
    if shared:
        out.append((ctx.evaluator, shared, np.stack([cases[k].F for k in shared])))  # type: ignore
    for k, c in enumerate(cases):
        if c.model is not None:
            ev = Evaluator(c.model)
            if ev.width == ctx.evaluator.width:
                out.append((ev, [k], None))
    return out


def _singular(ev: Evaluator, out: np.ndarray) -> str | None:
    code = int(out[ev.o_info + _core.ST_SINGULAR])
    if code:
        return str(singular_mass_error(ev.model, (code - 1) // 6, (code - 1) % 6))
    return None


def _load_error(ctx: Context, values: Mapping[str, Any]) -> str:
    """The message `mbody.load` gives a case whose joints do not close at t = 0."""
    try:
        ctx.model.with_values(values)
    except MbodyError as exc:
        return str(exc)
    return "the joints and drivers do not close at t = 0 with these values"


# -- kinematics: a driven mechanism's kinetostatics -------------------------------------

def _end(ctx: Context, case: Case) -> float:
    s = ctx.job.settings
    if s.revolutions is None:
        return float(s.t_end)  # type: ignore[arg-type]
    rate = float(case.extras[ctx.driver])  # type: ignore[index]
    if rate == 0.0 or not math.isfinite(rate):
        raise MbodyError(f"{turns_end(f'{s.revolutions:g}')}: the driver does not turn at "
                         f"t = 0 (its rate is {rate:g} rad/s) with these values")
    return 2.0 * math.pi * s.revolutions / abs(rate)


def _turn(ctx: Context, case: Case) -> float | None:
    """The time of one revolution (s) of the case's first driver when it turns at a
    constant rate (`revolution` of the case's model), else None."""
    if case.model is not None:  # built in full: its own law
        return revolution(case.model)
    if not ctx.turns_steadily or case.extras is None:
        return None
    rate = float(case.extras[0])  # the case's rate, of the family's law
    return 2.0 * math.pi / abs(rate) if rate != 0.0 and math.isfinite(rate) else None


def _per_second(ctx: Context, case: Case, span: float) -> float:
    """The samples a second of a case's ``kinematics`` run of `span` s (`instants`)."""
    s = ctx.job.settings
    if s.steps is not None:
        return (s.steps - 1) / span
    return s.fps if s.fps is not None else default_fps(_turn(ctx, case))


def instants(ctx: Context, case: Case, span: float) -> np.ndarray:
    """The instants of a case's ``kinematics`` run from 0 to `span` s: `Settings.steps`
    of them evenly spaced, or ``mbody kinematics``'s samples, k / fps with fps
    `Settings.fps` (as ``mbody kinematics --fps``) or by default the case's
    (`default_fps`: `SAMPLES_A_TURN` a revolution of the first driver at the case's
    rate, when it turns at a constant one), and `span` itself when they fall short of it
    (so that ``final:`` is the end's, as with `steps`)."""
    s = ctx.job.settings
    if s.steps is not None:
        return np.linspace(0.0, span, s.steps)
    fps = _per_second(ctx, case, span)
    count = math.floor(span * fps + 1e-9) + 1  # as `sample_times` counts
    most = LIMITS["steps"]
    if count > most.hi:
        given = s.fps is not None
        raise MbodyError(f"an end of {g_text(span)} s at {g_text(fps)} samples a second "
                         + (f"({option_name('fps')})" if given
                            else "(mbody kinematics' sampling)")
                         + f" is {number(count)} instants; at most {number(int(most.hi))} a "
                         "case: give "
                         + (f"a lower {option_name('fps')} (or {option_name('steps')})"
                            if given else option_name("steps"))
                         + ", or an earlier end")
    t = sample_times(span, fps)
    return np.append(t, span) if last_sample_warning(span, fps) else t


def _kinematics(ctx: Context, values: list[dict[str, Any]], cases: list[Case]
                ) -> tuple[np.ndarray, list]:
    out = np.full((len(values), ctx.width), np.nan)
    errors: list[str | None] = [c.error for c in cases]
    for ev, ks, F in _groups(ctx, cases):
        times: dict[int, np.ndarray] = {}
        for k in ks:
            try:
                times[k] = instants(ctx, cases[k], _end(ctx, cases[k]))
            except MbodyError as exc:
                errors[k] = str(exc)
        keep = [i for i, k in enumerate(ks) if k in times]
        ks = [ks[i] for i in keep]
        Fk = None if F is None else F[keep]
        if ks:
            _kinetostatics(ctx, ev, ks, Fk, cases, values, times, out, errors)
    return out, errors


def _kinetostatics(ctx: Context, ev: Evaluator, ks: list[int], F: np.ndarray | None,
                   cases: list[Case], values: list[dict[str, Any]],
                   times: dict[int, np.ndarray], out: np.ndarray,
                   errors: list[str | None]) -> None:
    """Cases `ks` (F: their rows, or None for a model of its own): each assembled at
    t = 0, its instants' kinematic analysis (one per distinct motion), then every
    instant's solve; their final positions and peaks into `out`."""
    Y0, ok = ev.assemble(np.stack([cases[k].start for k in ks]),  # type: ignore[misc]
                         F, None if F is None else np.arange(len(ks)))
    motions: dict[bytes, list[int]] = {}
    for j, k in enumerate(ks):
        if not ok[j]:
            errors[k] = _load_error(ctx, values[k])
            continue
        key = _motion_key(ctx, ev, None if F is None else F[j], cases[k].start,  # type: ignore
                          times[k], j)
        motions.setdefault(key, []).append(j)
    for js in motions.values():
        j0 = js[0]
        t = times[ks[j0]]
        steps = len(t)
        per_call = max(1, SOLVE_BLOCK // steps)
        Y = np.ascontiguousarray(np.tile(Y0[j0], (steps, 1)))
        chain = np.ones(steps, dtype=np.int64)
        chain[0] = 0
        info = ev.kinematics(t, Y, None if F is None else F[j0:j0 + 1],
                             None if F is None else np.zeros(steps, np.int64), chain,
                             fast=ev.fully_driven, predict=ev.fully_driven)
        bad = np.flatnonzero(~closed(info))
        if len(bad):
            msg = _kinematics_error(ctx, cases[ks[j0]], values[ks[j0]], t, Y, int(bad[0]))
            for j in js:
                errors[ks[j]] = msg
            continue
        final = final_values(ev.model, Y[-1:])[0]
        for b in range(0, len(js), per_call):
            part = js[b:b + per_call]
            res = ev.peaks(np.tile(t, len(part)), Y, np.tile(np.arange(steps), len(part)),
                           steps, F, None if F is None else np.repeat(part, steps))
            rows = np.array([ks[j] for j in part])
            out[rows] = np.concatenate((np.broadcast_to(final, (len(part), len(final))),
                                        res[:, :ev.m]), axis=1)
            for i in np.flatnonzero(res[:, ev.m]):
                code = int(res[i, ev.m]) - 1
                errors[rows[i]] = str(singular_mass_error(ev.model, code // 6, code % 6))


def _motion_key(ctx: Context, ev: Evaluator, F: np.ndarray | None, start: np.ndarray,
                t: np.ndarray, j: int) -> bytes:
    """What a case's motion depends on: for a fully driven mechanism its joints, drivers
    and expressions (F from `kin_from` on), the file's pose (the branch it starts on) and
    the instants; for any other, the case itself (masses and loads move it too)."""
    if not ev.fully_driven:
        return f"case {j}".encode()
    h = hashlib.sha256()
    if F is not None:
        h.update(F[ctx.kin_from:].tobytes())
    h.update(start[:7 * ev.model.n].tobytes())
    h.update(np.ascontiguousarray(t, dtype=float).tobytes())
    return h.digest()


def _kinematics_error(ctx: Context, case: Case, values: dict[str, Any], t: np.ndarray,
                      Y: np.ndarray, k: int) -> str:
    """The message `mbody.kinematics` gives where the loops did not close (instant k)."""
    try:
        model = case.model if case.model is not None else ctx.model.with_values(values)
        start = _state(model, Y[k - 1]) if k > 0 else model.initial
        kinematics_at(model, float(t[k]), start=start)
    except MbodyError as exc:
        return str(exc)
    return (f"the joints and drivers do not close at t = {t[k]:g} s (the batched analysis "
            "found no closure where the single one did: report it)")


def _state(model: Model, y: np.ndarray) -> State:
    n = model.n
    q = y[3 * n:7 * n].reshape(n, 4)
    return State(y[:3 * n].reshape(n, 3).copy(), q / np.linalg.norm(q, axis=1)[:, None],
                 y[7 * n:10 * n].reshape(n, 3).copy(), y[10 * n:13 * n].reshape(n, 3).copy())


# -- simulate and modes: one model per case ----------------------------------------------

def _per_model(ctx: Context, values: list[dict[str, Any]], cases: list[Case], one
               ) -> tuple[np.ndarray, list]:
    out = np.full((len(values), ctx.width), np.nan)
    errors: list[str | None] = [c.error for c in cases]
    for k, (v, c) in enumerate(zip(values, cases, strict=True)):
        if c.error is not None:
            continue
        try:
            model = c.model if c.model is not None else ctx.model.with_values(v)
            row = one(ctx, model, c)
        except MbodyError as exc:
            errors[k] = str(exc)
            continue
        if len(row) != ctx.width:
            errors[k] = ("these values change the model's sizes (bodies, reaction "
                         "components); sweep them apart")
            continue
        out[k] = row
    return out, errors


def _simulate(ctx: Context, model: Model, case: Case) -> np.ndarray:
    traj = simulate(model, t_end=_end(ctx, case), fps=ctx.job.settings.frame_rate)
    last = traj.state(len(traj.t) - 1)
    peaks = np.full(len(model.reactions), np.nan)
    labels = list(traj.reaction_labels)
    if labels and traj.reactions.size:
        where = {r: i for i, r in enumerate(labels)}
        mags = np.abs(np.asarray(traj.reactions)).max(axis=0)
        for i, r in enumerate(model.reactions):
            if r in where:
                peaks[i] = mags[where[r]]
    return np.concatenate((pose_values(model, last), peaks))


def _modes(ctx: Context, model: Model, case: Case) -> np.ndarray:
    """frequency:1 ... (NaN beyond the oscillations), growth:1 ... (NaN beyond the modes
    that grow), steady, stable, then the equilibrium's pose when the run is about it."""
    lin = modes.linearization(model, ctx.job.settings.equilibrium)
    k = len(lin.coordinates)
    f = np.asarray(lin.frequencies, dtype=float)  # ascending, at most one a coordinate
    row = np.full(k, np.nan)
    row[:len(f)] = f
    # the k fastest: more modes than coordinates grow only under forces that do work
    # on their own (a follower load), and `stable` says so whatever the count
    g = modes.growth_rates(lin)[:k]
    growth = np.full(k, np.nan)
    growth[:len(g)] = g
    parts = [row, growth, np.array(modes.verdict_values(lin))]
    if ctx.job.settings.equilibrium:
        parts.append(pose_values(model, lin.state))
    return np.concatenate(parts)
