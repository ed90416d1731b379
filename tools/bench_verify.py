"""Benchmark: what the joints' kinematics cost `mbody.verify` (time against size).

    python tools/bench_verify.py [--quick] [--repeat R]

On a hanging chain of n spherical links (tools/bench_chain.py's, turning as one rigid
body), one student equation of the last link is checked, best of R runs:

- rows: the body's rows alone (`mbody.answers.rows.body_rows` with the kinematics left
  out), what every check needs;
- kinematics: `mbody.answers.kinematics.body_kinematics`, the relations the joints
  impose on the link's accelerations (a dense SVD over the links joined to it, at most
  `MAX_COORDINATES` coordinates);
- verify: the whole `mbody.verify` of a wrong equation of the link (every step of the
  diagnosis runs; the assembly made once, outside).

The ratio is kinematics / rows. Beyond MAX_COORDINATES (50 spatial links) the
neighbourhood stops growing, and so does the cost.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

TOOLS = Path(__file__).resolve().parent
ROOT = TOOLS.parent
for _p in (ROOT, TOOLS):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

import bench_chain  # noqa: E402
import yaml  # noqa: E402
from timing import best  # noqa: E402

import mbody  # noqa: E402
from mbody.answers import kinematics, rows  # noqa: E402


def measure(n: int, repeat: int) -> str:
    """One line of the table: a chain of n links."""
    model = mbody.loads(yaml.safe_dump(bench_chain.chain_spec(n)))
    asm = mbody.assemble(model)
    body = model.body_names[-1]
    br = rows.body_rows(asm, body)
    labels = tuple(r.label for r in br.rows)
    accs = tuple(r.acc for r in br.rows)
    t_kin = best(lambda: kinematics.body_kinematics(asm, body, labels, accs), repeat)
    real = rows.body_kinematics
    rows.body_kinematics = lambda *args: None  # the rows alone
    try:
        t_rows = best(lambda: rows.body_rows(asm, body), repeat)
    finally:
        rows.body_kinematics = real
    eq = [{"body": body, "eq": "m*a_z = 0"}]  # wrong: every step of the diagnosis runs
    t_verify = best(lambda: mbody.verify(model, eq, asm=asm), repeat)
    kin = kinematics.body_kinematics(asm, body, labels, accs)
    count = len(kin.relations) if kin is not None else 0
    return (f"{n:>6} {6 * n:>7} {1e3 * t_rows:>9.2f} {1e3 * t_kin:>14.2f} "
            f"{t_kin / t_rows:>7.2f} {1e3 * t_verify:>10.2f} {count:>10}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small chains only")
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    sizes = [2, 10, 30] if a.quick else [2, 10, 30, 50, 100, 400]
    print(f"{'links':>6} {'coords':>7} {'rows ms':>9} {'kinematics ms':>14} {'ratio':>7} "
          f"{'verify ms':>10} {'relations':>10}")
    for n in sizes:
        print(measure(n, a.repeat), flush=True)


if __name__ == "__main__":
    main()
