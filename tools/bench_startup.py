"""Benchmark: start-up time of the `mbody` command, cold and warm, beside `import numpy`.

    python tools/bench_startup.py [--quick] [--runs N] [--model PATH]

Wall-clock time of fresh subprocesses of this interpreter (sys.executable):

- `python -c pass` and `python -c "import numpy"` (the floor for anything using numpy;
  the ratio column is against it), `python -c "import mbody"`;
- `mbody check|assemble|solve MODEL` and `mbody simulate MODEL -o run.npz` (default
  models/pendulum.yaml: 10 s of motion at 60 fps, saved), each the whole command:
  imports, argument parsing, loading the model, the work and the output.

**Cold** is the first run after a fresh install: the package (its sources and its
compiled core, `mbody/kernel/_core*.so`) is copied into a new folder with no bytecode,
and the command runs once from there, compiling and caching mbody's bytecode as the
first run after an install does (nothing else is compiled: the core was built by
`pip install`). Each command gets its own fresh copy. **Warm** is the best of N later
runs of that copy. The interpreter and numpy are the installed ones, their bytecode
cached as usual; the file-system cache is warm (the copy was just written).

Output of the commands goes to /dev/null (the run file to a temporary folder).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def fresh_copy(into: Path) -> Path:
    """mbody copied into `into` without bytecode (the compiled core included)."""
    shutil.copytree(ROOT / "mbody", into / "mbody",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "src"))
    return into


def run_once(argv: list[str], env: dict[str, str]) -> float:
    t0 = time.perf_counter()
    done = subprocess.run(argv, cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, check=False)
    dt = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"bench_startup: {' '.join(argv[1:])} exited with "
                         f"{done.returncode}:\n{done.stderr.decode(errors='replace')}")
    return dt


def env_for(path: Path) -> dict[str, str]:
    """This environment with `path` first on PYTHONPATH and bytecode written (as after a
    usual install, even where PYTHONDONTWRITEBYTECODE is set here)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(path), env.get("PYTHONPATH")]))
    env.pop("MBODY_DEBUG", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env.pop("PYTHONPYCACHEPREFIX", None)
    return env


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="3 warm runs per row instead of 7")
    p.add_argument("--runs", type=int, help="warm runs per row (best is reported)")
    p.add_argument("--model", default="models/pendulum.yaml",
                   help="model for the mbody commands (relative to the checkout's root)")
    p.add_argument("--pyc", action="store_true",
                   help="accepted for older instructions: bytecode is always cached now")
    a = p.parse_args(argv)
    runs = a.runs or (3 if a.quick else 7)
    if runs < 1:
        p.error("--runs must be at least 1")
    py = sys.executable
    rows: list[tuple[str, float | None, float]] = []
    with tempfile.TemporaryDirectory(prefix="mbody-startup-") as tmp:
        base = Path(tmp)
        plain = env_for(fresh_copy(base / "plain"))
        for label, code in (("python -c pass", "pass"), ("import numpy", "import numpy"),
                            ("import mbody", "import mbody")):
            argv_ = [py, "-c", code]
            run_once(argv_, plain)  # bytecode of the copy written once
            rows.append((label, None, min(run_once(argv_, plain) for _ in range(runs))))
        out = base / "run.npz"
        commands = [("check", []), ("assemble", []), ("solve", []),
                    ("simulate", ["-o", str(out)])]
        for cmd, extra in commands:
            env = env_for(fresh_copy(base / cmd))
            argv_ = [py, "-m", "mbody", cmd, a.model, *extra]
            cold = run_once(argv_, env)
            warm = min(run_once(argv_, env) for _ in range(runs))
            label = f"mbody {cmd} {a.model}" + (" -o run.npz" if extra else "")
            rows.append((label, cold, warm))
    numpy_s = dict((label, w) for label, _, w in rows)["import numpy"]
    width = max(len(label) for label, _, _ in rows)
    print(f"start-up, fresh processes ({py}, Python {sys.version.split()[0]}); cold: the "
          f"first run of a fresh copy of the package; warm: best of {runs} later runs")
    print(f"{'what':<{width}}  {'cold ms':>8}  {'warm ms':>8}  {'warm x numpy':>12}")
    for label, cold, warm in rows:
        c = "" if cold is None else f"{cold * 1e3:8.1f}"
        print(f"{label:<{width}}  {c:>8}  {warm * 1e3:8.1f}  {warm / numpy_s:12.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
