"""A 150-link chain hanging straight, its joint points given on each body: it assembles
and solves on the banded (linear) routes, with MuJoCo's values.

The chain is tools/bench_assembly_size.py's (`chain_spec`). Before the unknowns were
ordered from the ground (`mbody.equations.pack.band_order`), a straight chain's ground
joint came last in the order and its Cholesky pivot kept about 1/n of its diagonal (1/n³
with parallel revolute axes): past n = 100 `mbody.load`'s projection, and with parallel
revolutes the solve too, took the dense null-space route, cubic in n (14 s to load and
solve 120 parallel revolutes).
Its answers were right, so what this holds is the route (the work bound) and the values.

MuJoCo's equivalent is built from the chain's numbers alone (`chain_parts`), in joint
coordinates (nested bodies), at mbody's assembled state. Its joint reactions come from
`mj_rnePostConstraint`: ``cfrc_int[b]`` = [moment, force] the parent exerts on body b, the
moment about ``subtree_com`` of the root, world axes.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.equations.solution import METHODS

mujoco = pytest.importorskip("mujoco")

ROOT = Path(__file__).resolve().parent.parent
N = 150
EPS = np.finfo(float).eps


def _bench():
    name = "bench_assembly_size"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


bench = _bench()


def _quat(R: np.ndarray) -> list[float]:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_quat(scalar_first=True).tolist()


def _mujoco_chain(parts: dict[str, np.ndarray]):
    """The chain in joint coordinates, straight at qpos = 0: body i's frame at its top
    joint, world-aligned there, its mass centre L/2 below with principal axes W_R_B[i]."""
    spec = mujoco.MjSpec()
    spec.option.gravity = [0, 0, -bench.G0]
    parent = spec.worldbody
    for i in range(len(parts["mass"])):
        body = parent.add_body(name=f"l{i}", pos=[0, 0, 0 if i == 0 else -bench.L],
                               mass=float(parts["mass"][i]), ipos=[0, 0, -bench.L / 2],
                               iquat=_quat(parts["W_R_B"][i]),
                               inertia=parts["principal"][i].tolist(), explicitinertial=True)
        if parts["revolute"][i]:
            body.add_joint(type=mujoco.mjtJoint.mjJNT_HINGE, axis=parts["axis"][i].tolist())
        else:
            body.add_joint(type=mujoco.mjtJoint.mjJNT_BALL)
        parent = body
    m = spec.compile()
    return m, mujoco.MjData(m)


def _joint_frame(axis: np.ndarray) -> np.ndarray:
    """Columns x, y, z of a spatial joint's frame by the contract's rule: z along the
    axis, x the world axis least aligned with it (the first on a tie) less its z part."""
    z = axis / np.linalg.norm(axis)
    e = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = e - (e @ z) * z
    x /= np.linalg.norm(x)
    return np.column_stack((x, np.cross(z, x), z))


@pytest.fixture(scope="module", params=bench.KINDS)
def chain(request):
    kind = request.param
    model = mbody.load(bench.chain_spec(N, kind))
    return kind, model, bench.chain_parts(N, kind)


def test_the_assembly_stays_on_the_banded_routes(chain):
    """The work bound: the projection that assembled the chain (and every later one) and
    the solve take the banded Cholesky, linear in n, not the dense null-space route."""
    _, model, _ = chain
    assert bench.geometric_ratio(model) >= bench.ROBUST_BELOW
    sol = mbody.assemble(model).solve()
    assert sol.method == METHODS[0]
    assert sol.redundant == 0


def test_the_assembly_keeps_the_straight_pose(chain):
    """The file's pose already holds every joint: the assembly moves it by rounding only."""
    _, model, _ = chain
    size = bench.L * N
    assert np.abs(model.initial.position - model.file_state.position).max() <= 1e3 * EPS * size


def test_accelerations_and_reactions_equal_mujocos(chain):
    """At the assembled state (the file's random velocities, less what the joints forbid):
    every body's accelerations and every joint's force and couple equal MuJoCo's.

    The tolerance is the two solves' rounding, norm-wise: 10 (cond(S) + cond(M_q)) ε of
    the largest value of the kind, in one unit (an angular acceleration or a couple times
    or over the link length L): cond(S) the solve's own estimate, M_q MuJoCo's joint-space
    mass matrix (a long chain's compliance grows with n, and both with it)."""
    kind, model, parts = chain
    state = model.initial
    sol = mbody.assemble(model, state).solve(condition=True)
    m, d = _mujoco_chain(parts)
    R = parts["W_R_B"]
    assert np.allclose(state.W_R_B, R, atol=1e3 * EPS)  # the same pose
    omega_w = np.einsum("nij,nj->ni", R, state.omega)  # world axes
    relative = omega_w - np.vstack((np.zeros(3), omega_w[:-1]))
    for i in range(N):  # joint rates: body frames are world-aligned at qpos = 0
        a = m.jnt_dofadr[i]
        if parts["revolute"][i]:
            d.qvel[a] = relative[i] @ parts["axis"][i]
        else:
            d.qvel[a:a + 3] = relative[i]
    mujoco.mj_forward(m, d)
    mujoco.mj_rnePostConstraint(m, d)
    Mq = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, Mq)
    tol = 10.0 * (sol.condition + np.linalg.cond(Mq)) * EPS
    assert tol < 1e-5  # the check means something
    vel, res = np.zeros(6), np.zeros(6)
    v_mj, a_mj = np.zeros((N, 6)), np.zeros((N, 6))
    for i in range(N):
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, i + 1, vel, 0)
        v_mj[i] = np.concatenate((vel[3:], R[i].T @ vel[:3]))
        mujoco.mj_objectAcceleration(m, d, mujoco.mjtObj.mjOBJ_BODY, i + 1, res, 0)
        a_mj[i] = np.concatenate((res[3:] + [0, 0, -bench.G0], R[i].T @ res[:3]))
    L = bench.L
    # the same motion: mbody's velocities are ones the joints allow
    v_mb = np.hstack((state.velocity, state.omega))
    v_scale = max(np.abs(v_mj[:, :3]).max(), L * np.abs(v_mj[:, 3:]).max())
    assert np.abs(v_mb[:, :3] - v_mj[:, :3]).max() <= tol * v_scale
    assert L * np.abs(v_mb[:, 3:] - v_mj[:, 3:]).max() <= tol * v_scale
    acc = sol.accelerations.reshape(N, 6)
    a_scale = max(np.abs(a_mj[:, :3]).max(), L * np.abs(a_mj[:, 3:]).max())
    assert np.abs(acc[:, :3] - a_mj[:, :3]).max() <= tol * a_scale
    assert L * np.abs(acc[:, 3:] - a_mj[:, 3:]).max() <= tol * a_scale
    force, couple = np.zeros((N, 3)), np.zeros((N, 3))
    r = sol.reactions
    for i in range(N):
        if parts["revolute"][i]:
            E = _joint_frame(parts["axis"][i])
            force[i] = E @ [r[f"j{i}.Fx"], r[f"j{i}.Fy"], r[f"j{i}.Fz"]]
            couple[i] = E @ [r[f"j{i}.Mx"], r[f"j{i}.My"], 0.0]
        else:
            force[i] = [r[f"j{i}.F{c}"] for c in "xyz"]
    f_mj = d.cfrc_int[1:, 3:]
    points = np.column_stack((np.zeros(N), np.zeros(N), -L * np.arange(N)))
    c_mj = d.cfrc_int[1:, :3] - np.cross(points - d.subtree_com[1], f_mj)  # about the joint
    r_scale = max(np.abs(f_mj).max(), np.abs(c_mj).max() / L)
    assert np.abs(force - f_mj).max() <= tol * r_scale
    assert np.abs(couple - c_mj).max() / L <= tol * r_scale
    if kind == "mixed":  # a ball joint transmits no couple
        assert np.abs(c_mj[~parts["revolute"]]).max() / L <= tol * r_scale


@pytest.mark.parametrize("seed", range(5))
def test_the_order_brings_a_fresh_body_with_each_joint_of_a_tree(seed):
    """`band_order` on random forests (some trees held by the ground, some floating),
    components labelled in a random order: a permutation in which each joint's first
    component acts on a body no earlier component touches (so its pivot measures that
    joint), the ground counting as touched."""
    from mbody.equations.pack import band_order

    rng = np.random.default_rng(seed)
    n = 200
    parent = np.array([-1 if b == 0 or rng.random() < 0.05 else int(rng.integers(0, b))
                       for b in range(n)])
    floating = np.flatnonzero((parent == -1) & (rng.random(n) < 0.5))
    joints = [b for b in range(n) if b not in set(floating)]  # a floating root: no joint
    per = rng.integers(1, 6, len(joints))  # components of each joint
    joint = np.repeat(joints, per)
    labels = rng.permutation(len(joint))
    child, par = joint[labels], parent[joint[labels]]
    order = band_order(child, par, n)
    assert np.array_equal(np.sort(order), np.arange(len(child)))
    touched = np.zeros(n, bool)
    seen: set[int] = set()
    for k in order:
        c, p = int(child[k]), int(par[k])
        if c not in seen:  # the joint's first component
            assert not touched[c] or (p >= 0 and not touched[p])
            seen.add(c)
        touched[c] = True
        if p >= 0:
            touched[p] = True
