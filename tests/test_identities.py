"""Identities on seeded random models (spatial_v2's UnitTest style).

Every expected value is recomputed from the model dict and the state with scipy and the
contract's rules, never read back from mbody: M symmetric positive definite with the
file's masses and inertias; ω·b = 0; Newton's third law per joint column; Gᵀv equals the
relative velocity (and angular velocity) each joint forbids; results do not depend on
the order of the bodies; rotating the whole model rotates the results.

Tolerances: 1e-10 relative to the size of the quantities compared (all inputs are O(1)
to O(10), so this is about 10⁴ ulps: loose enough for rounding, far too tight for a
wrong sign, frame or lever arm).
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from randmodels import COMPONENTS, planar_model, rotation_of, spatial_model
from scipy.spatial.transform import Rotation

import mbody
from mbody.model import State

SEEDS = range(8)
TOL = 1e-10


def _close(a, b, scale: float = 1.0):
    a, b = np.asarray(a, float), np.asarray(b, float)
    s = max(scale, float(np.max(np.abs(b), initial=0.0)), 1.0)
    np.testing.assert_allclose(a, b, rtol=0, atol=TOL * s)


def _models() -> list:
    out = []
    for s in SEEDS:
        out.append(pytest.param(spatial_model(s, 5, n_joints=8), id=f"spatial{s}"))
        out.append(pytest.param(planar_model(s, 4, n_joints=6), id=f"planar{s}"))
    return out


# -- independent kinematics ------------------------------------------------------------

def _v3(x, d):
    x = np.asarray(x, float)
    return np.append(x, 0.0) if d == 2 else x


def _initial(spec: dict) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) initial positions and (n, 3, 3) W_R_B from the dict."""
    d = spec["dimension"]
    x0 = np.array([_v3(b.get("position", [0.0] * d), d) for b in spec["bodies"]])
    if d == 2:
        th = [[b.get("angle", 0.0)] for b in spec["bodies"]]
        R0 = Rotation.from_euler("z", th).as_matrix()
    else:
        R0 = np.array([rotation_of(b) for b in spec["bodies"]])
    return x0, R0


def _frame(axis, d) -> np.ndarray:
    """Contract section 4: the joint frame at the initial pose, axes as columns."""
    if d == 2:
        x = np.array([1.0, 0, 0]) if axis is None else _v3(axis, 2) / np.linalg.norm(axis)
        return np.column_stack((x, [-x[1], x[0], 0.0], [0, 0, 1.0]))
    z = np.array([0, 0, 1.0]) if axis is None else np.asarray(axis, float)
    z = z / np.linalg.norm(z)
    i = int(np.argmin(np.abs(z)))
    x = np.eye(3)[i] - z[i] * z
    x /= np.linalg.norm(x)
    return np.column_stack((x, np.cross(z, x), z))


def _random_state(spec: dict, rng) -> State:
    n, d = len(spec["bodies"]), spec["dimension"]
    if d == 2:
        th = rng.uniform(-3, 3, n)
        w = rng.normal(size=n)
        return State.planar(rng.normal(size=(n, 2)), th, rng.normal(size=(n, 2)), w)
    q = Rotation.random(n, random_state=rng).as_quat(scalar_first=True)
    return State(rng.normal(size=(n, 3)), q, rng.normal(size=(n, 3)),
                 rng.normal(size=(n, 3)))


def _stacked_velocity(state: State, d: int) -> np.ndarray:
    six = np.hstack((state.velocity, state.omega))
    return six[:, [0, 1, 5]].ravel() if d == 2 else six.ravel()


def _forbidden_velocities(spec: dict, state: State) -> tuple[list[str], np.ndarray]:
    """Per reaction label: the relative velocity along the constrained direction.

    Force components: e · (V_child(P) − V_parent(P)), P the child's attachment point and
    V_parent(P) the velocity of the parent's material point at the same place; moment
    components: e · (ω_child − ω_parent); e the joint axis carried by the parent."""
    d = spec["dimension"]
    idx = {b["name"]: i for i, b in enumerate(spec["bodies"])}
    x0, R0 = _initial(spec)
    R = Rotation.from_quat(state.quaternion, scalar_first=True).as_matrix()
    x, v = state.position, state.velocity
    w = np.einsum("nij,nj->ni", R, state.omega)  # world angular velocities
    labels, out = [], []
    for j in spec["joints"]:
        c, p = idx[j["child"]], idx.get(j["parent"], -1)
        at = _v3(j["at"], d)
        B_r = R0[c].T @ (at - x0[c])
        P = x[c] + R[c] @ B_r
        Vc, wc = v[c] + np.cross(w[c], P - x[c]), w[c]
        if p >= 0:
            Vp, wp = v[p] + np.cross(w[p], P - x[p]), w[p]
            carry = R[p] @ R0[p].T
        else:
            Vp, wp, carry = np.zeros(3), np.zeros(3), np.eye(3)
        E = carry @ _frame(j.get("axis"), d)
        for comp in COMPONENTS[d][j["type"]]:
            labels.append(f"{j['name']}.{comp}")
            if comp == "Mt":
                a1 = carry @ np.asarray(j["axis"])
                a2 = R[c] @ R0[c].T @ np.asarray(j["axis2"])
                e = np.cross(a1, a2)
                out.append(e @ (wc - wp) / np.linalg.norm(e))
            else:
                k = "xyz".index(comp[1])
                rel = Vc - Vp if comp[0] == "F" else wc - wp
                out.append(E[:, k] @ rel)
    return labels, np.array(out)


# -- the identities ----------------------------------------------------------------------

@pytest.mark.parametrize("spec", _models())
def test_mass_matrix_symmetric_positive_definite(spec):
    model = mbody.load(spec)
    M = mbody.assemble(model).M.toarray()
    assert np.array_equal(M, M.T)
    assert np.linalg.eigvalsh(M).min() > 0
    for i, b in enumerate(spec["bodies"]):
        if spec["dimension"] == 2:
            expected = np.diag([b["mass"], b["mass"], b["inertia"]])
            blk = M[3 * i:3 * i + 3, 3 * i:3 * i + 3]
        else:
            J = np.array(b["inertia"], float)
            J = np.diag(J) if J.ndim == 1 else J
            expected = np.zeros((6, 6))
            expected[:3, :3] = b["mass"] * np.eye(3)
            expected[3:, 3:] = J
            blk = M[6 * i:6 * i + 6, 6 * i:6 * i + 6]
        np.testing.assert_allclose(blk, expected, rtol=1e-14, atol=1e-14)
    # block diagonal: nothing outside the blocks
    k = 3 if spec["dimension"] == 2 else 6
    mask = np.kron(np.eye(len(spec["bodies"])), np.ones((k, k))) == 0
    assert np.all(M[mask] == 0)


@pytest.mark.parametrize("seed", SEEDS)
def test_gyroscopic_vector_orthogonal_to_omega(seed):
    spec = spatial_model(seed, 6)
    model = mbody.load(spec)
    rng = np.random.default_rng(100 + seed)
    state = _random_state(spec, rng)
    b = mbody.assemble(model, state).b.reshape(-1, 6)
    assert np.all(b[:, :3] == 0)
    for i, body in enumerate(spec["bodies"]):
        J = np.array(body["inertia"], float)
        J = np.diag(J) if J.ndim == 1 else J
        w = state.omega[i]
        _close(b[i, 3:], np.cross(w, J @ w))
        assert abs(w @ b[i, 3:]) <= TOL * np.linalg.norm(w) * np.linalg.norm(b[i, 3:]) + 1e-14


@pytest.mark.parametrize("spec", _models())
def test_third_law_per_joint_column(spec):
    """Each column: child half = +(force e at P, or couple e), parent half = its negative,
    so Newton rows sum to zero and the total moment about any point is zero."""
    d = spec["dimension"]
    model = mbody.load(spec)
    rng = np.random.default_rng(7)
    state = _random_state(spec, rng)
    asm = mbody.assemble(model, state)
    G = asm.G.toarray()
    R = Rotation.from_quat(state.quaternion, scalar_first=True).as_matrix()
    x = state.position
    k = 3 if d == 2 else 6
    O = rng.normal(size=3) * 3  # any common point
    idx = {b["name"]: i for i, b in enumerate(spec["bodies"])}
    col = 0
    for j in spec["joints"]:
        c, p = idx[j["child"]], idx.get(j["parent"], -1)
        for _comp in COMPONENTS[d][j["type"]]:
            F_tot, M_tot = np.zeros(3), np.zeros(3)
            halves = [c] if p < 0 else [c, p]
            for i in halves:
                rows = G[k * i:k * i + k, col]
                if d == 2:
                    F, M_body = np.array([rows[0], rows[1], 0.0]), np.array([0, 0, rows[2]])
                else:
                    F, M_body = rows[:3], rows[3:]
                M_G = R[i] @ M_body  # moment about the mass centre, world axes
                F_tot += F
                M_tot += M_G + np.cross(x[i] - O, F)
            # nothing else touched
            others = np.delete(G[:, col].reshape(-1, k), halves, axis=0)
            assert np.all(others == 0)
            if p >= 0:
                _close(F_tot, np.zeros(3))
                _close(M_tot, np.zeros(3))
            assert np.count_nonzero(G[:, col]) > 0
            col += 1
    assert col == G.shape[1]


@pytest.mark.parametrize("spec", _models())
def test_G_transpose_v_is_forbidden_relative_velocity(spec):
    """Gᵀ v against the joint kinematics computed from the state; 24 random velocity sets
    at each configuration pin every entry of G (Gᵀ is linear in v)."""
    d = spec["dimension"]
    model = mbody.load(spec)
    rng = np.random.default_rng(11)
    for _ in range(2):  # two configurations away from the initial pose
        base = _random_state(spec, rng)
        G = mbody.assemble(model, base).G
        for _ in range(24):
            s = _random_state(spec, rng)
            state = base.replace(velocity=s.velocity, omega=s.omega)
            labels, expected = _forbidden_velocities(spec, state)
            assert labels == model.reactions
            _close(G.T @ _stacked_velocity(state, d), expected, scale=10.0)


@pytest.mark.parametrize("spec", _models())
def test_G_transpose_v_at_initial_state(spec):
    """At the file's own state too (joint point = `at`, frames exactly as in section 4)."""
    model = mbody.load(spec)
    asm = mbody.assemble(model)
    labels, expected = _forbidden_velocities(spec, model.initial)
    assert labels == asm.reactions
    _close(asm.G.T @ _stacked_velocity(model.initial, spec["dimension"]), expected, 10.0)


@pytest.mark.parametrize("spec", _models())
def test_independent_of_body_order(spec):
    d = spec["dimension"]
    k = 3 if d == 2 else 6
    rng = np.random.default_rng(3)
    perm = rng.permutation(len(spec["bodies"]))
    while np.all(perm == np.arange(len(perm))):
        perm = rng.permutation(len(spec["bodies"]))
    shuffled = copy.deepcopy(spec)
    shuffled["bodies"] = [spec["bodies"][i] for i in perm]
    a1 = mbody.assemble(mbody.load(spec))
    a2 = mbody.assemble(mbody.load(shuffled))
    assert a1.reactions == a2.reactions
    acc1 = a1.solve().accelerations.reshape(-1, k)
    acc2 = a2.solve().accelerations.reshape(-1, k)
    G1, G2 = a1.G.toarray().reshape(-1, k, G1c := a1.G.shape[1]), a2.G.toarray()
    G2 = G2.reshape(-1, k, G1c)
    for new, old in enumerate(perm):
        name = spec["bodies"][old]["name"]
        assert a2.coordinates[k * new].startswith(name + ".")
        _close(acc2[new], acc1[old], 10.0)
        _close(a2.Q.reshape(-1, k)[new], a1.Q.reshape(-1, k)[old], 10.0)
        _close(a2.b.reshape(-1, k)[new], a1.b.reshape(-1, k)[old], 10.0)
        _close(G2[new], G1[old])
    assert not np.allclose(acc1, acc1[perm])  # the permutation really moved bodies


def _rotate_spec(spec: dict, Rw: np.ndarray) -> dict:
    """The same model turned by Rw as a whole (Rw about z in 2-D)."""
    d = spec["dimension"]
    out = copy.deepcopy(spec)

    def rot(v):
        return (Rw @ _v3(v, d))[:d].tolist()

    phi = float(np.arctan2(Rw[1, 0], Rw[0, 0]))
    for b in out["bodies"]:
        b["position"], b["velocity"] = rot(b["position"]), rot(b["velocity"])
        if d == 2:
            b["angle"] = b["angle"] + phi
        else:
            b["orientation"] = {"matrix": (Rw @ rotation_of(b)).tolist()}
    for ld in out["loads"]:
        if ld["type"] == "spring":
            ld["at"] = [rot(p) if body == "ground" else p
                        for body, p in zip(ld["bodies"], ld["at"], strict=True)]
        elif ld.get("frame", "world") == "world" and not (d == 2 and ld["type"] == "torque"):
            key = ld["type"]
            ld[key] = rot(ld[key])
    for j in out["joints"]:
        j["at"] = rot(j["at"])
        for key in ("axis", "axis2"):
            if key in j:
                j[key] = rot(j[key])
    out["gravity"] = rot(spec["gravity"])
    return out


@pytest.mark.parametrize("spec", _models())
def test_rotating_the_model_rotates_the_results(spec):
    """Newton rows turn with the model; Euler rows (body axes) are unchanged. Joint frames
    follow a fixed world rule, so each joint's columns are compared as a subspace, and the
    reactions are carried over as the same physical wrench."""
    d = spec["dimension"]
    k = 3 if d == 2 else 6
    rng = np.random.default_rng(5)
    Rw = (Rotation.from_euler("z", rng.uniform(0.3, 6)).as_matrix() if d == 2
          else Rotation.random(random_state=rng).as_matrix())
    turned = _rotate_spec(spec, Rw)
    a1 = mbody.assemble(mbody.load(spec))
    a2 = mbody.assemble(mbody.load(turned))

    def back(x):  # rows of the turned model expressed in the original world axes
        x = np.array(x, float).reshape(len(spec["bodies"]), k, -1)
        if d == 2:
            x[:, :2] = np.einsum("ji,njc->nic", Rw[:2, :2], x[:, :2])
        else:
            x[:, :3] = np.einsum("ji,njc->nic", Rw, x[:, :3])
        return x.reshape(-1, x.shape[-1])

    _close(back(a2.Q), a1.Q.reshape(-1, 1), 10.0)
    _close(back(a2.b), a1.b.reshape(-1, 1), 10.0)

    G1, G2 = a1.G.toarray(), back(a2.G.toarray())
    lam1 = np.array([spec["reactions"][r] for r in a1.reactions])
    lam2 = np.empty_like(lam1)
    start = 0
    for j in spec["joints"]:
        m = len(COMPONENTS[d][j["type"]])
        cols = slice(start, start + m)
        X, *_ = np.linalg.lstsq(G2[:, cols], G1[:, cols], rcond=None)
        _close(G2[:, cols] @ X, G1[:, cols])  # same subspace
        _close(X.T @ X, np.eye(m))  # related by an orthogonal change of frame
        lam2[cols] = X @ lam1[cols]
        start += m
    known2 = dict(zip(a2.reactions, lam2.tolist(), strict=True))
    acc1 = a1.solve().accelerations
    acc2 = a2.solve(known=known2).accelerations
    _close(back(acc2), acc1.reshape(-1, 1), 100.0)


@pytest.mark.parametrize("spec", _models())
def test_free_body_diagrams_add_up_to_the_equations(spec):
    """Per body: Σ forces on the diagram = Newton rows of Q + Gλ; Σ moments about G =
    Euler rows; each force's moment is B_r × (Rᵀ W_f); each point is x + R B_r; the
    written equations hold with the solved accelerations."""
    d = spec["dimension"]
    k = 3 if d == 2 else 6
    model = mbody.load(spec)
    state = _random_state(spec, np.random.default_rng(21))
    asm = mbody.assemble(model, state)
    lam = np.array([spec["reactions"][r] for r in asm.reactions])
    rhs = (asm.Q + asm.G @ lam).reshape(-1, k)
    R = Rotation.from_quat(state.quaternion, scalar_first=True).as_matrix()
    sol = asm.solve()
    acc = dict(zip(asm.coordinates, sol.accelerations, strict=True))
    for i, name in enumerate(model.body_names):
        be = asm.bodies[name]
        F, M = np.zeros(3), np.zeros(3)
        for f in be.fbd.forces:
            _close(f.W_point, state.position[i] + R[i] @ f.B_r, 10.0)
            if f.couple:
                _close(f.B_moment, R[i].T @ f.W_vector, 10.0)
            else:
                F += f.W_vector
                _close(f.B_moment, np.cross(f.B_r, R[i].T @ f.W_vector), 10.0)
            M += f.B_moment
        newton = rhs[i, :2] if d == 2 else rhs[i, :3]
        euler = rhs[i, 2:] if d == 2 else rhs[i, 3:]
        _close(F[:len(newton)], newton, 100.0)
        _close(M[2:] if d == 2 else M, euler, 100.0)
        n_reac = sum(1 for j in spec["joints"] for _ in COMPONENTS[d][j["type"]]
                     if name in (j["parent"], j["child"]))
        assert len(be.fbd.reactions) == n_reac
        for eq in be.equations:
            lhs = sum(c * acc[f"{name}.{_row_of(eq, a)}"] for a, c in eq.lhs.items()) + eq.gyro
            r = eq.rhs + sum(c * eq.known.get(lbl, spec["reactions"][lbl])
                             for lbl, c in eq.reactions.items())
            assert lhs == pytest.approx(r, abs=TOL * 100)


def _row_of(eq, acc_name: str) -> str:
    names = {"a_x": "x", "a_y": "y", "a_z": "z", "alpha_1": "w1", "alpha_2": "w2",
             "alpha_3": "w3", "alpha": "theta"}
    return names[acc_name]


@pytest.mark.parametrize("spec", _models())
def test_per_step_path_equals_assembly(spec):
    """`mbody.solve.dynamics.accelerations` (the simulation's kernel: springs, offsets, couples,
    gravity, reactions) gives the same v̇ as `assemble(...).solve()` at a random state."""
    dynamics = pytest.importorskip("mbody.dynamics")
    d = spec["dimension"]
    model = mbody.load(spec)
    state = _random_state(spec, np.random.default_rng(31))
    asm = mbody.assemble(model, state)
    lam = np.array([spec["reactions"][r] for r in asm.reactions])
    ref = asm.solve().accelerations.reshape(-1, 3 if d == 2 else 6)
    fast = np.asarray(dynamics.accelerations(model, state, lam))
    if d == 2:
        assert np.all(fast[:, 2:5] == 0)
        fast = fast[:, [0, 1, 5]]
    _close(fast, ref, 100.0)
