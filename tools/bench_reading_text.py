"""Reading time against input size for YAML model text and answers files: linear or not.

    python tools/bench_reading_text.py [--quick] [--repeat N] [--limit S] [--case NAME]

Each case in `CASES` makes an input of a given size and reads it the way the command
line does (`mbody.loads` for a model's text, with the validation and its hints;
`mbody.verify` for an answers file). Inputs a user or a fuzzer has sent that took time
growing with the square of their size:

- a model number written as a long run of digits with a stray character: quoted
  (``mass: "1000…0}"``, the number hint's regular expression) or plain with an
  underscore (``mass: 1000…0_x``, YAML 1.1's underscored number check): 80 kB took
  158 s;
- an answers file of many equations (16 000: 31 s; each entry split the whole text);
- equations on a model of many reactions whose labels the name token does not read
  whole (pin-3.Fx): each character of each equation tried every label (a quarter of a
  second an equation with 1000 labels).

And inputs the tests refuse or read, whose speed they once checked with a clock
(tests/test_hardening.py, tests/test_loader.py): an integer of thousands of digits (int()
of a long text is quadratic), a list of over a million values (refused at the
millionth), nesting 100 000 levels deep in three shapes (refused at 64 levels), and
10 000 bodies one a line through the located reader (`mbody.model.loader.load_text`,
which keeps every line mark).

For each case and size the table shows the best time of --repeat runs, the time per
unit of size, and the growth: log(t2/t1) / log(n2/n1) between a size and the one before
(1 is linear, 2 quadratic; small sizes are noisy). Under each case, the verdict: the
exponent of a least-squares fit of log t against log n over its sizes, PASS when at most
1.3 (tools/timing.py, `LINEAR`). A size whose read takes longer than --limit seconds ends
its case (the larger ones would take minutes if it is not linear); the verdict is then
the fit over the sizes run, and FAIL if only one was.

To be merged into tools/bench_reading.py (the same table for the other readers).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:  # tools/timing.py, also when loaded by path
    sys.path.insert(0, str(ROOT / "tools"))

from timing import best, linear_verdict  # noqa: E402

import mbody  # noqa: E402
from mbody.errors import MbodyError  # noqa: E402
from mbody.model.loader import load_text  # noqa: E402

PENDULUM = (ROOT / "models" / "pendulum.yaml").read_text(encoding="utf-8")


def model_with(value: str, key: str = "mass: 2.0") -> str:
    """The pendulum model with `key` (a line of it) replaced by `value`."""
    assert key in PENDULUM
    return PENDULUM.replace(key, value)


def nested(nest: str) -> str:
    """A model whose bodies are `nest`, nested deeper than `loader.MAX_DEPTH` (refused)."""
    return "dimension: 2\nbodies: " + nest + "\n"


def many_values(n: int) -> str:
    """A one-body model whose gravity lists n zeros (over 1 000 000 values is refused)."""
    return ("dimension: 2\nbodies: [{name: a, mass: 1, inertia: 1}]\ngravity: ["
            + ", ".join(["0"] * n) + "]\n")


def bodies_one_a_line(n: int) -> str:
    """n spatial bodies, each a flow mapping on its line (tests/test_loader.py's 10 000)."""
    body = ("  - {name: b%d, mass: 1.5, inertia: [2, 3, 4], position: [%d, 0, 0], "
            "angular_velocity: [1, 2, 3], orientation: {quaternion: [1, 0, 0, 0]}}\n")
    return "dimension: 3\nbodies:\n" + "".join(body % (i, i) for i in range(n))


def chain(n: int) -> str:
    """A planar chain of n bodies on revolute joints named pin-0 ... (labels such as
    pin-3.Fx, which the name token does not read whole)."""
    bodies = "\n".join(f"  - {{name: b{k}, mass: 1, inertia: 0.1, position: [{k + 0.5}, 0]}}"
                       for k in range(n))
    joints = "\n".join(f"  - {{name: pin-{k}, type: revolute, parent: "
                       f"{'ground' if k == 0 else f'b{k - 1}'}, child: b{k}, at: [{k}, 0]}}"
                       for k in range(n))
    return f"dimension: 2\ngravity: [0, -9.81]\nbodies:\n{bodies}\njoints:\n{joints}\n"


@dataclass(frozen=True)
class Case:
    """One input shape: `make(n)` gives the text for size n; `unit` names n; `model`,
    for an answers case, the model's text (default: models/pendulum.yaml)."""

    name: str
    kind: str  # "model" (read by mbody.loads), "text" (by the located reader alone,
    # mbody.model.loader.load_text) or "answers" (checked by mbody.verify)
    make: Callable[[int], str]
    unit: str = "kB"
    sizes: tuple[int, ...] = (10_000, 20_000, 40_000, 80_000)
    model: str = ""


CASES: list[Case] = [
    Case("quoted digits + stray '}'", "model", lambda n: model_with(f'mass: "1{"0" * n}}}"')),
    Case("plain digits + '_x'", "model", lambda n: model_with(f"mass: 1{'0' * n}_x")),
    Case("plain '1_1_…_1x'", "model", lambda n: model_with(f"mass: {'1_' * (n // 2)}x")),
    Case("quoted digits + ' kgx'", "model", lambda n: model_with(f'mass: "1{"0" * n} kg!"')),
    Case("decimal comma '1,00…0x'", "model", lambda n: model_with(f'mass: "1,{"0" * n}x"')),
    Case("angle '1…0 degrees!'", "model",
         lambda n: model_with(f'angle: "1{"0" * n} degrees!"', "angle: 30 deg")),
    Case("base 60 '1:2:…:x'", "model", lambda n: model_with(f"mass: {'1:2' * (n // 3)}:x")),
    Case("hex '0x_…_g'", "model", lambda n: model_with(f"mass: 0x{'_' * n}g")),
    Case("integer of n digits", "model", lambda n: model_with(f"mass: 1{'0' * n}")),
    Case("tiny '0.0…01'", "model", lambda n: model_with(f"mass: 0.{'0' * n}1")),
    Case("digits 'e' digits 'e'…", "model", lambda n: model_with(f"mass: {'1e' * (n // 2)}")),
    Case("unknown key of n letters", "model",
         lambda n: model_with(f"{'m' * n}ass: 2.0")),
    Case("a list of n values", "model", many_values, unit="1000 values",
         sizes=(137_500, 275_000, 550_000, 1_100_000)),
    Case("nesting '[' n levels deep", "model", lambda n: nested("[" * n + "]" * n),
         unit="1000 levels", sizes=(12_500, 25_000, 50_000, 100_000)),
    Case("nesting '- ' n levels deep", "model", lambda n: nested("\n  " + "- " * n + "x"),
         unit="1000 levels", sizes=(12_500, 25_000, 50_000, 100_000)),
    Case("nesting '{a: ' n levels deep", "model",
         lambda n: nested("{a: " * n + "1" + "}" * n), unit="1000 levels",
         sizes=(1250, 2500, 5000, 10_000)),
    Case("n bodies one a line, located", "text", bodies_one_a_line, unit="1000 bodies",
         sizes=(1250, 2500, 5000, 10_000)),
    Case("equations 'm*a_x = O.Fx'", "answers", lambda n: "equations:\n" + "".join(
        f'  - {{body: rod, eq: "m*a_x = O.Fx + {k}"}}\n' for k in range(n)),
        unit="1000 equations", sizes=(2000, 4000, 8000, 16000)),
    Case("equations with an unknown name", "answers", lambda n: "equations:\n" + "".join(
        f'  - {{body: rod, eq: "m*a_x = O.Fxx + {k}"}}\n' for k in range(n)),
        unit="1000 equations", sizes=(2000, 4000, 8000, 16000)),
    # each equation looked for the model's 1000 reaction labels at every character
    Case("equations, 1000 labels 'pin-k.Fx'", "answers", lambda n: "equations:\n" + "".join(
        f'  - {{body: b{k % 500}, eq: "m*a_x = pin-{k % 500}.Fx - pin-{k % 500 + 1}.Fx"}}\n'
        for k in range(n)), unit="1000 equations", sizes=(500, 1000, 2000, 4000),
        model=chain(501)),
]
"""The inputs measured (a new hang found by a fuzzer becomes a case here)."""


def reader(case: Case, folder: Path) -> Callable[[str], None]:
    """What reads one input of `case` (errors are expected: most inputs are refused)."""
    if case.kind == "model":
        def read(text: str) -> None:
            with contextlib.suppress(MbodyError):
                mbody.loads(text)
        return read
    if case.kind == "text":
        def located(text: str) -> None:
            with contextlib.suppress(MbodyError):
                load_text(text)
        return located
    model = mbody.loads(case.model) if case.model else mbody.load(
        ROOT / "models" / "pendulum.yaml")
    path = folder / "answers.yaml"

    def check(text: str) -> None:
        path.write_text(text, encoding="utf-8")
        with contextlib.suppress(MbodyError):
            mbody.verify(model, path)
    return check


def run(case: Case, repeat: int, limit: float, quick: bool, folder: Path) -> list[str]:
    read = reader(case, folder)
    sizes = case.sizes[:2] if quick else case.sizes
    per = 1000 if case.unit.startswith("1000") or case.unit == "kB" else 1
    rows = []
    last: tuple[int, float] | None = None
    measured: tuple[list[float], list[float]] = ([], [])
    stopped = False
    for n in sizes:
        text = case.make(n)
        t0 = time.perf_counter()
        read(text)
        once = time.perf_counter() - t0
        t = once if once > limit else best(lambda text=text: read(text), repeat)
        growth = (f"{math.log(t / last[1]) / math.log(n / last[0]):5.2f}" if last and t > 0
                  and last[1] > 0 else "    -")
        rows.append(f"  {case.name:<32} {n:>7} {t * 1e3:10.1f} ms {t / (n / per) * 1e3:9.2f} "
                    f"ms/{case.unit:<15} {growth}")
        last = (n, t)
        measured[0].append(n)
        measured[1].append(t)
        if once > limit:
            rows.append(f"  {'':<32} stopped: one read took {once:.1f} s (> --limit)")
            stopped = True
            break
    rows.append(f"  {'':<32} {linear_verdict(*measured, stopped=stopped)}")
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="the two smallest sizes only")
    ap.add_argument("--repeat", type=int, default=3, help="runs per size (best is shown)")
    ap.add_argument("--limit", type=float, default=5.0,
                    help="seconds for one read beyond which a case stops growing")
    ap.add_argument("--case", default="", help="only the cases whose name holds this text")
    a = ap.parse_args(argv)
    print(f"{'case':<34} {'size n':>7} {'time':>13} {'time per unit':>25} growth")
    with tempfile.TemporaryDirectory() as tmp:
        for case in CASES:
            if a.case and a.case not in case.name:
                continue
            for row in run(case, a.repeat, a.limit, a.quick, Path(tmp)):
                print(row, flush=True)
    print("growth: log(t2/t1)/log(n2/n1) from the size before (1 linear, 2 quadratic)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
