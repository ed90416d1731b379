"""Timing shared by the benchmarks in tools/: the best of several runs of a call.

These machines are shared and noisy (absolute times drift 2-5x between runs), so every
benchmark reports the best of `repeat` runs, each long enough to fill a small budget,
with the garbage collector off while timing.
"""

from __future__ import annotations

import gc
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
