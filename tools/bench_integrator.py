"""The compiled core's DOP853 against scipy's on plain ODEs: time per step, same steps.

    python tools/bench_integrator.py [--repeat N] [--quick]

Systems: the core's built-in test systems (harmonic oscillator, van der Pol with mu = 5,
Arenstorf's orbit, a pendulum at large amplitude), each integrated over the same span by

- scipy: ``scipy.integrate.DOP853`` stepped by ``step()``, the right-hand side a Python
  function (the same operations as the core's built-in one, tests/test_dop853.py);
- core, C rhs: ``mbody.kernel.dop853.DOP853`` on the built-in system, the whole run in
  one call (what a simulation with a compiled right-hand side pays);
- core, C rhs, step(): the same, one Python call per step;
- core, Python rhs: the core integrator calling the same Python function as scipy (the
  integrator's own overhead, beside the evaluations both pay).

Times are microseconds per accepted step (best of --repeat whole runs); the ratio
columns are scipy's time over the core's. Steps are counted for both: the two take the
same steps to within rounding of the error estimate (tests/test_dop853.py), so the
counts agree or differ by a rejection or two.
"""

from __future__ import annotations

import argparse
import sys
from functools import partial
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:
    sys.path.insert(0, str(ROOT / "tools"))
if str(ROOT / "tests") not in sys.path:  # tests/ode_systems.py: the test systems in Python
    sys.path.insert(0, str(ROOT / "tests"))

from ode_systems import SYSTEMS  # noqa: E402
from timing import best  # noqa: E402

from mbody.kernel.dop853 import DOP853  # noqa: E402


def scipy_run(fun, y0, t0, t_bound, rtol):
    from scipy.integrate import DOP853 as ScipyDOP853

    s = ScipyDOP853(fun, t0, np.array(y0, dtype=float), t_bound, rtol=rtol, atol=rtol * 1e-3)
    steps = 0
    while s.status == "running":
        s.step()
        steps += 1
    return steps


def core_run(rhs, params, y0, t0, t_bound, rtol, one_call=True):
    s = DOP853(rhs, t0, y0, t_bound, rtol=rtol, atol=rtol * 1e-3, params=params)
    if one_call:
        s.run(max_steps=10**9)
    else:
        while s.status == "running":
            s.step()
    return s.steps


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="whole runs timed, best kept")
    ap.add_argument("--quick", action="store_true", help="one tolerance, 2 repeats")
    args = ap.parse_args(argv)
    repeat = 2 if args.quick else args.repeat
    tolerances = (1e-8,) if args.quick else (1e-4, 1e-8, 1e-12)
    print("DOP853: microseconds per accepted step (best of "
          f"{repeat} whole runs); ratio = scipy / core")
    head = (f"{'system':<12} {'rtol':>6} {'steps':>11} {'scipy':>8} {'C rhs':>7} "
            f"{'step()':>7} {'Py rhs':>7} {'ratio C':>8} {'step()':>7} {'Py rhs':>7}")
    print(head)
    print("-" * len(head))
    ratios = []
    for name, (fun, params, y0, t0, t_bound) in SYSTEMS.items():
        for rtol in tolerances:
            n_scipy = scipy_run(fun, y0, t0, t_bound, rtol)
            n_core = core_run(name, params, y0, t0, t_bound, rtol)
            case = (y0, t0, t_bound, rtol)
            per = {
                "scipy": best(partial(scipy_run, fun, *case), repeat) / n_scipy,
                "C": best(partial(core_run, name, params, *case), repeat) / n_core,
                "step": best(partial(core_run, name, params, *case, one_call=False),
                             repeat) / n_core,
                "py": best(partial(core_run, fun, params, *case), repeat) / n_core,
            }
            us = {k: v * 1e6 for k, v in per.items()}
            r = (per["scipy"] / per["C"], per["scipy"] / per["step"],
                 per["scipy"] / per["py"])
            ratios.append(r)
            print(f"{name:<12} {rtol:>6.0e} {n_scipy:>5}/{n_core:<5} {us['scipy']:>8.1f} "
                  f"{us['C']:>7.2f} {us['step']:>7.2f} {us['py']:>7.1f} {r[0]:>7.0f}x "
                  f"{r[1]:>6.0f}x {r[2]:>6.1f}x")
    geo = np.exp(np.mean(np.log(np.array(ratios)), axis=0))
    print(f"{'geometric mean of the ratios':<57} {geo[0]:>7.0f}x {geo[1]:>6.0f}x "
          f"{geo[2]:>6.1f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
