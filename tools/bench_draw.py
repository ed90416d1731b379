"""Benchmark: `mbody fbd` (every body, SVG) and `mbody report` on 100-body models.

    python tools/bench_draw.py [--bodies N] [--repeat R]

Two models of N bodies (default 100): a planar chain of links on revolute pins with
forces and couples on them, and a spatial chain of boxes and cylinders on spherical pins
with side loads. Each command runs through `mbody.cli.main` in this process (the model
written to a temporary YAML file, as a user would have it), best of R runs.

The baseline, timed in the same process, is what matplotlib alone costs for the same
amount of picture: N bare figures, each with as many text objects as an average
free-body diagram of that model has labels and lines of text, saved as SVG. A ratio
below 1 means mbody draws a whole diagram faster than matplotlib writes its text alone.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import sys
import tempfile
import time
from pathlib import Path

import yaml
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from mbody.cli import main as cli

TEXTS_PER_BODY = 30
"""Texts in an average diagram: title, ~12 labels, ~12 equation lines, legend, triad."""


def planar_chain(n: int, L: float = 0.5) -> dict:
    """A hanging planar chain of n rods on revolute pins; pushes and motor torques."""
    bodies, joints, loads = [], [], []
    px, py = 0.0, 0.0
    for i in range(n):
        th = math.radians(20 + 7 * (i % 10))
        dx, dy = L * math.sin(th), -L * math.cos(th)
        bodies.append({"name": f"link{i}", "mass": 1.0 + 0.01 * i, "inertia": L**2 / 12,
                       "shape": {"box": [0.03, L]}, "position": [px + dx / 2, py + dy / 2],
                       "angle": th})
        joints.append({"name": f"J{i}", "type": "revolute", "at": [px, py],
                       "parent": "ground" if i == 0 else f"link{i - 1}", "child": f"link{i}"})
        if i % 2 == 0:
            loads.append({"name": f"push{i}", "type": "force", "body": f"link{i}",
                          "force": [10.0 + i, 0.0], "at": [0.0, 0.1], "frame": "world"})
        if i % 3 == 0:
            loads.append({"name": f"motor{i}", "type": "torque", "body": f"link{i}",
                          "torque": 2.0})
        px, py = px + dx, py + dy
    return {"model": f"planar-chain-{n}", "dimension": 2, "gravity": [0, -9.81],
            "bodies": bodies, "joints": joints, "loads": loads}


def spatial_chain(n: int, L: float = 0.3) -> dict:
    """A spatial chain of boxes and cylinders on spherical pins, turning; side loads."""
    bodies, joints, loads = [], [], []
    for i in range(n):
        shape = ({"cylinder": {"radius": 0.03, "length": L}} if i % 2
                 else {"box": [0.05, 0.05, L]})
        bodies.append({"name": f"seg{i}", "mass": 1.0, "inertia": [2e-3, 2e-3, 4e-4],
                       "shape": shape, "position": [0.0, 0.0, -L * (i + 0.5)]})
        joints.append({"name": f"S{i}", "type": "spherical", "at": [0.0, 0.0, -L * i],
                       "parent": "ground" if i == 0 else f"seg{i - 1}", "child": f"seg{i}"})
        if i % 2 == 0:
            loads.append({"name": f"side{i}", "type": "force", "body": f"seg{i}",
                          "force": [0, 5.0 + i, 0], "at": [0.05, 0, 0.1], "frame": "world"})
    return {"model": f"spatial-chain-{n}", "dimension": 3, "gravity": [0, 0, -9.81],
            "bodies": bodies, "joints": joints, "loads": loads}


def best_of(fn, repeat: int) -> float:
    out = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out = min(out, time.perf_counter() - t0)
    return out


def run_cli(args: list[str]) -> None:
    with contextlib.redirect_stdout(io.StringIO()):
        code = cli(args)
    if code:
        raise SystemExit(f"mbody {' '.join(args)} exited with {code}")


def bare_matplotlib(n_figures: int, texts: int, out: Path) -> None:
    """The baseline: figures holding only `texts` short texts each, saved as SVG."""
    for k in range(n_figures):
        fig = Figure(figsize=(8, 10), dpi=100)
        FigureCanvasAgg(fig)
        for j in range(texts):
            fig.text(0.05 + 0.3 * (j % 3), 0.03 * (j // 3 + 1), f"A{k}.Fx = {j * 1.5:.4g} N",
                     fontsize=9)
        fig.savefig(out / f"bare{k}.svg", format="svg", metadata={"Date": None})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bodies", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    n = a.bodies
    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp)
        base = best_of(lambda: bare_matplotlib(n, TEXTS_PER_BODY, tmp_path), a.repeat)
        print(f"{n} bodies, best of {a.repeat}; baseline: {n} bare matplotlib figures with "
              f"{TEXTS_PER_BODY} texts each, saved as SVG: {base:.2f} s")
        print(f"{'model':<20} {'command':<8} {'seconds':>8} {'per body':>9} {'/ baseline':>10}")
        for spec in (planar_chain(n), spatial_chain(n)):
            path = tmp_path / f"{spec['model']}.yaml"
            path.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
            out = tmp_path / spec["model"]
            for name, args in (("fbd", ["fbd", str(path), "-o", str(out)]),
                               ("report", ["report", str(path), "-o",
                                           str(tmp_path / "report.html")])):
                t = best_of(lambda args=args: run_cli(args), a.repeat)
                print(f"{spec['model']:<20} {name:<8} {t:8.2f} {1e3 * t / n:7.1f}ms "
                      f"{t / base:10.2f}", flush=True)
    sys.stdout.flush()


if __name__ == "__main__":
    main()
