"""The compiled core (`mbody.kernel._core`, C) against the two paths it replaces, and on
its own terms.

Ports: on every shipped model and on seeded random mechanisms of every joint type
(planar and spatial, trees and loops, some redundant or near singular), at the file's
state and at random ones, the C kernel must give what the numba path
(`mbody.solve.compiled`) and the numpy path (`mbody.equations.kernels`, `joints`,
`constraints`, `mbody.solve.kkt`) give: net wrenches, columns of G, γ, φ, Gᵀ v, the
solve (accelerations, λ, rank, not-unique flags, path), the right-hand side of a
simulation and the coordinate projection. Agreement is to 1e-12 relative; where S =
G_Uᵀ M⁻¹ G_U is ill-conditioned, rounding alone moves the answer by about cond(S) ε on
any path, so the bound there is 10 cond(S) ε (cond measured from `Unknowns.schur`).

Independent checks, which compare with no port: Gᵀ v = dφ/dt by central differences
along random motions at the file's pose (where every joint holds, as the identity needs
for the rotation primitives), −γ = d(Gᵀ v)/dt at v̇ = 0 at any state, Newton's third law
on every column, TURN's φ across ±π and its law's terms, SCREW against a nut on a fixed
screw, and prescribed motion through a law.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fourbar_chain import FourbarChain
from randmodels import planar_model, spatial_model

import mbody
from mbody.equations.constraints import gamma as np_gamma
from mbody.equations.constraints import phi as np_phi
from mbody.equations.joints import constraint_velocity, reaction_columns
from mbody.equations.loads import applied_loads, contributions
from mbody.equations.pack import Component, pack_model, pack_unknowns
from mbody.kernel import _core
from mbody.model.expressions import compile_expression

MODELS = sorted((Path(__file__).resolve().parent.parent / "models").glob("*.yaml"))
EPS = np.finfo(float).eps
KINDS = ("planar", "spatial")

PARTICLES = {  # particle links: ground -> p1 -> p2 (particle parent), a rod on p2
    "model": "particle-chain", "dimension": 3, "gravity": [0, 0, -9.81],
    "bodies": [
        {"name": "p1", "mass": 1.0, "inertia": 0, "position": [0.6, 0.0, -0.8]},
        {"name": "p2", "mass": 0.5, "inertia": 0, "position": [0.9, 0.4, -1.5]},
        {"name": "rod", "mass": 2.0, "inertia": [0.1, 0.2, 0.25],
         "position": [1.0, 0.5, -2.0], "velocity": [0.1, -0.2, 0.3],
         "angular_velocity": [0.5, -1.0, 2.0]},
    ],
    "joints": [
        {"name": "O", "type": "spherical", "parent": "ground", "child": "p1", "at": [0, 0, 0]},
        {"name": "A", "type": "spherical", "parent": "p1", "child": "p2", "at": [0.6, 0, -0.8]},
        {"name": "B", "type": "spherical", "parent": "p2", "child": "rod", "at": [0.9, 0.4, -1.5]},
    ],
}


# -- helpers --------------------------------------------------------------------------------
def numba():
    return pytest.importorskip("mbody.solve.compiled")


class Kernel:
    """A model packed for the C core, with its file's unknowns."""

    def __init__(self, model: mbody.Model, extra: tuple[Component, ...] = ()):
        self.model, self.extra = model, extra
        self.planar = model.dimension == 2
        self.F, self.I = pack_model(model, extra)
        self.core = _core.Model(self.F, self.I, self.planar)
        self.m = self.core.m

    def unknowns(self, U) -> _core.Unknowns:
        return _core.Unknowns(self.core, pack_unknowns(self.model, np.asarray(U), self.extra))

    def columns(self, t: float, y: np.ndarray) -> dict[str, np.ndarray]:
        m = self.m
        out = {"child6": np.empty((m, 6)), "parent6": np.empty((m, 6)),
               "W_e": np.empty((m, 3)), "W_P": np.empty((m, 3)), "gamma": np.empty(m),
               "phi": np.empty(m), "gtv": np.empty(m)}
        self.core.columns(t, y, *out.values())
        return out

    def cond(self, unknowns: _core.Unknowns, t: float, y: np.ndarray) -> float:
        """cond(S), for a singular S that of its nonzero part (eigenvalues above 1e-12 of
        the largest, as the numpy path's pseudo-inverse keeps)."""
        mu = unknowns.mu
        if mu == 0:
            return 1.0
        S = np.empty((mu, mu))
        unknowns.schur(t, y, S)
        w = np.linalg.eigvalsh(S)
        kept = w[w > 1e-12 * w[-1]]
        return float(kept[-1] / kept[0])


def random_model(kind: str, seed: int, known: str = "none") -> mbody.Model:
    make = planar_model if kind == "planar" else spatial_model
    spec = make(seed, n=5, n_joints=6, known=known != "none")
    if known == "some":  # every other component given, the rest solved
        spec["reactions"] = dict(list(spec["reactions"].items())[::2])
    return mbody.load(spec)


def state_vector(model: mbody.Model, state: mbody.State) -> np.ndarray:
    """[x | q | v | ω | θ (planar)], as a simulation integrates it."""
    theta = (2.0 * np.arctan2(state.quaternion[:, 3], state.quaternion[:, 0])
             if model.dimension == 2 else ())
    return np.concatenate((state.position.ravel(), state.quaternion.ravel(),
                           state.velocity.ravel(), state.omega.ravel(), theta))


def moved_state(model: mbody.Model, seed: int, t: float = 0.3) -> mbody.State:
    """The file's state moved and spun at random (joints broken: the paths must agree on
    inconsistent states too)."""
    rng = np.random.default_rng(seed)
    s = model.initial
    q = s.quaternion + rng.normal(scale=0.1, size=s.quaternion.shape)
    v = s.velocity + rng.normal(size=s.velocity.shape)
    w = s.omega + rng.normal(size=s.omega.shape)
    if model.dimension == 2:
        q[:, 1:3] = 0.0
        v[:, 2] = 0.0
        w[:, :2] = 0.0
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w[model.particle] = 0.0  # a particle does not turn (its rows are translations only)
    return s.replace(position=s.position + rng.normal(scale=0.1, size=s.position.shape),
                     quaternion=q, velocity=v, omega=w, t=t)


def rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    if not a.size:
        return 0.0
    scale = max(float(np.max(np.abs(b))), 1e-300)
    return float(np.max(np.abs(a - b))) / scale


def tolerance(cond: float) -> float:
    return max(1e-12, 10.0 * cond * EPS)


def all_models():
    """(id, model) of every shipped model and random mechanisms of every kind."""
    out = [(p.stem, mbody.load(p)) for p in MODELS]
    for kind in KINDS:
        for seed in range(4):
            out.append((f"{kind}{seed}", random_model(kind, seed)))
    out.append(("particles", mbody.load(PARTICLES)))
    return out


ALL = all_models()
IDS = [i for i, _ in ALL]


def numba_columns(C, k: Kernel, y: np.ndarray):
    F0, I0 = C.pack_model(k.model)
    pm = C._unpack(F0, I0)
    n, m = k.model.n, len(k.model.reactions)
    x, q, v, w = C._state(y, n)
    R = C._rotations(np.ascontiguousarray(q))
    out = [np.empty((m, 6)), np.empty((m, 6)), np.empty(m), np.empty(m), np.empty(m)]
    C._columns(pm.joints, pm.joints_i, pm.comps_i, x, R, v, w, *out)
    return dict(zip(("child6", "parent6", "gamma", "phi", "gtv"), out, strict=True))


# -- against the numba path ---------------------------------------------------------------------
@pytest.mark.parametrize(("name", "model"), ALL, ids=IDS)
def test_net_wrench_and_columns_equal_numba(name, model):
    C = numba()
    k = Kernel(model)
    for seed, state in ((None, model.initial), (1, moved_state(model, 1))):
        y = state_vector(model, state)
        t = state.t
        F0, I0 = C.pack_model(model)
        pm = C._unpack(F0, I0)
        x, q, v, w = C._state(y, model.n)
        R = C._rotations(np.ascontiguousarray(q))
        expect = np.empty((model.n, 6))
        C._net_wrench(pm.gravity, pm.bodies, pm.B_r, pm.springs, pm.loads_i, pm.springs_i,
                      x, R, v, w, np.array(model.forces.vector_at(t), float), expect)
        got = np.empty((model.n, 6))
        k.core.net_wrench(t, y, got)
        assert rel(got, expect) <= 1e-12, seed
        cols, ref = k.columns(t, y), numba_columns(C, k, y)
        for key, a in ref.items():
            # φ at the file's pose is rounding (~1e-16 m): compared on the length scale
            top = max(np.max(np.abs(a), initial=0.0), 1e-300)
            scale = 1.0 if key == "phi" and seed is None else top
            assert np.max(np.abs(cols[key] - a), initial=0.0) <= 1e-12 * scale, (key, seed)


def solve_both(C, k: Kernel, unknowns, U, lam, t, y):
    model = k.model
    F0, I0 = C.pack_model(model)
    Iu0 = C.pack_unknowns(model, np.asarray(U))
    N, lo, io = C.solve_layout(model.n, len(model.reactions), k.planar)
    a, b = np.zeros(io + C.INFO), np.zeros(io + C.INFO)
    C.solve(F0, I0, Iu0, y, np.array(model.forces.vector_at(t), float), lam, k.planar, a)
    unknowns.solve(t, y, lam, b)
    return a, b, N, io


def check_solve(a, b, N, io, m, cond):
    tol = tolerance(cond)
    assert rel(b[:N], a[:N]) <= tol
    assert rel(b[N:N + m], a[N:N + m]) <= tol
    assert np.array_equal(b[N + 2 * m:io], a[N + 2 * m:io])  # not-unique flags
    info_a, info_b = a[io:], b[io:]
    for slot in (_core.ST_RANK, _core.ST_BROKEN, _core.ST_MU, _core.ST_PATH,
                 _core.ST_SINGULAR):
        assert info_b[slot] == info_a[slot], slot
    assert info_b[_core.ST_BERR] <= max(1e-14, 10 * info_a[_core.ST_BERR])


@pytest.mark.parametrize(("name", "model"), ALL, ids=IDS)
def test_solve_equal_numba(name, model):
    C = numba()
    k = Kernel(model)
    plan = model.plan
    unk = plan.unknowns_at(0.3)
    cu = k.unknowns(unk.U)
    m = len(model.reactions)
    for state in (model.initial, moved_state(model, 2)):
        y = state_vector(model, state)
        a, b, N, io = solve_both(C, k, cu, unk.U, unk.lam, state.t, y)
        check_solve(a, b, N, io, m, k.cond(cu, state.t, y))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("known", ["none", "some", "all"])
def test_solve_and_derivative_equal_numba_on_random_mechanisms(seed, kind, known):
    C = numba()
    model = random_model(kind, seed + 20, known)
    k = Kernel(model)
    unk = model.plan.file_unknowns
    cu = k.unknowns(unk.U)
    m = len(model.reactions)
    F0, I0 = C.pack_model(model)
    Iu0 = C.pack_unknowns(model, unk.U)
    for state in (model.initial, moved_state(model, seed)):
        y = state_vector(model, state)
        cond = k.cond(cu, state.t, y)
        a, b, N, io = solve_both(C, k, cu, unk.U, unk.lam, state.t, y)
        check_solve(a, b, N, io, m, cond)
        y[3 * model.n] *= 1.01  # a quaternion off unit norm: both normalise it
        fvec = np.array(model.forces.vector_at(state.t), float)
        for rate in (0.0, 7.0):
            da, db = np.zeros_like(y), np.zeros_like(y)
            sa = C.derivative(F0, I0, Iu0, y, fvec, unk.lam, rate, k.planar, da)
            sb = cu.derivative(state.t, y, unk.lam, rate, db)
            assert sa == sb
            if sa == 0:
                assert rel(db, da) <= tolerance(cond)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("robust_below", [1e-6, 2.0])  # 2: the null-space route always
def test_project_equal_numba(seed, kind, robust_below):
    C = numba()
    model = random_model(kind, seed + 40)
    k = Kernel(model)
    unk = model.plan.file_unknowns
    cu = k.unknowns(unk.U)
    F0, I0 = C.pack_model(model)
    Iu0 = C.pack_unknowns(model, unk.U)
    state = moved_state(model, seed)
    y0 = state_vector(model, state)
    # small breaks: the Gauss-Newton steps converge (large ones may wander the same way
    # on both paths, but amplify rounding)
    y0 = state_vector(model, model.initial) + 1e-3 * (y0 - state_vector(model, model.initial))
    ya, yb = y0.copy(), y0.copy()
    ia, ib = np.zeros(4), np.zeros(4)
    C.project(F0, I0, Iu0, ya, k.planar, 3, robust_below, ia)
    cu.project(0.0, yb, 3, robust_below, False, ib)
    cond = k.cond(cu, 0.0, y0)
    assert ib[_core.PR_SINGULAR] == ia[_core.PR_SINGULAR]
    assert ib[_core.PR_RATIO] == pytest.approx(ia[_core.PR_RATIO], rel=tolerance(cond))
    if ia[_core.PR_SINGULAR] == 0:
        assert rel(yb - y0, ya - y0) <= tolerance(cond)


@pytest.mark.parametrize("theta", [1e-4, 1e-6, 1e-8, 0.0])
def test_near_singular_and_redundant_equal_numba(theta):
    """The flat four-bar chain: the null-space route near flat, rank 3 lost at flat."""
    C = numba()
    chain = FourbarChain(crank=0.25, spacing=0.5, width=0.03125)
    model = mbody.loads(chain.yaml(theta, 1.5))
    k = Kernel(model)
    unk = model.plan.file_unknowns
    cu = k.unknowns(unk.U)
    y = state_vector(model, model.initial)
    a, b, N, io = solve_both(C, k, cu, unk.U, unk.lam, 0.0, y)
    assert b[io + _core.ST_PATH] == 1  # the null-space route
    # both refine with compensated (Dot2) residuals; their SVDs differ (LAPACK's and a
    # one-sided Jacobi), which moves the answer by a few ulps of the refined solution
    check_solve(a, b, N, io, len(model.reactions), 1.0)
    if theta:  # at flat itself the branches meet: the parallel branch's ODE is not it
        assert rel(b[:N], chain.accelerations(theta, 1.5).ravel()) <= 1e-9


# -- against the numpy path ---------------------------------------------------------------------
@pytest.mark.parametrize(("name", "model"), ALL, ids=IDS)
def test_equal_numpy_path(name, model):
    k = Kernel(model)
    state = moved_state(model, 3)
    y, t = state_vector(model, state), state.t
    got = np.empty((model.n, 6))
    k.core.net_wrench(t, y, got)
    al = applied_loads(model, state)
    assert rel(got[:, :3], al.W_F) <= 1e-12 * max(1.0, rel(al.W_F, 0 * al.W_F))
    cols = reaction_columns(model, state)
    mine = k.columns(t, y)
    for key, ref in (("child6", cols.child6), ("parent6", cols.parent6), ("W_e", cols.W_e),
                     ("W_P", cols.W_P), ("phi", np_phi(model, state, cols=cols)),
                     ("gamma", np_gamma(model, state, cols)),
                     ("gtv", constraint_velocity(model, cols, state))):
        assert rel(mine[key], ref) <= 1e-12, key
    # the solve (Assembly.solve on the numpy path)
    from mbody.equations import plan as planmod

    previous = planmod.set_jit("off")
    try:
        sol = mbody.assemble(model, state).solve()
    finally:
        planmod.set_jit(previous)
    unk = model.plan.unknowns_at(t)
    cu = k.unknowns(unk.U)
    m = len(model.reactions)
    N, lo, io = _core.solve_layout(model.n, m, k.planar)
    out = np.zeros(io + _core.INFO)
    cu.solve(t, y, unk.lam, out)
    tol = tolerance(k.cond(cu, t, y))
    acc = out[:N][model.rows] if model.has_particles else out[:N]
    assert rel(acc, np.asarray(sol.accelerations).ravel()) <= tol
    lam = np.array([sol.reactions[r] for r in model.reactions])
    assert rel(out[lo:lo + m], lam) <= tol
    flagged = {model.reactions[i] for i in np.flatnonzero(out[lo + 2 * m:io])}
    assert flagged == set(sol.not_unique)


@pytest.mark.parametrize(("name", "model"), ALL, ids=IDS)
def test_load_wrenches_are_each_loads_share(name, model):
    """Each point load's and spring end's wrench equals the numpy path's contribution,
    and they sum with gravity and the gyroscopic term to net_wrench."""
    k = Kernel(model)
    state = moved_state(model, 4)
    y, t = state_vector(model, state), state.t
    kk, s = len(model.forces.names), len(model.springs.names)
    out = np.empty((kk + 2 * s, 7))
    k.core.load_wrenches(t, y, out)
    ref = contributions(model, state)
    body = out[:, 0].astype(int)
    order = np.r_[np.arange(kk), kk + np.arange(s), kk + s + np.arange(s)]  # a, then b
    mine = np.r_[out[:kk], out[kk::2][:s], out[kk + 1::2][:s]] if s else out[:kk]
    assert np.array_equal(np.r_[body[:kk], body[kk::2], body[kk + 1::2]],
                          ref.body) or not len(order)
    assert rel(mine[:, 1:4], ref.W_f) <= 1e-12
    assert rel(mine[:, 4:7], ref.B_m) <= 1e-12
    total = np.zeros((model.n, 6))
    total[:, :3] = model.mass[:, None] * model.gravity
    for row in out:
        if row[0] >= 0:
            total[int(row[0])] += row[1:]
    J, w = model.J, state.omega
    total[:, 3:] -= np.cross(w, np.einsum("nij,nj->ni", J, w))
    net = np.empty((model.n, 6))
    k.core.net_wrench(t, y, net)
    assert rel(total, net) <= 1e-13


def test_loads_and_known_values_of_t():
    """Loads and known reactions given as expressions of t, evaluated in C."""
    model = mbody.load(MODELS[0].parent / "planar_time_varying_force.yaml")
    k = Kernel(model)
    out = np.empty((len(model.forces.names), 3))
    for t in (0.0, 0.37, 2.5, 11.0):
        k.core.loads_at(t, out)
        assert rel(out, model.forces.vector_at(t)) <= 1e-15
    spec = spatial_model(5, n=3, n_joints=3, known=True)
    label = next(iter(spec["reactions"]))
    spec["reactions"][label] = "3*sin(2*t) + exp(-t)"
    model = mbody.load(spec)
    k = Kernel(model)
    i = model.reaction_index[label]
    lam = np.array([model.known_reactions.get(r, 0.0) for r in model.reactions])
    cu = k.unknowns(np.zeros(0, np.int64))
    m = len(model.reactions)
    N, lo, io = _core.solve_layout(model.n, m, False)
    out = np.zeros(io + _core.INFO)
    y = state_vector(model, model.initial)
    cu.solve(0.8, y, lam, out)
    assert out[lo + i] == pytest.approx(3 * math.sin(1.6) + math.exp(-0.8), rel=1e-15)
    sol = mbody.assemble(model, model.initial.replace(t=0.8)).solve()
    assert rel(out[:N], np.asarray(sol.accelerations).ravel()) <= 1e-12


def test_expressions_as_numpy_gives_them():
    cases = ["2*t^2 - 3", "sin(t)*cos(t)/tan(t+1)", "sqrt(abs(t - 2))", "log(t)", "1/t",
             "(-8)^(1/3)", "exp(-t^2)", "-t^-2"]
    exprs = [compile_expression(c) for c in cases]
    model = mbody.load(MODELS[0].parent / "pendulum.yaml")
    law = Component(0, _core.KIND_TURN, 2, law=(exprs[0], exprs[1], exprs[2]))
    laws = [Component(0, _core.KIND_TURN, 2, law=(exprs[i], exprs[i + 1], exprs[i + 2]))
            for i in range(3, 6)] + [law]
    k = Kernel(model, tuple(laws) + (Component(0, _core.KIND_TURN, 2,
                                                law=(exprs[6], exprs[7], exprs[0])),))
    assert k.core.n_expr == len(cases)
    with np.errstate(all="ignore"):
        for t in (0.0, 0.5, 2.0, -1.5):
            order = [3, 4, 5, 6, 7, 0, 1, 2]  # packing order: first use
            for e, c in enumerate(order):
                got, want = k.core.expression(e, t), float(exprs[c](np.float64(t)))
                assert got == pytest.approx(want, rel=1e-15, nan_ok=True), (cases[c], t)


# -- independent checks -------------------------------------------------------------------------
def move(model: mbody.Model, y: np.ndarray, s: float) -> np.ndarray:
    """y advanced by s along its velocities (v world, ω body axes constant)."""
    n = model.n
    out = y.copy()
    out[:3 * n] += s * y[7 * n:10 * n]
    q, w = y[3 * n:7 * n].reshape(n, 4), y[10 * n:13 * n].reshape(n, 3)
    ang = np.linalg.norm(w, axis=1) * s
    axis = w / np.maximum(np.linalg.norm(w, axis=1), 1e-300)[:, None]
    dq = np.concatenate((np.cos(ang / 2)[:, None], np.sin(ang / 2)[:, None] * axis), axis=1)
    qw, qv = q[:, :1], q[:, 1:]
    pw, pv = dq[:, :1], dq[:, 1:]  # q ⊗ dq
    new = np.concatenate((qw * pw - np.sum(qv * pv, axis=1, keepdims=True),
                          qw * pv + pw * qv + np.cross(qv, pv)), axis=1)
    out[3 * n:7 * n] = new.ravel()
    if model.dimension == 2:
        out[13 * n:] += s * w[:, 2]
    return out


def extras(model: mbody.Model, rng: np.random.Generator) -> tuple[Component, ...]:
    """A TURN and a SCREW about random joint axes of a spatial model (laws on some), on
    joints between rigid bodies (a particle has no orientation to turn)."""
    jt = model.joint_table
    rigid = [j for j in range(len(jt.parent)) if not model.particle[jt.child[j]]
             and (jt.parent[j] < 0 or not model.particle[jt.parent[j]])]
    if model.dimension == 2 or not rigid:
        return ()
    f = compile_expression("0.3*sin(1.7*t)")
    df = compile_expression("0.51*cos(1.7*t)")
    ddf = compile_expression("-0.867*sin(1.7*t)")
    def joint() -> int:
        return int(rigid[rng.integers(len(rigid))])

    return (Component(joint(), _core.KIND_TURN, int(rng.integers(3)), off=0.2),
            Component(joint(), _core.KIND_SCREW, int(rng.integers(3)),
                      h=float(rng.uniform(-0.2, 0.2)), law=(f, df, ddf)),
            Component(joint(), _core.KIND_TURN, int(rng.integers(3)), law=(f, df, ddf)))


def central(fn, h: float) -> tuple[np.ndarray, np.ndarray]:
    """(central difference at step h, its error estimate from the step h/2)."""
    d1 = (fn(h) - fn(-h)) / (2 * h)
    d2 = (fn(h / 2) - fn(-h / 2)) / h
    return d2, np.abs(d2 - d1)


@pytest.mark.parametrize(("name", "model"), ALL, ids=IDS)
def test_gtv_is_the_rate_of_phi(name, model):
    """Gᵀ v − f' = dφ/dt along random motions from the file's pose (joints hold there)."""
    rng = np.random.default_rng(7)
    k = Kernel(model, extras(model, rng))
    s = model.initial
    v = rng.normal(size=s.velocity.shape)
    w = rng.normal(size=s.omega.shape)
    if model.dimension == 2:
        v[:, 2], w[:, :2] = 0.0, 0.0
    y = state_vector(model, s.replace(velocity=v, omega=w))
    t0 = 0.4

    def phi(ds: float) -> np.ndarray:
        return k.columns(t0 + ds, move(model, y, ds))["phi"]

    got = k.columns(t0, y)["gtv"]
    d, err = central(phi, 1e-4)
    # the difference is O(h^2) wrong (estimated by halving h: the O(h^2) terms differ by
    # 3/4 of themselves) plus rounding eps |phi| / h
    assert np.all(np.abs(got - d) <= 2 * err + 1e-9), np.abs(got - d)


@pytest.mark.parametrize(("name", "model"), ALL, ids=IDS)
@pytest.mark.parametrize("where", ["pose", "broken"])
def test_gamma_is_minus_the_rate_of_gtv(name, model, where):
    """−γ = d(Gᵀ v − f')/dt at v̇ = 0: at the file's pose with random velocities, and at
    a random (broken) state. The universal joint's γ (RIGHT_ANGLE) differentiates
    a × b, not the unit a × b / |a × b| its column uses: the two agree where the joint
    holds (a ⟂ b, where |a × b| is stationary), so it is checked at the pose only (as
    the numpy and numba paths have it)."""
    rng = np.random.default_rng(8)
    k = Kernel(model, extras(model, rng))
    if where == "pose":
        state = moved_state(model, 5)
        state = model.initial.replace(velocity=state.velocity, omega=state.omega, t=0.6)
    else:
        state = moved_state(model, 5)
    y = state_vector(model, state)
    t0 = 0.6

    def gtv(ds: float) -> np.ndarray:
        return k.columns(t0 + ds, move(model, y, ds))["gtv"]

    got = k.columns(t0, y)["gamma"]
    d, err = central(gtv, 1e-4)
    check = np.ones(k.m, dtype=bool)
    if where == "broken":
        check = component_kinds(k) != _core.KIND_RIGHT_ANGLE
    assert np.all((np.abs(-got - d) <= 2 * err + 1e-8)[check]), np.abs(-got - d)


def component_kinds(k: Kernel) -> np.ndarray:
    """(m,) the packed kind of each component (I's component rows)."""
    model = k.model
    start = (_core.I_HEADER + 3 * len(model.forces.names) + 2 * len(model.springs.names)
             + 3 * len(model.joint_table.parent))
    return k.I[start:start + 4 * k.m].reshape(-1, 4)[:, 1]


@pytest.mark.parametrize(("name", "model"), ALL, ids=IDS)
def test_columns_keep_newtons_third_law(name, model):
    """Each column's wrench on the child and on the parent sum to zero force and zero
    moment about the world origin (a particle parent's is its point's, taken as a body's
    centre)."""
    rng = np.random.default_rng(9)
    k = Kernel(model, extras(model, rng))
    y = state_vector(model, moved_state(model, 6))
    n = model.n
    x, q = y[:3 * n].reshape(n, 3), y[3 * n:7 * n].reshape(n, 4)
    R = np.array([_rot(qi) for qi in q])
    cols = k.columns(0.2, y)
    jt = model.joint_table
    start = (_core.I_HEADER + 3 * len(model.forces.names) + 2 * len(model.springs.names)
             + 3 * len(jt.parent))
    for i, (j, kind, _, _) in enumerate(k.I[start:start + 4 * k.m].reshape(-1, 4)):
        p, c = jt.parent[j], jt.child[j]
        if p < 0 or jt.particle_parent[j]:
            continue
        c6, p6 = cols["child6"][i], cols["parent6"][i]
        assert np.allclose(c6[:3] + p6[:3], 0.0, atol=1e-15)
        # the child's force acts at P (the link: along the line, so at any of its points)
        m_c = R[c] @ c6[3:] + np.cross(x[c], c6[:3])
        m_p = R[p] @ p6[3:] + np.cross(x[p], p6[:3])
        scale = 1.0 + np.abs(x).max()
        assert np.max(np.abs(m_c + m_p)) <= 1e-13 * scale, (i, kind)


def _rot(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _quat_z(theta: float) -> np.ndarray:
    return np.array([math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2)])


NUT = {  # a nut (a disc) on a fixed vertical screw: cylindrical joint + the SCREW term
    "model": "nut", "dimension": 3, "gravity": [0, 0, -9.81],
    "bodies": [{"name": "nut", "mass": 0.3, "inertia": [2e-4, 2e-4, 3e-4],
                "position": [0, 0, 0]}],
    "joints": [{"name": "S", "type": "cylindrical", "parent": "ground", "child": "nut",
                "at": [0, 0, 0], "axis": [0, 0, 1]}],
}


def test_screw_is_a_nut_on_a_fixed_screw():
    """φ = z − h θ on the branch nearest z / h (several turns), and the motion under
    gravity: (m h² + J) θ'' = −m g h, z'' = h θ''."""
    model = mbody.load(NUT)
    h = 0.01 / (2 * math.pi)  # 10 mm per turn
    k = Kernel(model, (Component(0, _core.KIND_SCREW, 2, h=h),))
    y = state_vector(model, model.initial)
    n = model.n
    for theta in (-4.0, 0.5, 3.2, 7.0, 20.0):
        for delta in (0.0, 1e-4, -3e-3):
            yy = y.copy()
            yy[2] = h * theta + delta
            yy[3 * n:7 * n] = _quat_z(theta)
            assert k.columns(0.0, yy)["phi"][-1] == pytest.approx(delta, abs=1e-15)
    cu = k.unknowns(np.arange(k.m))
    N, lo, io = _core.solve_layout(n, k.m, False)
    out = np.zeros(io + _core.INFO)
    cu.solve(0.0, y, np.zeros(k.m), out)
    m, J, g = 0.3, 3e-4, 9.81
    alpha = -m * g * h / (m * h * h + J)
    assert out[2] == pytest.approx(h * alpha, rel=1e-12)
    assert out[5] == pytest.approx(alpha, rel=1e-12)
    # the axial wrench: the nut's weight less its inertial share
    assert out[lo + k.m - 1] == pytest.approx(m * (h * alpha + g), rel=1e-12)


PIN = {
    "model": "pin", "dimension": 3, "gravity": [0, -9.81, 0],
    "bodies": [{"name": "rod", "mass": 1.2, "inertia": [0.01, 0.1, 0.1],
                "position": [0.5, 0, 0]}],
    "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "rod",
                "at": [0, 0, 0], "axis": [0, 0, 1]}],
}


def _turned(model: mbody.Model, theta: float, omega: float) -> np.ndarray:
    """The rod turned by theta about the pin (world z) at rate omega."""
    s = model.initial
    c, si = math.cos(theta), math.sin(theta)
    return state_vector(model, s.replace(
        position=np.array([[0.5 * c, 0.5 * si, 0.0]]), quaternion=_quat_z(theta)[None],
        velocity=np.array([[-0.5 * si * omega, 0.5 * c * omega, 0.0]]),
        omega=np.array([[0.0, 0.0, omega]])))


def test_turn_is_continuous_across_pi_and_takes_its_law():
    """A driven pin: the law f(t) = θ(t) − 0.2 keeps φ at 0.2 while θ crosses ±π (the
    raw angle jumps by 2π there); φ − f, Gᵀ v − f', γ + f'' against the undriven TURN;
    and the prescribed acceleration through the solve."""
    model = mbody.load(PIN)
    f = compile_expression("3*t - 0.2")
    law = (f, compile_expression("3"), compile_expression("0"))
    free = Component(0, _core.KIND_TURN, 2)
    driven = Component(0, _core.KIND_TURN, 2, law=law)
    k = Kernel(model, (free, driven))
    for t in np.linspace(0.9, 1.2, 31):  # θ = 3 t crosses π at t = 1.047
        c = k.columns(t, _turned(model, 3 * t, 3.0))
        assert c["phi"][-1] == pytest.approx(0.2, abs=1e-14)
        raw = c["phi"][-2]  # the undriven angle, in (−π, π]
        assert -math.pi < raw <= math.pi
        assert raw == pytest.approx(math.remainder(3 * t, 2 * math.pi), abs=1e-14)
        assert c["gtv"][-1] == pytest.approx(c["gtv"][-2] - 3.0, abs=1e-14)
        assert c["gamma"][-1] == c["gamma"][-2]
    # a law with f'' ≠ 0, prescribed through the solve: α = f''(t) at a consistent state
    f = compile_expression("0.5*sin(2*t)")
    law = (f, compile_expression("cos(2*t)"), compile_expression("-2*sin(2*t)"))
    k = Kernel(model, (Component(0, _core.KIND_TURN, 2, law=law),))
    cu = k.unknowns(np.arange(k.m))
    N, lo, io = _core.solve_layout(1, k.m, False)
    out = np.zeros(io + _core.INFO)
    for t in (0.0, 0.4, 1.3):
        y = _turned(model, 0.5 * math.sin(2 * t), math.cos(2 * t))
        c = k.columns(t, y)
        assert np.max(np.abs(c["phi"])) <= 1e-15 and np.max(np.abs(c["gtv"])) <= 1e-15
        assert c["gamma"][-1] == pytest.approx(-2 * math.sin(2 * t), abs=1e-15)
        cu.solve(t, y, np.zeros(k.m), out)
        assert out[5] == pytest.approx(-2 * math.sin(2 * t), rel=1e-12, abs=1e-14)
        assert out[io + _core.ST_BROKEN] == 0


def test_derivative_and_project_follow_a_law():
    """The projection moves a driven pin onto its law at t (positions and velocities),
    and its homogeneous form onto Gᵀ v = 0."""
    model = mbody.load(PIN)
    f = compile_expression("0.5*sin(2*t)")
    law = (f, compile_expression("cos(2*t)"), compile_expression("-2*sin(2*t)"))
    k = Kernel(model, (Component(0, _core.KIND_TURN, 2, law=law),))
    cu = k.unknowns(np.arange(k.m))
    t = 0.7
    y = _turned(model, 0.5 * math.sin(2 * t) + 0.01, math.cos(2 * t) - 0.1)
    info = np.zeros(_core.PROJECT_INFO)
    cu.project(t, y, 5, 1e-6, False, info)
    want = _turned(model, 0.5 * math.sin(2 * t), math.cos(2 * t))
    assert rel(y[:13], want[:13]) <= 1e-12
    cu.project(t, y, 0, 1e-6, True, info)
    assert abs(y[12]) <= 1e-15  # the homogeneous velocity projection stops the pin
    ydot = np.zeros_like(y)
    assert cu.derivative(t, want, np.zeros(k.m), 10.0, ydot) == 0
    assert ydot[12] == pytest.approx(-2 * math.sin(2 * t), rel=1e-12)


# -- the bindings --------------------------------------------------------------------------------
def test_bad_buffers_are_clear_errors():
    model = mbody.load(MODELS[0].parent / "pendulum.yaml")
    F, I = pack_model(model)
    with pytest.raises(ValueError, match="F: expected a float64 array, got item format 'f'"):
        _core.Model(F.astype(np.float32), I, False)
    with pytest.raises(ValueError, match="I: expected a int64 array"):
        _core.Model(F, I.astype(np.int32), False)
    with pytest.raises(ValueError, match="do not add up"):
        _core.Model(F[:-1], I, False)
    bad = I.copy()
    bad[_core.I_HEADER] = 99  # a load on body 99
    if len(model.forces.names):
        with pytest.raises(ValueError, match="out of range"):
            _core.Model(F, bad, False)
    core = _core.Model(F, I, model.dimension == 2)
    out = np.empty((model.n, 6))
    y = state_vector(model, model.initial)
    with pytest.raises(ValueError, match=r"y: expected \d+ values \(the packed state\), got 5"):
        core.net_wrench(0.0, y[:5], out)
    with pytest.raises(ValueError, match="C-contiguous"):
        core.net_wrench(0.0, y, np.empty(12 * model.n)[::2])
    with pytest.raises(ValueError, match="out: expected 6 values"):
        core.net_wrench(0.0, y, np.empty(7))
    Iu = pack_unknowns(model, np.arange(len(model.reactions)))
    Iu[1] = 5  # a band wider than S
    with pytest.raises(ValueError, match="Iu does not describe"):
        _core.Unknowns(core, Iu)
    assert _core.solve_layout(2, 3, True) == (6, 6, 15)


@pytest.mark.parametrize("dimension", [2, 3])
def test_more_unknowns_than_rows_equal_numba(dimension):
    """A bar pinned to the ground twice and a second bar hung from it (redundant: more
    unknowns than the first bar's rows), through the null-space route (planar) or the
    pivoted one (spatial), and the null-space projection (its SVD of a wide matrix)."""
    C = numba()
    at = [[0, 0], [1, 0], [1, 0]] if dimension == 2 else [[0, 0, 0], [1, 0, 0], [1, 0, 0]]
    pos = [[0.5, 0], [1.5, 0.2]] if dimension == 2 else [[0.5, 0, 0], [1.5, 0.2, 0]]
    spec = {"model": "twice", "dimension": dimension,
            "gravity": [0, -9.81] + ([0] if dimension == 3 else []),
            "bodies": [{"name": "bar", "mass": 1.0, "inertia": 0.1 if dimension == 2
                        else [0.01, 0.1, 0.1], "position": pos[0]},
                       {"name": "arm", "mass": 0.5, "inertia": 0.05 if dimension == 2
                        else [0.01, 0.05, 0.05], "position": pos[1]}],
            "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "bar",
                        "at": at[0]},
                       {"name": "P", "type": "revolute", "parent": "ground", "child": "bar",
                        "at": at[1]},
                       {"name": "Q", "type": "revolute", "parent": "bar", "child": "arm",
                        "at": at[2]}]}
    if dimension == 3:
        for j in spec["joints"]:
            j["axis"] = [0, 0, 1]
    model = mbody.load(spec)
    k = Kernel(model)
    unk = model.plan.file_unknowns
    cu = k.unknowns(unk.U)
    y = state_vector(model, model.initial)
    a, b, N, io = solve_both(C, k, cu, unk.U, unk.lam, 0.0, y)
    assert b[io + _core.ST_RANK] < unk.U.size
    check_solve(a, b, N, io, len(model.reactions), k.cond(cu, 0.0, y))
    F0, I0 = C.pack_model(model)
    Iu0 = C.pack_unknowns(model, unk.U)
    moved = state_vector(model, moved_state(model, 3))
    y0 = y + 1e-3 * (moved - y)
    ya, yb = y0.copy(), y0.copy()
    ia, ib = np.zeros(4), np.zeros(4)
    C.project(F0, I0, Iu0, ya, k.planar, 3, 2.0, ia)
    cu.project(0.0, yb, 3, 2.0, False, ib)
    assert ib[_core.PR_SINGULAR] == ia[_core.PR_SINGULAR] == 0
    assert rel(yb - y0, ya - y0) <= 1e-10


def test_many_unknowns_are_band_ordered_and_equal_numba():
    """A chain of 16 rods on revolute joints (80 unknowns): pack_unknowns orders them
    by reverse Cuthill-McKee (S's half band stays that of a chain), the solve as numba's
    in label order."""
    C = numba()
    n = 16
    bodies = [{"name": f"r{i}", "mass": 1.0 + 0.1 * i, "inertia": [0.01, 0.1, 0.1],
               "position": [0.5 + i, 0, 0], "angular_velocity": [0, 0.3 * i, 0.5]}
              for i in range(n)]
    joints = [{"name": f"J{i}", "type": "revolute", "parent": "ground" if i == 0
               else f"r{i - 1}", "child": f"r{i}", "at": [float(i), 0, 0],
               "axis": [0, 1 if i % 2 else 0, 1]} for i in range(n)]
    model = mbody.load({"model": "chain", "dimension": 3, "gravity": [0, 0, -9.81],
                        "bodies": bodies, "joints": joints})
    k = Kernel(model)
    unk = model.plan.file_unknowns
    assert unk.U.size == 80
    cu = k.unknowns(unk.U)
    assert cu.bw < 10  # two joints' components (5 each) per body, whatever the labels
    y = state_vector(model, moved_state(model, 1))
    a, b, N, io = solve_both(C, k, cu, unk.U, unk.lam, 0.3, y)
    check_solve(a, b, N, io, len(model.reactions), k.cond(cu, 0.3, y))
