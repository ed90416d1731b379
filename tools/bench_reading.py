"""Reading time against input size, for inputs whose reading once grew with the square of
their size: time per MB that stays flat as the size doubles is linear reading.

    python tools/bench_reading.py [--sizes 0.25,0.5,1,2] [--repeat 2] [--limit 30]
                                  [--only NAME] [--no-refusals]

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
from the size before (1 linear, 2 quadratic). Under each case, the verdict: the exponent
of a least-squares fit of log t against log n, PASS when at most 1.3 (tools/timing.py).
A read longer than --limit seconds ends its case (its verdict is the fit over the sizes
read; FAIL if only one was).

Then the refusals (`REFUSALS`): files that would cost minutes, or forever, if read as
they ask, which `mbody.load` refuses (tests/test_loader.py and tests/test_hardening.py
check the refusal's message; this measures its speed). Each is timed to its refusal and
set against a reference timed in the same process: loading models/pendulum.yaml, or for
the reads that must take a set time or size, that time (a named pipe with no writer is
awaited `loader.FIFO_WAIT` seconds) or reading a regular file of that size. PASS when
the ratio is at most the case's bound:

- a sparse 200 MiB file, over the 32 MiB limit: refused from its size, unread;
- /dev/zero (an endless device): refused from its kind, unread;
- an endless pipe (``yes``) with a 1 MiB limit: read up to the limit, not forever;
- a named pipe with no writer: refused after FIFO_WAIT, not blocked forever;
- an alias bomb (9 levels of 9 aliases: 387 million strings if expanded): refused when
  the expansion passes `loader.MAX_ALIAS_NODES`.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import subprocess
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

from timing import best, linear_verdict  # noqa: E402

import mbody  # noqa: E402
from mbody.errors import MbodyError, ModelError  # noqa: E402
from mbody.model import loader  # noqa: E402
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


PENDULUM = ROOT / "models" / "pendulum.yaml"


def refused(path: Path | str, max_bytes: int | None = None) -> None:
    """Load `path`, which must be refused (a `ModelError`); anything else is a bug here."""
    try:
        mbody.load(path, max_bytes=max_bytes)
    except ModelError:
        return
    raise AssertionError(f"{path} was read, not refused")


@dataclass
class Refusal:
    """One hostile file: `run(folder, repeat)` gives (seconds to the refusal, seconds of the
    reference, what the reference is); PASS when their ratio is at most `bound`."""

    name: str
    run: Callable[[Path, int], tuple[float, float, str]]
    bound: float


def _pendulum(repeat: int) -> float:
    return best(lambda: mbody.load(PENDULUM), repeat)


def sparse_file(folder: Path, repeat: int) -> tuple[float, float, str]:
    path = folder / "huge.yaml"
    with open(path, "wb") as f:  # instant to make, minutes to parse if it were read
        f.truncate(200 * MB)
    return best(lambda: refused(path), repeat), _pendulum(repeat), "pendulum.yaml"


def endless_device(folder: Path, repeat: int) -> tuple[float, float, str]:
    return (best(lambda: refused("/dev/zero", max_bytes=MB), repeat), _pendulum(repeat),
            "pendulum.yaml")


def endless_pipe(folder: Path, repeat: int) -> tuple[float, float, str]:
    fifo = folder / "endless.yaml"
    os.mkfifo(fifo)
    times = []
    for _ in range(repeat):  # a writer for each read: the reader closes its end
        writer = subprocess.Popen(f"yes 'a: 1' > {fifo}", shell=True)
        try:
            times.append(best(lambda: refused(fifo, max_bytes=MB), 1, budget=0.0))
        finally:
            writer.kill()
            writer.wait()
    same = folder / "same.yaml"  # as many bytes from a regular file, read whole
    same.write_text("a: 1\n" * (MB // 5))
    return (min(times), best(lambda: loader.read_file(same, max_bytes=MB + 1), repeat),
            "a 1 MiB file")


def silent_pipe(folder: Path, repeat: int) -> tuple[float, float, str]:
    fifo = folder / "silent.yaml"
    os.mkfifo(fifo)
    return best(lambda: refused(fifo), 1, budget=0.0), loader.FIFO_WAIT, "FIFO_WAIT"


def alias_bomb(folder: Path, repeat: int) -> tuple[float, float, str]:
    lines = ['l0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"l{k}: &l{k} [" + ", ".join([f"*l{k - 1}"] * 9) + "]" for k in range(1, 10)]
    path = folder / "bomb.yaml"
    path.write_text("\n".join(lines) + "\n")
    return best(lambda: refused(path), repeat), _pendulum(repeat), "pendulum.yaml"


REFUSALS: list[Refusal] = [
    # refused from os.stat alone: less than reading and building a one-body model
    Refusal("sparse 200 MiB file (limit 32 MiB)", sparse_file, 1.0),
    Refusal("/dev/zero", endless_device, 1.0),
    # 1 MiB through a pipe, then refused: a few times a page-cached read of 1 MiB
    Refusal("endless pipe, max_bytes 1 MiB", endless_pipe, 10.0),
    # FIFO_WAIT, plus the last wait's 20 ms and the start
    Refusal("named pipe with no writer", silent_pipe, 1.5),
    # a hundred events and a count to MAX_ALIAS_NODES: about one small model's reading
    Refusal("alias bomb, 9 levels of 9", alias_bomb, 3.0),
]


def refusals(repeat: int, only: str | None) -> None:
    """The refusals' table (those named like `only`)."""
    cases = [r for r in REFUSALS if only is None or only.lower() in r.name.lower()]
    if not cases:
        return
    print(f"Refusals\n  {'file':<36} {'refused (s)':>11} {'reference (s)':>13} "
          f"{'of':<14} {'ratio':>7} verdict")
    with tempfile.TemporaryDirectory(prefix="mbody-bench-refusals.") as tmp:
        for k, r in enumerate(cases):
            if not hasattr(os, "mkfifo") and "pipe" in r.name:
                print(f"  {r.name:<36} (no named pipes here)")
                continue
            folder = Path(tmp) / str(k)
            folder.mkdir()
            t, ref, of = r.run(folder, repeat)
            ratio = t / ref
            print(f"  {r.name:<36} {t:11.5f} {ref:13.5f} {of:<14} {ratio:7.2f} "
                  f"{'PASS' if ratio <= r.bound else 'FAIL'} (at most {r.bound:g})",
                  flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="0.25,0.5,1,2",
                    help="input sizes in MB, comma-separated (default 0.25,0.5,1,2)")
    ap.add_argument("--repeat", type=int, default=2, help="runs per size; the best counts")
    ap.add_argument("--limit", type=float, default=30.0, metavar="SECONDS",
                    help="a read longer than this ends its case: the larger sizes would "
                    "take minutes if it is not linear (default 30)")
    ap.add_argument("--only", help="run the cases whose name contains this text")
    ap.add_argument("--no-refusals", action="store_true",
                    help="the time-vs-size tables only, not the refusals")
    a = ap.parse_args(argv)
    sizes = [int(float(s) * MB) for s in a.sizes.split(",")]
    cases = [(n, g) for n, g in CASES if a.only is None or a.only.lower() in n.lower()]
    named = [r.name for r in REFUSALS if a.only is None or a.only.lower() in r.name.lower()]
    if not cases and not named:
        ap.error(f"no case named like '{a.only}'; the cases: "
                 + "; ".join([n for n, _ in CASES] + [r.name for r in REFUSALS]))
    with tempfile.TemporaryDirectory(prefix="mbody-bench-reading.") as tmp:
        for name, make in cases:
            print(f"{name}\n  {'size (MB)':>10} {'time (s)':>10} {'s per MB':>10} "
                  f"{'vs smallest':>12} {'growth':>7}")
            first = last = None
            measured: tuple[list[float], list[float]] = ([], [])
            stopped = False
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
                measured[0].append(n / MB)
                measured[1].append(seconds)
                if seconds > a.limit:
                    print(f"  (stopped: {seconds:.0f} s > --limit)")
                    stopped = True
                    break
            print(f"  {linear_verdict(*measured, stopped=stopped)}")
    if cases:
        print("growth: log(t2/t1) / log(n2/n1) from the size before (1 linear, 2 quadratic; "
              "small sizes are noisy)")
    if not a.no_refusals:
        refusals(a.repeat, a.only)
    return 0


if __name__ == "__main__":
    sys.exit(main())
