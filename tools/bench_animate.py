"""Benchmark: the offline animation page of N free bodies (default 1000 over 2 s).

Times building the page through the API, `page_html(build_scene(traj, model))`, best of
--repeat runs, and compares it in the same process with a baseline: the same scene packed
the way meshcat packs animations, every keyframe number on its own
(`page_html(..., typed_arrays=False)`), instead of as Float32Arrays written by numpy.

    python tools/bench_animate.py [--bodies 1000] [--t-end 2] [--fps 60] [--repeat 5]
                                  [--simulate] [--profile]

The trajectory is made directly (each body drifts at constant velocity and spins at a
constant rate about a fixed axis), or with --simulate by `mbody.simulate` of the same
free bodies. --profile prints cProfile's top 15 functions (by own time) of one build.
"""

from __future__ import annotations

import argparse
import cProfile
import inspect
import pstats
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:  # tools/timing.py, also when loaded by path
    sys.path.insert(0, str(ROOT / "tools"))

from timing import best  # noqa: E402

import mbody  # noqa: E402
from mbody.present.animate import build_scene, page_html  # noqa: E402
from mbody.simulate.trajectory import Trajectory  # noqa: E402

DEFAULT_FPS = inspect.signature(mbody.simulate).parameters["fps"].default
"""`mbody.simulate`'s (and so `mbody animate MODEL`'s) frame rate."""


def free_bodies(n: int, seed: int = 0) -> tuple[mbody.Model, np.ndarray, np.ndarray]:
    """n boxes on a 10 x 10 x n/100 lattice, with random velocities and rates."""
    rng = np.random.default_rng(seed)
    bodies, v, w = [], rng.uniform(-1, 1, (n, 3)), rng.uniform(-1.15, 1.15, (n, 3))
    for i in range(n):
        a, b, c = rng.uniform(0.1, 1.0, 3)
        bodies.append({
            "name": f"b{i}", "mass": 1.0, "shape": {"box": [float(a), float(b), float(c)]},
            "position": [float(3 * (i % 10)), float(3 * (i // 10 % 10)), float(3 * (i // 100))],
            "velocity": v[i].tolist(), "angular_velocity": w[i].tolist()})
    model = mbody.load({"model": f"free-bodies-{n}", "dimension": 3, "bodies": bodies})
    return model, v, w


def drift_and_spin(model: mbody.Model, v: np.ndarray, w: np.ndarray, t_end: float,
                   fps: float) -> Trajectory:
    """r = r0 + v t and q = [cos(|w| t/2), sin(|w| t/2) w/|w|]: a cheap stand-in motion."""
    t = np.arange(int(round(t_end * fps)) + 1) / fps
    r0 = np.asarray(model.initial.position, dtype=float)
    pos = r0[None] + t[:, None, None] * v[None]
    rate = np.linalg.norm(w, axis=1)
    half = t[:, None] * rate[None] / 2
    q = np.concatenate([np.cos(half)[..., None],
                        np.sin(half)[..., None] * (w / rate[:, None])[None]], axis=-1)
    vel = np.broadcast_to(v, pos.shape).copy()
    return Trajectory(t, pos, vel, q, np.broadcast_to(w, pos.shape).copy(),
                      tuple(model.body_names), 3, model_name=model.name)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--bodies", type=int, default=1000)
    p.add_argument("--t-end", type=float, default=2.0)
    p.add_argument("--fps", type=float, default=DEFAULT_FPS)
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--simulate", action="store_true",
                   help="make the trajectory with mbody.simulate instead of in closed form")
    p.add_argument("--profile", action="store_true", help="cProfile one build: top 15")
    a = p.parse_args()

    model, v, w = free_bodies(a.bodies)
    traj = (mbody.simulate(model, t_end=a.t_end, fps=a.fps) if a.simulate
            else drift_and_spin(model, v, w, a.t_end, a.fps))
    scene = build_scene(traj, model)
    has_baseline = "typed_arrays" in inspect.signature(page_html).parameters  # old checkouts
    t_scene = best(lambda: build_scene(traj, model), a.repeat)
    t_page = best(lambda: page_html(scene), a.repeat)
    t_total = best(lambda: page_html(build_scene(traj, model)), a.repeat)
    size = len(page_html(scene).encode())

    print(f"animate {a.bodies} free bodies over {a.t_end:g} s at {a.fps:g} fps "
          f"({len(traj.t)} frames, {'simulated' if a.simulate else 'closed form'}): "
          f"page_html(build_scene(traj, model)), best of {a.repeat}")
    print(f"  build_scene            {t_scene:7.3f} s")
    print(f"  page_html              {t_page:7.3f} s   {size / 1e6:5.1f} MB")
    print(f"  total                  {t_total:7.3f} s")
    if has_baseline:
        t_old = best(lambda: page_html(scene, typed_arrays=False), a.repeat)
        old_size = len(page_html(scene, typed_arrays=False).encode())
        print("baseline, keyframes packed one float at a time as meshcat does:")
        print(f"  page_html              {t_old:7.3f} s   {old_size / 1e6:5.1f} MB")
        print(f"  total                  {t_scene + t_old:7.3f} s (build_scene + page_html)")
        print(f"ratio baseline / typed arrays: page_html {t_old / t_page:.1f}x, total "
              f"{(t_scene + t_old) / t_total:.1f}x, size {old_size / size:.1f}x")
    if a.profile:
        prof = cProfile.Profile()
        prof.runcall(lambda: page_html(build_scene(traj, model)))
        pstats.Stats(prof, stream=sys.stdout).strip_dirs().sort_stats("tottime").print_stats(15)


if __name__ == "__main__":
    main()
