"""The compiled small-model path (`mbody.compiled`) against the numpy path.

Both paths evaluate the same equations with different code: the numpy path vectorised
over bodies (`mbody.kernels`, `mbody.joints`, `mbody.constraints`, `mbody.kkt`), the
compiled one as loops under numba. Here they must agree on seeded random mechanisms of
every joint type, planar and spatial, open chains and closed loops, with every reaction
unknown, some given, or all given; and on every shipped model. Agreement is to 1e-12
relative where the constraints are independent; with redundant constraints the
minimum-norm reactions are only determined to about cond(S) · ε, so the tolerance there
is scaled by S's condition (measured, not assumed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from randmodels import planar_model, spatial_model

import mbody
from mbody.equations import plan as planmod

pytest.importorskip("numba")
MODELS = sorted((Path(__file__).resolve().parent.parent / "models").glob("*.yaml"))


@pytest.fixture
def jit():
    """Switch paths inside a test: jit("on") / jit("off"); restored afterwards."""
    previous = planmod.JIT

    def set_mode(mode: str) -> None:
        planmod.set_jit(mode)

    yield set_mode
    planmod.set_jit(previous)


def both(jit, model, state=None, known=None):
    """(numpy solution, compiled solution) of the same model and state."""
    jit("off")
    a = mbody.assemble(model, state).solve(known)
    jit("on")
    b = mbody.assemble(model, state).solve(known)
    assert b.method.endswith("compiled)") or not b.solved  # the compiled path served
    assert "compiled" not in a.method
    return a, b


def rel(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(float(np.max(np.abs(a))) if a.size else 0.0, 1e-300)
    return float(np.max(np.abs(a - b))) / scale if a.size else 0.0


def tolerance(sol) -> float:
    """1e-12, or 10 cond(S) ε where S = G_Uᵀ M⁻¹ G_U is ill-conditioned (nearly
    dependent random joints) or singular (redundant constraints, then the condition of
    its nonzero part): rounding alone moves the answer that much, whichever path."""
    cond = sol.condition if sol.condition is not None else 1.0
    return max(1e-12, 10 * cond * 2.2e-16)


def condition(model, state=None) -> float:
    """cond(S) from the numpy path; for a singular S, that of its nonzero part (largest
    over smallest eigenvalue kept by the pseudo-inverse)."""
    from mbody.solve.kkt import RANK_RTOL, ConstrainedSystem

    asm = mbody.assemble(model, state)
    sol = asm.solve(condition=True)
    if not sol.redundant:
        return sol.condition
    system = ConstrainedSystem(model, asm.columns, model.plan.file_unknowns)
    S = np.asarray(system.fact._S)
    w = np.linalg.eigvalsh(0.5 * (S + S.T))
    kept = w[w > RANK_RTOL * w[-1]]
    return float(kept[-1] / kept[0])


def check_equal(a, b, model) -> None:
    assert a.coordinates == b.coordinates
    assert a.solved == b.solved
    assert a.redundant == b.redundant
    assert a.not_unique == b.not_unique
    assert a.broken_joints == b.broken_joints
    lam_a = np.array([a.reactions[r] for r in model.reactions])
    lam_b = np.array([b.reactions[r] for r in model.reactions])
    tol = tolerance(a)
    assert rel(a.accelerations, b.accelerations) <= tol
    assert rel(lam_a, lam_b) <= tol
    if a.residual is not None:
        assert b.residual is not None and b.residual < max(1e-14, 10 * a.residual)


def random_model(kind: str, seed: int, known: str) -> mbody.Model:
    if kind == "planar":
        spec = planar_model(seed, n=5, n_joints=6, known=known != "none")
    else:
        spec = spatial_model(seed, n=5, n_joints=6, known=known != "none")
    if known == "some":  # every other component given, the rest solved
        spec["reactions"] = dict(list(spec["reactions"].items())[::2])
    return mbody.load(spec)


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("kind", ["planar", "spatial"])
@pytest.mark.parametrize("known", ["none", "some", "all"])
def test_solve_equal_on_random_mechanisms(jit, seed, kind, known):
    """Random bodies, loads, springs and joints of every type (trees and loops, often
    broken by the random state), every reaction unknown, some given, or all given."""
    model = random_model(kind, seed, known)
    jit("off")
    a_cond = condition(model)
    a = mbody.assemble(model).solve()
    object.__setattr__(a, "condition", a_cond)
    jit("on")
    b = mbody.assemble(model).solve()
    check_equal(a, b, model)


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.stem)
def test_solve_equal_on_shipped_models(jit, path):
    model = mbody.load(path)
    jit("off")
    cond = condition(model)
    a, b = both(jit, model)
    object.__setattr__(a, "condition", cond)
    check_equal(a, b, model)


def test_known_values_from_the_api(jit):
    """`known=` given at the call replaces unknowns: the compiled path solves the rest."""
    model = mbody.load(MODELS[0].parent / "slider_crank.yaml")
    a, b = both(jit, model, known={"P.Mz": 0.5, "O.Fx": -10.0})
    check_equal(a, b, model)
    assert "P.Mz" not in b.solved and b.reactions["P.Mz"] == 0.5


def random_state(model: mbody.Model, seed: int) -> mbody.State:
    """The initial state moved and spun at random (joints broken: both paths must agree
    on inconsistent states too)."""
    rng = np.random.default_rng(seed)
    s = model.initial
    q = s.quaternion + rng.normal(scale=0.1, size=s.quaternion.shape)
    if model.dimension == 2:
        q[:, 1:3] = 0.0
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    v = s.velocity + rng.normal(size=s.velocity.shape)
    w = s.omega + rng.normal(size=s.omega.shape)
    if model.dimension == 2:
        v[:, 2] = 0.0
        w[:, :2] = 0.0
    return s.replace(position=s.position + rng.normal(scale=0.1, size=s.position.shape),
                     quaternion=q, velocity=v, omega=w, t=0.3)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("kind", ["planar", "spatial"])
def test_solve_equal_at_random_states(jit, seed, kind):
    model = random_model(kind, seed + 100, "none")
    state = random_state(model, seed)
    jit("off")
    cond = condition(model, state)
    a, b = both(jit, model, state)
    object.__setattr__(a, "condition", cond)
    check_equal(a, b, model)


def packed(model: mbody.Model, state: mbody.State) -> np.ndarray:
    """The state as `simulate` integrates it: [x | q | v | ω | θ (planar)]."""
    theta = (2.0 * np.arctan2(state.quaternion[:, 3], state.quaternion[:, 0])
             if model.dimension == 2 else ())
    return np.concatenate((state.position.ravel(), state.quaternion.ravel(),
                           state.velocity.ravel(), state.omega.ravel(), theta))


def test_auto_mode_compiles_only_repeated_work(jit):
    """In automatic mode a one-off solve takes the numpy path (no numba import for the
    command line), repeated ones the compiled path."""
    jit("auto")
    model = mbody.load(MODELS[0].parent / "double_pendulum.yaml")
    first = mbody.assemble(model).solve()
    assert "compiled" not in first.method
    for _ in range(planmod.JIT_AFTER):
        last = mbody.assemble(model).solve()
    assert last.method.endswith("(compiled)")


def test_without_numba_the_numpy_path_serves(jit, monkeypatch):
    monkeypatch.setattr(planmod, "_compiled_module", False)  # as if numba were missing
    jit("on")
    model = mbody.load(MODELS[0].parent / "pendulum.yaml")
    sol = mbody.assemble(model).solve()
    assert "compiled" not in sol.method
