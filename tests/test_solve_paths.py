"""The solve's routes and its hot path, checked against what they replace and against
numbers computed here without the core.

- The redundant route (exactly redundant joints: the spatial four-bar, Bricard's
  mechanism, a bar pinned twice) at states along their motions: the accelerations and the
  minimum-norm reactions against the minimum-norm least-squares solution of the KKT
  system built from `Assembly.M`, `G`, `Q`, `b` and γ (numpy's SVD), within a bound
  from the system's condition; the not-unique components against the null space of G_U.
- `Assembly.solve()`'s plain path (the plan's constant fields) against its general one
  (the same solve with the condition asked for), every field but the condition, on every
  shipped model, at broken states too.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from golden_models import moved_state, pinned_twice

import mbody

MODELS = sorted((Path(__file__).resolve().parent.parent / "models").glob("*.yaml"))
EPS = np.finfo(float).eps


def states_along(model: mbody.Model, count: int) -> list[mbody.State]:
    """The initial state and `count - 1` states of a short simulated motion (on the
    joints: the redundancy is exact there)."""
    traj = mbody.simulate(model, t_end=0.5, fps=(count - 1) / 0.5)
    return [traj.state(k) for k in range(len(traj.t))][:count]


def minimum_norm(asm) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(v̇, λ_U, the not-unique mask over U, error bound relative to the largest |x|)
    of M v̇ − G_U λ_U = Q − b + G_K λ_K, G_Uᵀ v̇ = γ_U by the pseudo-inverse of the
    KKT matrix: v̇ is unique, and the minimum-norm [v̇; λ_U] has the minimum-norm λ_U."""
    model = asm.model
    known = model.known_reactions
    U = np.array([i for i, r in enumerate(model.reactions) if r not in known], dtype=int)
    K = np.array([i for i, r in enumerate(model.reactions) if r in known], dtype=int)
    lam_K = np.array([known[model.reactions[i]] for i in K])
    G = asm.G.toarray()
    M = asm.M.toarray()
    rhs = asm.Q - asm.b + (G[:, K] @ lam_K if len(K) else 0.0)
    gamma = np.asarray(asm.columns.gamma)[U]
    GU = G[:, U]
    N, mu = GU.shape
    kkt = np.block([[M, -GU], [GU.T, np.zeros((mu, mu))]])
    u, s, vt = np.linalg.svd(kkt)
    keep = s > s[0] * 1e-10
    x = vt[keep].T @ ((u[:, keep].T @ np.concatenate((rhs, gamma))) / s[keep])
    # backward-stable solves agree to about eps times the condition of the kept part
    bound = 100 * EPS * s[0] / s[keep][-1]
    _, sg, gvt = np.linalg.svd(GU)
    null = gvt[np.sum(sg > sg[0] * 1e-10):]
    mask = np.sqrt((null ** 2).sum(axis=0)) > 1e-8
    return x[:N], x[N:], mask, bound


@pytest.mark.parametrize("name", ["fourbar_spatial", "bricard"])
def test_the_redundant_route_gives_the_minimum_norm_reactions(name):
    model = mbody.load(Path(MODELS[0]).parent / f"{name}.yaml")
    known = model.known_reactions
    U = [r for r in model.reactions if r not in known]
    taken = 0
    for state in states_along(model, 6):
        asm = mbody.assemble(model, state)
        sol = asm.solve()
        acc, lam, mask, bound = minimum_norm(asm)
        assert sol.redundant > 0 and sol.method.startswith("pivoted Cholesky")
        taken += 1
        scale = max(np.abs(acc).max(), np.abs(lam).max())
        assert np.abs(sol.accelerations - acc).max() <= bound * scale
        mine = np.array([sol.reactions[r] for r in U])
        assert np.abs(mine - lam).max() <= bound * scale
        assert set(sol.not_unique) == {r for r, m in zip(U, mask, strict=True) if m}
    assert taken == 6


@pytest.mark.parametrize("dimension", [3])
def test_a_bar_pinned_twice_by_the_redundant_route(dimension):
    model = mbody.load(pinned_twice(dimension))
    asm = mbody.assemble(model)
    sol = asm.solve()
    acc, lam, mask, bound = minimum_norm(asm)
    scale = max(np.abs(acc).max(), np.abs(lam).max())
    assert sol.redundant > 0
    assert np.abs(sol.accelerations - acc).max() <= bound * scale
    assert np.abs(sol.reactions.array - lam).max() <= bound * scale  # none known
    assert set(sol.not_unique) == {r for r, m in zip(model.reactions, mask, strict=True) if m}


def general(asm) -> mbody.Solution:
    """The same solve through the general path (the condition asked for), less it."""
    return dataclasses.replace(asm.solve(condition=True), condition=None)


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.stem)
def test_the_plain_path_is_the_general_one(path):
    """Every field of `solve()` (the plain path for a full-rank or redundant solve with
    nothing broken) equals the general path's, at the file's state and at a broken one;
    a second call (the not-unique labels from the plan) equals the first."""
    model = mbody.load(path)
    for state in (model.initial, moved_state(model, 7)):
        asm = mbody.assemble(model, state)
        try:
            fast = asm.solve()
        except mbody.MbodyError as exc:  # a motion without mass: both paths say so
            with pytest.raises(mbody.MbodyError, match="not unique"):
                general(asm)
            assert "not unique" in str(exc)
            continue
        slow = general(asm)
        for f in dataclasses.fields(fast):
            a, b = getattr(fast, f.name), getattr(slow, f.name)
            if isinstance(a, np.ndarray):
                assert np.array_equal(a, b), f.name
            elif f.name == "reactions":
                assert dict(a) == dict(b)
                assert np.array_equal(a.array, b.array)
            else:
                assert a == b, f.name
        again = mbody.assemble(model, state).solve()
        assert again.not_unique == fast.not_unique and again.redundant == fast.redundant
        assert np.array_equal(again.accelerations, fast.accelerations)
