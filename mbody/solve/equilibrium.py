"""Static equilibrium: a configuration at rest where every acceleration vanishes.

With the bodies at rest (no gyroscopic terms) and the drivers held where their laws put
them at the time asked for, a state is an equilibrium when every generalized force
vanishes, f(q, 0) = 0 (`mbody.equations.generalized`: the free coordinates, less the
drivers'). It is found by Newton's method from the file's pose: the stiffness
K = −∂f/∂q comes from the linearisation (`mbody.solve.linearize`, differences of f with
Richardson extrapolation), each step δq = K⁻¹ f moves the bodies along v = T δq, at most
half a radian (or half the model's size) at a time, and back onto their joints
(`mbody.solve.configure`). Newton's method finds the equilibrium nearest the start,
stable or not; the linearisation there says which: the eigenvalues of M⁻¹K are the
squared frequencies of small oscillations (all positive: stable; one negative: it falls
away along that direction).

    state = mbody.equilibrium(model)            # a State, or an error
    found = find_equilibrium(model)             # found, moved, stiffness, stable
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from mbody.equations.coordinates import CoordinateSet
from mbody.equations.generalized import evaluate, state_with_velocities
from mbody.errors import MbodyError, real_number
from mbody.model.arguments import checked_model, checked_state
from mbody.model.calculus import derivative
from mbody.model.drivers import DriverTable
from mbody.model.expressions import compile_expression
from mbody.model.model import Model, State
from mbody.solve.configure import move, project
from mbody.solve.kinematics import kinematics
from mbody.solve.linearize import (
    STAGES,
    STEADY_RTOL,
    Linearization,
    free_coordinates,
    linearized,
    stiffness,
)
from mbody.util.progress import Progress, progress_of

NEWTON_STEPS = 50
"""Newton steps at most (a few from a nearby start)."""


class NoEquilibriumError(MbodyError):
    """Newton's method did not find a static equilibrium from the start."""


@dataclass(frozen=True)
class Equilibrium:
    """What `find_equilibrium` found.

    state: the configuration at rest (the last Newton iterate when none was found);
    found: whether every generalized force vanished (below `STEADY_RTOL` of the terms it
    is made of); moved: the largest distance a mass centre moved from the start (m) and
    the largest angle a body turned (rad); stiffness: the eigenvalues of M⁻¹K, the
    squared frequencies of small oscillations (1/s², ascending; negative: unstable);
    stable: the linearisation's verdict (None: not decided, a zero stiffness within its
    error bound, or no equilibrium); iterations: Newton steps taken; residual: the
    largest generalized force relative to its terms at the end.
    """

    state: State
    found: bool
    moved: tuple[float, float]
    stiffness: np.ndarray
    stable: bool | None
    iterations: int
    residual: float

    def __str__(self) -> str:
        if not self.found:
            return (f"no equilibrium found in {self.iterations} Newton steps: the loads "
                    f"never balanced (at best the largest generalized force was "
                    f"{self.residual:.2g} of the size of the terms it sums; 0 is balance, "
                    "1 no cancelling at all)")
        k = self.stiffness
        if not len(k):
            verdict = ("no free coordinate (the drivers prescribe every degree of freedom): "
                       "nothing to be stable or unstable")
        elif self.stable is False:
            verdict = "unstable (the stiffness has a negative direction)"
        elif self.stable is None:
            verdict = "neutral to the accuracy of the differences (a zero stiffness)"
        elif (k > 0).all():
            verdict = "stable (the stiffness is positive definite)"
        else:  # no growing mode, but directions of zero stiffness: free or cyclic motions
            zero = int((k <= 0).sum())
            verdict = (f"neutrally stable: no direction falls away, {zero} of the "
                       f"{len(k)} have no stiffness (a free or cyclic motion)")
        return (f"equilibrium found in {self.iterations} Newton steps: bodies moved up to "
                f"{self.moved[0]:.4g} m and turned up to {np.degrees(self.moved[1]):.4g} deg "
                f"from the start; {verdict}")


def held(model: Model, t: float) -> Model:
    """The model with each driver held at its law's value at t (a constant law: its rate
    and acceleration 0)."""
    d = model.drivers
    if d is None or not len(d):
        return model
    laws = []
    for law in d.laws:
        f = compile_expression(repr(float(law[0](t))))
        f1 = derivative(f)
        laws.append((f, f1, f1))
    table = DriverTable(d.names, d.joint, d.kind, d.axis, d.component, d.offset,
                        tuple(laws), d.where)
    return dataclasses.replace(model, drivers=table)


@dataclass(frozen=True)
class _Newton:
    """Where Newton's method ended: the held model, its free coordinates, the start and
    the last state at rest, whether f vanished there, the steps and the best ratio."""

    model: Model
    cs: CoordinateSet
    begin: State
    state: State
    found: bool
    steps: int
    best: float


def _newton(model: Model, start: State | None, t: float, bar: Progress) -> _Newton:
    """Newton's method for f(q, 0) = 0 from `start` (module doc), its steps on `bar`."""
    if not isinstance(model, Model):
        model = checked_model(model)
    t = real_number(t, "t", "a number of seconds")
    begin = (model.initial if start is None else checked_state(model, start, "start")
             ).replace(t=t)
    m = held(model, t)
    bar.step("choosing the coordinates")
    cs = free_coordinates(m)
    zero = np.zeros(len(cs))
    state = _at_rest(m, cs, kinematics(m, float(t), start=begin))
    best, found, steps = np.inf, False, 0
    for steps in range(NEWTON_STEPS + 1):
        g = evaluate(m, state, cs, zero)
        ratio = float(np.max(np.abs(g.f) / np.maximum(g.f_scale, 1e-300), initial=0.0))
        best = min(best, ratio)
        if np.all(np.abs(g.f) <= STEADY_RTOL * g.f_scale):
            found = True
            break
        if steps == NEWTON_STEPS:
            break
        bar.context = f"equilibrium, Newton step {steps + 1} (f at {ratio:.1e} of its terms): "
        K = stiffness(m, state, cs, bar)
        bar.context = ""
        try:
            dq = np.linalg.lstsq(K, g.f, rcond=1e-12)[0]
        except np.linalg.LinAlgError:
            break
        size = float(np.max(np.abs(dq) / cs.scales)) if len(dq) else 0.0
        if size > 0.5:  # at most half a radian (or half the model's size) a step
            dq *= 0.5 / size
        state = project(m, cs, move(m, state, g.T @ dq))
    return _Newton(m, cs, begin, _at_rest(m, cs, state), found, steps, best)


def find_equilibrium(model: Model, *, start: State | None = None, t: float = 0.0,
                     progress: bool | Progress = False) -> Equilibrium:
    """An equilibrium near `start` (default: the file's pose), the drivers held at time t
    (module doc); `Equilibrium.found` says whether Newton's method converged (`progress`:
    as `equilibrium`'s)."""
    with progress_of(progress, f"equilibrium {getattr(model, 'name', '')}", STAGES) as bar:
        run = _newton(model, start, t, bar)
        m, cs, state, begin = run.model, run.cs, run.state, run.begin
        squared = np.zeros(0)
        stable: bool | None = None
        if run.found and len(cs):
            lin = linearized(m, state, cs, bar)
            squared = _squared_frequencies(lin)
            stable = lin.stable
    moved = (float(np.linalg.norm(state.position - begin.position, axis=1).max(initial=0.0)),
             float((2 * np.arccos(np.abs((state.quaternion * begin.quaternion).sum(axis=1))
                                  .clip(0, 1))).max(initial=0.0)))
    return Equilibrium(state, run.found, moved, squared, stable, run.steps, run.best)


def equilibrium(model: Model, *, start: State | None = None, t: float = 0.0,
                progress: bool | Progress = False) -> State:
    """A configuration at rest where every acceleration vanishes, near `start` (the file's
    pose by default), the drivers held at time t (`find_equilibrium` says more: how far
    it moved, whether it is stable).

    Parameters
    ----------
    model : Model
        The model.
    start : State, optional
        Where Newton's method starts (its velocities are dropped).
    t : float
        Time (s) at which the drivers are held and the loads taken.
    progress : bool or Progress
        Say on standard error what is being computed (each Newton step's stiffness), once
        it has taken a second (`mbody.util.progress`; or the steps on a `Progress` of the
        caller's).

    Returns
    -------
    State
        At rest, every generalized force below `STEADY_RTOL` of the terms it is made of.

    Raises
    ------
    NoEquilibriumError
        Newton's method did not converge from the start (no equilibrium near it, or
        loads that never balance: a constant torque on a free wheel).
    MbodyError
        A `model` or `start` that is not one of this model (`mbody.model.arguments`).
    """
    with progress_of(progress, f"equilibrium {getattr(model, 'name', '')}", STAGES) as bar:
        run = _newton(model, start, t, bar)
    if not run.found:  # the message find_equilibrium's result gives
        found = Equilibrium(run.state, False, (0.0, 0.0), np.zeros(0), None, run.steps,
                            run.best)
        raise NoEquilibriumError(f"{model.name!r}: {found}; the loads may never balance (a "
                                 "constant torque on a free wheel), or start nearer one")
    return run.state


def _at_rest(model: Model, cs: CoordinateSet, state: State) -> State:
    """`state` with the velocities of q' = 0 (a held driver's rate is 0 too)."""
    g = evaluate(model, state, cs, np.zeros(len(cs)))
    return state_with_velocities(model, state, g.v_e)


def _squared_frequencies(lin: Linearization) -> np.ndarray:
    """The eigenvalues of M⁻¹K (1/s²), ascending: real for the symmetric K of a static
    equilibrium (M symmetric positive definite)."""
    w = np.linalg.eigvals(np.linalg.solve(lin.M, lin.K))
    return np.sort(w.real)
