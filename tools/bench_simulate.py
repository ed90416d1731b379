"""Benchmark: simulate N free, torque-free rigid bodies for T seconds (default 1000, 10 s).

Reports the integrator's steps and derivative evaluations, the cost per body-step, and
how much of the cost is fixed Python overhead when the accelerations are given as a
Python `dynamics` (called from the core's DOP853 at every evaluation): the cost of one
evaluation is modelled as c(n) = a + b n, with a (overhead, independent of n) measured on
1 body and b (the work per body) from the difference with N bodies. The same runs on the
compiled core alone (the default, no `dynamics`) are timed beside.

    python tools/bench_simulate.py [--bodies 1000] [--t-end 10] [--fps 60]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import mbody
from mbody.simulate import known_reaction_dynamics


def free_bodies(n: int, seed: int = 0) -> mbody.Model:
    """n torque-free bodies with random realisable principal inertias and rates < 2 rad/s."""
    rng = np.random.default_rng(seed)
    bodies = []
    for i in range(n):
        a, b, c = rng.uniform(0.1, 1.0, 3)  # box edges: inertia is always realisable
        bodies.append({
            "name": f"b{i}", "mass": 1.0, "shape": {"box": [float(a), float(b), float(c)]},
            "position": [float(3 * (i % 10)), float(3 * (i // 10 % 10)), float(3 * (i // 100))],
            "velocity": rng.uniform(-1, 1, 3).tolist(),
            "angular_velocity": rng.uniform(-1.15, 1.15, 3).tolist(),
        })
    return mbody.load({"model": f"free-bodies-{n}", "dimension": 3, "bodies": bodies})


def run(model: mbody.Model, t_end: float, fps: float) -> dict:
    inner = known_reaction_dynamics(model)
    spent = [0.0]

    def timed(model, state):  # the same derivative, timed
        t0 = time.perf_counter()
        out = inner(model, state)
        spent[0] += time.perf_counter() - t0
        return out

    t0 = time.perf_counter()
    traj = mbody.simulate(model, t_end, fps, dynamics=timed)
    wall = time.perf_counter() - t0
    i = traj.info
    core = mbody.simulate(model, t_end, fps).info  # the default: the compiled core alone
    # "wall": the integration loop only; "post": drift figures and Trajectory, once per run.
    return {"n": model.n, "wall": i["wall_time_s"], "post": wall - i["wall_time_s"],
            "steps": i["steps"], "evals": i["evaluations"],
            "accel": spent[0], "samples": i["samples"], "core": core["wall_time_s"],
            "core_evals": core["evaluations"],
            "drift": (max(np.abs(traj.kinetic_energy() / traj.kinetic_energy()[0] - 1)))}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--bodies", type=int, default=1000)
    p.add_argument("--t-end", type=float, default=10.0)
    p.add_argument("--fps", type=float, default=60.0)
    a = p.parse_args()

    big = run(free_bodies(a.bodies), a.t_end, a.fps)
    one = run(free_bodies(1, seed=1), a.t_end, a.fps)
    print(f"simulate {a.bodies} free bodies for {a.t_end:g} s (DOP853, rtol 1e-10, "
          f"atol 1e-12, {a.fps:g} fps output); times are for the integration loop; "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")
    print(f"{'bodies':>7} {'wall s':>8} {'steps':>6} {'evals':>6} {'us/eval':>8} "
          f"{'accel us/eval':>13} {'us/body-step':>12} {'max |dT/T|':>10}")
    for r in (one, big):
        print(f"{r['n']:>7} {r['wall']:>8.3f} {r['steps']:>6} {r['evals']:>6} "
              f"{1e6 * r['wall'] / r['evals']:>8.1f} {1e6 * r['accel'] / r['evals']:>13.1f} "
              f"{1e6 * r['wall'] / (r['steps'] * r['n']):>12.3f} {r['drift']:>10.1e}")
    for r in (one, big):
        print(f"{r['n']:>7} bodies on the compiled core (no dynamics given: no Python per "
              f"evaluation): {r['core']:.3f} s, {r['core_evals']} evaluations, "
              f"{1e6 * r['core'] / r['core_evals']:.2f} us/eval")
    print(f"after the loop, drift figures and the Trajectory took {big['post']:.3f} s "
          f"({big['samples']} samples x {big['n']} bodies)")
    a_ = one["wall"] / one["evals"]  # per evaluation, almost all fixed overhead
    c = big["wall"] / big["evals"]
    b = (c - a_) / (big["n"] - 1)
    print(f"per evaluation: fixed overhead a = {1e6 * a_:.1f} us (measured on 1 body), "
          f"per body b = {1e6 * b:.3f} us")
    print(f"at {big['n']} bodies the fixed (Python) overhead is {100 * a_ / c:.1f}% of the "
          f"cost; the work per body is {100 * (1 - a_ / c):.1f}%")
    print(f"a body-step costs {1e6 * big['wall'] / (big['steps'] * big['n']):.3f} us at "
          f"{big['n']} bodies vs {1e6 * one['wall'] / one['steps']:.1f} us for a lone body "
          f"({one['wall'] / one['steps'] / (big['wall'] / (big['steps'] * big['n'])):.0f}x)")


if __name__ == "__main__":
    main()
