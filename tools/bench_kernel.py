"""Per-call time of the compiled core (`mbody.kernel._core`, C) beside the numba path
(`mbody.solve.compiled`, warm) and MuJoCo's mj_forward, on the shipped small mechanisms.

For each system of `bench_small.SYSTEMS`: one `Unknowns.solve` and one
`Unknowns.derivative` of the C kernel, the numba path's `solve` and `derivative` with the
same packed inputs, and `mj_forward` of the MuJoCo equivalent `bench_small` builds (its
builders are imported, not copied). Each is the best of several runs (`timing.best`),
in µs per call, whole Python call included; then the ratios C / numba and C / MuJoCo.
Target: the C kernel no slower than the numba path (ratio <= 1).

    python tools/bench_kernel.py [--repeat N]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
for p in (ROOT, ROOT / "tools"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

import bench_small  # noqa: E402
from timing import best  # noqa: E402

from mbody.equations.pack import pack_model, pack_unknowns  # noqa: E402
from mbody.kernel import _core  # noqa: E402


def c_calls(model, y, lam):
    """(solve, derivative) closures of the C kernel at (0, y)."""
    planar = model.dimension == 2
    F, I = pack_model(model)
    core = _core.Model(F, I, planar)
    unk = model.plan.file_unknowns
    cu = _core.Unknowns(core, pack_unknowns(model, unk.U))
    N, lo, io = _core.solve_layout(model.n, len(model.reactions), planar)
    out = np.zeros(io + _core.INFO)
    ydot = np.zeros_like(y)
    return (lambda: cu.solve(0.0, y, lam, out),
            lambda: cu.derivative(0.0, y, lam, 0.0, ydot), (core, cu, out))


def numba_calls(model, y, lam):
    """(solve, derivative) closures of the numba path at y (warm: each called once)."""
    from mbody.solve import compiled as C

    planar = model.dimension == 2
    F, I = C.pack_model(model)
    Iu = C.pack_unknowns(model, model.plan.file_unknowns.U)
    fvec = np.array(model.forces.vector_at(0.0), float)
    N, lo, io = C.solve_layout(model.n, len(model.reactions), planar)
    out = np.zeros(io + C.INFO)
    ydot = np.zeros_like(y)

    def solve():
        C.solve(F, I, Iu, y, fvec, lam, planar, out)

    def derivative():
        C.derivative(F, I, Iu, y, fvec, lam, 0.0, planar, ydot)

    solve(), derivative()
    return solve, derivative


def mujoco_call(model):
    """mj_forward of the MuJoCo equivalent, or None when it has none (or no MuJoCo)."""
    try:
        import mujoco

        eq = bench_small.mujoco_equivalent(model)
        m, d = eq.make()
    except Exception:  # noqa: BLE001 - a system without an equivalent is shown as '-'
        return None
    return lambda: mujoco.mj_forward(m, d)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=7, help="runs per figure (best is kept)")
    args = ap.parse_args(argv)
    head = (f"{'system':18s} {'C solve':>8s} {'nb solve':>8s} {'C deriv':>8s} "
            f"{'nb deriv':>8s} {'mj_fwd':>7s} | {'C/nb sol':>8s} {'C/nb der':>8s} "
            f"{'C/mj sol':>8s}")
    print("µs per call, best of", args.repeat)
    print(head)
    print("-" * len(head))
    worst = 0.0
    for label, file in bench_small.SYSTEMS:
        model = bench_small.load(file)
        y = bench_small.initial_y(model)
        lam = model.plan.file_unknowns.lam
        cs, cd, _keep = c_calls(model, y, lam)
        ns, nd = numba_calls(model, y, lam)
        mj = mujoco_call(model)
        t = [best(f, args.repeat) * 1e6 for f in (cs, ns, cd, nd)]
        tm = best(mj, args.repeat) * 1e6 if mj else float("nan")
        worst = max(worst, t[0] / t[1], t[2] / t[3])
        print(f"{label:18s} {t[0]:8.2f} {t[1]:8.2f} {t[2]:8.2f} {t[3]:8.2f} {tm:7.2f} | "
              f"{t[0] / t[1]:8.2f} {t[2] / t[3]:8.2f} {t[0] / tm:8.2f}")
    # the bindings' own cost: a call on a model with nothing to do
    model = bench_small.load("pendulum.yaml")
    y = bench_small.initial_y(model)
    _, _, (core, cu, out) = c_calls(model, y, model.plan.file_unknowns.lam)
    net = np.empty((model.n, 6))
    print(f"\nnet_wrench on the pendulum (the binding's cost and little else): "
          f"{best(lambda: core.net_wrench(0.0, y, net), args.repeat) * 1e6:.2f} µs")
    verdict = "met" if worst <= 1.0 else "NOT met"
    print(f"target C <= numba per call: {verdict} (worst ratio {worst:.2f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
