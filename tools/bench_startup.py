"""Benchmark: start-up time of the `mbody` command, from a checkout.

    python tools/bench_startup.py [--quick] [--runs N] [--model PATH] [--pyc]

Wall-clock time of fresh subprocesses of this interpreter (sys.executable), best of N runs
(default 7; --quick: 3), for

- `python -c pass` (the interpreter alone),
- `python -c "import numpy"` (the floor for anything using numpy; the ratio column is
  against this row),
- `python -c "import mbody"`,
- `python -m mbody check|assemble|solve MODEL` (default models/pendulum.yaml), i.e. the
  whole command: imports, argument parsing, loading the model, the work and the output.

Every run starts a new process, so each time includes interpreter start-up and every
import (warm file-system cache: the first, cold run is one of the N). Output goes to
/dev/null. The checkout's root is put first on PYTHONPATH, so the `mbody` measured is the
one in this working tree.

The environment is passed on as it is. Where PYTHONDONTWRITEBYTECODE is set, no .pyc
files are written, so every run also compiles mbody's sources (tens of ms); --pyc
measures the usual case instead: bytecode is cached in a temporary PYTHONPYCACHEPREFIX
(outside the checkout) and warmed by one untimed run of each row.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def cases(model: str) -> list[tuple[str, list[str]]]:
    py = sys.executable
    return [
        ("python -c pass", [py, "-c", "pass"]),
        ("import numpy", [py, "-c", "import numpy"]),
        ("import mbody", [py, "-c", "import mbody"]),
        *[(f"mbody {cmd} {model}", [py, "-m", "mbody", cmd, model])
          for cmd in ("check", "assemble", "solve")],
    ]


def best_time(argv: list[str], runs: int, env: dict[str, str]) -> float:
    best = float("inf")
    for _ in range(runs):
        t0 = time.perf_counter()
        done = subprocess.run(argv, cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, check=False)
        dt = time.perf_counter() - t0
        if done.returncode != 0:
            raise SystemExit(f"bench_startup: {' '.join(argv[1:])} exited with "
                             f"{done.returncode}:\n{done.stderr.decode(errors='replace')}")
        best = min(best, dt)
    return best


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="3 runs per row instead of 7")
    p.add_argument("--runs", type=int, help="runs per row (best is reported)")
    p.add_argument("--model", default="models/pendulum.yaml",
                   help="model for the mbody commands (relative to the checkout's root)")
    p.add_argument("--pyc", action="store_true",
                   help="cache bytecode in a temporary folder (as after a usual install) "
                   "even if PYTHONDONTWRITEBYTECODE is set")
    a = p.parse_args(argv)
    runs = a.runs or (3 if a.quick else 7)
    if runs < 1:
        p.error("--runs must be at least 1")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    env.pop("MBODY_DEBUG", None)

    with tempfile.TemporaryDirectory(prefix="mbody-pyc-") as pyc:
        if a.pyc:
            env.pop("PYTHONDONTWRITEBYTECODE", None)
            env["PYTHONPYCACHEPREFIX"] = pyc
            for _, cmd in cases(a.model):
                best_time(cmd, 1, env)
        rows = [(label, best_time(cmd, runs, env)) for label, cmd in cases(a.model)]
    numpy_s = dict(rows)["import numpy"]
    width = max(len(label) for label, _ in rows)
    cached = "no" if env.get("PYTHONDONTWRITEBYTECODE") else (
        "yes, in a temporary folder" if a.pyc else "yes")
    print(f"start-up, best of {runs} fresh processes ({sys.executable}, Python "
          f"{sys.version.split()[0]}; bytecode cached: {cached})")
    print(f"{'what':<{width}}  {'wall ms':>8}  {'x numpy':>7}")
    for label, s in rows:
        print(f"{label:<{width}}  {s * 1e3:8.1f}  {s / numpy_s:7.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
