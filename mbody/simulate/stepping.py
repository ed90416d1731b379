"""How a simulation steps: the compiled core's DOP853, or one of scipy's integrators.

- **DOP853** (the default) is the core's (`mbody.kernel.dop853`, written from Hairer,
  Nørsett and Wanner; its steps are scipy's DOP853's, tests/test_dop853.py). With the
  core's right-hand side (`mbody.solve.dynamics.StateDerivative` on the compiled core)
  the whole run is in C: the stages, the step-size control, the projection onto the
  joints after each step (`mbody.simulate.mechanism`: the stage projection and the
  error along the joints near singular positions too), the loads' and laws' expressions
  of t, the dense output at the output samples and their projection. `CoreRun.advance`
  returns to Python only every so many steps (progress, budgets). A `dynamics` given in
  Python is called from the same C loop.
- **RK45, RK23, Radau, BDF, LSODA** are scipy's, through its public `OdeSolver` API only
  (the constructor, `step()`, `t`, `y`, `step_size`, `nfev`, `status`,
  `dense_output()`); scipy is imported for them alone. Nothing is written into scipy's
  objects, so mechanisms are held by Baumgarte's terms in the right-hand side
  (`mbody.simulate.mechanism`), not by projection.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from mbody.errors import MbodyError, option_name, option_setting
from mbody.kernel import _core
from mbody.kernel.dop853 import DOP853, TOO_SMALL_STEP
from mbody.simulate.mechanism import ITERATIONS, STAGE_ITERATIONS, STAGE_PIVOT_RTOL
from mbody.solve.dynamics import StateDerivative, status_error

REFRESH_ATOL = 1e-2
"""A projection that moves the state by more than this fraction of atol restarts the
next step from the derivative at the projected state (one evaluation); a smaller one is
left to the next step's error control."""

MARKS = 64
"""Window marks one `CoreRun.advance` may note before it returns (a run's step-rate
windows are 20, `mbody.simulate.simulation._StepRate`)."""

CORE = ("DOP853",)
"""The methods the compiled core steps; the others are scipy's."""
IMPLICIT = ("Radau", "BDF", "LSODA")
"""The methods for stiff problems (LSODA switches to BDF when it finds stiffness)."""


_MECH_SETTINGS = np.zeros(_core.MECH_PARAMS)
_MECH_SETTINGS[_core.MECH_ROBUST] = STAGE_PIVOT_RTOL
_MECH_SETTINGS[_core.MECH_ITERS] = ITERATIONS
_MECH_SETTINGS[_core.MECH_STAGE_ITERS] = STAGE_ITERATIONS
"""The core's settings of a mechanism's run (``_core.MECH_*``) but its Baumgarte rate, which
each run's right-hand side sets; the known reaction values follow them."""


class CoreRun:
    """DOP853 in the compiled core from (0, y0) to t_bound (tolerances, largest step), on
    the right-hand side `rhs`; with `project`, the state is moved onto the joints of
    ``rhs.unknowns`` after every step and at every output sample, and `filter_first`
    says whether the first step starts near a singular position."""

    method = "DOP853"

    def __init__(self, rhs: StateDerivative, y0: np.ndarray, t_bound: float, rtol: float,
                 atol: float, max_step: float, *, project: bool = False,
                 filter_first: bool = False):
        self.rhs, self.projecting = rhs, project
        core = True if project else None
        if rhs.solver is not None:
            params = np.concatenate((_MECH_SETTINGS, rhs.lam))
            params[_core.MECH_RATE] = rhs.rate
            self.solver = DOP853(rhs.solver, 0.0, y0, t_bound, rtol=rtol, atol=atol,
                                 max_step=max_step, params=params, project=core,
                                 stage=core, tangent=core, refresh=REFRESH_ATOL,
                                 filter_first=filter_first)
        else:  # a Python right-hand side (`dynamics`), called from the core's loop
            self.solver = DOP853(rhs, 0.0, y0, t_bound, rtol=rtol, atol=atol,
                                 max_step=max_step)
        self._raise_stop(self.solver.status)
        self._marks = np.empty((MARKS, 2))
        self._marked = 0
        self._marking = False

    def mark_windows(self, width: float) -> bool:
        """Have the core note (t, steps) at the first step reaching each multiple of
        `width`, and at t_bound, while it runs (`marks`): a caller that follows the run
        window by window need not stop it at each window's end. True (scipy's runs
        cannot)."""
        self.solver.mark_windows(width)
        self._marking = True
        return True

    def return_after(self, seconds: float) -> None:
        """Each `advance` also comes back after the first step that ends `seconds` of wall
        time after it began, however many steps that is (the core's clock)."""
        self.solver.return_after(seconds)

    def marks(self) -> list[list[float]]:
        """The [t, steps] the last `advance` noted (`mark_windows`)."""
        return self._marks[:self._marked].tolist()

    @property
    def integration_time(self) -> float:
        """Seconds the core spent stepping (its own clock: steps, dense output and the
        samples' projections; no Python round trip counted)."""
        return self.solver.core_time

    @property
    def status(self) -> str:
        return self.solver.status

    @property
    def t(self) -> float:
        return self.solver.t

    @property
    def y(self) -> np.ndarray:
        return self.solver.y

    @property
    def step_size(self) -> float:
        return abs(self.solver.step_size)

    @property
    def steps(self) -> int:
        return self.solver.steps

    @property
    def nfev(self) -> int:
        return self.solver.nfev

    @property
    def sampling_evaluations(self) -> int:
        return self.solver.dense_evaluations

    @property
    def refreshed(self) -> int:
        return self.solver.refreshed

    def advance(self, t_stop: float, max_steps: int, t_eval: np.ndarray, k: int,
                Y: np.ndarray) -> tuple[int, str | None]:
        """Steps until the first that reaches t_stop, at most max_steps of them, with the
        samples t_eval[k ..] they reach written into Y's rows (projected with the state);
        returns (the first sample not yet written, why the run failed or None)."""
        if self._marking:
            k, self._marked = self.solver.sampled_marks(t_stop, max_steps, t_eval, k, Y,
                                                        self.projecting, self._marks)
        else:
            k = self.solver.sampled(t_stop, max_steps, t_eval, k, Y, self.projecting)
        status = self.solver.status
        self._raise_stop(status)
        return k, TOO_SMALL_STEP if status == "failed" else None

    def _raise_stop(self, status: str) -> None:
        """A callback that stopped the run (`status` "stopped"): a motion without mass
        (the core's code)."""
        if status == "stopped":
            raise status_error(self.rhs.model, self.solver.code)


class ScipyRun:
    """scipy.integrate's `method` (RK45, RK23, Radau, BDF, LSODA) from (0, y0) to t_bound
    on `rhs`, one step per `advance`, through its public API only."""

    def __init__(self, method: str, rhs: StateDerivative, y0: np.ndarray, t_bound: float,
                 rtol: float, atol: float, max_step: float):
        import scipy.integrate  # only for these methods: DOP853 runs never import it

        self.method, self.rhs = method, rhs
        self._steps, self._y_ok = 0, True

        def fun(t: float, y: np.ndarray) -> np.ndarray:
            # Radau's and BDF's Jacobian estimates pass strided columns of y
            return rhs(t, np.ascontiguousarray(y))

        with np.errstate(all="ignore"):  # its first-step norm may overflow: checked later
            self.solver: Any = getattr(scipy.integrate, method)(
                fun, 0.0, y0, t_bound, rtol=rtol, atol=atol, max_step=max_step)

    @property
    def status(self) -> str:
        return str(self.solver.status)

    @property
    def t(self) -> float:
        return float(self.solver.t)

    @property
    def y(self) -> np.ndarray:
        return self.solver.y

    @property
    def step_size(self) -> float:
        h = self.solver.step_size
        return 0.0 if h is None else float(h)

    @property
    def steps(self) -> int:
        return self._steps

    @property
    def nfev(self) -> int:
        return int(self.solver.nfev)

    sampling_evaluations = 0
    """Their interpolants are free."""
    refreshed = 0
    integration_time = None
    """Not timed apart from the loop (the caller's wall time is all integration)."""

    def mark_windows(self, width: float) -> bool:
        """False: one step per `advance`, the caller follows the windows itself."""
        return False

    def return_after(self, seconds: float) -> None:
        """Nothing to do: each `advance` is one step."""

    def marks(self) -> list[list[float]]:
        return []

    def advance(self, t_stop: float, max_steps: int, t_eval: np.ndarray, k: int,
                Y: np.ndarray) -> tuple[int, str | None]:
        """One step, with the samples t_eval[k ..] it reached written into Y's rows (from
        the step's interpolant); returns (the first sample not yet written, why the run
        failed or None)."""
        solver = self.solver
        try:  # overflow in an implicit method's Jacobian estimate is handled below
            with np.errstate(all="ignore"), warnings.catch_warnings():
                if self.method in IMPLICIT:  # LinAlgWarning on a singular iteration,
                    warnings.simplefilter("ignore")  # LSODA's convergence failures
                msg = solver.step()
        except (ValueError, np.linalg.LinAlgError) as exc:
            if self.method not in IMPLICIT:
                raise
            others = " or ".join(m for m in ("LSODA", "BDF") if m != self.method)
            raise MbodyError(
                f"the integrator {self.method} failed at t = {solver.t:.6g} s: {exc} (its "
                "numerical Jacobian broke down, as it can where the state barely changes). "
                f"Try another stiff integrator ({option_name('method')} {others}) or looser "
                f"tolerances (e.g. {option_setting('rtol', 1e-6)} "
                f"{option_setting('atol', 1e-9)})") from None
        if solver.status == "failed":
            return k, msg
        self._steps += 1
        j = int(np.searchsorted(t_eval, solver.t, side="right"))
        if j > k:
            Y[k:j] = solver.dense_output()(t_eval[k:j]).T
        return j, None


def start(method: str, rhs: StateDerivative, y0: np.ndarray, t_bound: float, rtol: float,
          atol: float, max_step: float = math.inf, *, project: bool = False,
          filter_first: bool = False) -> CoreRun | ScipyRun:
    """The run of `method` from (0, y0): the core's (`CORE`) or scipy's; each steps a
    copy of y0, which is left as it is."""
    if method in CORE:
        return CoreRun(rhs, y0, t_bound, rtol, atol, max_step, project=project,
                       filter_first=filter_first)
    if project:
        raise ValueError(f"{method} is scipy's: it does not project (Baumgarte's terms hold "
                         "the joints)")
    # scipy's solvers may keep y0 itself as their state
    return ScipyRun(method, rhs, y0.copy(), t_bound, rtol, atol, max_step)
