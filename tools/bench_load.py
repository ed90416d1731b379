"""Time per body of reading and checking a large model file, against json and MuJoCo.

    python tools/bench_load.py [--quick] [--repeat N] [--sizes 10000,100000]

Files (written by ``yaml.dump`` with ``CSafeDumper``, ``default_flow_style=None``,
``width=200``, as tools/bench_assembly.py writes its model file):

- free: n free spatial bodies, each with a random mass, a full (non-diagonal) inertia
  tensor, a rotated pose, a velocity and an angular velocity, and one world-frame force
  at an offset point (tools/bench_assembly.py's model: 800 bytes a body);
- chain: n spatial bodies in a chain of revolute joints (the first to ground), principal
  inertias, a torque on every body (about 490 bytes a body).

Both take the fast path (mbody/model/fast.py) whole: bodies, loads and joints.

Columns, best of --repeat runs, in one process:

- ``mbody.load``: read, check and build the `Model` (µs per body);
- located: the same through the located path alone (``validate(load_text(...))``, what
  every file went through before the fast path), on files up to --located-limit bodies;
- ``json.loads`` of the same document as JSON text (a floor for any reader that builds
  Python values), and the ratio mbody/json;
- peak: the most memory ``mbody.load`` adds, over the file size, measured in a child
  process: tracemalloc's peak; and rss, the growth of the peak resident set (VmHWM) over
  a child that does everything but the load (it includes pages freed but kept);
- MuJoCo: ``mujoco.MjModel.from_xml_string`` of the same free bodies (MJCF, free
  joints, full inertia). Its compiler takes time that grows faster than n, so it is
  timed on at most --mujoco-limit bodies (marked †).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:  # tools/timing.py, also when loaded by path
    sys.path.insert(0, str(ROOT / "tools"))

from bench_assembly import draw, free_bodies_spec  # noqa: E402
from timing import best  # noqa: E402

import mbody  # noqa: E402
from mbody.model.loader import load_text  # noqa: E402
from mbody.model.validate import validate  # noqa: E402

_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def chain_spec(n: int, seed: int = 0) -> dict:
    """n spatial bodies in a chain of revolute joints along x, a torque on each."""
    d = draw(n, seed)
    f = lambda a: [float(x) for x in np.ravel(a)]  # noqa: E731
    bodies = [{"name": f"b{i}", "mass": float(d["mass"][i]),
               "inertia": f(np.sort(np.diag(d["inertia"][i]))[::-1] * [1, 1, 1]),
               "position": [float(i) + 0.5, 0.0, 0.0], "velocity": [0.0, 0.0, 0.0],
               "angular_velocity": f(d["omega"][i] * 0.1)} for i in range(n)]
    joints = [{"name": f"j{i}", "type": "revolute", "parent": "ground" if i == 0
               else f"b{i - 1}", "child": f"b{i}", "at": [float(i), 0.0, 0.0],
               "axis": [0.0, 0.0, 1.0]} for i in range(n)]
    loads = [{"name": f"t{i}", "type": "torque", "body": f"b{i}",
              "torque": f(d["force"][i] * 0.1)} for i in range(n)]
    return {"model": f"chain-{n}", "dimension": 3, "gravity": [0.0, 0.0, -9.81],
            "bodies": bodies, "loads": loads, "joints": joints}


def write(spec: dict, path: Path) -> int:
    """Write `spec` as the benchmark's YAML; its size in bytes."""
    path.write_text(yaml.dump(spec, Dumper=_DUMPER, sort_keys=False,
                              default_flow_style=None, width=200))
    return path.stat().st_size


_CHILD = """
import resource, sys, tracemalloc
sys.path.insert(0, {root!r})
import mbody
path, size, how = sys.argv[1], int(sys.argv[2]), sys.argv[3]
mbody.loads("dimension: 3\\nbodies: [{{name: a, mass: 1, inertia: [1, 1, 1]}}]")  # imports
if how == "tracemalloc":
    tracemalloc.start()
    model = mbody.load(path, max_bytes=size + 1)
    print(tracemalloc.get_traced_memory()[1])
else:
    if how == "rss":
        model = mbody.load(path, max_bytes=size + 1)
    try:  # ru_maxrss survives exec on Linux: a child of a large parent starts that large
        with open("/proc/self/status") as f:
            print(next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmHWM")))
    except OSError:
        print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
"""


def peak(path: Path, size: int, how: str) -> float:
    """Peak memory a fresh process adds while loading `path`, over the file size:
    tracemalloc's peak, or ("rss") the growth of the peak resident set over a process
    that does all the same but the load."""

    def child(how: str) -> int:
        out = subprocess.run([sys.executable, "-c", _CHILD.format(root=str(ROOT)),
                              str(path), str(size), how], capture_output=True, text=True,
                             check=True)
        return int(out.stdout.split()[-1])

    if how == "tracemalloc":
        return child(how) / size
    return (child("rss") - child("base")) / size


def mjcf(spec: dict) -> str:
    """The free bodies of a `free_bodies_spec` as MJCF (free joints, full inertia)."""
    parts = ['<mujoco><option gravity="0 0 -9.81"/><worldbody>']
    for b in spec["bodies"]:
        J = b["inertia"]
        parts.append(f'<body name="{b["name"]}" pos="{" ".join(map(repr, b["position"]))}">'
                     f'<freejoint/><inertial pos="0 0 0" mass="{b["mass"]!r}" fullinertia="'
                     f'{J[0][0]!r} {J[1][1]!r} {J[2][2]!r} {J[0][1]!r} {J[0][2]!r} '
                     f'{J[1][2]!r}"/></body>')
    parts.append("</worldbody></mujoco>")
    return "".join(parts)


def row(kind: str, n: int, spec: dict, path: Path, repeat: int, located_limit: int) -> None:
    size = write(spec, path)
    text = json.dumps(spec)
    reps = repeat if n <= 20_000 else max(1, repeat // 3)
    t_load = best(lambda: mbody.load(path, max_bytes=size + 1), reps, 0.0)
    t_json = best(lambda: json.loads(text), reps, 0.0)
    located = "-"
    if n <= located_limit:
        yaml_text = path.read_text()
        t_loc = best(lambda: validate(load_text(yaml_text, str(path))), 1, 0.0)
        located = f"{t_loc * 1e6 / n:.0f}"
    mem = peak(path, size, "tracemalloc")
    rss = peak(path, size, "rss")
    print(f"{kind:6} {n:>7} {size / 1e6:7.1f} {t_load * 1e6 / n:8.1f} {located:>8} "
          f"{t_json * 1e6 / n:8.1f} {t_load / t_json:6.2f} {mem:7.2f} {rss:7.2f}", flush=True)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="small sizes only (CI smoke run)")
    p.add_argument("--repeat", type=int, default=3, help="timed runs per entry (best kept)")
    p.add_argument("--sizes", help="comma-separated body counts (overrides --quick)")
    p.add_argument("--located-limit", type=int, default=10_000, metavar="N",
                   help="largest file also timed through the located path alone")
    p.add_argument("--mujoco-limit", type=int, default=2000, metavar="N",
                   help="largest MuJoCo model compiled (its compile time grows faster "
                        "than N)")
    a = p.parse_args(argv)
    if a.sizes:
        sizes = [int(s) for s in a.sizes.split(",")]
    else:
        sizes = [500, 2000] if a.quick else [10_000, 100_000]
    repeat = max(1, a.repeat)
    print("µs per body (best of runs); peak = memory added by mbody.load / file size")
    print(f"{'file':6} {'bodies':>7} {'MB':>7} {'mbody':>8} {'located':>8} {'json':>8} "
          f"{'ratio':>6} {'peak':>7} {'rss':>7}")
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            row("free", n, free_bodies_spec(n), Path(tmp) / f"free_{n}.yaml", repeat,
                a.located_limit)
        for n in sizes:
            row("chain", n, chain_spec(n), Path(tmp) / f"chain_{n}.yaml", repeat,
                a.located_limit)
    try:
        import mujoco
    except ImportError:
        print("(MuJoCo skipped: mujoco is not importable)")
        return 0
    k = min(max(sizes), 200 if a.quick else a.mujoco_limit)
    xml = mjcf(free_bodies_spec(k))
    t0 = time.perf_counter()
    mujoco.MjModel.from_xml_string(xml)
    t_mj = time.perf_counter() - t0
    print(f"MuJoCo MjModel.from_xml_string, {k} free bodies†: {t_mj * 1e6 / k:.0f} µs per "
          f"body ({t_mj:.2f} s)")
    print(f"† at most {k} bodies: the compile time per body grows with n "
          "(see docs/performance.md)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
