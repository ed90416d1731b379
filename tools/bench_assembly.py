"""Time per body of mbody's assembly and per-step paths, against a naive loop and MuJoCo.

    python tools/bench_assembly.py [--quick] [--repeat N] [--sizes 10,1000]

Model: n free spatial bodies, each with a random mass, a full (non-diagonal) inertia
tensor, a rotated pose, a velocity and an angular velocity, one world-frame force applied
at an offset point, and gravity. Columns (nanoseconds per body, best of --repeat runs):

- (a) ``mbody.assemble(model, state).solve()``: the stacked equations, then v̇;
- (b) ``mbody.solve.dynamics.accelerations(model, state)``: what a simulation calls per step
  (b, Q and v̇ with M and J⁻¹ kept), and the same with a reused ``out=`` buffer;
- naive: the same numbers from a per-body Python loop on numpy 3-vectors;
- MuJoCo: ``mj_forward`` on the same bodies (free joints, same masses, inertias, poses,
  velocities and gravity; each offset force given as ``xfrc_applied`` force + moment).

Ratios are naive/mbody and MuJoCo/mbody (higher = mbody faster), measured in one process.
The last line times loading and validating a 10 000-body model file. MuJoCo's compiler
takes time quadratic in the number of bodies, so its column is measured on at most
--mujoco-limit bodies (marked †); see docs/performance.md.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:  # tools/timing.py, also when loaded by path
    sys.path.insert(0, str(ROOT / "tools"))

from timing import best  # noqa: E402

import mbody  # noqa: E402
from mbody.model import Body, ForceTable, Load, Model, State  # noqa: E402
from mbody.solve import dynamics  # noqa: E402

GRAVITY = np.array([0.0, 0.0, -9.81])


# -- the model ----------------------------------------------------------------------------
def draw(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Random arrays for n free bodies (see the module docstring); all SI, as in a file."""
    rng = np.random.default_rng(seed)
    mass = rng.uniform(0.5, 5.0, n)
    edges = rng.uniform(0.2, 1.5, (n, 3))
    a2, b2, c2 = (edges ** 2).T
    principal = mass[:, None] / 12.0 * np.stack((b2 + c2, a2 + c2, a2 + b2), axis=1)
    S = _quat_matrix(_unit_quats(rng, n))  # principal axes, tilted in the body
    J = np.einsum("nij,nj,nkj->nik", S, principal, S)
    J = 0.5 * (J + J.transpose(0, 2, 1))
    return {
        "mass": mass, "inertia": J, "position": rng.normal(size=(n, 3)),
        "quaternion": _unit_quats(rng, n), "velocity": rng.normal(size=(n, 3)),
        "omega": rng.normal(size=(n, 3)), "force": rng.normal(scale=10.0, size=(n, 3)),
        "at": rng.normal(scale=0.3, size=(n, 3)),
    }


def _unit_quats(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q * np.where(q[:, :1] < 0, -1.0, 1.0)


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    from mbody.util.spatial import quat_to_matrix

    return quat_to_matrix(q)


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=float)
    a.flags.writeable = False
    return a


def free_bodies(n: int, seed: int = 0) -> Model:
    """The benchmark model, built straight from arrays (the file path is timed apart)."""
    d = draw(n, seed)
    names = tuple(f"b{i}" for i in range(n))
    J = _ro(d["inertia"])
    state = State(_ro(d["position"]), _ro(d["quaternion"]), _ro(d["velocity"]),
                  _ro(d["omega"]))
    bodies = {nm: Body(nm, i, float(d["mass"][i]), J[i], None, None)
              for i, nm in enumerate(names)}
    loads = tuple(Load(f"f{i}", "force", (nm,), d["force"][i], "world", (d["at"][i],))
                  for i, nm in enumerate(names))
    forces = ForceTable(tuple(ld.name for ld in loads), np.arange(n, dtype=np.intp),
                        _ro(d["force"]), np.zeros(n, bool), _ro(d["at"]), np.zeros(n, bool))
    # Empty spring and joint tables (and any field added later) from a one-body file.
    base = mbody.load({"model": "base", "dimension": 3,
                       "bodies": [{"name": "b", "mass": 1.0, "inertia": [1, 1, 1]}]})
    return replace(base, name=f"free-bodies-{n}", file="<bench>", body_names=names,
                   mass=_ro(d["mass"]), J=J, J_inv=_ro(np.linalg.inv(J)),
                   gravity=_ro(GRAVITY), initial=state, bodies=bodies, loads=loads,
                   forces=forces)


def free_bodies_spec(n: int, seed: int = 0) -> dict:
    """The same model as a model-file dict (for `mbody.load` and for writing YAML)."""
    d = draw(n, seed)
    f = lambda a: [float(x) for x in np.ravel(a)]  # noqa: E731
    bodies = [{"name": f"b{i}", "mass": float(d["mass"][i]),
               "inertia": [f(row) for row in d["inertia"][i]],
               "position": f(d["position"][i]),
               "orientation": {"quaternion": f(d["quaternion"][i])},
               "velocity": f(d["velocity"][i]), "angular_velocity": f(d["omega"][i])}
              for i in range(n)]
    loads = [{"name": f"f{i}", "type": "force", "body": f"b{i}", "force": f(d["force"][i]),
              "at": f(d["at"][i]), "frame": "world"} for i in range(n)]
    return {"model": f"free-bodies-{n}", "dimension": 3, "gravity": f(GRAVITY),
            "bodies": bodies, "loads": loads}


# -- the naive per-body loop --------------------------------------------------------------
def naive_step(model: Model, state: State) -> np.ndarray:
    """Per body, with numpy 3-vectors: a = F/m + g, ω̇ = J⁻¹(r × Rᵀf − ω × Jω)."""
    out = np.empty((model.n, 6))
    ft = model.forces
    for i in range(model.n):
        w, x, y, z = state.quaternion[i]
        R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        f = ft.vector[i]
        M = np.cross(ft.B_r[i], R.T @ f)
        om = state.omega[i]
        out[i, :3] = f / model.mass[i] + model.gravity
        out[i, 3:] = model.J_inv[i] @ (M - np.cross(om, model.J[i] @ om))
    return out


def naive_assemble_solve(model: Model, state: State) -> np.ndarray:
    """Per body: fill Q and b, then solve block by block (flat, in coordinate order)."""
    n = model.n
    Q, b = np.zeros(6 * n), np.zeros(6 * n)
    ft = model.forces
    for i in range(n):
        w, x, y, z = state.quaternion[i]
        R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        f = ft.vector[i]
        Q[6 * i:6 * i + 3] = f + model.mass[i] * model.gravity
        Q[6 * i + 3:6 * i + 6] = np.cross(ft.B_r[i], R.T @ f)
        om = state.omega[i]
        b[6 * i + 3:6 * i + 6] = np.cross(om, model.J[i] @ om)
    acc = np.empty(6 * n)
    for i in range(n):
        rhs = Q[6 * i:6 * i + 6] - b[6 * i:6 * i + 6]
        acc[6 * i:6 * i + 3] = rhs[:3] / model.mass[i]
        acc[6 * i + 3:6 * i + 6] = model.J_inv[i] @ rhs[3:]
    return acc


# -- MuJoCo ----------------------------------------------------------------------------------
def mujoco_setup(model: Model, state: State):
    """(MjModel, MjData) of the same free bodies with the loads in xfrc_applied.

    xfrc_applied is a force and a moment about the mass centre, world axes: the offset
    force's moment is (W_R_B B_r) × W_f. The free joint's qvel is [v_G world, ω body].
    """
    import mujoco

    from mbody.util.spatial import quat_to_matrix

    g = " ".join(repr(float(x)) for x in model.gravity)
    # No geoms and contacts off: nothing but the free bodies' dynamics is computed.
    parts = [f'<mujoco><option gravity="{g}"><flag contact="disable"/></option><worldbody>']
    for i in range(model.n):
        J = model.J[i].tolist()
        parts.append(
            f'<body name="b{i}"><freejoint/><inertial pos="0 0 0" '
            f'mass="{float(model.mass[i])!r}" fullinertia="{J[0][0]!r} {J[1][1]!r} '
            f'{J[2][2]!r} {J[0][1]!r} {J[0][2]!r} {J[1][2]!r}"/></body>')
    parts.append("</worldbody></mujoco>")
    m = mujoco.MjModel.from_xml_string("".join(parts))
    d = mujoco.MjData(m)
    qpos = d.qpos.reshape(model.n, 7)
    qpos[:, :3] = state.position
    qpos[:, 3:] = state.quaternion
    qvel = d.qvel.reshape(model.n, 6)
    qvel[:, :3] = state.velocity
    qvel[:, 3:] = state.omega
    ft = model.forces
    R = quat_to_matrix(state.quaternion[ft.body])
    xf = d.xfrc_applied[1:]  # row 0 is the world body
    xf[ft.body, :3] = ft.vector
    xf[ft.body, 3:] = np.cross(np.einsum("nij,nj->ni", R, ft.B_r), ft.vector)
    return m, d


def mujoco_accelerations(m, d) -> np.ndarray:
    """mj_forward's qacc per body as [a_G world, ω̇ body] (rows of the free joint)."""
    import mujoco

    mujoco.mj_forward(m, d)
    return d.qacc.reshape(-1, 6).copy()


# -- timing ----------------------------------------------------------------------------------


_mujoco_cache: dict[int, float] = {}


def mujoco_ns(n: int, repeat: int) -> float:
    """mj_forward time per body (ns) on the n-body benchmark model."""
    if n not in _mujoco_cache:
        model = free_bodies(n)
        m, d = mujoco_setup(model, model.initial)
        _mujoco_cache[n] = best(lambda: mujoco_accelerations(m, d), repeat) * 1e9 / n
    return _mujoco_cache[n]


def row(n: int, repeat: int, naive_limit: int, mujoco_limit: int) -> str:
    """One line of the table for n bodies (mujoco_limit 0: no MuJoCo column)."""
    model = free_bodies(n)
    state = model.initial
    ns = 1e9 / n
    ta = best(lambda: mbody.assemble(model, state).solve(), repeat) * ns
    tb = best(lambda: dynamics.accelerations(model, state), repeat) * ns
    buf = np.empty((6, n)).T
    tb2 = best(lambda: dynamics.accelerations(model, state, out=buf), repeat) * ns
    k = min(n, naive_limit)  # the naive loop is linear in n: time it on k bodies
    sub = model if k == n else free_bodies(k)
    r = max(1, min(repeat, 3))
    tna = best(lambda: naive_assemble_solve(sub, sub.initial), r, 0.0) * 1e9 / k
    tnb = best(lambda: naive_step(sub, sub.initial), r, 0.0) * 1e9 / k
    star = "*" if k < n else " "
    line = (f"{n:>7} | {ta:7.1f} {tb:7.1f} {tb2:7.1f} | {tna:7.0f}{star} {tna / ta:6.0f} "
            f"{tnb:7.0f}{star} {tnb / tb:6.0f}")
    if mujoco_limit:
        tm = mujoco_ns(min(n, mujoco_limit), repeat)
        mark = "†" if n > mujoco_limit else " "
        line += f" | {tm:7.1f}{mark} {tm / ta:6.2f} {tm / tb:6.2f}"
    return line


def run(sizes: list[int], repeat: int, naive_limit: int, mujoco_limit: int,
        file_bodies: int) -> None:
    try:
        import mujoco  # noqa: F401

        have_mujoco = True
    except ImportError:
        have_mujoco = False
    print(f"ns per body, best of {repeat}; ratio = other / mbody (higher: mbody faster)")
    print("(a) assemble + solve    (b) per-step dynamics.accelerations "
          "(b') the same with out= buffer")
    head = (f"{'n':>7} | {'(a)':>7} {'(b)':>7} {'(b′)':>7} | {'naive a':>8} {'×':>6} "
            f"{'naive b':>8} {'×':>6}")
    if have_mujoco:
        head += f" | {'MuJoCo':>8} {'×(a)':>6} {'×(b)':>6}"
    print(head)
    print("-" * len(head))
    for n in sizes:
        print(row(n, repeat, naive_limit, mujoco_limit if have_mujoco else 0), flush=True)
    if any(n > naive_limit for n in sizes):
        print(f"* naive loop timed on {naive_limit} bodies (its cost is linear in n)")
    if have_mujoco and any(n > mujoco_limit for n in sizes):
        print(f"† MuJoCo timed on {mujoco_limit} bodies: its model compiler is quadratic in "
              "the body count (~12 s at 4000, ~100 s at 10 000), and per body mj_forward "
              "only gets slower as n outgrows the cache, so this favours MuJoCo")
    if not have_mujoco:
        print("(MuJoCo columns skipped: mujoco is not importable)")

    import yaml

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"free_{file_bodies}.yaml"
        spec = free_bodies_spec(file_bodies)
        dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
        path.write_text(yaml.dump(spec, Dumper=dumper, sort_keys=False,
                                  default_flow_style=None, width=200))
        size = path.stat().st_size
        tl = best(lambda: mbody.load(path), 1 if file_bodies > 2000 else repeat, 0.0)
    print(f"\nload + validate a {file_bodies}-body file ({size / 1e6:.1f} MB): "
          f"{tl * 1e6 / file_bodies:.1f} µs per body ({tl:.2f} s)")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="small sizes only (CI smoke run)")
    p.add_argument("--repeat", type=int, default=9, help="timed runs per entry (best is kept)")
    p.add_argument("--sizes", help="comma-separated body counts (overrides --quick)")
    p.add_argument("--file-bodies", type=int, metavar="N",
                   help="bodies in the timed model file (default 10000; 1000 with --quick)")
    p.add_argument("--mujoco-limit", type=int, default=4000, metavar="N",
                   help="largest MuJoCo model compiled (compile time is quadratic in N)")
    a = p.parse_args(argv)
    if a.sizes:
        sizes = [int(s) for s in a.sizes.split(",")]
    else:
        sizes = [10, 100, 1000] if a.quick else [10, 100, 1000, 10_000, 100_000]
    run(sizes, max(1, a.repeat), naive_limit=2000 if a.quick else 20_000,
        mujoco_limit=1000 if a.quick else a.mujoco_limit,
        file_bodies=a.file_bodies or (1000 if a.quick else 10_000))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
