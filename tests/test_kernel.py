"""The compiled core (`mbody.kernel._core`, C) on its own terms. (That it gives today's
results — what the numba and numpy paths it replaced gave — is tests/test_golden.py.)

Independent checks, which compare with no other implementation: Gᵀ v = dφ/dt by central
differences along random motions at the file's pose (where every joint holds, as the
identity needs for the rotation primitives), −γ = d(Gᵀ v)/dt at v̇ = 0 at any state,
Newton's third law on every column, each load's share summing to the net wrench with
gravity and the gyroscopic term (written out here), TURN's φ across ±π and its law's
terms, SCREW against a nut on a fixed screw, prescribed motion through a law, the four-bar
chain near flat against its closed form on the null-space route, a bar pinned twice
(redundant: more unknowns than rows), and the band order of many unknowns.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fourbar_chain import FourbarChain
from golden_models import all_models, chain16, moved_state, pinned_twice, state_vector
from randmodels import spatial_model

import mbody
from mbody.equations.pack import Component, pack_model, pack_unknowns
from mbody.kernel import _core
from mbody.model.expressions import compile_expression

MODELS = sorted((Path(__file__).resolve().parent.parent / "models").glob("*.yaml"))
EPS = np.finfo(float).eps
KINDS = ("planar", "spatial")



# -- helpers --------------------------------------------------------------------------------


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








def rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    if not a.size:
        return 0.0
    scale = max(float(np.max(np.abs(b))), 1e-300)
    return float(np.max(np.abs(a - b))) / scale


def tolerance(cond: float) -> float:
    return max(1e-12, 10.0 * cond * EPS)




ALL = [(name, model) for name, model in all_models()
       if not name.startswith(("fourbar-chain", "pinned", "chain16"))]
IDS = [i for i, _ in ALL]




# -- against the numba path ---------------------------------------------------------------------














# -- against the numpy path ---------------------------------------------------------------------


@pytest.mark.parametrize(("name", "model"), ALL, ids=IDS)
def test_load_wrenches_are_each_loads_share(name, model):
    """Each point load's and spring end's wrench, summed with gravity m g and the
    gyroscopic term ω × J ω (written out here), is net_wrench."""
    k = Kernel(model)
    state = moved_state(model, 4)
    y, t = state_vector(model, state), state.t
    kk, s = len(model.forces.names), len(model.springs.names)
    out = np.empty((kk + 2 * s, 7))
    k.core.load_wrenches(t, y, out)
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
    """Gᵀ v − f' = dφ/dt along random motions from the file's pose, where no joint has
    turned yet. A TURN about a random joint axis (`extras`) is an angle whose rate is its
    column's only there, where the joint has not turned about another axis: a model that
    load assembles (helical_chain, whose joints are a few mm apart in the file) starts
    from the file's pose too, not from the assembled one."""
    rng = np.random.default_rng(7)
    k = Kernel(model, extras(model, rng))
    s = model.initial if model.file_state is None else model.file_state
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



def incidence_by_sorting(child_all: np.ndarray, parent_all: np.ndarray, n: int,
                         U: np.ndarray) -> np.ndarray:
    """Iu as numpy made it before the core did (kernel.h's layout): the incidence sorted
    by (body, position in U), child side first, and bw from each body's first and last."""
    mu = len(U)
    pos = np.arange(mu)
    body = np.concatenate((child_all[U], parent_all[U]))
    side = np.concatenate((np.zeros(mu, np.int64), np.ones(mu, np.int64)))
    where = np.concatenate((pos, pos))
    keep = body >= 0
    body, side, where = body[keep], side[keep], where[keep]
    order = np.lexsort((where, body))
    body, side, where = body[order], side[order], where[order]
    inc_ptr = body.searchsorted(np.arange(n + 1))
    bw = max((int(where[inc_ptr[b + 1] - 1] - where[inc_ptr[b]]) for b in range(n)
              if inc_ptr[b + 1] > inc_ptr[b]), default=0)
    inc = np.stack((where, side), axis=1).ravel()
    return np.concatenate(([mu, bw, len(where)], U, inc_ptr, inc)).astype(np.int64)


@pytest.mark.parametrize("seed", range(40))
def test_the_cores_unknowns_array_is_the_sorted_incidence(seed):
    """`_core.pack_unknowns` (one pass in U's order) against the sort it replaced, on
    random mechanisms: some components to the ground, U any subset in any order."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 30))
    m = int(rng.integers(1, 120))
    child = rng.integers(0, n, m)
    parent = np.where(rng.random(m) < 0.3, -1, (child + rng.integers(1, n + 1, m)) % (n + 1) - 1)
    parent[parent == child] = -1  # a component joins two bodies, or a body to the ground
    U = rng.permutation(m)[:int(rng.integers(0, m + 1))]
    out = np.full(3 + 5 * len(U) + n + 1, -7, dtype=np.int64)
    used = _core.pack_unknowns(child, parent, n, U, out)
    np.testing.assert_array_equal(out[:used], incidence_by_sorting(child, parent, n, U))


def test_every_shipped_models_unknowns_array_is_the_sorted_incidence():
    for path in MODELS:
        model = mbody.load(path)
        U = np.arange(len(model.reactions))
        jt, joint = model.joint_table, model.reaction_table.joint
        np.testing.assert_array_equal(
            pack_unknowns(model, U),
            incidence_by_sorting(jt.child[joint], jt.parent[joint], model.n, U), path.name)


def test_the_cores_unknowns_array_refuses_what_it_cannot_hold():
    child, parent, U = np.array([0, 1]), np.array([-1, 0]), np.array([0, 1])
    with pytest.raises(ValueError, match=r"out: expected at least 3 \+ 5 mu \+ n \+ 1 "
                       r"values for n = 2 bodies and mu = 2 unknowns, got 15"):
        _core.pack_unknowns(child, parent, 2, U, np.empty(15, np.int64))
    none = np.zeros(0, np.int64)
    with pytest.raises(ValueError, match="out: expected at least"):  # no overflow to pass
        _core.pack_unknowns(none, none, 2**63 - 4, none, np.empty(8, np.int64))
    with pytest.raises(ValueError, match="n: expected n >= 0"):
        _core.pack_unknowns(none, none, -1, none, np.empty(8, np.int64))
    out = np.zeros(3 + 5 * 50 + 2, np.int64)  # an input inside out: refused, not read
    with pytest.raises(ValueError, match="shares memory"):
        _core.pack_unknowns(out[60:110], np.full(50, -1), 1, np.arange(50), out)
    for c, p, u, n in [([0, 2], [-1, 0], [0, 1], 2), ([0, 1], [-1, -2], [0, 1], 2),
                       ([0, 1], [-1, 0], [0, 2], 2)]:
        with pytest.raises(ValueError, match="index out of range"):
            _core.pack_unknowns(np.array(c), np.array(p), n, np.array(u),
                                np.empty(40, np.int64))
    with pytest.raises(ValueError, match="parent: expected 2 values"):
        _core.pack_unknowns(child, parent[:1], 2, U, np.empty(40, np.int64))





def file_unknowns(k: Kernel) -> tuple[_core.Unknowns, np.ndarray]:
    """The core's unknowns of the file's known values, and lam."""
    model = k.model
    known = model.known_reactions
    lam = np.array([known.get(r, 0.0) for r in model.reactions])
    U = np.array([i for i, r in enumerate(model.reactions) if r not in known], dtype=int)
    return k.unknowns(U), lam


@pytest.mark.parametrize("theta", [1e-4, 1e-6, 1e-8])
def test_four_bar_chain_near_flat_takes_the_null_space_route_and_its_closed_form(theta):
    chain = FourbarChain(crank=0.25, spacing=0.5, width=0.03125)
    model = mbody.loads(chain.yaml(theta, 1.5))
    k = Kernel(model)
    cu, lam = file_unknowns(k)
    y = state_vector(model, model.initial)
    m = len(model.reactions)
    N, lo, io = _core.solve_layout(model.n, m, k.planar)
    out = np.zeros(io + _core.INFO)
    cu.solve(0.0, y, lam, out)
    assert out[io + _core.ST_PATH] == 1  # the null-space route
    assert out[io + _core.ST_RANK] == cu.mu  # near flat, no constraint is redundant
    assert rel(out[:N], chain.accelerations(theta, 1.5).ravel()) <= 1e-9


@pytest.mark.parametrize("dimension", [2, 3])
def test_a_bar_pinned_twice_is_redundant_and_its_solve_consistent(dimension):
    """More unknowns than the first bar's rows: the solve names the redundancy, and its
    answer satisfies the equations (M v̇ − G_U λ = r, G_Uᵀ v̇ = γ) to rounding."""
    model = mbody.load(pinned_twice(dimension))
    k = Kernel(model)
    cu, lam = file_unknowns(k)
    y = state_vector(model, model.initial)
    m = len(model.reactions)
    N, lo, io = _core.solve_layout(model.n, m, k.planar)
    out = np.zeros(io + _core.INFO)
    cu.solve(0.0, y, lam, out)
    assert out[io + _core.ST_RANK] < cu.mu
    assert out[io + _core.ST_BERR] <= 1e-13
    assert np.any(out[lo + 2 * m:io] > 0)  # components named not unique


def test_many_unknowns_are_band_ordered():
    """A chain of 16 rods on revolute joints (80 unknowns): pack_unknowns orders them
    breadth-first from the ground joint, so S's half band stays that of a chain whatever
    the labels."""
    model = mbody.load(chain16())
    k = Kernel(model)
    cu, lam = file_unknowns(k)
    assert cu.mu == 80
    assert cu.bw < 10  # two joints' components (5 each) per body
