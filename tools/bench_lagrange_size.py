"""Benchmark: generalized coordinates, modes and a refused answers file, time against size.

    python tools/bench_lagrange_size.py [--sizes 50,200,500,1000,2000] [--modes-up-to N]
                                        [--repeat R] [--limit SECONDS] [--quick]

A planar chain of n rods (0.1 m, 1 kg, revolute pins), every rod at 0.1 rad from the
vertical, at rest: n generalized coordinates (a spanning tree's joint angles). Per size,
seconds of process CPU time (these machines are shared: wall time in brackets), the best
of --repeat runs:

- load: ``mbody.load`` of its YAML file;
- choose: the default coordinates (`mbody.equations.coordinates.choose`: the compiled core
  proves the tree's angles independent, `mb_independence`);
- generalized: ``generalized(model)``, the coordinates chosen (T, M_q, f_q by the core's
  banded QR), and the ``mbody lagrange`` text (`generalized_text`, bounded above 200
  coordinates);
- modes: ``mbody.linearize(model)`` and its modes (K and D by differences, the
  first-order system A, its spectrum: the core's up to 150 rows, LAPACK's above), with
  the share of its stages: the differences (K, D), A, and the eigenvalues with the mode
  shapes; sizes above --modes-up-to (default 1000) are left out (2000 rods: about two
  minutes, most of it LAPACK's eigenvalues of a 4000 x 4000 system).

Checked before anything is timed: the accelerations of M q'' = f (T q'' + a0) are the
Newton-Euler solve's within the equations' own rounding model (as
tests/test_lagrange_large.py checks them).

Then the refusal of an answers file of N entries without ``body:`` (Newton-Euler names,
``m*a_x = jK.Fx - jK+1.Fx``) on a 400-rod chain: ``mbody.verify`` raising its
AnswersError, for N = 200, 2000 and 20000 (the most an answers file holds).

Each table ends with the growth exponent between its last two sizes (log of the time
ratio over log of the size ratio): 2 is what the output itself costs (M has n^2 entries);
3 the dense eigenvalues. A measurement whose previous size took more than --limit
seconds is skipped ('-').
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))

import mbody  # noqa: E402
from mbody.answers import AnswersError  # noqa: E402
from mbody.equations.coordinates import choose  # noqa: E402
from mbody.equations.generalized import generalized  # noqa: E402
from mbody.kernel import _core  # noqa: E402
from mbody.present.lagrange import generalized_text  # noqa: E402
from mbody.solve.linearize import ROUNDING, linearize  # noqa: E402

L, ANGLE = 0.1, 0.1


def chain_yaml(n: int) -> str:
    """n rods hanging in a chain at ANGLE from the vertical, at rest."""
    s, c = math.sin(ANGLE), math.cos(ANGLE)
    bodies = "".join(f"  - {{name: l{i}, mass: 1, inertia: 0.000833333333333, position: "
                     f"[{(i + 0.5) * L * s!r}, {-(i + 0.5) * L * c!r}], angle: {ANGLE!r}}}\n"
                     for i in range(n))
    joints = "".join(f"  - {{name: j{i}, type: revolute, parent: "
                     f"{'ground' if i == 0 else f'l{i - 1}'}, child: l{i}, "
                     f"at: [{i * L * s!r}, {-i * L * c!r}]}}\n" for i in range(n))
    return (f"model: chain-{n}\ndimension: 2\ngravity: [0, -9.81]\nbodies:\n{bodies}"
            f"joints:\n{joints}")


def timed(fn: Callable[[], object], repeat: int) -> tuple[float, float, object]:
    """(best CPU seconds, best wall seconds, the last result) of `repeat` calls."""
    cpu = wall = math.inf
    out = None
    for _ in range(repeat):
        c0, w0 = time.process_time(), time.perf_counter()
        out = fn()
        cpu = min(cpu, time.process_time() - c0)
        wall = min(wall, time.perf_counter() - w0)
    return cpu, wall, out


def check(model: mbody.Model) -> None:
    """The accelerations of M q'' = f against the Newton-Euler solve's."""
    g = generalized(model)
    acc = mbody.assemble(model).solve().accelerations
    df = ROUNDING * g.f_scale / g.rank
    bound = np.abs(g.T) @ (np.abs(np.linalg.inv(g.M)) @ df) + \
        1e3 * np.finfo(float).eps * np.abs(acc).max()
    err = np.abs(g.body_accelerations(g.accelerations()) - acc)
    if not np.all(err <= bound):
        raise SystemExit(f"{model.name}: the generalized accelerations are off the solve's "
                         f"by {err.max():.3g} (bound {bound[np.argmax(err - bound)]:.3g})")


def cell(cpu: float | None, wall: float | None = None) -> str:
    if cpu is None:
        return f"{'-':>17s}"
    return f"{cpu:8.2f} [{wall:6.1f}]"


def growth(sizes: list[int], times: list[float | None]) -> str:
    known = [(n, t) for n, t in zip(sizes, times, strict=True) if t]
    if len(known) < 2:
        return "-"
    (n1, t1), (n2, t2) = known[-2], known[-1]
    return f"{math.log(t2 / t1) / math.log(n2 / n1):.2f}"


class Stages:
    """The linearisation's stages' CPU seconds, from its progress callback."""

    GROUPS = {_core.STAGE_GENERALIZED: "equations", _core.STAGE_DAMPING: "differences",
              _core.STAGE_STIFFNESS: "differences", _core.STAGE_SYSTEM: "system"}

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self.stage: str | None = None
        self.at = time.process_time()

    def step(self, what: str, total: int | None = None) -> None:
        self._switch("eigenvalues" if what not in self.GROUPS.values() else what)

    def core(self, stage: int, done: int, total: int) -> None:
        self._switch(self.GROUPS.get(stage, "eigenvalues"))

    def _switch(self, stage: str) -> None:
        now = time.process_time()
        if self.stage is not None:
            self.seconds[self.stage] = self.seconds.get(self.stage, 0.0) + now - self.at
        self.stage, self.at = stage, now


def modes_with_stages(model: mbody.Model) -> tuple[object, dict[str, float]]:
    from mbody.util.progress import Progress

    stages = Stages()

    class Recorder(Progress):
        def step(self, what: str, total: int | None = None) -> None:
            stages.step(what, total)

        def core(self, stage: int, done: int, total: int) -> None:
            stages.core(stage, done, total)

        @property
        def callback(self):
            return self.core

    lin = linearize(model, progress=Recorder(False, model.name))
    lin.modes  # noqa: B018  (made now: on the clock)
    stages._switch("")
    return lin, stages.seconds


class Table:
    """A time-against-size table's columns; a measurement is skipped once the size before
    took more than `limit` seconds (wall)."""

    def __init__(self, keys: tuple[str, ...], repeat: int, limit: float):
        self.columns: dict[str, list[float | None]] = {k: [] for k in keys}
        self.repeat, self.limit = repeat, limit
        self.last: dict[str, float] = {}
        self.row: list[str] = []

    def run(self, key: str, fn: Callable[[], object], repeat: int | None = None) -> object:
        if self.last.get(key, 0.0) > self.limit:
            self.skip(key)
            return None
        cpu, wall, out = timed(fn, repeat or self.repeat)
        self.last[key] = wall
        self.columns[key].append(cpu)
        self.row.append(cell(cpu, wall))
        return out

    def skip(self, key: str) -> None:
        self.columns[key].append(None)
        self.row.append(cell(None))

    def line(self) -> str:
        out, self.row = " ".join(self.row), []
        return out


def chains(sizes: list[int], modes_up_to: int, repeat: int, limit: float,
           folder: Path) -> None:
    head = (f"{'rods':>5s} {'load':>17s} {'choose':>17s} {'generalized':>17s} "
            f"{'lagrange text':>17s} {'modes':>17s}  modes' stages (differences / A / "
            "eigenvalues and shapes)")
    print("chain of n rods, n coordinates: CPU seconds [wall seconds], best of "
          f"{repeat}")
    print(head)
    print("-" * len(head))
    table = Table(("load", "choose", "gen", "text", "modes"), repeat, limit)
    for n in sizes:
        path = folder / f"chain{n}.yaml"
        path.write_text(chain_yaml(n), encoding="utf-8")
        table.run("load", lambda p=path: mbody.load(p))
        model = mbody.load(path)
        check(model)
        table.run("choose", lambda m=model: choose(m))  # not kept with the model
        g = generalized(model)
        table.run("gen", lambda m=model: generalized(m))
        table.run("text", lambda g=g: generalized_text(g))
        shares = ""
        if n <= modes_up_to:
            out = table.run("modes", lambda m=model: modes_with_stages(m), 1)
            if isinstance(out, tuple):
                s = out[1]
                shares = (f"  {s.get('differences', 0):.2f} / {s.get('system', 0):.2f} / "
                          f"{s.get('eigenvalues', 0):.2f}")
        else:
            table.skip("modes")
        print(f"{n:5d} " + table.line() + shares, flush=True)
    print(f"{'growth':>5s} " + " ".join(f"{growth(sizes, c):>17s}"
                                         for c in table.columns.values()))


def refusals(repeat: int, folder: Path) -> None:
    n = 400
    path = folder / "chain400.yaml"
    path.write_text(chain_yaml(n), encoding="utf-8")
    model = mbody.load(path)
    print()
    print(f"an answers file of N entries without body: on the {n}-rod chain, refused "
          "(CPU seconds [wall])")
    print(f"{'entries':>8s} {'refused in':>17s}  problems  shown with a did-you-mean")
    counts, times = [200, 2000, 20000], []
    for count in counts:
        sheet = folder / f"answers{count}.yaml"
        sheet.write_text("equations:\n" + "".join(
            f'  - {{eq: "m*a_x = j{i % n}.Fx - j{(i % n) + 1}.Fx"}}\n' for i in range(count)),
            encoding="utf-8")

        def refuse(s=sheet) -> AnswersError:
            try:
                mbody.verify(model, s)
            except AnswersError as exc:
                return exc
            raise SystemExit("the answers were not refused")

        cpu, wall, err = timed(refuse, repeat)
        assert isinstance(err, AnswersError)
        times.append(cpu)
        hinted = sum(1 for i in err.issues if i.hint)
        print(f"{count:8d} {cell(cpu, wall)}  {len(err.issues):8d}  {hinted}", flush=True)
    print(f"{'growth':>8s} {growth(counts, times):>17s}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="50,200,500,1000,2000",
                    help="chain lengths, separated by commas")
    ap.add_argument("--modes-up-to", type=int, default=1000,
                    help="the longest chain whose modes are computed")
    ap.add_argument("--repeat", type=int, default=3, help="runs per measurement (best kept)")
    ap.add_argument("--limit", type=float, default=300.0,
                    help="skip a measurement once the size before took this many seconds")
    ap.add_argument("--quick", action="store_true", help="sizes 50 and 200, one run each")
    a = ap.parse_args(argv)
    sizes = [50, 200] if a.quick else [int(s) for s in a.sizes.split(",")]
    repeat = 1 if a.quick else a.repeat
    with tempfile.TemporaryDirectory() as tmp:
        chains(sizes, a.modes_up_to, repeat, a.limit, Path(tmp))
        refusals(repeat, Path(tmp))
    return 0


if __name__ == "__main__":
    sys.exit(main())
