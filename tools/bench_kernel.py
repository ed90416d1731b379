"""Per-call time of the compiled core (`mbody.kernel._core`, C) beside MuJoCo's mj_forward,
on the shipped small mechanisms.

    python tools/bench_kernel.py [--repeat N]

For each system of `bench_small.SYSTEMS`: one `Unknowns.solve` and one
`Unknowns.derivative` of the core, as the model's workspace (`mbody.equations.workspace`)
prepares them for `Assembly.solve` and `simulate`, on the packed initial state, and
`mj_forward` of the MuJoCo equivalent `bench_small` builds (its builders are imported,
not copied). Each is the best of several runs (`timing.best`, the three taking turns),
in µs per call, the whole Python call included; then the ratios core / mj_forward.
Target: the core's solve at most 5× mj_forward on every system that has an equivalent.

There is one numeric path (the core); the numba path this benchmark once compared with
is gone.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
for p in (ROOT, ROOT / "tools"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

import bench_small  # noqa: E402
from timing import best  # noqa: E402

from mbody.equations.workspace import workspace  # noqa: E402
from mbody.kernel import _core  # noqa: E402

TARGET = 5.0
"""The core's solve per call / mj_forward per call, at most."""


def core_calls(model):
    """(solve, derivative) closures of the core at the model's initial state (t = 0), with
    the unknowns and the known reaction values of the file, as `Assembly.solve` and
    `simulate` call it."""
    ws = workspace(model)
    unknowns = ws.file_unknowns
    plan = ws.solve_plan(unknowns)
    y13 = ws.pack_state(model.initial)  # what a solve reads: [x | q | v | ω]
    y = ws.state_vector(model.initial)  # what a simulation integrates (planar: with θ)
    out = np.empty(plan.o_info + _core.INFO)
    ydot = np.empty_like(y)
    return (lambda: plan.solver.solve(0.0, y13, unknowns.lam, out),
            lambda: plan.solver.derivative(0.0, y, unknowns.lam, 0.0, ydot))


def mujoco_call(model):
    """mj_forward of the MuJoCo equivalent, or None when it has none (or no MuJoCo)."""
    try:
        import mujoco

        eq = bench_small.mujoco_equivalent(model)
        m, d = eq.make()
    except Exception:  # noqa: BLE001 - a system without an equivalent is shown as '-'
        return None
    return lambda: mujoco.mj_forward(m, d)


def interleaved(calls, repeat: int) -> list[float]:
    """µs per call of each of `calls` (nan for None): the best of `repeat` rounds in
    which each call takes its turn (`timing.best` once), so that a burst of load from
    other processes on this shared machine spreads over all of them."""
    out = [math.inf if f else math.nan for f in calls]
    for _ in range(repeat):
        for k, f in enumerate(calls):
            if f:
                out[k] = min(out[k], best(f, 1) * 1e6)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=7, help="runs per figure (best is kept)")
    args = ap.parse_args(argv)
    head = (f"{'system':18s} {'solve':>8s} {'deriv':>8s} {'mj_fwd':>8s} | "
            f"{'solve/mj':>8s} {'deriv/mj':>8s}")
    print("µs per call, best of", args.repeat, "(solve, deriv: the core's Unknowns.solve "
          "and Unknowns.derivative; mj_fwd: MuJoCo's mj_forward on the equivalent model)")
    print(head)
    print("-" * len(head))
    worst = 0.0
    for label, file in bench_small.SYSTEMS:
        model = bench_small.load(file)
        solve, derivative = core_calls(model)
        mj = mujoco_call(model)
        ts, td, tm = interleaved((solve, derivative, mj), args.repeat)
        if mj:
            worst = max(worst, ts / tm)
        print(f"{label:18s} {ts:8.2f} {td:8.2f} {tm:8.2f} | {ts / tm:8.2f} {td / tm:8.2f}")
    # the binding's own cost: a call on a model with little to do
    model = bench_small.load("pendulum.yaml")
    ws = workspace(model)
    y13 = ws.pack_state(model.initial)
    net = np.empty((model.n, 6))
    print(f"\nnet_wrench on the pendulum (the binding's cost and little else): "
          f"{best(lambda: ws.core.net_wrench(0.0, y13, net), args.repeat) * 1e6:.2f} µs")
    verdict = "met" if worst <= TARGET else "NOT met"
    print(f"target: the core's solve ≤ {TARGET:g}× mj_forward per call: {verdict} "
          f"(worst ratio {worst:.2f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
