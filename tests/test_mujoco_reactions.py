"""Cross-check of the constrained solve against MuJoCo (an independent engine).

MuJoCo works in joint coordinates (ball joints here), so its accelerations carry no
constraint drift and its joint reactions come from `mj_rnePostConstraint`:
``cfrc_int[b]`` = [moment, force] that the parent exerts on body b, the moment taken
about ``subtree_com[rootid[b]]``, world axes. ``mj_objectAcceleration`` gives a body's
angular acceleration and the mass centre's acceleration minus gravity, world axes.
"""

from __future__ import annotations

import numpy as np
import pytest

import mbody

mujoco = pytest.importorskip("mujoco")

G0 = 9.81


def _chain_xml(inertias, masses, L):
    bodies, close = "", ""
    for i, (I, m) in enumerate(zip(inertias, masses, strict=True)):
        pos = "0 0 0" if i == 0 else f"0 0 {-L}"
        bodies += (f'<body name="l{i}" pos="{pos}"><joint name="j{i}" type="ball" pos="0 0 0"/>'
                   f'<inertial pos="0 0 {-L / 2}" mass="{m}" diaginertia="{I[0]} {I[1]} {I[2]}"/>')
        close += "</body>"
    return (f'<mujoco><option gravity="0 0 {-G0}"/><worldbody>{bodies}{close}'
            "</worldbody></mujoco>")


def _mujoco_chain(n, seed):
    rng = np.random.default_rng(seed)
    L = 0.3
    inertias = [np.sort(rng.uniform(0.03, 0.05, 3)) for _ in range(n)]  # realisable
    masses = rng.uniform(0.5, 2.0, n)
    m = mujoco.MjModel.from_xml_string(_chain_xml(inertias, masses, L))
    d = mujoco.MjData(m)
    for i in range(n):
        q = rng.normal(size=4)
        d.qpos[4 * i:4 * i + 4] = q / np.linalg.norm(q) if i else [1, 0, 0, 0]
    d.qpos[:4] = rng.normal(size=4)
    d.qpos[:4] /= np.linalg.norm(d.qpos[:4])
    d.qvel[:] = rng.normal(scale=2.0, size=m.nv)
    mujoco.mj_forward(m, d)
    mujoco.mj_rnePostConstraint(m, d)
    return m, d, inertias, masses


def _mbody_from_mujoco(m, d, inertias, masses, names):
    bodies, joints = [], []
    vel = np.zeros(6)
    for i, name in enumerate(names):
        b = i + 1
        R = d.ximat[b].reshape(3, 3)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)
        bodies.append({"name": name, "mass": float(masses[i]),
                       "inertia": [float(x) for x in inertias[i]],
                       "position": d.xipos[b].tolist(), "orientation": {"matrix": R.tolist()},
                       "velocity": vel[3:].tolist(),
                       "angular_velocity": (R.T @ vel[:3]).tolist()})
        joints.append({"name": f"j{i}", "type": "spherical",
                       "parent": "ground" if i == 0 else names[i - 1], "child": name,
                       "at": d.xanchor[i].tolist()})
    return {"model": "mujoco-chain", "dimension": 3, "gravity": [0, 0, -G0],
            "bodies": bodies, "joints": joints}


@pytest.mark.parametrize("n, seed", [(1, 0), (2, 1), (6, 2), (12, 3)])
def test_ball_chain_accelerations_and_reactions_agree_with_mujoco(n, seed):
    """n = 1 is a heavy top on a spherical joint; longer ones are spatial chains."""
    m, d, inertias, masses = _mujoco_chain(n, seed)
    names = [f"l{i}" for i in range(n)]
    spec = _mbody_from_mujoco(m, d, inertias, masses, names)
    asm = mbody.assemble(mbody.load(spec))
    sol = asm.solve()
    acc = sol.accelerations.reshape(n, 6)
    res = np.zeros(6)
    g = np.array([0, 0, -G0])
    root_com = d.subtree_com[1]
    for i in range(n):
        b = i + 1
        R = d.ximat[b].reshape(3, 3)
        mujoco.mj_objectAcceleration(m, d, mujoco.mjtObj.mjOBJ_BODY, b, res, 0)
        assert acc[i, :3] == pytest.approx(res[3:] + g, rel=1e-8, abs=1e-8)
        assert acc[i, 3:] == pytest.approx(R.T @ res[:3], rel=1e-8, abs=1e-8)
        force = np.array([sol.reactions[f"j{i}.F{c}"] for c in "xyz"])
        assert force == pytest.approx(d.cfrc_int[b, 3:], rel=1e-8, abs=1e-8)
        # A ball joint transmits no couple: MuJoCo's moment is the force's moment about root_com.
        P = d.xanchor[i]
        assert np.cross(P - root_com, force) == pytest.approx(d.cfrc_int[b, :3], rel=1e-8,
                                                          abs=1e-8)
    assert sol.residual < 1e-13
