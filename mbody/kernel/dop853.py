"""The compiled core's DOP853 integrator (`src/dop853.h`) driven from Python.

`DOP853` steps an ODE y' = f(t, y) with Dormand and Prince's 8(5,3) pair, Hairer, Nørsett
and Wanner's step-size control and the 7th-order dense output: the same accepted steps
as ``scipy.integrate.DOP853`` (tests/test_dop853.py). The right-hand side is one of the
core's built-in test systems (`SYSTEMS`, evaluated in C), a mechanism of the core (a
``_core.Unknowns``: ``mb_derivative`` with its projection, src/mechanism.h; a whole
simulation then steps without Python) or a Python callable (a few microseconds an
evaluation more). The run's whole state lives in two numpy arrays,
``state`` (slots ``_core.DOP_*``) and ``work`` (rows of n: y, f, the last step's stages,
its dense output), which the core reads and writes in place.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from mbody.kernel import _core

SYSTEMS = {
    "oscillator": _core.DOP_SYSTEM_OSCILLATOR,  # x'' = -w^2 x; params [w]
    "van_der_pol": _core.DOP_SYSTEM_VAN_DER_POL,  # x'' = mu (1 - x^2) x' - x; [mu]
    "arenstorf": _core.DOP_SYSTEM_ARENSTORF,  # restricted three-body problem; [mu]
    "pendulum": _core.DOP_SYSTEM_PENDULUM,  # theta'' = -(g/L) sin(theta); [g/L]
}
"""The core's built-in test systems by name: their state and parameters (src/
dop853_module.c)."""

STATUS = {_core.DOP_RUNNING: "running", _core.DOP_FINISHED: "finished",
          _core.DOP_TOO_SMALL: "failed", _core.DOP_STOPPED: "stopped"}
"""scipy's words for the core's statuses (`stopped`: a callback asked to stop)."""

TOO_SMALL_STEP = "Required step size is less than spacing between numbers."
"""What a run stopped by the minimal step says (scipy's words)."""

Rhs = Callable[[float, np.ndarray], np.ndarray]

_STATE = np.zeros(_core.DOP_STATE_SIZE)
_STATE[_core.DOP_SAFETY], _STATE[_core.DOP_FAC_MIN], _STATE[_core.DOP_FAC_MAX] = 0.9, 0.2, 10.0
"""A run's state slots before its own settings: Hairer, Nørsett and Wanner's safety factor
and bounds of the step's change (copied for each run: a run starts in a few
microseconds, and each slot written from Python costs a tenth of one)."""


class DOP853:
    """DOP853 from (t0, y0) towards t_bound.

    Parameters
    ----------
    rhs : str, callable or _core.Unknowns
        A name in `SYSTEMS` (with `params`), f(t, y) -> y' (array of len(y0)), or the
        core's solver of a mechanism, with `params` = [``_core.MECH_*`` settings, the
        known reaction values (m)] (src/mechanism.h).
    t0, y0, t_bound : float, array, float
        Start and end of the run (t_bound < t0 integrates backwards).
    rtol, atol : float; float or array
        Tolerances per component: the local error of y_i is kept below about
        atol_i + rtol |y_i|.
    max_step : float
        Longest step.
    first_step : float, optional
        The first step's size; by default Hairer, Nørsett and Wanner's estimate.
    project, stage, tangent : callable or True, optional
        `project(t, y) -> info` moves y in place after each accepted step and returns
        up to four numbers: the size of the move (above `refresh` times atol, the next
        step starts from a fresh f(t, y)), whether the next step is filtered, and two of
        the caller's own (kept in `info`). In a filtered step each evaluation is made at
        `stage(t, y)`'s move of a copy of its state, and the error estimates pass through
        `tangent(t, y, e)` (e mapped in place). See src/dop853.h. True, with a mechanism
        as `rhs`: the core's own (src/mechanism.h), no Python called.
    """

    def __init__(self, rhs: str | Rhs | _core.Unknowns, t0: float,
                 y0: Sequence[float] | np.ndarray, t_bound: float, *, rtol: float = 1e-3,
                 atol: float | np.ndarray = 1e-6, max_step: float = math.inf,
                 first_step: float | None = None,
                 params: Sequence[float] | np.ndarray = (),
                 project: Callable | bool | None = None,
                 stage: Callable | bool | None = None,
                 tangent: Callable | bool | None = None, refresh: float = 0.0,
                 filter_first: bool = False):
        y0 = np.array(y0, dtype=float).ravel()
        self.n = n = len(y0)
        atol_vector = not isinstance(atol, (float, int)) and np.ndim(atol) > 0
        self.state = s = _STATE.copy()
        self.work = np.zeros(_core.dop853_work_size(n))
        s[_core.DOP_RTOL], s[_core.DOP_MAX_STEP], s[_core.DOP_T_BOUND] = rtol, max_step, t_bound
        s[_core.DOP_ATOL] = 0.0 if atol_vector else float(atol)
        s[_core.DOP_REFRESH] = refresh
        s[_core.DOP_FILTER_NEXT] = float(filter_first)
        if isinstance(rhs, str):
            core_rhs: int | Callable | _core.Unknowns = SYSTEMS[rhs]
        elif isinstance(rhs, _core.Unknowns):
            core_rhs = rhs
        else:
            fun = rhs

            def core_rhs(t: float, y: memoryview, out: memoryview) -> None:
                np.frombuffer(out)[:] = fun(t, np.frombuffer(y).copy())

        self.problem = (core_rhs, np.array(params, dtype=float), _project(project),
                        _stage(stage), _tangent(tangent),
                        np.array(atol, dtype=float).ravel() if atol_vector else None)
        _core.dop853_start(self.problem, float(t0), y0, float(first_step or 0.0), s,
                           self.work)

    def run(self, t_stop: float | None = None, max_steps: int = 1) -> str:
        """Steps until the first that reaches t_stop (default t_bound), at most
        max_steps of them; returns `status`."""
        t_stop = self.state[_core.DOP_T_BOUND] if t_stop is None else t_stop
        _core.dop853_run(self.problem, float(t_stop), int(max_steps), self.state, self.work)
        return self.status

    def sampled(self, t_stop: float, max_steps: int, t_eval: np.ndarray, k: int,
                out: np.ndarray, project_samples: bool = False) -> int:
        """Steps as `run`, and after each step the dense output at the times t_eval[k],
        t_eval[k + 1], ... the step reached, into out's rows k, k + 1, ... (out:
        (len(t_eval), n), C-contiguous), each moved by the projection when
        `project_samples`; returns the first row not yet written."""
        _, k = _core.dop853_sampled(self.problem, float(t_stop), int(max_steps), t_eval,
                                    int(k), out, bool(project_samples), self.state,
                                    self.work)
        return int(k)

    def sampled_marks(self, t_stop: float, max_steps: int, t_eval: np.ndarray, k: int,
                      out: np.ndarray, project_samples: bool, marks: np.ndarray
                      ) -> tuple[int, int]:
        """`sampled`, and at each step that reaches the next mark (`mark_windows`) or
        t_bound, the row (t, accepted steps) into `marks` (rows of 2, C-contiguous; the
        run returns when they are full); returns (the first row of out not yet written,
        the rows of marks written)."""
        _, k, count = _core.dop853_sampled(self.problem, float(t_stop), int(max_steps),
                                           t_eval, int(k), out, bool(project_samples),
                                           self.state, self.work, marks)
        return int(k), int(count)

    def mark_windows(self, width: float) -> None:
        """Marks (`sampled_marks`) at the first step reaching each multiple of `width`
        after the current time, and at t_bound."""
        self.state[_core.DOP_MARK_WIDTH] = width
        self.state[_core.DOP_MARK_NEXT] = (math.floor(self.t / width) + 1) * width

    def return_after(self, seconds: float) -> None:
        """`sampled` and `sampled_marks` calls also return after the first step that ends
        `seconds` (wall time, > 0; 0: never) after the call began."""
        self.state[_core.DOP_RETURN_AFTER] = seconds

    @property
    def core_time(self) -> float:
        """Seconds the core spent starting the run (f(t0, y0), the first step's size)
        and in `sampled` and `sampled_marks` calls (steps, dense output, sample
        projections), by a monotonic clock."""
        return float(self.state[_core.DOP_WALL])

    def step(self) -> str | None:
        """One step (scipy's `OdeSolver.step`): None, or why the run failed."""
        self.run(max_steps=1)
        return TOO_SMALL_STEP if self.status == "failed" else None

    def dense(self, t: float | Sequence[float] | np.ndarray) -> np.ndarray:
        """The last step's dense output at t inside it: (n,) for a number, (len(t), n)
        for an array (a sample a row)."""
        times = np.atleast_1d(np.asarray(t, dtype=float)).ravel()
        out = np.empty((len(times), self.n))
        _core.dop853_dense(self.problem, times, out, self.state, self.work)
        return out[0] if np.ndim(t) == 0 else out

    def _row(self, row: int) -> np.ndarray:
        return self.work[row * self.n:(row + 1) * self.n]

    @property
    def y(self) -> np.ndarray:
        """y at `t` (a view of the work array: copy it to keep it)."""
        return self._row(_core.DOP_W_Y)

    @property
    def f(self) -> np.ndarray:
        """y' at (t, y) as the next step starts from it."""
        return self._row(_core.DOP_W_F)

    @property
    def y_start(self) -> np.ndarray:
        """y at the start of the last step."""
        return self._row(_core.DOP_W_Y_OLD)

    @property
    def t(self) -> float:
        return float(self.state[_core.DOP_T])

    @property
    def step_start(self) -> float:
        """Start of the last accepted step."""
        return float(self.state[_core.DOP_T_OLD])

    @property
    def next_step(self) -> float:
        """The next step's size, as proposed."""
        return float(self.state[_core.DOP_H])

    @property
    def step_size(self) -> float:
        """The last accepted step's size (signed)."""
        return float(self.state[_core.DOP_H_OLD])

    @property
    def nfev(self) -> int:
        return int(self.state[_core.DOP_NFEV])

    @property
    def steps(self) -> int:
        """Accepted steps."""
        return int(self.state[_core.DOP_STEPS])

    @property
    def rejected(self) -> int:
        return int(self.state[_core.DOP_REJECTED])

    @property
    def dense_evaluations(self) -> int:
        """Evaluations made for dense output (3 per step interpolated; part of nfev)."""
        return int(self.state[_core.DOP_DENSE_NFEV])

    @property
    def code(self) -> int:
        """The callback's code that stopped the run (status "stopped"), else 0."""
        return int(self.state[_core.DOP_CODE])

    @property
    def refreshed(self) -> int:
        """Fresh derivatives after a projection."""
        return int(self.state[_core.DOP_REFRESHED])

    @property
    def status(self) -> str:
        return STATUS[int(self.state[_core.DOP_STATUS])]

    @property
    def info(self) -> np.ndarray:
        """The last projection's info."""
        return self.state[_core.DOP_INFO:_core.DOP_INFO + _core.DOP_PROJECT_INFO].copy()


def _project(fn: Callable | bool | None) -> Callable | bool | None:
    if fn is None or fn is True:
        return fn
    assert callable(fn)

    def project(t: float, y: memoryview, info: memoryview) -> None:
        values = np.atleast_1d(np.asarray(fn(t, np.frombuffer(y)), dtype=float))
        out = np.frombuffer(info)
        out[:] = 0.0
        out[:len(values)] = values
    return project


def _stage(fn: Callable | bool | None) -> Callable | bool | None:
    if fn is None or fn is True:
        return fn
    assert callable(fn)

    def stage(t: float, y: memoryview) -> None:
        fn(t, np.frombuffer(y))
    return stage


def _tangent(fn: Callable | bool | None) -> Callable | bool | None:
    if fn is None or fn is True:
        return fn
    assert callable(fn)

    def tangent(t: float, y: memoryview, e: memoryview) -> None:
        fn(t, np.frombuffer(y).copy(), np.frombuffer(e))
    return tangent
