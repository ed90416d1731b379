"""The compiled core gives today's results: tests/data/golden.npz holds what the numba
path (which agreed with the numpy path to 1e-12) gave before both were replaced by the
core (tools/make_golden.py), on every shipped model and seeded random mechanisms of every
joint type, at the file's state and at a moved one. Here the same quantities come from
the public API (`assemble(...).solve()`) and the model's workspace: agreement to 1e-12
relative, or 10 cond(S) ε where S = G_Uᵀ M⁻¹ G_U is ill-conditioned (rounding alone moves
an answer by about cond(S) ε on any path).

One deliberate change: a mechanism redundant at every configuration (its G_U's rank at
generic configurations, `Unknowns.generic_rank`, below the number of unknowns) is now
solved as redundant at a broken state too, where the old paths called its loop rigid
whenever rounding left the redundant singular values above 1e-12 (issue 23, Bricard).
At such states (the "moved" ones of such models) the solve, ẏ and the projection are not
held to the old numbers; the formulas (Q − b, columns, γ, φ, Gᵀ v) are, as everywhere;
tests/test_bricard.py tests the decision itself."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from golden_models import all_models

import mbody
from mbody.equations.workspace import workspace
from mbody.kernel import _core

GOLDEN = Path(__file__).resolve().parent / "data" / "golden.npz"
EPS = np.finfo(float).eps
DATA = np.load(GOLDEN)
ALL = all_models()
CASES = [(name, model, tag) for name, model in ALL for tag in ("file", "moved")
         if f"{name}/{tag}/y" in DATA]


def rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    if not a.size:
        return 0.0
    return float(np.max(np.abs(a - b))) / max(float(np.max(np.abs(b))), 1e-300)


def state_of(model: mbody.Model, y: np.ndarray, t: float) -> mbody.State:
    n = model.n
    return mbody.State(y[:3 * n].reshape(n, 3), y[3 * n:7 * n].reshape(n, 4),
                       y[7 * n:10 * n].reshape(n, 3), y[10 * n:13 * n].reshape(n, 3), t)


@pytest.mark.parametrize(("name", "model", "tag"), CASES,
                         ids=[f"{n}-{t}" for n, _, t in CASES])
def test_the_core_gives_todays_results(name, model, tag):
    g = {k.rsplit("/", 1)[1]: DATA[k] for k in DATA.files if k.startswith(f"{name}/{tag}/")}
    y, t = g["y"], float(g["t"])
    tol = max(1e-12, 10.0 * float(g["cond"]) * EPS)
    state = state_of(model, y, t)
    m = len(model.reactions)
    N = int(g["N"])
    old = g["solve"]
    # the solve, through the public API
    ws = workspace(model)
    unknowns = ws.unknowns(model.known_reactions_at(t))
    solver = ws.solver(unknowns)
    sol = mbody.assemble(model, state).solve()
    if tag == "moved" and solver.generic_rank < solver.mu:  # redundant by geometry
        # kept redundant wherever the extra singular values are the state's distance
        # from the manifold (below MB_GENERIC_GAP), rigid where the state is that far off
        assert np.all(np.isfinite(sol.accelerations))
        return check_formulas(model, g, tag)
    acc = old[:N][model.rows] if model.has_particles else old[:N]  # a particle: no turning
    assert rel(sol.accelerations, acc) <= tol
    lam = np.array([sol.reactions[r] for r in model.reactions])
    assert rel(lam, old[N:N + m]) <= tol
    flags = np.array([r in sol.not_unique for r in model.reactions])
    assert np.array_equal(flags, old[N + 2 * m:N + 3 * m] > 0)
    info = old[int(g["info_at"]):]
    if g["mask"].any():
        assert sol.redundant == int(info[_core.ST_MU] - info[_core.ST_RANK])
    check_formulas(model, g, tag)
    # ẏ of a simulation (Baumgarte rate 0 and 7) and the projection
    for rate, key in ((0.0, "d0"), (7.0, "d7")):
        if np.isnan(g[key]).any():
            continue
        d = np.empty(len(y))
        assert solver.derivative(t, y, unknowns.lam, rate, d) == 0
        assert rel(d, g[key]) <= tol, key
    yp = y.copy()
    pinfo = np.empty(_core.PROJECT_INFO)
    solver.project(t, yp, 3, 1e-2, 0, pinfo)
    assert rel(yp, g["projected"]) <= max(tol, 1e-12)


def check_formulas(model: mbody.Model, g: dict, tag: str) -> None:
    """Q − b, the columns of G, γ, φ, Gᵀ v (the formulas, at any state)."""
    ws = workspace(model)
    y, t = g["y"], float(g["t"])
    n, m = model.n, len(model.reactions)
    net = np.empty((n, 6))
    ws.core.net_wrench(t, y, net)
    assert rel(net, g["net"]) <= 1e-12
    cols = {"child6": np.empty((m, 6)), "parent6": np.empty((m, 6)),
            "W_e": np.empty((m, 3)), "W_P": np.empty((m, 3)), "gamma": np.empty(m),
            "phi": np.empty(m), "gtv": np.empty(m)}
    ws.core.columns(t, y, *cols.values())
    # Gᵀ v sums column entries times velocities: its rounding is relative to the size of
    # those terms, not to the sum, which is itself rounding (~1e-16) where v keeps the
    # joints (the file's states; at the moved ones the sum is of the terms' size)
    terms = float(np.max(np.abs(np.concatenate((g["child6"].ravel(), g["parent6"].ravel()))),
                         initial=0.0)) * float(np.max(np.abs(y[7 * n:13 * n]), initial=0.0))
    for key in ("child6", "parent6", "gamma", "phi", "gtv"):
        # φ at the file's pose is rounding (~1e-16 m): compared on the length scale
        scale = 1.0 if key == "phi" and tag == "file" else max(
            float(np.max(np.abs(g[key]), initial=0.0)),
            terms if key == "gtv" and tag == "file" else 0.0,
            1e-300)
        assert np.max(np.abs(cols[key] - g[key]), initial=0.0) <= 1e-12 * scale, key
