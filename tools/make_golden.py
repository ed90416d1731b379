"""Record what the physics gave before the compiled core replaced the numba and numpy
paths: tests/data/golden.npz, which tests/test_golden.py holds the core to.

This is the record of how those data were made, not a tool to run on today's tree: it
calls the old numba path (`mbody.solve.compiled`), which commit a33363f removed. On a
checkout without it the script says so and exits with status 2; importing it works
anywhere (its models come from tests/golden_models.py, which does not need the old path).

It must run at commit 95ff550, the one the file records (its `__commit__` entry), the
last with the old paths: its mbody/ and models/ are what the data describe (models
shipped since are not in them). This script and tests/golden_models.py, its list of
models and states, came after it: copy both in.

    git worktree add /tmp/golden 95ff550 && cd /tmp/golden
    python3 -m venv .venv && .venv/bin/pip install -e .   # numba is a dependency there
    cp <this checkout>/tools/make_golden.py tools/
    cp <this checkout>/tests/golden_models.py tests/
    .venv/bin/python tools/make_golden.py                  # -> tests/data/golden.npz

Run so (on a copy of 2d4a3e0, whose mbody/ and models/ are 95ff550's), it gave every
entry of today's golden.npz bit for bit but one: chain16/moved/cond, 0.8 % apart, an
estimate made with random start vectors (scipy's onenormest on the sparse S).

For every shipped model and seeded random mechanisms of every joint type (planar and
spatial, trees and loops, some with known reactions), at the file's state and at a
moved state (joints broken: the formulas must agree off the manifold too), with the old
numba path: the accelerations, every reaction value, the not-unique flags, the rank,
Q - b per body, the columns of G, γ, φ, Gᵀ v, ẏ at Baumgarte rate 0 and 7, and the
state after a projection; and cond(S), from which the test derives its tolerance.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from golden_models import all_models, moved_state, state_vector  # noqa: E402

import mbody  # noqa: E402

RECORDED_AT = "95ff550d61d79bf232ab9fd2e34484b28d9bad2d"
"""The commit tests/data/golden.npz was made at (its `__commit__`)."""


def old_path() -> ModuleType:
    """The old numba path, `mbody.solve.compiled` (only on a checkout that has it)."""
    from mbody.solve import compiled  # type: ignore[attr-defined]  # gone since a33363f

    return compiled


def record(C: ModuleType, model: mbody.Model, state: mbody.State) -> dict[str, np.ndarray]:
    """The old path's results for `model` at `state` (`C`: `old_path()`)."""
    planar = model.dimension == 2
    y = state_vector(model, state)
    t = state.t
    F, I = C.pack_model(model)
    n, m = model.n, len(model.reactions)
    known = model.known_reactions_at(t)
    mask = np.array([lab not in known for lab in model.reactions], dtype=bool)
    lam = np.array([known.get(lab, 0.0) for lab in model.reactions], dtype=float)
    U = np.flatnonzero(mask)
    Iu = C.pack_unknowns(model, U)
    loads = np.array(model.forces.vector_at(t), float)
    N, lo, io = C.solve_layout(n, m, planar)
    out = np.zeros(io + C.INFO)
    C.solve(F, I, Iu, y, loads, lam, planar, out)
    pm = C._unpack(F, I)
    x, q, v, w = C._state(y, n)
    R = C._rotations(np.ascontiguousarray(q))
    net = np.empty((n, 6))
    C._net_wrench(pm.gravity, pm.bodies, pm.B_r, pm.springs, pm.loads_i, pm.springs_i,
                  x, R, v, w, loads, net)
    cols = [np.empty((m, 6)), np.empty((m, 6)), np.empty(m), np.empty(m), np.empty(m)]
    C._columns(pm.joints, pm.joints_i, pm.comps_i, x, R, v, w, *cols)
    size = len(y)
    d0, d7 = np.empty(size), np.empty(size)
    s0 = C.derivative(F, I, Iu, y, loads, lam, 0.0, planar, d0)
    s7 = C.derivative(F, I, Iu, y, loads, lam, 7.0, planar, d7)
    yp = y.copy()
    info = np.empty(C.PROJECT_INFO)
    C.project(F, I, Iu, yp, planar, 3, 1e-2, info)
    # cond(S) of the unknowns, from the S the path factorises (for the test's tolerance)
    asm = mbody.assemble(model, state)
    sol = asm.solve(condition=True) if len(U) else None
    cond = 1.0 if sol is None or sol.condition is None else sol.condition
    return {"y": y, "t": np.array(t), "solve": out, "N": np.array(N), "info_at": np.array(io),
            "net": net, "child6": cols[0], "parent6": cols[1], "gamma": cols[2],
            "phi": cols[3], "gtv": cols[4], "d0": d0 if s0 == 0 else np.full(size, np.nan),
            "d7": d7 if s7 == 0 else np.full(size, np.nan), "projected": yp,
            "project_info": info, "cond": np.array(cond), "mask": mask}


def main() -> int:
    try:
        C = old_path()
    except ImportError:
        print(f"make_golden.py needs the old numba path (mbody.solve.compiled), removed in "
              f"a33363f: run it on a checkout of {RECORDED_AT[:7]}, as its docstring says",
              file=sys.stderr)
        return 2
    data: dict[str, np.ndarray] = {}
    models = all_models()
    for name, model in models:
        for tag, state in (("file", model.initial), ("moved", moved_state(model, 1))):
            try:
                rec = record(C, model, state)
            except mbody.MbodyError as exc:  # e.g. a singular mass at the moved state
                print(f"{name}/{tag}: skipped ({exc})")
                continue
            for k, v in rec.items():
                data[f"{name}/{tag}/{k}"] = np.asarray(v)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                            cwd=ROOT).stdout.strip()
    data["__commit__"] = np.array(commit)
    out = ROOT / "tests" / "data" / "golden.npz"
    out.parent.mkdir(exist_ok=True)
    np.savez_compressed(out, **data)
    print(f"{out}: {len(models)} models, {out.stat().st_size / 1024:.0f} KB, from {commit[:10]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
