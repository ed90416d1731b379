"""Benchmark: build and solve a hanging chain of n links with every pin reaction unknown.

    python tools/bench_chain.py [--quick] [--repeat R]

Per link, best of R runs, all in one process:
- mbody: `assemble(model, state)` + `solve()` (accelerations and every reaction), with the
  relative backward error and the Schur complement's condition estimate;
- baseline: scipy's general sparse LU (splu) of the whole KKT matrix [[M, -G], [Gᵀ, 0]]
  built from the same M and G (what a direct approach without structure costs);
- MuJoCo `mj_forward` on the same chain in maximal coordinates (free bodies held by
  `connect` equality constraints) and in joint coordinates (nested ball joints; its cost
  grows as n², so only up to 1000 links).
Ratios are against mbody in the same process. Spherical pins: 3 reaction unknowns a link.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import mbody

L, G0 = 0.1, 9.81


OMEGA = np.array([0.3, -0.2, 0.1])
"""The chain turns as one rigid body about its top pin (a state its joints allow)."""


def chain_spec(n: int) -> dict:
    bodies, joints = [], []
    for i in range(n):
        x = np.array([0.0, 0.0, -L * (i + 0.5)])
        bodies.append({"name": f"l{i}", "mass": 1.0, "inertia": [1e-3, 1e-3, 2e-4],
                       "position": x.tolist(), "angular_velocity": OMEGA.tolist(),
                       "velocity": np.cross(OMEGA, x).tolist()})  # turning as one rigid body
        joints.append({"name": f"j{i}", "type": "spherical",
                       "parent": "ground" if i == 0 else f"l{i - 1}", "child": f"l{i}",
                       "at": [0.0, 0.0, -L * i]})
    return {"model": f"chain-{n}", "dimension": 3, "gravity": [0, 0, -G0], "bodies": bodies,
            "joints": joints}


def best(fn, repeat: int, *args) -> float:
    out = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn(*args)
        out = min(out, time.perf_counter() - t0)
    return out


def build_and_solve(model: mbody.Model, state: mbody.State) -> None:
    mbody.assemble(model, state).solve()


def kkt_splu(asm: mbody.Assembly) -> None:
    M, G = asm.M.tocsc(), asm.G.tocsc()
    m = G.shape[1]
    K = sp.bmat([[M, -G], [G.T, sp.csc_matrix((m, m))]], format="csc")
    rhs = np.concatenate((asm.Q - asm.b, asm.jacobian().gamma))
    spla.splu(K).solve(rhs)


def mujoco_models(n: int, joint_coordinates: bool):
    import mujoco

    inertial = '<inertial pos="0 0 0" mass="1" diaginertia="1e-3 1e-3 2e-4"/>'
    if joint_coordinates:  # nested 1000 deep: built with MjSpec (XML limits nesting)
        spec = mujoco.MjSpec()
        spec.option.gravity = [0, 0, -G0]
        parent = spec.worldbody
        for i in range(n):
            body = parent.add_body(name=f"l{i}", pos=[0, 0, -L / 2 if i == 0 else -L],
                                   mass=1.0, inertia=[1e-3, 1e-3, 2e-4],
                                   explicitinertial=True)
            body.add_joint(type=mujoco.mjtJoint.mjJNT_BALL, pos=[0, 0, L / 2])
            parent = body
        m = spec.compile()
        return mujoco, m, mujoco.MjData(m)
    else:
        body = "".join(f'<body name="l{i}" pos="0 0 {-L * (i + 0.5)}"><freejoint/>{inertial}'
                       "</body>" for i in range(n))
        eq = '<connect body1="world" body2="l0" anchor="0 0 0"/>' + "".join(
            f'<connect body1="l{i - 1}" body2="l{i}" anchor="0 0 {-L / 2}"/>'
            for i in range(1, n))
        xml = (f'<mujoco><option gravity="0 0 {-G0}" jacobian="sparse"/><size memory="2G"/>'
               f"<worldbody>{body}</worldbody>"
               f"<equality>{eq}</equality></mujoco>")
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    return mujoco, m, d


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="n up to 1000 only")
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    sizes = [10, 100, 1000] if a.quick else [10, 100, 1000, 10_000]
    try:
        import mujoco  # noqa: F401

        have_mj = True
    except ImportError:
        have_mj = False
    print("chain of n links, spherical pins (3 unknowns a link); microseconds per link, "
          "best of", a.repeat)
    print(f"{'n':>7} {'mbody':>8} {'KKT splu':>9} {'ratio':>6} {'MJ max':>8} {'ratio':>6} "
          f"{'MJ joint':>9} {'ratio':>6} {'back.err':>9} {'cond':>9}")
    for n in sizes:
        model = mbody.load(chain_spec(n))
        state = model.initial
        t_mb = best(build_and_solve, a.repeat, model, state) / n
        sol = mbody.assemble(model, state).solve(condition=True)
        asm = mbody.assemble(model, state)
        t_lu = best(kkt_splu, max(1, a.repeat // 2), asm) / n
        cols = [f"{n:>7} {1e6 * t_mb:8.2f} {1e6 * t_lu:9.2f} {t_lu / t_mb:6.1f}"]
        if have_mj:
            mj, m, d = mujoco_models(n, joint_coordinates=False)
            t_max = best(mj.mj_forward, a.repeat, m, d) / n
            cols.append(f"{1e6 * t_max:8.2f} {t_max / t_mb:6.1f}")
            if n <= 1000:
                mj, m, d = mujoco_models(n, joint_coordinates=True)
                t_j = best(mj.mj_forward, a.repeat, m, d) / n
                cols.append(f"{1e6 * t_j:9.2f} {t_j / t_mb:6.1f}")
            else:
                cols.append(f"{'-':>9} {'-':>6}")
        cols.append(f"{sol.residual:9.1e} {sol.condition:9.1e}")
        print(" ".join(cols), flush=True)
    print("ratio = that column's time / mbody's time (above 1: mbody is faster)")


if __name__ == "__main__":
    main()
