"""Benchmark: time against size of a long spatial chain whose joint points are given on
each body, from the file to the reactions.

    python tools/bench_assembly_size.py [--sizes 20,50,100] [--repeat R] [--limit S]

The chain hangs straight down from a ground pin: n links of length L, each turned to a
random orientation of its own (so each joint's two points, given in the bodies' axes from
their mass centres, are distinct and off the origin), random masses and principal
inertias, joints alternating revolute (random axes) and spherical (`--kinds mixed`) or
all revolute about one axis (`--kinds revolute`), the file's velocities random (the
assembly keeps what the joints allow). Per size, best of --repeat (`tools/timing.py`):

- load: ``mbody.load(spec)``: reading the model and assembling it onto its joints (the
  core's projection, `Unknowns.project`; each joint's points must meet);
- solve: ``mbody.assemble(model).solve()``: the equations and every reaction;
- ratio: the projection's geometric ratio at the assembled pose (the smallest share of
  its diagonal a Cholesky pivot of the joints' scaled Gᵀ G keeps, in the core's order of
  the unknowns); below 1e-2 the projection takes the dense null-space route, cubic in n;
- route: the solve's route (`Solution.method`).

A straight chain is the case where a long chain looked singular: before the unknowns were
ordered from the ground (`mbody.equations.pack.band_order`), the ground joint could come
last in the order (where reverse Cuthill-McKee put it), its pivot ratio then fell as 1/n
(1/n³ with parallel revolute axes), and the load took the dense route (see
docs/performance.md, "Long chains"). The verdict line fits t ~ n^p over the sizes run
(`timing.linear_verdict`); a size that takes longer than --limit ends its kind.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:  # tools/timing.py, also when loaded by path
    sys.path.insert(0, str(ROOT / "tools"))

from timing import best, linear_verdict  # noqa: E402

import mbody  # noqa: E402

L = 0.3
"""Link length (m): each link's joint points are L/2 above and below its mass centre."""
G0 = 9.81
SIZES = "20,50,100,110,120,140,200,500,1000"
KINDS = ("mixed", "revolute")
ROBUST_BELOW = 1e-2
"""The geometric ratio under which `mbody.load`'s projection (`mbody.kinematics`) takes
the null-space route."""


def chain_parts(n: int, kind: str = "mixed", seed: int = 0) -> dict[str, np.ndarray]:
    """The chain's numbers (module docstring), SI: mass (n,), principal inertia (n, 3),
    W_R_B (n, 3, 3) each link's body axes, revolute (n,) which joints are revolute, axis
    (n, 3) their world axes at the file's pose (0 for a spherical joint), velocity and
    omega (n, 3) the file's (world; body axes), random, not what the joints allow."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    mass = rng.uniform(0.5, 2.0, n)
    principal = np.sort(rng.uniform(0.03, 0.05, (n, 3)), axis=1)  # each a realisable body
    R = Rotation.random(n, random_state=rng).as_matrix()
    if kind == "mixed":
        revolute = np.arange(n) % 2 == 0
        axis = rng.normal(size=(n, 3))
        axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    elif kind == "revolute":
        revolute = np.ones(n, bool)
        axis = np.tile([1.0, 0.0, 0.0], (n, 1))
    else:
        raise ValueError(f"unknown kind {kind!r}: one of {', '.join(KINDS)}")
    axis[~revolute] = 0.0
    return {"mass": mass, "principal": principal, "W_R_B": R, "revolute": revolute,
            "axis": axis, "velocity": rng.normal(scale=0.5, size=(n, 3)),
            "omega": rng.normal(scale=0.5, size=(n, 3))}


def chain_spec(n: int, kind: str = "mixed", seed: int = 0) -> dict:
    """The model dict of `chain_parts`: link i's mass centre at (0, 0, -(i + 1/2) L),
    its joint to the link above (the ground for link 0, at the origin) at its top end."""
    p = chain_parts(n, kind, seed)
    up = np.array([0.0, 0.0, L / 2])
    bodies, joints = [], []
    for i in range(n):
        R = p["W_R_B"][i]
        q = _quaternion(R)
        bodies.append({"name": f"l{i}", "mass": float(p["mass"][i]),
                       "inertia": p["principal"][i].tolist(),
                       "position": [0.0, 0.0, -L * (i + 0.5)],
                       "orientation": {"quaternion": q.tolist()},
                       "velocity": p["velocity"][i].tolist(),
                       "angular_velocity": p["omega"][i].tolist()})
        above = [0.0, 0.0, 0.0] if i == 0 else (p["W_R_B"][i - 1].T @ -up).tolist()
        joint = {"name": f"j{i}", "type": "revolute" if p["revolute"][i] else "spherical",
                 "parent": "ground" if i == 0 else f"l{i - 1}", "child": f"l{i}",
                 "at": [above, (R.T @ up).tolist()]}
        if p["revolute"][i]:
            joint["axis"] = p["axis"][i].tolist()
        joints.append(joint)
    return {"model": f"straight-chain-{kind}-{n}", "dimension": 3, "gravity": [0, 0, -G0],
            "bodies": bodies, "joints": joints}


def _quaternion(R: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_quat(scalar_first=True)


def geometric_ratio(model: mbody.Model) -> float:
    """The projection's geometric ratio at `model`'s initial state (module docstring)."""
    from mbody.equations.workspace import workspace
    from mbody.kernel import _core

    ws = workspace(model)
    solver = ws.solver(ws.unknowns({}))
    y = ws.state_vector(model.initial)
    info = np.empty(_core.PROJECT_INFO)
    solver.project(0.0, y, 0, 0.0, 1, info)  # no step: the ratio only
    return float(info[_core.PR_RATIO])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default=SIZES, help=f"numbers of links (default {SIZES})")
    ap.add_argument("--kinds", default=",".join(KINDS),
                    help=f"chains to run, comma-separated (default {','.join(KINDS)})")
    ap.add_argument("--repeat", type=int, default=3, help="runs per size; the best counts")
    ap.add_argument("--limit", type=float, default=20.0, metavar="SECONDS",
                    help="a size whose load and solve take longer than this ends its kind "
                    "(default 20)")
    a = ap.parse_args(argv)
    sizes = [int(s) for s in a.sizes.split(",")]
    for kind in a.kinds.split(","):
        print(f"straight chain, {kind} joints, joint points on each body; seconds, best of "
              f"{a.repeat}")
        print(f"  {'n':>5} {'load':>9} {'solve':>9} {'µs/link':>8} {'ratio':>8}  route")
        measured: tuple[list[float], list[float]] = ([], [])
        stopped = False
        for n in sizes:
            spec = chain_spec(n, kind)
            model = mbody.load(spec)
            t_load = best(lambda spec=spec: mbody.load(spec), a.repeat)
            t_solve = best(lambda model=model: mbody.assemble(model).solve(), a.repeat)
            ratio = geometric_ratio(model)
            method = mbody.assemble(model).solve().method
            total = t_load + t_solve
            print(f"  {n:5d} {t_load:9.4f} {t_solve:9.4f} {1e6 * total / n:8.1f} "
                  f"{ratio:8.2g}  projection {'null-space' if ratio < ROBUST_BELOW else 'banded'}"
                  f", solve {method.split(' (')[0]}", flush=True)
            measured[0].append(n)
            measured[1].append(total)
            if total > a.limit:
                print(f"  (stopped: {total:.0f} s > --limit)")
                stopped = True
                break
        print(f"  {linear_verdict(*measured, stopped=stopped)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
