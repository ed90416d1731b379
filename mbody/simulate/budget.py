"""A run that outgrows its budget, or fails: the whole run's cost predicted from its
start (`predict`), why it costs so much and what helps (`cost_cause`), the paragraph a
run stopped by a budget reports (`budget_message`), and the load expression to blame when
the integration fails (`blame_expression`).

Only such runs import this module (`mbody.simulate.simulation` imports it where it needs
it: a fresh process's first run pays for every module it imports, docs/performance.md);
the step rate a run keeps to judge its pace is `simulation._StepRate`.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from mbody.errors import MbodyError, option_name, option_setting
from mbody.model.expressions import Expression, check_times
from mbody.model.model import Model
from mbody.simulate.stepping import IMPLICIT


class Pace(Protocol):
    """A run's pace so far in words (`simulation._StepRate`), made only for a message."""

    def so_far(self, t: float, steps: int) -> str: ...

PREDICT_FACTOR = 1.5
"""A run predicted to need this many times its step or wall-time budget stops at once."""
SPIN_STEPS_PER_RAD = 50.0
"""Steps per radian of the fastest initial spin up to which a run's cost is put down to
that spin (DOP853 at rtol 1e-10 takes about 1.5 steps per radian of a free spin)."""


def predict(model: Model, method: str, t: float, t_end: float, steps: int, rate: Pace,
            max_steps: int | None, max_wall: float | None, elapsed: float) -> None:
    """Stop now, with the cause and what to do, a run whose pace so far needs more than
    `PREDICT_FACTOR` times a budget: a very stiff model or a fast spin otherwise takes
    minutes to reach the budget (hours without one) and ends with nothing."""
    if t <= 0:
        return
    need_steps = steps * t_end / t
    need_wall = elapsed * t_end / t
    if max_steps is not None and need_steps > PREDICT_FACTOR * max_steps:
        over = (f"about {need_steps:.2g} steps, more than {PREDICT_FACTOR:g} times the budget "
                f"({option_setting('max_steps', max_steps)})")
        raise_it = f"raise {option_name('max_steps')}"
    elif max_wall is not None and need_wall > PREDICT_FACTOR * max_wall:
        over = (f"about {need_wall:.2g} s, more than {PREDICT_FACTOR:g} times the budget "
                f"({option_setting('max_wall', float(max_wall))})")
        raise_it = f"raise {option_name('max_wall')}"
    else:
        return
    cause, remedies = cost_cause(model, steps / t, method)
    raise MbodyError(
        f"the simulation was stopped early: after {steps} steps it is at t = {t:.3g} s of "
        f"{t_end:g} s ({rate.so_far(t, steps)}); at that rate the whole run needs {over}. "
        f"{cause} To go on: {remedies}, or {raise_it}. No trajectory is kept (rerun with "
        f"{option_setting('t_end', figure(t))} to see the motion up to here).")


def cost_cause(model: Model, steps_per_second: float, method: str) -> tuple[str, str]:
    """Why the run costs so much, and what helps: a fast spin (which every integrator must
    follow), inertias too far apart for double precision (rounding noise that no
    integrator steps over), stiffness (which an implicit integrator steps over), or
    nothing but its length (steps no shorter than smooth motion takes)."""
    w = np.linalg.norm(np.asarray(model.initial.omega), axis=1) if model.n else np.zeros(0)
    i = int(np.argmax(w)) if len(w) else 0
    spin = float(w[i]) if len(w) else 0.0
    if spin > 0 and steps_per_second < SPIN_STEPS_PER_RAD * spin:
        return (f"The steps follow the fastest motion: '{model.body_names[i]}' spins at "
                f"{spin:.3g} rad/s ({spin / (2 * math.pi):.3g} rev/s), and any integrator "
                "must take steps shorter than a turn, so a stiff integrator would not help.",
                f"a shorter {option_name('t_end')} (the cost grows with it), a looser "
                f"{option_name('rtol')} (e.g. 1e-6), a slower spin")
    moments = np.linalg.eigvalsh(np.asarray(model.J)) if model.n else np.ones((1, 3))
    smallest = np.min(np.where(moments > 0, moments, np.inf), axis=1)  # a zero is no scale
    spread = np.where(np.isfinite(smallest), moments[:, 2] / smallest, 1.0)
    k = int(np.argmax(spread))
    if spread[k] > INERTIA_SPREAD:
        return (f"The body '{model.body_names[k]}' has principal moments of inertia from "
                f"{smallest[k]:.3g} to {moments[k, 2]:.3g} kg m^2 (a ratio of "
                f"{spread[k]:.2g}): its Euler equation divides the rounding errors of the "
                "large moments by the small one, and the steps shrink to follow that noise; "
                "no integrator steps over it.",
                "a realistic smallest moment (a thin rod's m r^2 / 2 with its real radius), "
                f"a shorter {option_name('t_end')}")
    if steps_per_second <= MODEST_STEP_RATE:
        return (f"The steps are not short ({steps_per_second:.4g} per simulated second, as "
                "smooth motion takes at these tolerances): the run is long, and its cost "
                f"grows with {option_name('t_end')}; a stiff integrator would not help.",
                f"a shorter {option_name('t_end')}, a looser {option_name('rtol')} (e.g. 1e-6)")
    fastest = f"{spin:.3g} rad/s" if spin > 0 else "none"
    cause = (f"That is far more steps than the motion explains (the fastest spin at the "
             f"start: {fastest}): the model is stiff (time scales far apart, such as a very "
             "stiff spring on a light body)")
    if method in IMPLICIT:
        return (cause + f", and even {method} needs short steps.",
                f"a shorter {option_name('t_end')}, a looser {option_name('rtol')} (e.g. 1e-6)")
    return (cause + ", and an explicit integrator must resolve the fastest of them.",
            f"a stiff integrator ({option_name('method')} LSODA, BDF or Radau), a shorter "
            f"{option_name('t_end')}")


MODEST_STEP_RATE = 2000.0
"""Steps per simulated second up to which a run's cost is put down to its length: the
shipped models take 14 (a free body) to 920 (the slider-crank turning 16 times a second)
at the default tolerances; the stiff spring of tests/test_hardening.py (1e9 N/m on 1 kg)
about 160 000."""

INERTIA_SPREAD = 1e10
"""Ratio of a body's largest to smallest principal moment beyond which rounding noise
(relative 1e-16 of the largest, divided by the smallest) is blamed for short steps."""


def budget_message(what: str, t: float, t_end: float, steps: int, rate: Pace,
                   estimate: str, raise_it: str) -> str:
    """The one paragraph a run stopped by a budget reports."""
    t_end_ = option_name("t_end")
    return (f"the simulation stopped at {what}, at t = {t:.6g} s of {t_end:g} s: "
            f"{rate.so_far(t, steps)}; {estimate}. No trajectory is kept (rerun with "
            f"{option_setting('t_end', figure(t))} to see the motion up to here). To go on: "
            f"a shorter {t_end_}, a looser {option_name('rtol')} (e.g. 1e-8), a stiff "
            f"integrator such as {option_setting('method', 'Radau')} if the model is stiff "
            f"(very stiff springs), or {raise_it}.")


def figure(t: float) -> float:
    """`t` to the three figures a message gives it (an end time to rerun with)."""
    return float(f"{t:.3g}")


def blame_expression(varying: list[tuple[str, Expression]], t0: float, t1: float,
                      h: float | None) -> str:
    """When the integration fails between t0 and t1: the load expression that is not
    finite there, or that grows without bound (1/(t - pi) near pi), else ''."""
    if not varying:
        return ""
    w = max(1e-9 * max(1.0, abs(t1)), 100 * (h or 0.0))
    near = np.union1d(np.linspace(t0, t1 + w, 4001), [t0, t1, np.nextafter(t1, np.inf)])
    worst = ("", 0.0)
    for what, e in varying:
        v = np.abs(e(near))
        bad = ~np.isfinite(v)
        if bad.any():
            k = int(np.argmax(bad))
            return (f"{what} = \"{e.text}\" is not finite at t = {near[k]:.9g} s "
                    f"({e(near[k])}): change the expression, or simulate to before that time")
        earlier = check_times(t0) if t0 > 0 else np.zeros(1)
        earlier = earlier[earlier < t0 - 1e-3] if t0 > 2e-3 else earlier[:1]
        before = float(np.max(np.abs(e(earlier))))
        ratio = float(v.max()) / max(before, 1e-300)
        if ratio > 1e6 and ratio > worst[1]:
            k = int(np.argmax(v))
            worst = (f"{what} = \"{e.text}\" grows without bound near t = {near[k]:.9g} s "
                     f"(|value| {v[k]:.3g}, {ratio:.2g} times its largest before): change the "
                     "expression, or simulate to before that time", ratio)
    return worst[0]
