"""Bricard's mechanism (IFToMM benchmark A04, models/bricard.yaml): wall time per simulated
second, and the error against the independent reference of tests/bricard_reference.py.

    python tools/bench_bricard.py [--repeat N] [--t-end S]

Each row is 10 s (or --t-end) of the benchmark, sampled at 60 per second, run as
tests/bricard_run.py drives the compiled core (its DOP853, derivative and projection:
what `mbody.simulate` will run once it is on the core). Wall time: the best of --repeat
runs. Error: the largest distance of the benchmark's point P3 from the reference's over
the samples; energy drift: the largest |E - E(0)|. Then the cost of one call of the
core's derivative and of its projection at the file's pose (µs, best of several), which
the run's time is made of. Target (issue 23): at most 1 s of wall time per simulated
second at rtol 1e-8.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
for p in (ROOT, ROOT / "tools", ROOT / "tests"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

import bricard_reference  # noqa: E402
import bricard_run  # noqa: E402
from timing import best  # noqa: E402

import mbody  # noqa: E402
from mbody.equations.workspace import workspace  # noqa: E402
from mbody.kernel import _core  # noqa: E402

ROWS = [(1e-6, 1e-9), (1e-8, 1e-10), (1e-8, 1e-12), (1e-10, 1e-10), (1e-10, 1e-12)]
"""(rtol, atol) per row; (1e-8, 1e-10) is the target's, (1e-10, 1e-12) mbody.simulate's
defaults."""
TARGET = 1.0
"""Seconds of wall time per simulated second, at rtol 1e-8."""
FPS = 60.0


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--t-end", type=float, default=10.0)
    args = ap.parse_args(argv)
    model = mbody.load(bricard_run.MODEL)
    t = np.arange(int(args.t_end * FPS + 1e-9) + 1) / FPS
    print(f"Bricard's mechanism, {args.t_end:g} s at {FPS:g} samples/s; reference: "
          "tests/bricard_reference.py (rtol 1e-13)")
    ref = bricard_reference.motion(t)
    print(f"  reference energy drift {np.abs(ref.energy - ref.energy[0]).max():.1e} J, "
          f"{ref.evaluations} evaluations")
    print(f"{'rtol':>7} {'atol':>7} {'wall s':>8} {'s per sim s':>11} {'steps':>6} "
          f"{'rejected':>8} {'evals':>6} {'P3 error m':>11} {'energy drift J':>14}  target")
    for rtol, atol in ROWS:
        runs = []
        for _ in range(args.repeat):
            runs.append(bricard_run.run(model, args.t_end, FPS, rtol=rtol, atol=atol))
        r = min(runs, key=lambda r: r.wall)
        per = r.wall / args.t_end
        err = float(np.abs(bricard_run.p3(model, r) - ref.p3).max())
        E = bricard_run.energy(model, r)
        drift = float(np.abs(E - E[0]).max())
        mark = (("PASS" if per <= TARGET else "MISS") + f" (<= {TARGET:g} s/s)"
                if (rtol, atol) == (1e-8, 1e-10) else "")
        print(f"{rtol:7.0e} {atol:7.0e} {r.wall:8.3f} {per:11.4f} {r.steps:6d} "
              f"{r.rejected:8d} {r.evaluations:6d} {err:11.1e} {drift:14.1e}  {mark}")
    ws = workspace(model)
    unknowns = ws.file_unknowns
    solver = ws.solver(unknowns)
    y = ws.state_vector(model.initial)
    out = np.empty_like(y)
    info = np.empty(_core.PROJECT_INFO)
    d = best(lambda: solver.derivative(0.0, y, unknowns.lam, 0.0, out), args.repeat)
    p = best(lambda: solver.project(0.0, y, 3, bricard_run.ROBUST_BELOW, 0, info),
             args.repeat)
    print(f"one call at the file's pose: derivative {d * 1e6:.1f} us, projection "
          f"{p * 1e6:.1f} us (a run projects after every step and at every sample)")


if __name__ == "__main__":
    main()
