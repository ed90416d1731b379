"""Cross-check against MuJoCo: free rigid bodies with full inertias, offset forces,
couples (world and body frame), gravity and arbitrary v, ω.

Frames: MuJoCo's free-joint qvel/qacc is [linear velocity/acceleration of the body
frame origin, world axes; angular velocity/acceleration, body (local) axes]. The body
frame is put at the mass centre (inertial pos = 0), so qacc matches mbody's rows
[a_G (world), ω̇ (body axes)] one for one. `xfrc_applied` is a world force and a world
torque about the body's mass centre, so each load is converted by hand (with scipy's
rotations, not mbody's): F_W = F (world) or R F (body); τ_W = (R r) × F_W for a force at
the body point r, τ (world) or R τ (body) for a couple.

Tolerance: |mbody − MuJoCo| ≤ 1e-9 · max(1, |a|) per row (MuJoCo factorises M in double
precision; observed differences are below 1e-14 relative).
"""

from __future__ import annotations

import numpy as np
import pytest
from randmodels import rotation_of, spatial_model
from scipy.spatial.transform import Rotation

import mbody
from mbody.model import State

mujoco = pytest.importorskip("mujoco")

RTOL = 1e-9


def _inertia(b: dict) -> np.ndarray:
    J = np.array(b["inertia"], float)
    return np.diag(J) if J.ndim == 1 else J


def _mjcf(spec: dict) -> str:
    g = spec.get("gravity", [0.0, 0.0, 0.0])
    parts = [f'<mujoco><option gravity="{g[0]!r} {g[1]!r} {g[2]!r}"/><worldbody>']
    for b in spec["bodies"]:
        J = _inertia(b)
        full = " ".join(repr(float(x)) for x in
                        (J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]))
        parts.append(f'<body name="{b["name"]}"><freejoint/>'
                     f'<inertial pos="0 0 0" mass="{b["mass"]!r}" fullinertia="{full}"/>'
                     "</body>")
    parts.append("</worldbody></mujoco>")
    return "".join(parts)


def _xfrc(spec: dict, R: np.ndarray) -> np.ndarray:
    """(n, 6) world force and world torque about each mass centre, from the load list."""
    idx = {b["name"]: i for i, b in enumerate(spec["bodies"])}
    out = np.zeros((len(idx), 6))
    for ld in spec["loads"]:
        i = idx[ld["body"]]
        body = ld.get("frame", "world") == "body"
        if ld["type"] == "force":
            F = R[i] @ ld["force"] if body else np.asarray(ld["force"])
            out[i, :3] += F
            out[i, 3:] += np.cross(R[i] @ ld["at"], F)
        else:
            out[i, 3:] += R[i] @ ld["torque"] if body else np.asarray(ld["torque"])
    return out


def _mujoco_qacc(spec: dict, pos, quat, vel, omega) -> np.ndarray:
    m = mujoco.MjModel.from_xml_string(_mjcf(spec))
    d = mujoco.MjData(m)
    n = len(spec["bodies"])
    d.qpos[:] = np.hstack((pos, quat)).ravel()
    d.qvel[:] = np.hstack((vel, omega)).ravel()
    R = Rotation.from_quat(quat, scalar_first=True).as_matrix()
    d.xfrc_applied[1:] = _xfrc(spec, R)
    mujoco.mj_forward(m, d)
    return d.qacc.reshape(n, 6).copy()


def _compare(ours: np.ndarray, theirs: np.ndarray) -> None:
    np.testing.assert_allclose(ours, theirs, rtol=0,
                               atol=RTOL * max(1.0, float(np.abs(theirs).max())))


def _free_bodies(seed: int, n: int = 12) -> dict:
    return spatial_model(seed, n, n_joints=0, n_forces=3 * n, n_torques=2 * n,
                         n_springs=0, known=False)


@pytest.mark.parametrize("seed", range(6))
def test_free_bodies_at_file_state(seed):
    spec = _free_bodies(seed)
    model = mbody.load(spec)
    ours = mbody.assemble(model).solve().accelerations.reshape(-1, 6)
    bodies = spec["bodies"]
    pos = np.array([b["position"] for b in bodies])
    quat = Rotation.from_matrix([rotation_of(b) for b in bodies]).as_quat(scalar_first=True)
    vel = np.array([b["velocity"] for b in bodies])
    omega = np.array([b["angular_velocity"] for b in bodies])
    theirs = _mujoco_qacc(spec, pos, quat, vel, omega)
    _compare(ours, theirs)
    # the case must be non-trivial: gyroscopic and load moments both matter
    assert np.abs(theirs[:, 3:]).max() > 1.0
    assert np.abs(np.asarray(mbody.assemble(model).b)).max() > 0.1


@pytest.mark.parametrize("seed", range(4))
def test_free_bodies_at_arbitrary_state(seed):
    """`assemble(model, state)` away from the file's pose and speeds."""
    spec = _free_bodies(50 + seed, 20)
    model = mbody.load(spec)
    rng = np.random.default_rng(seed)
    n = len(spec["bodies"])
    quat = Rotation.random(n, random_state=rng).as_quat(scalar_first=True)
    pos, vel = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    omega = rng.normal(scale=4.0, size=(n, 3))
    state = State(pos, quat, vel, omega)
    ours = mbody.assemble(model, state).solve().accelerations.reshape(-1, 6)
    _compare(ours, _mujoco_qacc(spec, pos, quat, vel, omega))


def test_single_body_known_numbers_agree():
    """A hand-checkable case through MuJoCo: principal body turned 90° about z, 2 N along
    world x at body point r = (0, 0.5, 1)."""
    spec = {"model": "one", "dimension": 3, "bodies": [
        {"name": "b", "mass": 2.0, "inertia": [1.0, 2.0, 2.5],
         "orientation": {"euler": [np.pi / 2, 0.0, 0.0], "sequence": "ZYX"}}],
        "loads": [{"type": "force", "body": "b", "force": [2.0, 0.0, 0.0],
                   "at": [0.0, 0.5, 1.0]}]}
    # (R r) = (−0.5, 0, 1); τ_W = (−0.5, 0, 1) × (2, 0, 0) = (0, 2, 0);
    # body axes: Rᵀ τ_W = (2, 0, 0); ω̇ = (2/1, 0, 0).
    ours = mbody.assemble(mbody.load(spec)).solve().accelerations
    np.testing.assert_allclose(ours, [1.0, 0, 0, 2.0, 0, 0], atol=1e-14)
    q = Rotation.from_euler("ZYX", [np.pi / 2, 0, 0]).as_quat(scalar_first=True)
    theirs = _mujoco_qacc(spec, np.zeros((1, 3)), q[None], np.zeros((1, 3)), np.zeros((1, 3)))
    _compare(ours.reshape(1, 6), theirs)


@pytest.mark.parametrize("seed", range(3))
def test_per_step_path_agrees_with_mujoco(seed):
    """The simulation's per-step kernel (`mbody.solve.dynamics.accelerations`, a separate
    implementation of the same loads) against MuJoCo at an arbitrary state."""
    dynamics = pytest.importorskip("mbody.dynamics")
    spec = _free_bodies(80 + seed, 40)
    model = mbody.load(spec)
    rng = np.random.default_rng(seed)
    n = len(spec["bodies"])
    quat = Rotation.random(n, random_state=rng).as_quat(scalar_first=True)
    pos, vel = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    omega = rng.normal(scale=4.0, size=(n, 3))
    ours = np.asarray(dynamics.accelerations(model, State(pos, quat, vel, omega)))
    _compare(ours, _mujoco_qacc(spec, pos, quat, vel, omega))
