"""Timing shared by the benchmarks in tools/: the best of several runs of a call, and the
growth exponent of a time-vs-size table with its verdict.

These machines are shared and noisy (absolute times drift 2-5x between runs), so every
benchmark reports the best of `repeat` runs, each long enough to fill a small budget,
with the garbage collector off while timing.
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable


def best(fn: Callable[[], object], repeat: int, budget: float = 0.01) -> float:
    """Best time of one call (s): `repeat` runs, each of as many calls as fill `budget`."""
    t0 = time.perf_counter()
    fn()
    once = time.perf_counter() - t0
    number = max(1, int(budget / max(once, 1e-9)))
    times = []
    gc.disable()
    try:
        for _ in range(repeat):
            t0 = time.perf_counter()
            for _ in range(number):
                fn()
            times.append((time.perf_counter() - t0) / number)
    finally:
        gc.enable()
    return min(times)


LINEAR = 1.3
"""Largest growth exponent still called linear: timings on these machines wobble by tens of
percent between sizes, and a quadratic reading shows 2."""


def growth(sizes: list[float], seconds: list[float]) -> float:
    """The growth exponent p of t ~ n^p: the least-squares slope of log t against log n
    (1 linear, 2 quadratic); nan for fewer than two usable points."""
    pts = [(math.log(n), math.log(t)) for n, t in zip(sizes, seconds, strict=True)
           if n > 0 and t > 0]
    if len(pts) < 2:
        return math.nan
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    if sxx == 0:
        return math.nan
    return sum((x - mx) * (y - my) for x, y in pts) / sxx


def linear_verdict(sizes: list[float], seconds: list[float], stopped: bool = False) -> str:
    """One line: the fitted growth exponent and PASS when it is at most `LINEAR`.

    `stopped`: the last size took longer than the benchmark's limit and the larger ones
    were not run; the fit over the sizes run still decides (a linear but slow case, on a
    loaded machine, passes), unless there are fewer than two: then FAIL."""
    p = growth(sizes, seconds)
    note = " (stopped at the time limit)" if stopped else ""
    if math.isnan(p):
        return ("fit: the first size took longer than the time limit: FAIL" if stopped
                else "fit: too few sizes for a fit")
    return (f"fit: t ~ n^{p:.2f} over n = {sizes[0]:.3g} .. {sizes[-1]:.3g}: "
            f"{'PASS' if p <= LINEAR else 'FAIL'} (linear: exponent at most {LINEAR}){note}")
