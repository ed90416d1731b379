"""Export to MJCF, checked by loading the file in MuJoCo (an independent engine).

Frames: each exported MuJoCo body frame is the mbody body frame (mass centre, body axes)
at the initial pose, so MuJoCo's ``xipos`` is the mass centre and ``xmat`` is W_R_B.
``mj_objectAcceleration`` (after ``mj_rnePostConstraint``) gives a body's angular
acceleration and its mass centre's acceleration minus gravity, world axes; mbody's rows
are [a_G (world), ω̇ (body axes)], planar [a_x, a_y, θ̈]. ``cfrc_int[b]`` is [moment,
force] that the tree parent exerts on body b, the moment about
``subtree_com[rootid[b]]``, world axes; mbody's is the joint's columns of G times its
reaction values, on the rows of the same body.

The file's point forces and couples are not in MJCF (MuJoCo has no constant applied
loads): they are put into ``xfrc_applied`` here, as the file's header says. Springs are
spatial tendons of the file itself.

Tolerance: |mbody − MuJoCo| ≤ 1e-9 · max(1, |a|) for tree-structured models; closed
loops are soft in MuJoCo (see `test_closed_loops_load_and_nearly_agree`), and so are the
couplings of helical joints, whose softness MuJoCo's own data give exactly (see
`test_screws_agree_with_mujoco_to_the_softness_of_their_coupling`). MuJoCo has no
drivers: a driven model is compared with the same model without its drivers.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from randmodels import planar_model, spatial_model

import mbody
from mbody import conventions as cv
from mbody.cli.app import main
from mbody.errors import ModelError
from mbody.io.interop.mjcf import read_mjcf
from mbody.io.interop.mjcf_write import spanning_tree, to_mjcf
from mbody.model import State
from mbody.model.loader import load_text
from mbody.model.yaml_write import dump_document

mujoco = pytest.importorskip("mujoco")

MODELS = Path(__file__).resolve().parent.parent / "models"
RTOL = 1e-9
ALL = sorted(p.name for p in MODELS.glob("*.yaml"))
LOOPS = {"fourbar_planar.yaml", "fourbar_spatial.yaml", "slider_crank.yaml",
         "spinning_disc_bearings.yaml", "bricard.yaml", "scotch_yoke.yaml",
         "slider_crank_driven.yaml"}
SCREWS = {"screw_jack.yaml", "helical_chain.yaml"}
"""Trees with a helical joint: its slide and hinge are coupled by a (soft) equality."""
TREES = [n for n in ALL if n not in LOOPS | SCREWS]


def _load(name: str, *, known: bool = True, driven: bool = True) -> mbody.Model:
    """A shipped model; without its known reaction values when `known` is False, without
    its drivers when `driven` is False (MuJoCo's model: it has none)."""
    if known and driven:
        return mbody.load(MODELS / name)
    data = load_text((MODELS / name).read_text(), name).data
    if not known:
        data.pop("reactions", None)
    if not driven:
        data.pop("drivers", None)
    return mbody.load(data)


def _random_state(m, d, rng: np.random.Generator) -> None:
    """Random joint positions and rates in MuJoCo's coordinates (so they respect every
    joint), from the keyframe."""
    mujoco.mj_resetDataKeyframe(m, d, 0)
    d.qvel[:] = rng.normal(scale=2.0, size=m.nv)
    mujoco.mj_integratePos(m, d.qpos, rng.normal(scale=0.5, size=m.nv), 1.0)


def _mujoco(model: mbody.Model):
    m = mujoco.MjModel.from_xml_string(to_mjcf(model))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("initial").id)
    return m, d


def _state(model: mbody.Model, m, d) -> State:
    """MuJoCo's state as an mbody State (mass centres, body axes)."""
    n = model.n
    pos, quat = np.zeros((n, 3)), np.zeros((n, 4))
    vel, omega = np.zeros((n, 3)), np.zeros((n, 3))
    out = np.zeros(6)
    for i, name in enumerate(model.body_names):
        b = m.body(name).id
        R = d.xmat[b].reshape(3, 3)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, out, 0)
        pos[i], vel[i] = d.xipos[b], out[3:]
        if model.particle[i]:  # no orientation in mbody: the file's, and no spin
            quat[i] = model.initial.quaternion[i]
        else:
            quat[i], omega[i] = d.xquat[b], R.T @ out[:3]
    if model.dimension == cv.PLANAR:
        angle = 2 * np.arctan2(quat[:, 3], quat[:, 0])
        return State.planar(pos[:, :2], angle, vel[:, :2], omega[:, 2], d.time)
    return State(pos, quat / np.linalg.norm(quat, axis=1, keepdims=True), vel, omega, d.time)


def _apply_loads(model: mbody.Model, m, d, state: State) -> None:
    """The file's point forces and couples at `state` as xfrc_applied: a world force
    and a world torque about the mass centre (computed here with numpy, not mbody)."""
    d.xfrc_applied[:] = 0.0
    f = model.forces
    vec = f.vector_at(state.t)
    for k in range(len(f.names)):
        i = int(f.body[k])
        b = m.body(model.body_names[i]).id
        R = d.xmat[b].reshape(3, 3)
        v = R @ vec[k] if f.in_body[k] else vec[k]
        if f.couple[k]:
            d.xfrc_applied[b, 3:] += v
        else:
            d.xfrc_applied[b, :3] += v
            d.xfrc_applied[b, 3:] += np.cross(R @ f.B_r[k], v)


def _forward(model: mbody.Model, m, d) -> None:
    mujoco.mj_forward(m, d)
    _apply_loads(model, m, d, _state(model, m, d))
    mujoco.mj_forward(m, d)
    mujoco.mj_rnePostConstraint(m, d)


def _accelerations(model: mbody.Model, m, d) -> np.ndarray:
    """MuJoCo's accelerations in the order of mbody's coordinates."""
    res = np.zeros(6)
    rows = []
    for i, name in enumerate(model.body_names):
        b = m.body(name).id
        mujoco.mj_objectAcceleration(m, d, mujoco.mjtObj.mjOBJ_BODY, b, res, 0)
        a = res[3:] + m.opt.gravity
        alpha = d.xmat[b].reshape(3, 3).T @ res[:3]
        if model.dimension == cv.PLANAR:
            rows.append(a[:2] if model.particle[i] else [a[0], a[1], alpha[2]])
        else:
            rows.append(a if model.particle[i] else np.concatenate((a, alpha)))
    return np.concatenate(rows)


def _compare(ours: np.ndarray, theirs: np.ndarray, rtol: float = RTOL) -> float:
    scale = max(1.0, float(np.abs(theirs).max()))
    err = float(np.abs(ours - theirs).max()) / scale
    assert err <= rtol, f"max relative difference {err:.2e}"
    return err


def _reaction_wrenches(model: mbody.Model, asm, sol, state: State) -> dict[str, np.ndarray]:
    """Per tree child: [moment about its mass centre (world), force (world)] that its
    joint to the tree parent puts on it, from mbody's G and reaction values."""
    tree = spanning_tree(model)
    G = asm.G.toarray()
    lam = np.array([sol.reactions[r] for r in asm.reactions])
    out = {}
    for body, joint in tree.joint.items():
        if joint is None:
            continue
        i = model.index[body]
        cols = [asm.reactions.index(r) for r in joint.labels]
        rows = model.body_rows(i)
        w = G[np.ix_(rows, cols)] @ lam[cols]
        R = _quat_matrix(state.quaternion[i])
        if model.dimension == cv.PLANAR:
            force = np.array([w[0], w[1], 0.0])
            moment = np.array([0.0, 0.0, w[2] if len(w) > 2 else 0.0])
        else:
            force = w[:3]
            moment = R @ w[3:] if len(w) > 3 else np.zeros(3)
        out[body] = np.concatenate((moment, force))
    return out


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _check_reactions(model: mbody.Model, m, d, asm, sol, state: State) -> float:
    worst = 0.0
    for body, (moment, force) in ((b, (w[:3], w[3:])) for b, w in
                                  _reaction_wrenches(model, asm, sol, state).items()):
        b = m.body(body).id
        c = d.subtree_com[m.body_rootid[b]]
        i = model.index[body]
        theirs = d.cfrc_int[b]
        ours = np.concatenate((moment + np.cross(state.position[i] - c, force), force))
        worst = max(worst, _compare(ours, theirs))
    return worst


@pytest.mark.parametrize("name", TREES)
def test_tree_models_agree_with_mujoco_at_the_keyframe(name):
    model = _load(name, driven=False)  # MuJoCo's model has no drivers (flyball_governor)
    m, d = _mujoco(model)
    assert m.nkey == 1 and m.neq == 0
    _forward(model, m, d)
    state = _state(model, m, d)
    # the keyframe is the file's state
    np.testing.assert_allclose(state.position, model.initial.position, atol=1e-12)
    np.testing.assert_allclose(state.velocity, model.initial.velocity, atol=1e-9)
    asm = mbody.assemble(model, state)
    sol = asm.solve()
    _compare(sol.accelerations, _accelerations(model, m, d))
    if not len(model.springs.names):
        _check_reactions(model, m, d, asm, sol, state)


@pytest.mark.parametrize("name", TREES)
def test_tree_models_agree_with_mujoco_at_random_states(name):
    """Random joint positions and rates (MuJoCo's coordinates, so every state respects
    the joints); the file's known reaction values are dropped (they hold at one state),
    and its drivers (MuJoCo's model has none)."""
    model = _load(name, known=False, driven=False)
    m, d = _mujoco(model)
    rng = np.random.default_rng(sum(map(ord, name)))
    for _ in range(3):
        _random_state(m, d, rng)
        _forward(model, m, d)
        state = _state(model, m, d)
        asm = mbody.assemble(model, state)
        sol = asm.solve()
        _compare(sol.accelerations, _accelerations(model, m, d))
        if not len(model.springs.names):
            _check_reactions(model, m, d, asm, sol, state)


@pytest.mark.parametrize("name", sorted(LOOPS))
def test_closed_loops_load_and_nearly_agree(name):
    """A loop's closing joint is an equality constraint (connect, weld), which MuJoCo
    keeps softly: with the export's stiffest impedance (0.9999) the accelerations agree
    to about 1e-4 of their size (measured: 7e-7 to 2.3e-4 on these models), and without
    the constraint they do not agree at all."""
    model = _load(name)
    m, d = _mujoco(model)
    assert m.neq >= 1 and len(spanning_tree(model).loops) == 1
    _forward(model, m, d)
    free = _load(name, driven=False)  # a driven model (scotch_yoke): MuJoCo has no drivers
    ours = mbody.assemble(free, _state(model, m, d)).solve().accelerations
    _compare(ours, _accelerations(model, m, d), rtol=1e-3)
    m.eq_active0[:] = 0
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    _forward(model, m, d)
    with pytest.raises(AssertionError, match="max relative difference"):
        _compare(ours, _accelerations(model, m, d), rtol=1e-2)


def _softness(m, d) -> float:
    """ρ = R/(A + R) of the one equality row MuJoCo holds at `d`: A = J M⁻¹ Jᵀ, the row's
    inverse inertia, and R its regularisation (from solimp). MuJoCo's force is A/(A + R)
    of the rigid one, so with a zero reference acceleration (the state on the constraint,
    moving along it) its accelerations are a_rigid + ρ (a_free − a_rigid), a_free those
    without the constraint: the softness, exactly."""
    assert d.nefc == 1
    J = d.efc_J.reshape(1, m.nv).copy()
    X = np.zeros_like(J)
    mujoco.mj_solveM(m, d, X, J)
    return float(d.efc_R[0] / (J[0] @ X[0] + d.efc_R[0]))


def _uncoupled(model: mbody.Model, m, d):
    """MuJoCo at the state of `d` with every equality switched off."""
    free = mujoco.MjData(m)
    free.qpos[:], free.qvel[:] = d.qpos, d.qvel
    free.eq_active[:] = 0
    _forward(model, m, free)
    return free


def _on_the_screws(m, d, rng: np.random.Generator) -> None:
    """A random state (MuJoCo's coordinates) that keeps every joint equality: joint1 −
    ref = polycoef[1] (joint2 − ref), and so for the rates."""
    _random_state(m, d, rng)
    for k in range(m.neq):
        assert m.eq_type[k] == mujoco.mjtEq.mjEQ_JOINT and not m.eq_data[k, [0, 2, 3, 4]].any()
        j1, j2 = m.eq_obj1id[k], m.eq_obj2id[k]
        q1, q2 = m.jnt_qposadr[j1], m.jnt_qposadr[j2]
        a = m.eq_data[k, 1]
        d.qpos[q1] = m.qpos0[q1] + a * (d.qpos[q2] - m.qpos0[q2])
        d.qvel[m.jnt_dofadr[j1]] = a * d.qvel[m.jnt_dofadr[j2]]


@pytest.mark.parametrize("name", sorted(SCREWS))
def test_screws_agree_with_mujoco_to_the_softness_of_their_coupling(name):
    """A helical joint is a slide and a hinge on its axis coupled by a joint equality,
    soft in MuJoCo. At the keyframe and at random states on the screw, MuJoCo's
    accelerations are mbody's plus ρ (a_free − mbody's), ρ its softness from its own
    data (`_softness`; 1.4e-5 for the jack, 5.7e-7 for the chain), to 1e-9 of their size;
    and so are the joints' reactions (``cfrc_int``): the screw's axial wrench included.
    Without the coupling they do not agree at all."""
    model = _load(name)
    m, d = _mujoco(model)
    assert m.neq == 1 and m.eq_type[0] == mujoco.mjtEq.mjEQ_JOINT
    rng = np.random.default_rng(sum(map(ord, name)))
    for k in range(3):
        if k:
            _on_the_screws(m, d, rng)
        _forward(model, m, d)
        state = _state(model, m, d)
        asm = mbody.assemble(model, state)
        sol = asm.solve()
        assert sol.residual < 1e-12  # the state keeps the screw
        rho = _softness(m, d)
        assert 0 < rho < 1e-4
        free = _uncoupled(model, m, d)
        ours, theirs = sol.accelerations, _accelerations(model, m, d)
        loose = _accelerations(model, m, free)
        scale = max(1.0, float(np.abs(theirs).max()))
        np.testing.assert_allclose(theirs - ours, rho * (loose - ours), rtol=0,
                                   atol=RTOL * scale)
        assert np.abs(loose - ours).max() > 1e-3 * scale  # the coupling matters
        for body, w in _reaction_wrenches(model, asm, sol, state).items():
            b = m.body(body).id
            c = d.subtree_com[m.body_rootid[b]]
            i = model.index[body]
            mine = np.concatenate((w[:3] + np.cross(state.position[i] - c, w[3:]), w[3:]))
            size = max(1.0, float(np.abs(d.cfrc_int[b]).max()))
            np.testing.assert_allclose(d.cfrc_int[b] - mine,
                                       rho * (free.cfrc_int[b] - mine), rtol=0,
                                       atol=RTOL * size)


def test_a_screw_written_against_the_tree():
    """A nut (b) on a screw whose screw body (a) hangs from ground: from the tree, the
    helical joint runs from its child to its parent; the inverse of a screw motion is a
    screw of the same pitch about the same line, so the same slide, hinge and coupling
    hold it. It agrees with MuJoCo to the softness and comes back the same."""
    spec = {"model": "against", "dimension": 3, "gravity": [0, 0, -9.81],
            "bodies": [{"name": "a", "mass": 2, "inertia": [0.1, 0.2, 0.25],
                        "position": [0.3, 0, 0]},
                       {"name": "b", "mass": 1, "inertia": [0.05, 0.05, 0.02],
                        "position": [0.6, 0.1, -0.2],
                        "orientation": {"euler": [10, 20, 30], "sequence": "ZYX"}}],
            "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "a",
                        "at": [0, 0, 0], "axis": [0, 1, 0]},
                       {"name": "H", "type": "helical", "parent": "b", "child": "a",
                        "at": [0.6, 0, 0], "axis": [0.3, 0.2, 1], "pitch": 0.05}]}
    model = mbody.load(spec)
    assert spanning_tree(model).parent["b"] == "a"
    back, _ = _through_mjcf(model)
    _same_model(model, back)
    m, d = _mujoco(model)
    rng = np.random.default_rng(1)
    for _ in range(3):
        _on_the_screws(m, d, rng)
        _forward(model, m, d)
        sol = mbody.assemble(model, _state(model, m, d)).solve()
        assert sol.residual < 1e-12
        rho = _softness(m, d)
        ours, theirs = sol.accelerations, _accelerations(model, m, d)
        loose = _accelerations(model, m, _uncoupled(model, m, d))
        np.testing.assert_allclose(theirs - ours, rho * (loose - ours), rtol=0,
                                   atol=RTOL * max(1.0, float(np.abs(theirs).max())))


def test_a_screw_is_written_so_that_mujoco_holds_it_stiffly():
    """The coupling is written as θ = s/h (joint1 the hinge) when |h| < 1: MuJoCo's
    estimate of the row's inverse inertia (the joints' own weights, added) then holds
    the true one's larger term in full (softness 1.4e-5). Written s = h θ, MuJoCo's
    force on the jack's screw is 4 % of the rigid one (0.96)."""
    model = _load("screw_jack.yaml")
    xml = to_mjcf(model)
    h = 0.005 / (2 * np.pi)
    assert f'joint1="N:turn" joint2="N:slide" polycoef="0 {1 / h!r} 0 0 0"' in xml
    m, d = _mujoco(model)
    _forward(model, m, d)
    assert _softness(m, d) < 1e-4
    other = xml.replace(f'joint1="N:turn" joint2="N:slide" polycoef="0 {1 / h!r} 0 0 0"',
                        f'joint1="N:slide" joint2="N:turn" polycoef="0 {h!r} 0 0 0"')
    m2 = mujoco.MjModel.from_xml_string(other)
    d2 = mujoco.MjData(m2)
    mujoco.mj_resetDataKeyframe(m2, d2, 0)
    _forward(model, m2, d2)
    assert _softness(m2, d2) > 0.9


def test_a_wrong_export_is_caught():
    """The comparison can fail: the same file with one mass changed disagrees."""
    model = _load("double_pendulum.yaml")
    xml = to_mjcf(model).replace('mass="1"', 'mass="1.001"', 1)
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    _forward(model, m, d)
    ours = mbody.assemble(model, _state(model, m, d)).solve().accelerations
    with pytest.raises(AssertionError, match="max relative difference"):
        _compare(ours, _accelerations(model, m, d))


JOINT_MIXES = [None, ("spherical", "fixed", "universal", "revolute"),
               ("cylindrical", "spherical", "prismatic", "fixed")]


def _random_trees(kind: str, types, springs: int, count: int = 3, *,
                  upright: bool = False) -> list[dict]:
    """The first `count` random models (seeds 0, 1, ...) whose joints form a tree (with
    `upright`, each joint's child farther from the root than its parent)."""
    out = []
    for seed in range(100):
        if kind == "spatial":
            spec = spatial_model(seed, 5, n_joints=4, known=False, n_springs=springs,
                                 joint_types=types)
        else:
            spec = planar_model(seed, 5, n_joints=4, known=False, n_springs=springs)
        tree = spanning_tree(mbody.load(spec))
        if upright and any(j.child != b for b, j in tree.joint.items() if j is not None):
            continue
        if not tree.loops:
            out.append(spec)
            if len(out) == count:
                return out
    raise AssertionError("too few random trees")


@pytest.mark.parametrize("springs", [0, 2])
@pytest.mark.parametrize("kind, types", [("spatial", t) for t in JOINT_MIXES]
                         + [("planar", None)])
def test_random_trees_of_every_joint_type_agree_with_mujoco(kind, types, springs):
    """Random models (full inertias, rotated bodies, offset forces in world and body
    axes, couples, gravity, damped springs) whose joints of every type form a tree, some
    joints running against the tree (the child nearer the root): accelerations and, without
    springs, every joint's reaction agree with MuJoCo at random states."""
    reversed_joints = 0
    for k, spec in enumerate(_random_trees(kind, types, springs)):
        model = mbody.load(spec)
        tree = spanning_tree(model)
        reversed_joints += sum(j.child != b for b, j in tree.joint.items() if j is not None)
        m, d = _mujoco(model)
        assert m.ntendon == springs
        rng = np.random.default_rng(k)
        for _ in range(2):
            _random_state(m, d, rng)
            _forward(model, m, d)
            state = _state(model, m, d)
            asm = mbody.assemble(model, state)
            sol = asm.solve()
            assert sol.residual < 1e-12  # MuJoCo's state respects every joint
            _compare(sol.accelerations, _accelerations(model, m, d))
            if not springs:
                _check_reactions(model, m, d, asm, sol, state)
    assert reversed_joints > 0


def _dense(x) -> np.ndarray:
    return x.toarray() if hasattr(x, "toarray") else np.asarray(x, dtype=float)


def _same_equations(a: mbody.Model, b: mbody.Model, rtol: float = 0.0) -> None:
    """M, b, Q, G of both models at their initial states agree (rows and columns matched
    by label, so a reader may order bodies and joints its own way)."""
    A, B = mbody.assemble(a), mbody.assemble(b)
    assert sorted(A.coordinates) == sorted(B.coordinates)
    assert sorted(A.reactions) == sorted(B.reactions)
    r = [B.coordinates.index(c) for c in A.coordinates]
    c = [B.reactions.index(x) for x in A.reactions]
    pairs = {"M": (_dense(A.M), _dense(B.M)[np.ix_(r, r)]), "b": (A.b, np.asarray(B.b)[r]),
             "Q": (A.Q, np.asarray(B.Q)[r]), "G": (_dense(A.G), _dense(B.G)[np.ix_(r, c)])}
    for key, (x, y) in pairs.items():
        scale = max(1.0, float(np.abs(x).max(initial=0.0)))
        assert np.abs(np.asarray(x) - y).max(initial=0.0) <= rtol * scale, key


@pytest.mark.parametrize("name", ALL)
def test_yaml_round_trip_is_exact(name):
    """load → document → dump → load: the same document, so the same equations bit for
    bit (numbers written as repr floats read back as the same doubles)."""
    text = (MODELS / name).read_text()
    document = load_text(text, name).data
    dumped = dump_document(document, source=f"models/{name}")
    assert dumped.startswith(f"# Converted by mbody {mbody.__version__} (mbody convert) "
                             f"from models/{name}.\n")
    assert load_text(dumped, "dumped").data == document
    _same_equations(mbody.load(MODELS / name), mbody.loads(dumped))


def test_yaml_numbers_and_text_read_back_as_written():
    document = {"model": "yes", "description": "a: b # c, [d]", "dimension": 3,
                "gravity": [1e-300, 5e-324, -0.0],
                "bodies": [{"name": "on", "mass": 0.1 + 0.2, "inertia": [1e22, 2.5e-7, 3],
                            "orientation": {"euler": ["30 deg", "1e3", 0],
                                            "sequence": "ZYX"},
                            "color": "#c0392b"}],
                "loads": [], "joints": []}
    text = dump_document(document, source=None)
    assert "mass: 0.30000000000000004" in text and "1.0e+22" in text
    assert "name: \"on\"" in text and "model: \"yes\"" in text  # YAML 1.1 booleans quoted
    assert load_text(text, "t").data == document
    import yaml  # a YAML 1.1 reader sees the same values

    assert yaml.safe_load(text) == document


def test_yaml_keeps_drivers_pitches_and_points_per_body_as_written():
    """Every driver law (an angle in degrees, a displacement, a speed with its unit), a
    pitch and joint points per body come back from YAML as the file writes them: the
    same document, the same model (through MJCF too, where the laws are kept as text and
    a speed in rad/s)."""
    document = {
        "model": "laws", "dimension": 3, "gravity": [0, 0, -9.81],
        "bodies": [{"name": "nut", "mass": 2.0, "inertia": [0.01, 0.01, 0.004],
                    "position": [0, 0, 0.101]},
                   {"name": "arm", "mass": 0.5, "inertia": [0.001, 0.02, 0.02],
                    "position": [0.2, 0, 0.1]},
                   {"name": "slider", "mass": 0.3, "inertia": [0.001, 0.001, 0.001],
                    "position": [0.4, 0, 0.1]}],
        "joints": [{"name": "H", "type": "helical", "parent": "ground", "child": "nut",
                    "at": [[0, 0, 0.1], [0, 0, 0]], "axis": [0, 0, 1], "pitch": 0.004},
                   {"name": "A", "type": "revolute", "parent": "nut", "child": "arm",
                    "at": [[0.1, 0, 0], [-0.1, 0, 0]], "axis": [0, 0, 1]},
                   {"name": "P", "type": "prismatic", "parent": "arm", "child": "slider",
                    "at": [[0.1, 0, 0], [-0.1, 0, 0]], "axis": [1, 0, 0]}],
        "drivers": [{"name": "spin", "joint": "H", "speed": "120 rpm"},
                    {"name": "swing", "joint": "A", "angle": "10 deg*sin(3*t)"},
                    {"name": "push", "joint": "P", "displacement": "0.02*t*t"}]}
    text = dump_document(document, source=None)
    assert "  - {name: swing, joint: A, angle: \"10 deg*sin(3*t)\"}" in text
    assert "pitch: 0.004}" in text and "at: [[0, 0, 0.1], [0, 0, 0]]" in text
    assert load_text(text, "t").data == document
    model = mbody.loads(text)
    assert model.file_state is not None and len(model.drivers) == 3
    _same_equations(mbody.load(document), model)
    back, xml = _through_mjcf(model)
    assert 'name="mbody:driver:swing" data=\'{"joint": "A", "angle": "10 deg*sin(3*t)"}\'' \
        in xml
    _same_model(model, back)


def _through_mjcf(model: mbody.Model) -> tuple[mbody.Model, str]:
    """YAML → MJCF (loaded by MuJoCo as written) → the MJCF reader → YAML → model."""
    xml = to_mjcf(model)
    mujoco.MjModel.from_xml_string(xml)  # the mbody entries do not stop MuJoCo
    document = read_mjcf(xml, keyframe="initial")
    assert not document.warnings  # nothing of the export is left unread
    return mbody.loads(dump_document(document.data, source="exported.xml")), xml


def _same_model(a: mbody.Model, b: mbody.Model) -> None:
    """The same equations (1e-12) and everything the equations are named by."""
    _same_equations(a, b, rtol=1e-12)
    assert b.dimension == a.dimension
    assert sorted(b.body_names) == sorted(a.body_names)
    assert [bool(b.particle[b.index[n]]) for n in a.body_names] == list(a.particle)
    assert {(j.name, j.type, j.parent, j.child) for j in b.joints} == {
        (j.name, j.type, j.parent, j.child) for j in a.joints}
    assert [(ld.name, ld.type, ld.bodies) for ld in b.loads] == [
        (ld.name, ld.type, ld.bodies) for ld in a.loads]
    assert b.known_reactions == a.known_reactions
    assert {k: str(e) for k, e in b.known_expressions.items()} == {
        k: str(e) for k, e in a.known_expressions.items()}
    for t in (0.0, 0.013):  # loads and known values that vary in time vary alike
        np.testing.assert_array_equal(b.forces.vector_at(t), a.forces.vector_at(t))
        assert b.known_reactions_at(t) == a.known_reactions_at(t)
    assert _drivers(b) == _drivers(a)
    if a.drivers is not None:  # the same laws (a speed's offset: the file's angles)
        assert b.drivers is not None
        for t in (0.0, 0.013):
            np.testing.assert_allclose([law[0](t) for law in b.drivers.laws],
                                       [law[0](t) for law in a.drivers.laws], rtol=1e-12)
    assert (b.file_state is None) == (a.file_state is None)  # assembled at load alike


def _drivers(model: mbody.Model) -> list[tuple]:
    d = model.drivers
    if d is None:
        return []
    return [(n, model.joints[int(j)].name, c, s if s is not None else str(law[0]))
            for n, j, c, s, law in zip(d.names, d.joint, d.component, d.speed, d.laws,
                                       strict=True)]


@pytest.mark.parametrize("name", ALL)
def test_every_shipped_model_round_trips_through_mjcf(name):
    """YAML → MJCF → YAML gives the same M, b, Q, G (rows and columns matched by label)
    for every shipped model, planar and spatial: the mbody entries of ``<custom>`` bring
    back the dimension, loads, springs, known reactions, fixed joints, particles and
    each joint's direction."""
    model = mbody.load(MODELS / name)
    back, xml = _through_mjcf(model)
    _same_model(model, back)
    assert "<custom>" in xml and xml.count('name="mbody:load:') == len(model.loads)


def test_without_the_mbody_entries_the_file_is_plain_mjcf():
    """The entries are the only source of what MJCF cannot say: a file without them
    reads as MuJoCo's model (spatial; no point loads; springs are tendons mbody does not
    read)."""
    def plain(name: str):
        xml = to_mjcf(mbody.load(MODELS / name))
        head, rest = xml.split("  <!-- What MJCF cannot say", 1)
        return read_mjcf(head + rest.split("  </custom>\n", 1)[1], keyframe="initial")

    doc = plain("gyroscope_gimbals.yaml")
    assert doc.data["dimension"] == 3 and "loads" not in doc.data
    spec = _random_trees("spatial", None, 2, count=1)[0]
    xml = to_mjcf(mbody.load(spec))
    head, rest = xml.split("  <!-- What MJCF cannot say", 1)
    doc = read_mjcf(head + rest.split("  </custom>\n", 1)[1], keyframe="initial")
    assert "tendons (s0, s1)" in doc.warnings[0].message
    assert "loads" not in doc.data
    with pytest.raises(ModelError, match="no joint with two sliding directions"):
        plain("spring_mass_damper.yaml")  # a free planar body: MJCF's x, y slides, z hinge


def test_a_round_trip_that_loses_something_is_caught():
    """The comparison can fail: an entry removed from the file changes the equations."""
    model = mbody.load(MODELS / "practice_2_flywheel.yaml")
    xml = to_mjcf(model)
    line = next(ln for ln in xml.splitlines() if 'name="mbody:reaction:' in ln)
    document = read_mjcf(xml.replace(line + "\n", ""), keyframe="initial")
    back = mbody.loads(dump_document(document.data, source="exported.xml"))
    with pytest.raises(AssertionError):
        _same_model(model, back)


def test_the_file_pose_entries_are_what_keeps_an_assembled_model():
    """A model assembled at load is written at its assembled pose; its joints' axes (the
    mbody:joint entries) are in world axes at the file's pose. Read back without the
    file's pose (the mbody:body entries removed), the helical chain's pin axis is taken at
    the assembled pose, another direction in the carriage: G differs."""
    model = _load("helical_chain.yaml")
    xml = to_mjcf(model)
    assert "Assembled pose:" in xml and xml.count('name="mbody:body:') == 2
    cut = "\n".join(ln for ln in xml.splitlines() if "mbody:body:" not in ln)
    back = mbody.loads(dump_document(read_mjcf(cut, keyframe="initial").data, source="x"))
    with pytest.raises(AssertionError, match="G"):
        _same_equations(model, back, rtol=1e-6)


@pytest.mark.parametrize("old, new, message", [
    ('"joint": "O", "speed"', '"joint": "Q", "speed"', "drivers[0].joint: no joint named 'Q'"),
    ('"speed": 62.83185307179586', '"speed": "fast"', "drivers[0].speed: expected a rate"),
    ("mbody:driver:", "mbody:drivr:", "did you mean 'driver'?"),
    ('"position": [0.043, 0.0]', '"position": [0.043]', "position: expected 2 components"),
    ('"at": [[0.0, 0.0], [0.05, 0.0]]', '"at": [[0.0, 0.0], [0.05]]', "at[1]: expected 2"),
])
def test_a_wrong_entry_is_an_error_at_its_line(tmp_path, old, new, message):
    """The entries of a driver, a file's pose and a joint's per-body points are checked
    as the model file is, each problem reported at the entry's line (exit 2)."""
    xml = to_mjcf(_load("scotch_yoke.yaml"))
    assert old in xml
    path = tmp_path / "yoke.xml"
    path.write_text(xml.replace(old, new, 1))
    line = next(k for k, ln in enumerate(path.read_text().splitlines(), 1) if new in ln)
    with pytest.raises(ModelError) as info:
        mbody.load(path)
    assert message in str(info.value) and f"yoke.xml:{line}:" in str(info.value)


def _pinned_slot() -> dict:
    """A crank pinned to ground and a slotted link hanging on the crank's pin (a slot
    whose parent is the link: in MuJoCo's tree, from the crank, the joint runs against
    the tree); gravity −y."""
    c, s = np.cos(0.5), np.sin(0.5)
    return {"model": "pinned-slot", "dimension": 2, "gravity": [0, -9.81],
            "bodies": [{"name": "crank", "mass": 1.0, "inertia": 0.01,
                        "position": [0.05 * c, 0.05 * s], "angle": 0.5},
                       {"name": "link", "mass": 0.7, "inertia": 0.02,
                        "position": [0.1 * c, 0.1 * s - 0.2], "angle": 0.3}],
            "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "crank",
                        "at": [0, 0]},
                       {"name": "S", "type": "slot", "parent": "link", "child": "crank",
                        "at": [0.1 * c, 0.1 * s], "axis": [0.2, 1.0]}]}


def test_a_slot_written_against_the_tree_turns_before_it_slides():
    """A pin in a slot seen from the pin's body: the link turns about the pin, then
    slides along its own slot (MuJoCo: S:turn, then S:slide, in the link). Exact in
    MuJoCo (a tree): the accelerations and the pin's force agree at random states, and
    the model comes back with the slot's parent and child."""
    model = mbody.load(_moving(_pinned_slot()))  # with rates that keep the joints
    tree = spanning_tree(model)
    assert tree.joint["link"].name == "S" and tree.parent["link"] == "crank"
    xml = to_mjcf(model)
    assert xml.index('name="S:turn"') < xml.index('name="S:slide"')
    m, d = _mujoco(model)
    assert m.neq == 0
    rng = np.random.default_rng(3)
    for k in range(3):
        if k:
            _random_state(m, d, rng)
        _forward(model, m, d)
        state = _state(model, m, d)
        asm = mbody.assemble(model, state)
        sol = asm.solve()
        assert sol.residual < 1e-12
        _compare(sol.accelerations, _accelerations(model, m, d))
        _check_reactions(model, m, d, asm, sol, state)
    back, _ = _through_mjcf(model)
    _same_model(model, back)
    assert [(j.name, j.parent, j.child) for j in back.joints if j.type == "slot"] == [
        ("S", "link", "crank")]


def _plain_screw(coupling: str, slide_axis: str = "0 0 1", key: str = "") -> str:
    """A MuJoCo file of its own (no mbody entries): a nut on a screw tilted about y (a
    slide and a hinge on one axis, coupled by `coupling`, a joint equality at MuJoCo's
    default softness) carrying a swinging arm."""
    h = 0.012
    key = key or f'qpos="{0.7 * h!r} 0.7 0.3" qvel="{2 * h!r} 2 -1"'
    if slide_axis.startswith("0 0 -"):
        key = key.replace(f'"{0.7 * h!r} ', f'"{-0.7 * h!r} ').replace(f'"{2 * h!r} ',
                                                                       f'"{-2 * h!r} ')
    return f"""<mujoco model="screw">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="nut" pos="0.1 0 0.3" euler="0 20 0">
      <joint name="lift" type="slide" axis="{slide_axis}"/>
      <joint name="spin" type="hinge" axis="0 0 1"/>
      <inertial pos="0 0 0" mass="3" diaginertia="0.02 0.02 0.01"/>
      <body name="arm" pos="0.2 0 0">
        <joint name="swing" type="hinge" pos="-0.1 0 0" axis="0 1 0"/>
        <inertial pos="0 0 0" mass="0.5" diaginertia="0.001 0.004 0.004"/>
      </body>
    </body>
  </worldbody>
  <equality>{coupling}</equality>
  <keyframe><key name="k" {key}/></keyframe>
</mujoco>
"""


@pytest.mark.parametrize("coupling, slide_axis", [
    ('<joint joint1="lift" joint2="spin" polycoef="0 0.012 0 0 0"/>', "0 0 1"),
    (f'<joint joint1="spin" joint2="lift" polycoef="0 {1 / 0.012!r} 0 0 0"/>', "0 0 1"),
    ('<joint joint1="lift" joint2="spin" polycoef="0 -0.012 0 0 0"/>', "0 0 -1"),
])
def test_a_mujoco_screw_is_read_as_a_helical_joint(tmp_path, coupling, slide_axis):
    """A slide and a hinge on one axis tied by a joint equality with polycoef "0 a 0 0 0"
    (either way round, the slide along or against the hinge's axis) is mbody's helical
    joint of pitch 2π h (h: the advance along the hinge's axis per radian), exact in
    mbody. MuJoCo keeps the equality softly, at its default impedance here: its
    accelerations are mbody's plus ρ (a_free − mbody's), ρ from its own data."""
    path = tmp_path / "screw.xml"
    path.write_text(_plain_screw(coupling, slide_axis))
    doc = read_mjcf(path, keyframe="k")
    assert not doc.warnings  # the equality is the screw itself
    [screw] = [j for j in doc.data["joints"] if j["name"] == "lift+spin"]
    assert screw["type"] == "helical"
    assert screw["pitch"] == pytest.approx(2 * np.pi * 0.012, rel=1e-15)
    model = mbody.load(path, keyframe="k")
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    _forward(model, m, d)
    state = _state(model, m, d)
    np.testing.assert_allclose(state.position, model.initial.position, atol=1e-12)
    sol = mbody.assemble(model, state).solve()
    assert sol.residual < 1e-12
    rho = _softness(m, d)
    free = _uncoupled(model, m, d)
    ours, theirs = sol.accelerations, _accelerations(model, m, d)
    np.testing.assert_allclose(theirs - ours, rho * (_accelerations(model, m, free) - ours),
                               rtol=0, atol=RTOL * max(1.0, float(np.abs(theirs).max())))


@pytest.mark.parametrize("coupling, why", [
    ('<joint joint1="lift" joint2="spin" polycoef="0 0.012 0.5 0 0"/>', "not linear"),
    ('<joint joint1="lift" joint2="spin" polycoef="0.001 0.012 0 0 0"/>', "an offset"),
    ('<joint joint1="spin" joint2="lift" polycoef="0 0 0 0 0"/>', "the hinge locked"),
    ('<joint joint1="lift" joint2="swing" polycoef="0 0.012 0 0 0"/>', "another body"),
])
def test_a_joint_equality_that_is_not_a_screw_is_listed(coupling, why):
    """Anything but an exactly linear tie of the body's own slide and hinge on one axis
    stays what it was: a cylindrical joint, the equality listed as not imported."""
    doc = read_mjcf(_plain_screw(coupling), keyframe="k")
    assert [j["type"] for j in doc.data["joints"] if j["name"] == "lift+spin"] == [
        "cylindrical"], why
    assert "equality constraints (joint" in doc.warnings[0].message


def test_a_state_off_the_screw_is_said():
    """A keyframe that breaks the coupling: mbody's screw starts from the state as given
    (MuJoCo would pull it back), and the warning says by how much."""
    doc = read_mjcf(_plain_screw('<joint joint1="lift" joint2="spin" polycoef="0 0.012"/>',
                                 key='qpos="0.02 0.7 0.3" qvel="0 2 -1"'), keyframe="k")
    assert "screw couplings broken by the state" in doc.warnings[0].message
    assert "by 0.0116 m, 0.024 m/s" in doc.warnings[0].message


def test_a_slot_needs_a_hinge_about_z():
    """A slide in the plane and a hinge across it, about world x, are no pin in a slot
    (the hinge would turn the body out of the plane): refused, naming the joints."""
    xml = to_mjcf(_load("scotch_yoke.yaml"))
    hinge = '<joint name="S:turn" type="hinge" pos="0.05 0 0" axis="0 0 1"/>'
    assert hinge in xml  # in the crank's axes, turned 30 deg: world x is (cos, -sin, 0)
    tilted = xml.replace(hinge, hinge.replace('axis="0 0 1"',
                                              f'axis="{float(np.cos(np.pi / 6))!r} -0.5 0"'))
    with pytest.raises(ModelError, match=r"slide 'S:slide', hinge 'S:turn'\) that no single"):
        read_mjcf(tilted, keyframe="initial")


def test_a_hinge_then_a_slide_on_the_world_is_refused():
    """In a planar export, a slide in the plane then a hinge about z is a pin in a slot;
    a hinge then a slide puts the slot in the body and the pin on its parent, which
    cannot be the world (a joint's child is never ground)."""
    xml = to_mjcf(_load("scotch_yoke.yaml"))
    assert '<joint name="S:slide"' in xml and '<joint name="S:turn"' in xml
    body = re.search(r'<body name="yoke".*?</body>', xml, re.S)
    assert body is not None
    turned = body.group(0).replace('<joint name="P" type="slide" pos="0 0 0" axis="1 0 0"/>',
                                   '<joint name="P:turn" type="hinge" axis="0 0 1"/>\n'
                                   '      <joint name="P:slide" type="slide" axis="1 0 0"/>', 1)
    assert turned != body.group(0)
    xml = re.sub(r"  <keyframe>.*</keyframe>\n", "", xml.replace(body.group(0), turned),
                 flags=re.S)
    with pytest.raises(ModelError, match="a pin in a slot whose pin is the world's"):
        read_mjcf(xml)


def test_one_letter_joints_and_free_particles_round_trip():
    """A universal joint 'A' (hinges A:1, A:2) and a cylindrical joint 'C' (C:slide,
    C:turn) come back named A and C; a free particle of a spatial model, written as three
    orthogonal slides, comes back a free particle."""
    spec = {"model": "letters", "dimension": 3, "gravity": [0, 0, -9.81],
            "bodies": [{"name": "a", "mass": 2, "inertia": [1, 2, 2.5],
                        "position": [0, 0, -0.5]},
                       {"name": "c", "mass": 1, "inertia": [0.1, 0.2, 0.25],
                        "position": [0, 0, -1.5]},
                       {"name": "p", "mass": 0.5, "inertia": 0, "position": [1, 2, 3],
                        "velocity": [0.5, -1, 2]}],
            "loads": [{"name": "push", "type": "force", "body": "p", "force": [1, 2, 3]}],
            "joints": [{"name": "A", "type": "universal", "parent": "ground", "child": "a",
                        "at": [0, 0, 0], "axis": [1, 0, 0], "axis2": [0, 1, 0]},
                       {"name": "C", "type": "cylindrical", "parent": "a", "child": "c",
                        "at": [0, 0, -1], "axis": [0, 0, 1]}]}
    model = mbody.load(spec)
    back, xml = _through_mjcf(model)
    assert 'name="A:1"' in xml and 'name="C:slide"' in xml and 'name="p:z"' in xml
    _same_model(model, back)
    assert sorted(j.name for j in back.joints) == ["A", "C"]


def test_round_trip_through_mjcf_gives_the_same_equations():
    """YAML → MJCF → YAML for random trees of every joint type, planar and spatial, with
    offset forces, couples, damped springs, fixed joints and joints that run against the
    tree (the child nearer the root): the same equations, names and directions."""
    mixes = [None, ("spherical", "universal", "revolute", "cylindrical"),
             ("spherical", "fixed", "universal", "revolute"),
             ("cylindrical", "spherical", "prismatic", "fixed")]
    specs = [spec for t in mixes for spec in _random_trees("spatial", t, 2, count=2)]
    specs += _random_trees("planar", None, 2, count=3)
    reversed_joints = fixed = 0
    for spec in specs:
        model = mbody.load(_moving(spec))
        tree = spanning_tree(model)
        reversed_joints += sum(j.child != b for b, j in tree.joint.items() if j is not None)
        fixed += sum(j.type == "fixed" for j in model.joints)
        back, _ = _through_mjcf(model)
        _same_model(model, back)
    assert reversed_joints > 0 and fixed > 0


def _per_body(spec: dict, seed: int) -> dict:
    """`spec` with every joint point given on each body (``at: [[parent], [child]]``,
    from the joint table: where the file's world point is on each body) and every body
    moved off its joints by about a millimetre and a degree: `mbody.load` assembles it
    (Newton from the file's pose, which turns the parents and so the joint frames)."""
    model = mbody.load(spec)
    rng = np.random.default_rng(seed)
    jt = model.joint_table
    joints = [{**j, "at": [_floats(jt.B_r_parent[k]), _floats(jt.B_r_child[k])]}
              for k, j in enumerate(spec["joints"])]
    bodies = []
    for i, b in enumerate(spec["bodies"]):
        turn = 0.02 * rng.normal(size=3)
        q = model.initial.quaternion[i]
        dq = np.concatenate(([1.0], turn / 2))
        w1, v1 = q[0], q[1:]
        w2, v2 = dq[0], dq[1:]
        moved = np.concatenate(([w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)))
        bodies.append({**b, "position": _floats(np.asarray(b["position"])
                                                + 1e-3 * rng.normal(size=3)),
                       "orientation": {"quaternion": _floats(moved / np.linalg.norm(moved))}})
    return {**spec, "bodies": bodies, "joints": joints}


def _floats(v) -> list[float]:
    return [float(x) for x in np.ravel(v)]


def test_joint_points_per_body_round_trip_and_agree_with_mujoco():
    """Random spatial trees of every joint type, rewritten with their joint points on
    each body and moved off their joints: the export writes the assembled pose (MuJoCo's
    accelerations and reactions agree with mbody's there, to 1e-9), and the model read
    back (the file's pose, points and axes from the entries) assembles to the same
    equations."""
    mixes = [None, ("spherical", "fixed", "universal", "revolute"),
             ("cylindrical", "spherical", "prismatic", "fixed")]
    turned = 0.0
    for k, spec in enumerate(s for t in mixes for s in _random_trees("spatial", t, 0,
                                                                     count=2)):
        model = mbody.load(_per_body(spec, k))
        assert model.file_state is not None
        turned = max(turned, float(np.abs(model.initial.quaternion
                                          - model.file_state.quaternion).max()))
        m, d = _mujoco(model)
        _forward(model, m, d)
        state = _state(model, m, d)
        np.testing.assert_allclose(state.position, model.initial.position, atol=1e-12)
        asm = mbody.assemble(model, state)
        sol = asm.solve()
        assert sol.residual < 1e-12  # MuJoCo's keyframe keeps every joint
        _compare(sol.accelerations, _accelerations(model, m, d))
        _check_reactions(model, m, d, asm, sol, state)
        back, _ = _through_mjcf(model)
        _same_model(model, back)
    assert turned > 1e-3  # the assembly turned bodies, and so joint frames


def _moving(spec: dict) -> dict:
    """`spec` at its pose with random velocities that respect its joints (MuJoCo's joint
    rates), so that the keyframe holds them exactly."""
    model = mbody.load(spec)
    m, d = _mujoco(model)
    d.qvel[:] = np.random.default_rng(7).normal(scale=2.0, size=m.nv)
    mujoco.mj_forward(m, d)
    state = _state(model, m, d)
    planar = model.dimension == cv.PLANAR
    bodies = [{**b, "velocity": state.velocity[i, :2 if planar else 3].tolist(),
               "angular_velocity": (float(state.omega[i, 2]) if planar
                                    else state.omega[i].tolist())}
              for i, b in enumerate(spec["bodies"])]
    return {**spec, "bodies": bodies}


def test_convert_yaml_to_mjcf_and_yaml(tmp_path, capsys):
    src = str(MODELS / "slider_crank.yaml")
    xml, yml = tmp_path / "sc.xml", tmp_path / "sc.yaml"
    assert main(["convert", src, "-o", str(xml)]) == 0
    assert "wrote" in capsys.readouterr().out
    m = mujoco.MjModel.from_xml_path(str(xml))
    assert (m.nbody, m.njnt, m.neq, m.nkey) == (4, 3, 1, 1)
    text = xml.read_text()
    assert "force 'gas' on 'piston': [-4000*exp(-200*t), 0, 0]" in text  # left out, said
    assert main(["convert", src, "-o", str(yml)]) == 0
    _same_equations(mbody.load(src), mbody.load(yml))
    assert yml.read_text().startswith(f"# Converted by mbody {mbody.__version__}")


@pytest.mark.parametrize("args, message", [
    (["-o", "{tmp}/out.ymal"], "did you mean '.yaml'?"),
    (["-o", "{tmp}/out.urdf"], "does not write it"),
    (["-o", "{tmp}/exists.xml"], "exists; give --force"),
    (["-o", "/proc/none/out.xml"], "cannot write"),
])
def test_convert_refuses_clearly(tmp_path, capsys, args, message):
    (tmp_path / "exists.xml").write_text("keep")
    argv = ["convert", str(MODELS / "pendulum.yaml")] + [a.format(tmp=tmp_path) for a in args]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert (tmp_path / "exists.xml").read_text() == "keep"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["exists.xml"]  # nothing partial
