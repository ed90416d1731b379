"""The integrator classes a simulation steps with: scipy's, refined for mechanisms.

Two refinements, each a subclass of the scipy class the user chose:

- **Compiled steps** (DOP853 on a compiled model): scipy's DOP853 calls the right-hand
  side twelve times a step from Python and combines the stages with numpy, about 6 µs
  an evaluation on top of the evaluation itself, and the simulation loop adds its own
  Python per step; on a small mechanism that is several times the physics.
  `Stepper.advance` takes the steps up to the next output sample in one call of
  `mbody.solve.compiled.rk_run`: scipy's step-size control and DOP853's stages and error norm
  (`rk_attempt`), the projection after each step and the loads' expressions of time, all
  compiled. The solver's fields are left as scipy's own steps leave them, so its dense
  output and `step()` go on from there, and the steps are scipy's to rounding
  (`tests/test_stepping.py`).
- **Error along the joints** (a mechanism held by projection, near a singular position,
  ``rhs.project_stages``): the error estimate counts only the part along the joints
  (`mbody.simulate.projection.tangent_error`); those steps take scipy's path.
"""

from __future__ import annotations

import math
import sys
from typing import Any, NamedTuple

import numpy as np

from mbody.equations.plan import compiled as compiled_module
from mbody.simulate.projection import STAGE_PIVOT_RTOL, tangent_error
from mbody.solve.dynamics import StateDerivative
from mbody.solve.kkt import singular_mass_error

REFRESH_ATOL = 1e-2
"""A projection that moves the state by more than this fraction of atol restarts the
next step from the derivative at the projected state (one evaluation); a smaller one is
left to the next step's error control."""

COMPILED_STEPS = True
"""Whether DOP853 steps of compiled models go through `mbody.solve.compiled.rk_attempt` (the
tests switch it off to compare with scipy's own steps)."""


def integrator(method: str, rhs: StateDerivative) -> type[Any]:
    """scipy's integrator class `method`, or a subclass refining it for `rhs` (module
    docstring)."""
    import scipy.integrate

    base: type[Any] = getattr(scipy.integrate, method)  # an OdeSolver subclass
    projection = rhs.projection
    compiled = (COMPILED_STEPS and method == "DOP853" and rhs.compiled
                and rhs.known_at is None)
    if projection is None and not compiled:
        return base
    class Stepper(base):
        def _estimate_error_norm(self, K, h, scale):
            if projection is None or not rhs.project_stages:
                return super()._estimate_error_norm(K, h, scale)
            if hasattr(self, "E5"):  # DOP853's two embedded estimates (as scipy combines them)
                e5 = tangent_error(projection, self.y, K.T @ self.E5) / scale
                e3 = tangent_error(projection, self.y, K.T @ self.E3) / scale
                n5, n3 = float(e5 @ e5), float(e3 @ e3)
                if n5 == 0 and n3 == 0:
                    return 0.0
                return abs(h) * n5 / math.sqrt((n5 + 0.01 * n3) * len(scale))
            e = tangent_error(projection, self.y, (K.T @ self.E) * h) / scale
            return float(np.linalg.norm(e)) / math.sqrt(len(e))

        if compiled:
            def advance(self, t_stop: float, max_steps: int) -> Advance | None:
                """Steps (each followed by the projection, when the run has one) until
                the first that reaches t_stop, at most max_steps of them, in one compiled
                call; None when the next step needs the Python path (near a singular
                position, or vector tolerances): take it with `step()`."""
                if rhs.project_stages or np.ndim(self.atol) or np.ndim(self.rtol):
                    return None
                return _compiled_run(self, rhs, t_stop, max_steps)

    Stepper.__name__ = base.__name__
    return Stepper


class Advance(NamedTuple):
    """What one `advance` did: steps taken, fresh derivatives after a projection, and
    `mbody.simulate.projection.geometric_ratio` before the last step's projection (1 without)."""

    steps: int
    refreshed: int
    ratio: float


def _compiled_run(solver, rhs: StateDerivative, t_stop: float, max_steps: int) -> Advance:
    """Steps by `mbody.solve.compiled.rk_run`; the solver's fields left as scipy's own steps
    leave them (so that its dense output and next `step()` go on from there)."""
    c = compiled_module()
    model = rhs.model
    run = np.zeros(c.RUN_SIZE)
    run[c.RUN_T], run[c.RUN_H] = solver.t, solver.h_abs
    y, f = solver.y.copy(), solver.f.copy()
    y_old = np.empty_like(y)
    projection = rhs.projection
    c.rk_run(rhs._F, rhs._I, rhs._Iu, *model.plan.load_program, rhs._lam, rhs.rate,
             rhs.planar, solver.A, solver.B, solver.C, solver.E3, solver.E5, solver.rtol,
             solver.atol, solver.max_step, solver.t_bound, t_stop, max_steps,
             projection is not None, STAGE_PIVOT_RTOL, REFRESH_ATOL * solver.atol,
             y, f, solver.K, y_old, run)
    steps = int(run[c.RUN_STEPS])
    solver.nfev += int(run[c.RUN_NFEV])
    status = run[c.RUN_STATUS]
    if status == 2.0:
        code = int(run[c.RUN_RATIO])
        raise singular_mass_error(model, (code - 1) // 6, (code - 1) % 6)
    solver.h_abs = run[c.RUN_H]
    if steps:
        solver.t_old, solver.h_previous = run[c.RUN_T_OLD], run[c.RUN_H_OLD]
        solver.t, solver.y, solver.y_old, solver.f = run[c.RUN_T], y, y_old, f
    if status == 1.0:
        solver.status = "failed"
    elif solver.direction * (solver.t - solver.t_bound) >= 0:
        solver.status = "finished"
    return Advance(steps, int(run[c.RUN_REFRESHED]),
                   float(run[c.RUN_RATIO]) if steps else 1.0)


class CompileClock:
    """The wall time numba spends compiling while this is entered: the time inside its
    ``numba:compile`` events (numba's event API; a compile nested in another counted once).
    Loading machine code from numba's cache raises no such event, so a run that loads the
    cached fast path counts 0 here, and the first run after an install counts the one-off
    compile of `mbody.solve.compiled`'s kernels (about a minute), which its timing leaves
    out of the integration's. Numba is not imported here: `watch` starts listening once
    it is (after `state_derivative` has picked the compiled path); without numba, 0."""

    def __init__(self) -> None:
        self._listener: Any = None

    def __enter__(self) -> CompileClock:
        self.watch()
        return self

    def __exit__(self, *exc: object) -> None:
        if self._listener is not None:  # kept: `seconds` reads it after the run
            from numba.core import event

            event.unregister("numba:compile", self._listener)

    def watch(self) -> None:
        """Start listening, if numba is imported and this is not listening yet."""
        if self._listener is not None or "numba" not in sys.modules:
            return
        try:
            from numba.core import event

            listener = event.TimingListener()
            event.register("numba:compile", listener)
        except Exception:  # noqa: BLE001 - numba's event API moved: time nothing, never fail
            return
        self._listener = listener

    @property
    def seconds(self) -> float:
        """Compiling so far (s), compiles under way not counted."""
        lis = self._listener
        return float(lis.duration) if lis is not None and lis.done else 0.0
