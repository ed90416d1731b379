"""Generalized coordinates and linearisation against a solve(), on every shipped model.

    python tools/bench_lagrange.py [--repeat N] [--quick]

Per model (microseconds per call, best of --repeat runs, tools/timing.py):

- solve: ``mbody.assemble(model).solve()`` (accelerations and every unknown reaction);
- generalized: ``mbody.assemble(model).generalized()`` (T, M_q, f_q at the state);
- linearize: ``mbody.linearize(model)`` with its verdict and frequencies
  (``.stable``, ``.frequencies``: the eigenvalues of the first-order system), and
  ``modes`` with the mode shapes as well (``.modes``).

Each is printed with its ratio to solve; the target (issue 26) is 50x for generalized and
linearize. The four measurements of a model are interleaved, run after run (the best of
each kept), so that a busy moment of the shared machine does not fall on one of them
only. The models are read from models/ (and models/robots/*.xml).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:
    sys.path.insert(0, str(ROOT / "tools"))

from timing import best  # noqa: E402

import mbody  # noqa: E402

TARGET = 50.0
"""generalized() and linearize() within this many solve()s (issue 26)."""


def models(quick: bool) -> list[Path]:
    out = sorted((ROOT / "models").glob("*.yaml"))
    out += sorted((ROOT / "models" / "robots").glob("*.xml"))
    return out[:6] if quick else out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15,
                    help="interleaved runs per measurement (the best kept)")
    ap.add_argument("--quick", action="store_true", help="the first six models only")
    a = ap.parse_args(argv)
    rows = []
    head = (f"{'model':32s} {'solve':>8s} {'general.':>9s} {'ratio':>6s} {'linearize':>10s} "
            f"{'ratio':>6s} {'modes':>8s} {'ratio':>6s}")
    print(head)
    print("-" * len(head))
    for path in models(a.quick):
        model = mbody.load(path)

        def lin(m=model) -> object:
            out = mbody.linearize(m)
            return out.stable, out.frequencies

        def modes(m=model) -> object:
            return mbody.linearize(m).modes

        calls = (lambda m=model: mbody.assemble(m).solve(),
                 lambda m=model: mbody.assemble(m).generalized(), lin, modes)
        times = [min(best(f, 1) for _ in range(1)) for f in calls]
        for _ in range(a.repeat - 1):
            times = [min(t, best(f, 1)) for t, f in zip(times, calls, strict=True)]
        solve, gen, tl, tm = times
        rows.append((gen / solve, tl / solve, tm / solve))
        print(f"{path.stem:32s} {solve * 1e6:8.1f} {gen * 1e6:9.1f} {gen / solve:6.1f} "
              f"{tl * 1e6:10.1f} {tl / solve:6.1f} {tm * 1e6:8.1f} {tm / solve:6.1f}")
    worst_g = max(r[0] for r in rows)
    worst_l = max(r[1] for r in rows)
    worst_m = max(r[2] for r in rows)
    print()
    for what, worst in (("generalized()", worst_g), ("linearize() with its verdict", worst_l),
                        ("linearize() with mode shapes", worst_m)):
        verdict = "PASS" if worst <= TARGET else "MISS"
        print(f"{what:30s} worst {worst:5.1f} x solve (target {TARGET:g} x): {verdict}")
    return 0 if max(worst_g, worst_l) <= TARGET else 1


if __name__ == "__main__":
    sys.exit(main())
