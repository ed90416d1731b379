"""Reading time against input size, for inputs whose reading once grew with the square of
their size: time per MB that stays flat as the size doubles is linear reading.

    python tools/bench_reading.py [--sizes 0.25,0.5,1,2] [--repeat 2] [--limit 30]
                                  [--only NAME]

Each case is one entry of `CASES`: a name and a generator that makes an input of about
the size asked (in bytes) and says how it is read (`Input`). To add a case (another
format, another reader), append an entry: the table shows it too.

The cases (issue 22):

- MJCF, one long line: a small arm, then sites on the same line as everything else
  (2.6 MB on one line took 29 s: each attribute's column was counted from the start of
  its line);
- MJCF, one element with many attributes (200 000 attributes took over 95 s);
- MJCF, '>' inside an attribute value (legal XML; 80 kB took 42 s: an element's
  attributes were searched for up to its first '>', inside the value, by a pattern that
  tried every start in it);
- MJCF, many bodies: free bodies, one a line (what a large scene is), read whole
  into a model (the import's own work: forward kinematics, masses, the document);
- MJCF, many screws: bodies each on a slide and a hinge tied by a joint equality, read
  as helical joints (each equality's joints are found by name: once per file, not once
  per equality, which would be quadratic);
- URDF, one long line: the same for a robot file (materials after a small arm);
- URDF, one element with many attributes: a URDF reader notes names outside the
  specification (tools' extensions) and reads on.

Every input is read whole, as ``mbody check`` reads it (`mbody.load`: read, check,
build), in this process; an input mbody refuses (the many attributes are unknown ones)
is timed up to its error. Columns: the input's size, the best time of --repeat runs
(tools/timing.py), the time per MB, that figure over the smallest size's (a constant
ratio is linear; a quadratic one doubles with each doubling), and the growth exponent
from the size before (1 linear, 2 quadratic). A read longer than --limit seconds ends
its case.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:  # tools/timing.py, also when loaded by path
    sys.path.insert(0, str(ROOT / "tools"))

from timing import best  # noqa: E402

import mbody  # noqa: E402
from mbody.errors import MbodyError  # noqa: E402
from mbody.util.budget import byte_budget  # noqa: E402

MB = 2**20


def read_model(path: Path) -> None:
    """Read a model file as every command reads it; a refusal is an answer too."""
    with contextlib.suppress(MbodyError):
        mbody.load(path)


@dataclass
class Input:
    """One generated input: its text, the file suffix it is read with, and the reader."""

    text: str
    suffix: str
    read: Callable[[Path], object] = read_model


ARM = ('<body name="a" pos="0 0 1"><joint name="j" axis="0 1 0"/>'
       '<geom type="capsule" size="0.05" fromto="0 0 0 0.5 0 0"/></body>')
URDF_ARM = ('<link name="base"/><joint name="j" type="revolute"><parent link="base"/>'
            '<child link="arm"/><axis xyz="0 1 0"/></joint><link name="arm"><inertial>'
            '<mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'
            "</inertial></link>")


def _repeat(unit: str, size: int) -> str:
    return unit * max(1, size // len(unit))


def mjcf_one_line(size: int) -> Input:
    sites = _repeat('<site pos="0.1 0.2 0.3" size="0.01"/>', size)
    return Input(f'<mujoco model="line"><worldbody>{ARM}{sites}</worldbody></mujoco>',
                 ".xml")


def mjcf_many_attributes(size: int) -> Input:
    n = max(1, size // len(' a100000="1"'))
    attrs = "".join(f' a{k}="1"' for k in range(n))
    return Input(f'<mujoco model="attrs"{attrs}><worldbody>{ARM}</worldbody></mujoco>',
                 ".xml")


def mjcf_angle_brackets(size: int) -> Input:
    note = "x" * max(1, size - 200) + " -> y"  # one long value, a '>' near its end
    return Input(f'<mujoco model="gt"><worldbody>{ARM}</worldbody><custom>'
                 f'<text name="note" data="{note}"/></custom></mujoco>', ".xml")


def mjcf_many_bodies(size: int) -> Input:
    body = ('<body name="b{k}" pos="{k} 0 1"><freejoint/>'
            '<geom type="box" size="0.1 0.2 0.3" euler="10 20 30"/></body>\n')
    n = max(1, size // len(body.format(k=1000)))
    bodies = "".join(body.format(k=k) for k in range(n))
    return Input(f'<mujoco model="many"><worldbody>\n{bodies}</worldbody></mujoco>', ".xml")


def mjcf_many_screws(size: int) -> Input:
    body = ('<body name="n{k}" pos="{k} 0 1"><joint name="s{k}" type="slide"/>'
            '<joint name="t{k}" type="hinge"/><geom type="cylinder" size="0.1 0.05"/></body>\n')
    tie = '<joint joint1="t{k}" joint2="s{k}" polycoef="0 1000 0 0 0"/>\n'
    n = max(1, size // len(body.format(k=1000) + tie.format(k=1000)))
    bodies = "".join(body.format(k=k) for k in range(n))
    ties = "".join(tie.format(k=k) for k in range(n))
    return Input(f'<mujoco model="screws"><worldbody>\n{bodies}</worldbody>'
                 f"<equality>\n{ties}</equality></mujoco>", ".xml")


def urdf_many_attributes(size: int) -> Input:
    n = max(1, size // len(' a100000="1"'))
    attrs = "".join(f' a{k}="1"' for k in range(n))
    return Input(f'<robot name="attrs">{URDF_ARM}<material name="m"{attrs}/></robot>',
                 ".urdf")


def urdf_one_line(size: int) -> Input:
    materials = _repeat('<material name="m"><color rgba="0.1 0.2 0.3 1"/></material>', size)
    return Input(f'<robot name="line">{URDF_ARM}{materials}</robot>', ".urdf")


CASES: list[tuple[str, Callable[[int], Input]]] = [
    ("MJCF, one long line", mjcf_one_line),
    ("MJCF, one element with many attributes", mjcf_many_attributes),
    ("MJCF, '>' inside an attribute value", mjcf_angle_brackets),
    ("MJCF, many bodies", mjcf_many_bodies),
    ("MJCF, many screws", mjcf_many_screws),
    ("URDF, one long line", urdf_one_line),
    ("URDF, one element with many attributes", urdf_many_attributes),
]
"""(name, generator): the generator makes an input of about the size given in bytes."""


def measure(make: Callable[[int], Input], size: int, repeat: int, folder: Path
            ) -> tuple[int, float]:
    """(bytes, best seconds) of reading the input `make` gives for `size`."""
    item = make(size)
    path = folder / f"input{item.suffix}"
    data = item.text.encode("utf-8")
    path.write_bytes(data)
    with byte_budget(max(len(data) + 1, 32 * MB)):
        seconds = best(lambda: item.read(path), repeat, budget=0.0)
    return len(data), seconds


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="0.25,0.5,1,2",
                    help="input sizes in MB, comma-separated (default 0.25,0.5,1,2)")
    ap.add_argument("--repeat", type=int, default=2, help="runs per size; the best counts")
    ap.add_argument("--limit", type=float, default=30.0, metavar="SECONDS",
                    help="a read longer than this ends its case: the larger sizes would "
                    "take minutes if it is not linear (default 30)")
    ap.add_argument("--only", help="run the cases whose name contains this text")
    a = ap.parse_args(argv)
    sizes = [int(float(s) * MB) for s in a.sizes.split(",")]
    cases = [(n, g) for n, g in CASES if a.only is None or a.only.lower() in n.lower()]
    if not cases:
        ap.error(f"no case named like '{a.only}'; the cases: "
                 + "; ".join(n for n, _ in CASES))
    with tempfile.TemporaryDirectory(prefix="mbody-bench-reading.") as tmp:
        for name, make in cases:
            print(f"{name}\n  {'size (MB)':>10} {'time (s)':>10} {'s per MB':>10} "
                  f"{'vs smallest':>12} {'growth':>7}")
            first = last = None
            for size in sizes:
                n, seconds = measure(make, size, a.repeat, Path(tmp))
                per = seconds / (n / MB)
                first = per if first is None else first
                growth = (f"{math.log(seconds / last[1]) / math.log(n / last[0]):7.2f}"
                          if last and seconds > 0 and last[1] > 0 and n != last[0]
                          else "      -")
                print(f"  {n / MB:10.2f} {seconds:10.3f} {per:10.3f} {per / first:12.2f} "
                      f"{growth}", flush=True)
                last = (n, seconds)
                if seconds > a.limit:
                    print(f"  (stopped: {seconds:.0f} s > --limit)")
                    break
    print("growth: log(t2/t1) / log(n2/n1) from the size before (1 linear, 2 quadratic; "
          "small sizes are noisy)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
