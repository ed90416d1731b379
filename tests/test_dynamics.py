"""`mbody.solve.dynamics.accelerations` and the kernels under `assemble`, against an independent
per-body computation (a Python loop over loads with scipy rotations), on seeded random
models, shipped models and the benchmark's model builder. No timing here."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
import randmodels as rm
from scipy.spatial.transform import Rotation

import mbody
from mbody import conventions as cv
from mbody.errors import MbodyError
from mbody.model import State
from mbody.solve import dynamics

ROOT = Path(__file__).resolve().parent.parent
TOL = 1e-9


def _bench():
    spec = importlib.util.spec_from_file_location("bench_assembly",
                                                  ROOT / "tools" / "bench_assembly.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("bench_assembly", mod)
    spec.loader.exec_module(mod)
    return mod


# -- the independent reference ------------------------------------------------------------
def reference_rows(model: mbody.Model, state: State) -> tuple[np.ndarray, np.ndarray]:
    """Per body, by hand: Q (n, 6) = [Σ W_f + m g; Σ B_r × Rᵀ W_f + couples] and
    b (n, 6) = [0; ω × J ω], from the model's load records (not its tables)."""
    n = model.n
    R = Rotation.from_quat(state.quaternion, scalar_first=True).as_matrix()
    Q, b = np.zeros((n, 6)), np.zeros((n, 6))
    for i in range(n):
        Q[i, :3] = model.mass[i] * model.gravity
        om = state.omega[i]
        b[i, 3:] = np.cross(om, model.J[i] @ om)
    vectors = dict(zip(model.forces.names, model.forces.vector_at(state.t), strict=True))
    for ld in model.loads:
        if ld.type in ("force", "torque"):
            i = model.index[ld.bodies[0]]
            v = vectors[ld.name]
            if ld.type == "torque":
                Q[i, 3:] += v if ld.frame == "body" else R[i].T @ v
                continue
            W_f = R[i] @ v if ld.frame == "body" else v
            r = ld.at[0] if ld.at else np.zeros(3)
            Q[i, :3] += W_f
            Q[i, 3:] += np.cross(r, R[i].T @ W_f)
        else:  # spring-damper
            ends = []
            for name, r in zip(ld.bodies, ld.at, strict=True):
                if name == cv.GROUND:
                    ends.append((None, r, np.zeros(3)))
                else:
                    j = model.index[name]
                    P = state.position[j] + R[j] @ r
                    V = state.velocity[j] + R[j] @ np.cross(state.omega[j], r)
                    ends.append((j, P, V))
            (ja, Pa, Va), (jb, Pb, Vb) = ends
            d = Pb - Pa
            L = np.linalg.norm(d)
            u = d / L
            T = ld.stiffness * (L - ld.rest_length) + ld.damping * (u @ (Vb - Va))
            for j, r, sign in ((ja, ld.at[0], 1.0), (jb, ld.at[1], -1.0)):
                if j is not None:
                    Q[j, :3] += sign * T * u
                    Q[j, 3:] += np.cross(r, R[j].T @ (sign * T * u))
    return Q, b


def reference_accelerations(model, state, G=None, lam=None) -> np.ndarray:
    """(n, 6) v̇ = M⁻¹ (Q + G λ − b) with dense 6×6 blocks."""
    Q, b = reference_rows(model, state)
    rhs = Q - b
    if lam is not None and len(lam):
        rhs = rhs + _rows(model, G.toarray() @ lam)
    out = np.empty_like(rhs)
    for i in range(model.n):
        Mi = np.zeros((6, 6))
        Mi[:3, :3] = model.mass[i] * np.eye(3)
        Mi[3:, 3:] = model.J[i]
        out[i] = np.linalg.solve(Mi, rhs[i])
    return out


def random_state(model: mbody.Model, seed: int, t: float = 0.0) -> State:
    """A state away from the initial one (planar models stay planar)."""
    rng = np.random.default_rng(seed)
    n = model.n
    if model.dimension == cv.PLANAR:
        return State.planar(rng.normal(size=(n, 2)), rng.uniform(-3, 3, n),
                            rng.normal(size=(n, 2)), rng.normal(size=n), t)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return State(rng.normal(size=(n, 3)), q, rng.normal(size=(n, 3)),
                 rng.normal(scale=2, size=(n, 3)), t)


def _rows(model, flat: np.ndarray) -> np.ndarray:
    """Flat stacked vector -> (n, 6) per-body rows (planar rows padded with 0)."""
    if model.dimension == cv.SPATIAL:
        return flat.reshape(-1, 6)
    out = np.zeros((model.n, 6))
    out[:, cv.PLANAR_SELECT] = flat.reshape(-1, 3)
    return out


def _known(asm) -> np.ndarray:
    values = asm.reaction_values()
    return np.array([values[r] for r in asm.reactions])


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("kind", ["spatial", "planar"])
def test_matches_reference_on_random_models(seed, kind):
    d = (rm.spatial_model(seed, n=7, n_forces=14, n_torques=6, n_springs=3)
         if kind == "spatial" else rm.planar_model(seed, n=6, n_forces=9, n_springs=3))
    model = mbody.load(d)
    for state in (model.initial, random_state(model, seed + 100)):
        asm = mbody.assemble(model, state)
        lam = _known(asm)
        expect = reference_accelerations(model, state, asm.G, lam)
        got = dynamics.accelerations(model, state, lam)
        assert got.shape == (model.n, 6)
        np.testing.assert_allclose(got, expect, rtol=TOL, atol=TOL)
        keep = np.arange(6) if kind == "spatial" else cv.PLANAR_SELECT
        np.testing.assert_allclose(asm.solve().accelerations, expect[:, keep].ravel(),
                                   rtol=TOL, atol=TOL)
        Q, b = reference_rows(model, state)
        if kind == "planar":
            Q[:, [2, 3, 4]] = 0.0  # rows a planar body does not have
            b[:] = 0.0
        np.testing.assert_allclose(_rows(model, asm.Q), Q, rtol=TOL, atol=TOL)
        np.testing.assert_allclose(_rows(model, asm.b), b, rtol=TOL, atol=TOL)


def test_no_reactions_means_zero_reaction_forces():
    model = mbody.load(rm.spatial_model(3, n=5))
    state = random_state(model, 3)
    np.testing.assert_allclose(dynamics.accelerations(model, state),
                               reference_accelerations(model, state), rtol=TOL, atol=TOL)


def test_diagonal_and_asymmetric_inertia_storage():
    """Principal-axis bodies and a tensor that is symmetric only to the validator's
    tolerance both match the reference."""
    d = rm.spatial_model(4, n=4, n_joints=0)
    for b in d["bodies"]:
        b["inertia"] = rm._f(rm.box_principal(np.random.default_rng(1), b["mass"]))
    model = mbody.load(d)
    state = random_state(model, 4)
    np.testing.assert_allclose(dynamics.accelerations(model, state),
                               reference_accelerations(model, state), rtol=TOL, atol=TOL)
    d = rm.spatial_model(5, n=4, n_joints=0)
    J = np.array(d["bodies"][0]["inertia"])
    J[0, 1] += 1e-9 * np.abs(J).max()
    d["bodies"][0]["inertia"] = [rm._f(r) for r in J]
    model = mbody.load(d)
    state = random_state(model, 5)
    np.testing.assert_allclose(dynamics.accelerations(model, state),
                               reference_accelerations(model, state), rtol=TOL, atol=TOL)


@pytest.mark.parametrize("name", ["spinning_disc_bearings", "slider_crank",
                                  "rotor_gyroscopic_bearings", "practice_2_flywheel"])
def test_known_reactions_on_shipped_models(name, models_dir):
    """The file's known values, and made-up values for the components it leaves unknown."""
    model = mbody.load(models_dir / f"{name}.yaml")
    asm = mbody.assemble(model)
    values = asm.reaction_values()
    rng = np.random.default_rng(0)
    given = {r: float(rng.normal(scale=10)) for r in asm.reactions if r not in values}
    values.update(given)
    lam = np.array([values[r] for r in asm.reactions])
    expect = reference_accelerations(model, model.initial, asm.G, lam)
    got = dynamics.accelerations(model, model.initial, lam)
    np.testing.assert_allclose(got, expect, rtol=TOL, atol=TOL)
    sol = asm.solve(known=given)
    keep = np.arange(6) if model.dimension == cv.SPATIAL else cv.PLANAR_SELECT
    np.testing.assert_allclose(sol.accelerations, got[:, keep].ravel(), rtol=TOL, atol=TOL)


def test_spinning_disc_bearings_by_hand(models_dir):
    """Disc: weight 98.1 N down, bearing forces 91.2375 + 6.8625 = 98.1 N up: a_G = 0.
    Steady precession: the spin axis (world x) turns with the frame at Ω = 0.5 about
    world z, so ω̇ = Ω ẑ × 300 x̂ = 150 ŷ (world y = body axis 1): ω̇ = (150, 0, 0)."""
    model = mbody.load(models_dir / "spinning_disc_bearings.yaml")
    asm = mbody.assemble(model)
    values = asm.reaction_values()  # the bearings' (A, B) values are given in the file
    assert all(f"{j}.F{c}" in values for j in "AB" for c in "xyz")
    # The turntable's (T) act on the frame only: any values leave the disc's rows alone.
    lam = np.array([values.get(r, 123.0) for r in asm.reactions])
    acc = dynamics.accelerations(model, model.initial, lam)
    disc = model.index["disc"]
    np.testing.assert_allclose(acc[disc], [0, 0, 0, 150, 0, 0], atol=1e-9)


def test_time_varying_loads_are_taken_at_state_t(models_dir):
    """Plate: m = 2, F_x = 50 sin 2t at G, couple 0.5 cos 3t, gravity −9.81."""
    model = mbody.load(models_dir / "planar_time_varying_force.yaml")
    for t in (0.0, 0.3, 1.1, 0.3):  # revisiting t reuses or rebuilds the cached sums
        acc = dynamics.accelerations(model, model.initial.replace(t=t))
        np.testing.assert_allclose(acc[0], [25 * np.sin(2 * t), -9.81, 0, 0, 0,
                                            0.5 * np.cos(3 * t) / 0.1], atol=1e-12)
        sol = mbody.assemble(model, model.initial.replace(t=t)).solve()
        np.testing.assert_allclose(sol.accelerations, acc[0, cv.PLANAR_SELECT], atol=1e-12)


def test_out_buffer_in_any_layout_and_bad_reactions():
    model = mbody.load(rm.spatial_model(7, n=5))
    state = random_state(model, 7)
    asm = mbody.assemble(model, state)
    lam = _known(asm)
    fresh = dynamics.accelerations(model, state, lam)
    for out in (np.full((5, 6), np.nan), np.full((6, 5), np.nan).T):
        got = dynamics.accelerations(model, state, lam, out=out)
        assert got is out
        np.testing.assert_array_equal(got, fresh)
    with pytest.raises(MbodyError, match="expected"):
        dynamics.accelerations(model, state, lam[:-1])


def test_derivative_packs_velocity_quaternion_rate_and_accelerations():
    model = mbody.load(rm.spatial_model(8, n=4, n_joints=0))
    state = random_state(model, 8)
    y = dynamics.pack(state)
    back = dynamics.unpack(y, state.t)
    for a, b in ((back.position, state.position), (back.quaternion, state.quaternion),
                 (back.velocity, state.velocity), (back.omega, state.omega)):
        np.testing.assert_array_equal(a, b)
    yd = dynamics.derivative(model, state).reshape(-1, 13)
    np.testing.assert_array_equal(yd[:, 0:3], state.velocity)
    np.testing.assert_allclose(yd[:, 7:13], reference_accelerations(model, state),
                               rtol=TOL, atol=TOL)
    # q̇ against a central difference of q(h) = q ⊗ exp(ω h / 2) (ω constant, body axes).
    h = 1e-6
    rot = Rotation.from_quat(state.quaternion, scalar_first=True)
    step = lambda s: (rot * Rotation.from_rotvec(state.omega * s)).as_quat(  # noqa: E731
        scalar_first=True)
    qp, qm = step(h), step(-h)
    sign = np.sign(np.sum(qp * state.quaternion, axis=1, keepdims=True))
    np.testing.assert_allclose(yd[:, 3:7], sign * (qp - qm) / (2 * h), atol=1e-7)


def test_mass_matrix_blocks():
    for d in (rm.spatial_model(9, n=3), rm.planar_model(9, n=3)):
        model = mbody.load(d)
        M = mbody.assemble(model).M.toarray()
        k = model.rows_per_body
        for i in range(model.n):
            block = np.zeros((6, 6))
            block[:3, :3] = model.mass[i] * np.eye(3)
            block[3:, 3:] = model.J[i]
            keep = np.arange(6) if k == 6 else cv.PLANAR_SELECT
            np.testing.assert_array_equal(M[i * k:(i + 1) * k, i * k:(i + 1) * k],
                                          block[np.ix_(keep, keep)])
        assert M.shape == (k * model.n, k * model.n)
        assert np.count_nonzero(M) == sum(np.count_nonzero(
            M[i * k:(i + 1) * k, i * k:(i + 1) * k]) for i in range(model.n))


def test_contributions_are_lazy_and_sum_to_Q():
    model = mbody.load(rm.spatial_model(10, n=5))
    state = random_state(model, 10)
    loads = mbody.assemble(model, state).loads
    assert "contributions" not in loads.__dict__
    c = loads.contributions
    W_F = np.zeros((model.n, 3))
    B_M = np.zeros((model.n, 3))
    on = c.body >= 0
    np.add.at(W_F, c.body[on], c.W_f[on])
    np.add.at(B_M, c.body[on], c.B_m[on])
    np.testing.assert_allclose(W_F + model.mass[:, None] * model.gravity, loads.W_F,
                               rtol=TOL, atol=TOL)
    np.testing.assert_allclose(B_M, loads.B_M, rtol=TOL, atol=TOL)


# -- the benchmark's model ------------------------------------------------------------------
def test_benchmark_builder_matches_the_file_path_and_a_hand_computation():
    bench = _bench()
    n = 40
    built = bench.free_bodies(n, seed=3)
    loaded = mbody.load(bench.free_bodies_spec(n, seed=3))
    assert built.body_names == loaded.body_names and built.n == n
    for a, b in ((built.mass, loaded.mass), (built.J, loaded.J), (built.gravity, loaded.gravity),
                 (built.forces.vector, loaded.forces.vector), (built.forces.B_r, loaded.forces.B_r),
                 (built.forces.body, loaded.forces.body),
                 (built.initial.position, loaded.initial.position),
                 (built.initial.velocity, loaded.initial.velocity),
                 (built.initial.omega, loaded.initial.omega)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(built.initial.quaternion, loaded.initial.quaternion, atol=1e-12)
    assert not built.forces.in_body.any() and not built.forces.couple.any()
    assert np.all(np.linalg.norm(built.forces.B_r, axis=1) > 0)  # every force is offset

    # By hand, per body: a = f/m + g; ω̇ = J⁻¹ (r × Rᵀ f − ω × J ω).
    st = built.initial
    expect = np.empty((n, 6))
    for i in range(n):
        R = Rotation.from_quat(st.quaternion[i], scalar_first=True).as_matrix()
        f, r, om, J = built.forces.vector[i], built.forces.B_r[i], st.omega[i], built.J[i]
        expect[i, :3] = f / built.mass[i] + np.array([0, 0, -9.81])
        expect[i, 3:] = np.linalg.solve(J, np.cross(r, R.T @ f) - np.cross(om, J @ om))
    for model in (built, loaded):
        np.testing.assert_allclose(dynamics.accelerations(model, model.initial), expect,
                                   rtol=TOL, atol=TOL)
        np.testing.assert_allclose(mbody.assemble(model).solve().accelerations,
                                   expect.ravel(), rtol=TOL, atol=TOL)
    np.testing.assert_allclose(bench.naive_step(built, st), expect, rtol=TOL, atol=TOL)
    np.testing.assert_allclose(bench.naive_assemble_solve(built, st), expect.ravel(),
                               rtol=TOL, atol=TOL)


def test_benchmark_mujoco_model_matches():
    pytest.importorskip("mujoco")
    bench = _bench()
    model = bench.free_bodies(20, seed=4)
    m, d = bench.mujoco_setup(model, model.initial)
    np.testing.assert_allclose(bench.mujoco_accelerations(m, d),
                               dynamics.accelerations(model, model.initial),
                               rtol=1e-8, atol=1e-8)
