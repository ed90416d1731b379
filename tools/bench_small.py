"""Small shipped models: mbody against MuJoCo on the same systems, in one process.

    python tools/bench_small.py [--quick] [--repeat N] [--sim-limit S] [--no-accuracy]

Systems: pendulum, double and triple pendulum, heavy top, slider-crank, planar four-bar,
gyroscope in gimbals, and the spatial four-bar (redundant constraints) as an extra row,
each read from models/. Measured per system (microseconds per call, best of --repeat):

- solve: ``mbody.assemble(model, model.initial).solve()`` (accelerations and every
  unknown reaction, as a user calls it), and beside it the compiled core's solve alone
  (`Unknowns.solve` of the model's workspace, `mbody.equations.workspace`, on the packed
  state: what the public call costs beyond the core is the difference). There is one
  numeric path, the core (`mbody.kernel`); the numba and numpy paths this table once
  compared are gone;
- MuJoCo: ``mj_forward`` on an equivalent model built here from the mbody model's numbers
  (masses, inertias, poses, joint points and axes, loads, gravity, initial velocities):
  a tree of hinge, slide and ball joints, one MuJoCo body frame per mbody body at its mass
  centre; a closed loop is cut at one pin and closed by an ``<equality><connect>``.
  MuJoCo's equality constraints are soft (here as stiff as it allows), so on those rows
  its accelerations differ a little from the rigid ones: the rows compare time only;
- RHS: one call ``f(0.0, y)`` of ``mbody.simulate``'s right-hand side, with y built as
  `simulate` builds it (blocks ``[x | q | v | ω | θ (planar)]``);
- 10 s of ``mbody.simulate(model, t_end=10)`` at its defaults (DOP853, rtol 1e-10,
  atol 1e-12): wall time of the whole call, steps and right-hand-side evaluations.

Then time to accuracy on the double pendulum and the heavy top (trees: their MuJoCo
equivalents are exact) and the slider-crank (a closed loop, coasting without its loads):
the mass-centre position error at t = 10 s against a tight reference, and the wall time
each engine needs for a given error (the whole ``mbody.simulate`` call over a range of
tolerances, later calls in this process and the first call in a fresh process apart, the
latter the median of `--first-runs` fresh processes;
MuJoCo's RK4 over a range of fixed steps, stepped in C by ``mujoco.rollout``, its own
first call in a fresh process shown beside for context); and the
open double pendulum against Exudyn's minimal-coordinate kinematic tree with its DOPRI5
(``pip install -e ".[bench]"``; skipped when Exudyn is not installed).
Before timing anything, each MuJoCo equivalent is checked against
mbody at the initial state (positions, velocities and accelerations of every mass
centre and body rotation) and the result printed. Targets (from the issue) are printed
beside the numbers with PASS/MISS.
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tools") not in sys.path:  # tools/timing.py, also when loaded by path
    sys.path.insert(0, str(ROOT / "tools"))

from timing import best  # noqa: E402

import mbody  # noqa: E402
from mbody.equations.workspace import workspace  # noqa: E402
from mbody.kernel import _core  # noqa: E402

MODELS = ROOT / "models"
SYSTEMS = (
    ("pendulum", "pendulum.yaml"),
    ("double pendulum", "double_pendulum.yaml"),
    ("triple pendulum", "triple_pendulum.yaml"),
    ("heavy top", "heavy_top.yaml"),
    ("slider-crank", "slider_crank.yaml"),
    ("four-bar planar", "fourbar_planar.yaml"),
    ("gimbals", "gyroscope_gimbals.yaml"),
    ("four-bar spatial", "fourbar_spatial.yaml"),  # extra: 3 redundant constraints
)
"""(label, file in models/) of every system in the first table."""
ACCURACY = ("double pendulum", "heavy top", "slider-crank")
"""Models of the time-to-accuracy part: two trees (their MuJoCo equivalents are exact) and
the slider-crank, a closed loop (MuJoCo closes it with a soft equality constraint), which
coasts here from its initial state without its loads (MuJoCo's `xfrc_applied` cannot vary
in time inside a rollout)."""
WITHOUT_LOADS = ("slider-crank",)
"""Accuracy models run without their (time-varying) loads."""

T_SIM = 10.0
SOLVE_TARGET, SOLVE_STRETCH = 5.0, 3.0    # solve time / mj_forward time (issue 24: 5x)
RHS_TARGET_US = 15.0                      # one right-hand-side call, µs
SIM_TARGET_S = 1.0                        # 10 s of simulation, wall s
ACCURACY_TARGET = 1.0                     # whole simulate() / MuJoCo RK4, same error
EXUDYN_TARGET = 2.0                       # whole simulate() / Exudyn's tree (DOPRI5)
CHECK_RTOL = 1e-8                         # MuJoCo equivalents agree with mbody to this
SOLIMP = "0.9999 0.9999 0.001"
"""Impedance of the loop-closing `connect` constraints: the stiffest MuJoCo allows (its
default, 0.9 .. 0.95, leaves the slider-crank's accelerations 13 % from the rigid ones;
this leaves 1e-4). It does not change mj_forward's time."""


def load(file: str) -> mbody.Model:
    return mbody.load(MODELS / file)


def load_without_loads(file: str) -> mbody.Model:
    """The shipped model with its `loads:` left out (the same bodies, joints, state)."""
    import yaml

    spec = yaml.safe_load((MODELS / file).read_text(encoding="utf-8"))
    spec.pop("loads", None)
    return mbody.load(spec)


# -- timing --------------------------------------------------------------------------------


def best_once(fn, repeat: int, limit: float = 2.0):
    """(best wall time, last result) of up to `repeat` single calls; stops repeating once
    a call takes more than `limit` seconds (long runs vary little)."""
    times, out = [], None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
        if times[-1] > limit:
            break
    return min(times), out


# -- mbody ---------------------------------------------------------------------------------
def state_derivative(model: mbody.Model):
    """`mbody.simulate`'s right-hand side (the package attribute `simulate` is the
    function, so the module is imported by name)."""
    return importlib.import_module("mbody.simulate").state_derivative(model)


def initial_y(model: mbody.Model) -> np.ndarray:
    """The state vector exactly as `simulate` builds it: blocks [x | q | v | ω] flattened
    block by block, then θ = 2 atan2(q_z, q_w) for planar models."""
    s0 = model.initial
    theta0 = (2.0 * np.arctan2(s0.quaternion[:, 3], s0.quaternion[:, 0])
              if model.dimension == 2 else ())
    return np.concatenate((s0.position.ravel(), s0.quaternion.ravel(), s0.velocity.ravel(),
                           s0.omega.ravel(), theta0))


def mbody_accelerations(model: mbody.Model, state=None) -> np.ndarray:
    """(n, 6) [a_G, ω̇] of every body, both in WORLD axes, from
    ``assemble(model, state).solve()`` (default: the initial state; planar rows are
    [a_x, a_y, α], spatial ω̇ is in body axes)."""
    state = model.initial if state is None else state
    acc = np.asarray(mbody.assemble(model, state).solve().accelerations, float)
    n = model.n
    out = np.zeros((n, 6))
    if model.dimension == 2:
        a = acc.reshape(n, 3)
        out[:, :2], out[:, 5] = a[:, :2], a[:, 2]
    else:
        a = acc.reshape(n, 6)
        out[:, :3] = a[:, :3]
        out[:, 3:] = np.einsum("nij,nj->ni", state.W_R_B, a[:, 3:])
    return out


def unknown_count(model: mbody.Model) -> int:
    given = set(model.known_reactions) | set(model.known_expressions)
    return sum(1 for r in model.reactions if r not in given)


# -- the MuJoCo equivalent -----------------------------------------------------------------
def _q(q: np.ndarray) -> np.ndarray:
    return np.asarray(q, float) / np.linalg.norm(q)


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, v1, w2, v2 = a[0], a[1:], b[0], b[1:]
    return np.concatenate(([w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)))


def _conj(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], -q[1], -q[2], -q[3]])


def _f(v) -> str:
    return " ".join(repr(float(x)) for x in np.ravel(v))


@dataclass
class Equivalent:
    """A MuJoCo model of an mbody model (see `mujoco_equivalent`)."""

    xml: str
    body_ids: np.ndarray   # MuJoCo body id of mbody body i
    qvel: np.ndarray       # initial joint velocities (qpos0 is the initial pose)
    xfrc: np.ndarray       # (n, 6) world force and world torque about each mass centre
    tree: list[str]        # mbody joints that are MuJoCo joints
    loops: list[str]       # mbody joints closed by an equality `connect`
    loads_vary: bool = False  # xfrc holds loads of t at t = 0 (right at t = 0 only)

    def make(self):
        """(MjModel, MjData) with the initial state and loads set and mj_forward run."""
        import mujoco

        m = mujoco.MjModel.from_xml_string(self.xml)
        d = mujoco.MjData(m)
        self.reset(m, d)
        return m, d

    def reset(self, m, d) -> None:
        import mujoco

        mujoco.mj_resetData(m, d)
        d.qvel[:] = self.qvel
        d.xfrc_applied[self.body_ids] = self.xfrc
        mujoco.mj_forward(m, d)


def mujoco_equivalent(model: mbody.Model, *, timestep: float = 0.002,
                      integrator: str = "Euler") -> Equivalent:
    """MJCF of the same system: one MuJoCo body per mbody body, its frame at the mass
    centre with the body axes at the initial pose (so qpos0 IS the initial pose and its
    inertia is mbody's J in body axes). The joints form a spanning tree found breadth
    first from the ground (revolute -> hinge, prismatic -> slide, spherical -> ball);
    a joint that closes a loop (revolute or spherical) becomes a `connect` equality at
    its point. Loads become `xfrc_applied` (world force and torque about the mass
    centre); loads that vary in time take their values at t = 0, so the equivalent is
    right at the initial state only (`loads_vary`). Springs and known reactions are not
    translated."""
    if len(model.springs.names) or model.known_reactions or model.known_expressions:
        raise NotImplementedError(f"{model.name}: springs or known reactions")
    s = model.initial
    n = model.n
    planar = model.dimension == 2
    R = s.W_R_B
    names = list(model.body_names)
    index = {nm: i for i, nm in enumerate(names)}
    # spanning tree, breadth first from the ground, joints in file order at each level
    parent_joint: dict[str, object] = {}
    tree = []
    frontier, placed = ["ground"], {"ground"}
    remaining = list(model.joints)
    while frontier:
        nxt = []
        for j in list(remaining):
            if j.parent in frontier or j.child in frontier:
                b = j.child if j.parent in frontier else j.parent  # the body it would add
                if b in placed:
                    continue
                if b != j.child:
                    raise NotImplementedError(f"joint {j.name}: tree would be reversed")
                parent_joint[b] = j
                placed.add(b)
                nxt.append(b)
                tree.append(j)
                remaining.remove(j)
        frontier = nxt
    loops = remaining
    if len(placed) != n + 1:
        raise NotImplementedError(f"{model.name}: bodies without a joint to the tree")
    for j in loops:
        if j.type not in ("revolute", "spherical"):
            raise NotImplementedError(f"loop joint {j.name} of type {j.type}")

    def world_axis(j) -> np.ndarray:
        if j.axis is not None:
            return _q(j.axis)
        return np.array([1.0, 0, 0]) if (j.type == "prismatic" and planar) \
            else np.array([0, 0, 1.0])

    def omega_w(name: str) -> np.ndarray:
        return np.zeros(3) if name == "ground" else R[index[name]] @ s.omega[index[name]]

    def point_velocity(name: str, p: np.ndarray) -> np.ndarray:
        if name == "ground":
            return np.zeros(3)
        i = index[name]
        return s.velocity[i] + np.cross(omega_w(name), p - s.position[i])

    kids: dict[str, list[str]] = {}
    for b, j in parent_joint.items():
        kids.setdefault(j.parent, []).append(b)
    qvel: list[float] = []
    order: list[str] = []  # MuJoCo body order (depth first, as MJCF nests them)

    def body_xml(b: str) -> str:
        i, j = index[b], parent_joint[b]
        order.append(b)
        if j.parent == "ground":
            pos, quat = s.position[i], s.quaternion[i]
        else:
            p = index[j.parent]
            pos = R[p].T @ (s.position[i] - s.position[p])
            quat = _qmul(_conj(s.quaternion[p]), s.quaternion[i])
        J = model.J[i]
        inertial = (f'<inertial pos="0 0 0" mass="{float(model.mass[i])!r}" fullinertia="'
                    f'{_f([J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]])}"/>')
        at = R[i].T @ (j.at - s.position[i])  # joint point in the child's frame
        kind = {"revolute": "hinge", "prismatic": "slide", "spherical": "ball"}.get(j.type)
        if kind is None:
            raise NotImplementedError(f"joint {j.name} of type {j.type}")
        joint = f'<joint name="{j.name}" type="{kind}" pos="{_f(at)}"'
        if kind == "ball":  # qvel: the relative angular velocity in the child's axes
            qvel.extend((R[i].T @ (omega_w(b) - omega_w(j.parent))).tolist())
            joint += "/>"
        else:
            axis = world_axis(j)
            joint += f' axis="{_f(R[i].T @ axis)}"/>'
            qvel.append(float(axis @ (omega_w(b) - omega_w(j.parent)) if kind == "hinge"
                              else axis @ (point_velocity(b, j.at)
                                           - point_velocity(j.parent, j.at))))
        inner = "".join(body_xml(c) for c in kids.get(b, []))
        return (f'<body name="{b}" pos="{_f(pos)}" quat="{_f(quat)}">{joint}{inertial}'
                f"{inner}</body>")

    bodies = "".join(body_xml(b) for b in kids.get("ground", []))
    eq = ""
    for j in loops:
        if j.parent == "ground":
            b1, anchor = "world", j.at
        else:
            p = index[j.parent]
            b1, anchor = j.parent, R[p].T @ (j.at - s.position[p])
        eq += (f'<connect name="{j.name}" body1="{b1}" body2="{j.child}" '
               f'anchor="{_f(anchor)}" solimp="{SOLIMP}"/>')
    xml = (f'<mujoco model="{model.name}"><option gravity="{_f(model.gravity)}" '
           f'timestep="{timestep!r}" integrator="{integrator}">'
           '<flag contact="disable"/></option>'
           f"<worldbody>{bodies}</worldbody>"
           + (f"<equality>{eq}</equality>" if eq else "") + "</mujoco>")
    body_ids = np.array([1 + order.index(b) for b in names])
    xfrc = np.zeros((n, 6))
    ft = model.forces
    values = ft.vector_at(0.0)
    for k in range(len(ft.names)):
        i = int(ft.body[k])
        v = R[i] @ values[k] if ft.in_body[k] else np.asarray(values[k], float)
        if ft.couple[k]:
            xfrc[i, 3:] += v
        else:
            xfrc[i, :3] += v
            xfrc[i, 3:] += np.cross(R[i] @ ft.B_r[k], v)
    return Equivalent(xml, body_ids, np.array(qvel), xfrc, [j.name for j in tree],
                      [j.name for j in loops], ft.varying is not None)


def mujoco_accelerations(m, d, eq: Equivalent) -> np.ndarray:
    """(n, 6) [a_G, ω̇] of each mass centre in world axes, from the state in `d` after
    mj_forward (mj_rnePostConstraint fills the body accelerations; MuJoCo starts them
    from −g, an accelerometer's convention, so g is added back)."""
    import mujoco

    mujoco.mj_rnePostConstraint(m, d)
    out = np.zeros((len(eq.body_ids), 6))
    res = np.zeros(6)
    for i, b in enumerate(eq.body_ids):
        mujoco.mj_objectAcceleration(m, d, mujoco.mjtObj.mjOBJ_BODY, int(b), res, 0)
        out[i, :3] = res[3:] + m.opt.gravity
        out[i, 3:] = res[:3]
    return out


def relative_difference(ours: np.ndarray, theirs: np.ndarray) -> float:
    """max |Δ| / scale, separately for the linear and the angular parts (each against its
    own largest magnitude, or the overall one when that part is all zero)."""
    overall = max(float(np.abs(ours).max()), 1e-300)
    out = 0.0
    for sl in (slice(0, 3), slice(3, 6)):
        scale = float(np.abs(ours[:, sl]).max())
        if scale < 1e-12 * overall:
            scale = overall
        out = max(out, float(np.abs(ours[:, sl] - theirs[:, sl]).max()) / scale)
    return out


@dataclass
class Check:
    """mbody against its MuJoCo equivalent at the initial state."""

    pose: float    # max |x_G − xipos| (m) and |W_R_B − xmat| of every body
    velocity: float  # max |Δ| of mass-centre velocities and angular velocities (world)
    acc: float     # relative difference of the accelerations (`relative_difference`)
    qacc: float    # planar chains and the top: from qacc, the conversion (or nan)
    exact: bool    # a tree (no soft equality constraints)


def check_equivalent(model: mbody.Model, eq: Equivalent | None = None) -> Check:
    import mujoco

    eq = eq or mujoco_equivalent(model)
    m, d = eq.make()
    s = model.initial
    ids = eq.body_ids
    pose = max(float(np.abs(d.xipos[ids] - s.position).max()),
               float(np.abs(d.xmat[ids].reshape(-1, 3, 3) - s.W_R_B).max()))
    vel = np.zeros((len(ids), 6))
    for i, b in enumerate(ids):
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, int(b), vel[i], 0)
    w_world = np.einsum("nij,nj->ni", s.W_R_B, s.omega)
    velocity = max(float(np.abs(vel[:, 3:] - s.velocity).max()),
                   float(np.abs(vel[:, :3] - w_world).max()))
    ours = mbody_accelerations(model)
    acc = relative_difference(ours, mujoco_accelerations(m, d, eq))
    return Check(pose, velocity, acc, _qacc_check(model, eq, m, d, ours), not eq.loops)


def _qacc_check(model: mbody.Model, eq: Equivalent, m, d, ours: np.ndarray) -> float:
    """The issue's conversion, where it applies: for a planar chain of hinges each link's
    angular acceleration is the sum of the hinge accelerations down the chain; for one
    ball joint to the ground, qacc is the body's ω̇ in body axes."""
    import mujoco

    joints = {j.name: j for j in model.joints}
    if eq.loops:
        return math.nan
    if model.dimension == 2 and all(joints[n].type == "revolute" for n in eq.tree):
        alpha: dict[str, float] = {}
        for name in eq.tree:  # breadth first: parents come first
            j = joints[name]
            k = m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)]
            alpha[j.child] = alpha.get(j.parent, 0.0) + float(d.qacc[k])
        mine = np.array([alpha[b] for b in model.body_names])
        ref = ours[:, 5]
        return float(np.abs(mine - ref).max() / max(np.abs(ref).max(), 1e-300))
    if len(eq.tree) == 1 and joints[eq.tree[0]].type == "spherical":
        ref = model.initial.W_R_B[0].T @ ours[0, 3:]
        return float(np.abs(d.qacc - ref).max() / max(np.abs(ref).max(), 1e-300))
    return math.nan


# -- the first table -----------------------------------------------------------------------
@dataclass
class Row:
    label: str
    n: int
    m: int
    solve: float         # assemble(model, state).solve(), s per call
    core: float          # the core's Unknowns.solve alone, s per call
    mj: float
    rhs: float
    rhs_compiled: bool
    sim_wall: float
    sim_steps: int
    sim_evals: int
    sim_t: float         # simulated seconds
    sim_note: str
    check: Check | None
    loads_vary: bool = False


def time_solve(model: mbody.Model, repeat: int) -> tuple[float, float]:
    """Seconds per call of ``assemble(model, state).solve()`` and of the core's solve
    alone (`Unknowns.solve` with the file's unknowns on the packed state), at the
    initial state."""
    state = model.initial
    ws = workspace(model)
    unknowns = ws.file_unknowns
    plan = ws.solve_plan(unknowns)
    y = ws.pack_state(state)
    out = np.empty(plan.o_info + _core.INFO)

    def solve():
        return mbody.assemble(model, state).solve()

    def core():
        plan.solver.solve(state.t, y, unknowns.lam, out)

    for _ in range(3):  # warm: the workspace is made on the first call
        solve(), core()
    return best(solve, repeat, 0.02), best(core, repeat, 0.02)


def time_rhs(model: mbody.Model, repeat: int) -> tuple[float, bool]:
    f = state_derivative(model)
    y = initial_y(model)
    assert len(f(0.0, y)) == len(y), "state layout"
    for _ in range(3):
        f(0.0, y)
    return best(lambda: f(0.0, y), repeat, 0.02), bool(f.compiled)


def simulate_kwargs(model: mbody.Model, file: str, sim_limit: float) -> tuple[dict, str]:
    """simulate() arguments for the 10 s run, its wall time bounded by --sim-limit."""
    return {"t_end": T_SIM, "max_wall": sim_limit}, ""


def time_simulation(model: mbody.Model, file: str, sim_limit: float):
    """(wall s, steps, evaluations, simulated s, note) of the 10 s run; a run stopped by
    its budget (an MbodyError) reports the wall time it took and 0 steps."""
    kw, note = simulate_kwargs(model, file, sim_limit)
    mbody.simulate(model, t_end=0.05)  # the compiled derivative is loaded and warm
    t0 = time.perf_counter()
    try:
        traj = mbody.simulate(model, **kw)
    except mbody.MbodyError as exc:
        first = str(exc).splitlines()[0].split(". ")[0]  # the first sentence
        return (time.perf_counter() - t0, 0, 0, 0.0,
                f"stopped within --sim-limit {sim_limit:g} s: {first}")
    wall = time.perf_counter() - t0
    return wall, traj.info["steps"], traj.info["evaluations"], float(traj.t[-1]), note


def measure(label: str, file: str, repeat: int, sim_limit: float, have_mj: bool) -> Row:
    model = load(file)
    t_solve, t_core = time_solve(model, repeat)
    rhs, compiled = time_rhs(model, repeat)
    mj, check, vary = math.nan, None, False
    if have_mj:
        import mujoco

        eq = mujoco_equivalent(model)
        check = check_equivalent(model, eq)
        m, d = eq.make()
        mj = best(lambda: mujoco.mj_forward(m, d), repeat, 0.02)
        vary = eq.loads_vary
    wall, steps, evals, t_done, note = time_simulation(model, file, sim_limit)
    return Row(label, model.n, unknown_count(model), t_solve, t_core, mj, rhs, compiled, wall,
               steps, evals, t_done, note, check, vary)


def mark(ok: bool) -> str:
    return "PASS" if ok else "MISS"


def print_table(rows: list[Row], repeat: int) -> None:
    print(f"per call: µs, best of {repeat}; ratio = mbody / MuJoCo mj_forward "
          "(lower: mbody faster)")
    head = (f"{'system':<17}{'n':>2}{'m':>4} |{'solve':>7}{'core':>8}{'MuJoCo':>8}"
            f"{'×':>6}{'core×':>6}   ≤5× |{'RHS':>6}   C ≤15µs |{'10 s':>7}{'steps':>7}"
            f"{'evals':>8}{'f %':>5}  ≤1 s")
    print(head)
    print("-" * len(head))
    for r in rows:
        ratio, ratio_core = r.solve / r.mj, r.core / r.mj
        soft = "‡" if r.check is not None and not r.check.exact else " "
        solve_mark = ("  -  " if math.isnan(ratio) else
                      mark(ratio <= SOLVE_TARGET) + ("*" if ratio <= SOLVE_STRETCH else " "))
        rhs_mark = mark(r.rhs * 1e6 <= RHS_TARGET_US)
        if r.sim_t >= T_SIM - 1e-9:
            sim_mark = mark(r.sim_wall <= SIM_TARGET_S)
        else:  # stopped by its budget (a MISS once that took longer than the target) or 1 s
            sim_mark = "MISS" if r.sim_wall > SIM_TARGET_S and r.sim_t == 0 else " n/a"
        dagger = "†" if r.sim_note else " "
        share = r.sim_evals * r.rhs / r.sim_wall if r.sim_wall > 0 else math.nan
        print(f"{r.label:<17}{r.n:>2}{r.m:>4} |{r.solve * 1e6:7.1f}"
              f"{r.core * 1e6:8.1f}{r.mj * 1e6:7.2f}{soft}{ratio:6.1f}{ratio_core:6.1f} "
              f"{solve_mark}|{r.rhs * 1e6:6.1f} {'yes' if r.rhs_compiled else ' no'} "
              f"{rhs_mark}  |{r.sim_wall:6.2f}{dagger}{r.sim_steps:7d}{r.sim_evals:8d}"
              f"{100 * share:5.0f}  {sim_mark}", flush=True)
    print("n bodies, m unknown reaction components; solve = assemble(model, state).solve(), "
          "core = the compiled core's Unknowns.solve alone (one path: the core); "
          "RHS C: evaluated in the core (yes) or in Python;")
    print(f"targets: solve ≤ {SOLVE_TARGET:g}× mj_forward (* also the stretch "
          f"≤ {SOLVE_STRETCH:g}×); RHS ≤ {RHS_TARGET_US:g} µs a call (simulate's f(t, y)); "
          f"{T_SIM:g} s of simulate() at its defaults ≤ {SIM_TARGET_S:g} s wall")
    print("f %: evaluations × the RHS time measured from Python as a share of the 10 s "
          "run's wall time; the run calls the same right-hand side from C, without "
          "Python's call overhead, so this can exceed 100 %")
    if any(r.check is not None and not r.check.exact for r in rows):
        print("‡ closed loop: MuJoCo cuts it at one pin and closes it with an equality "
              f"constraint (connect, solimp {SOLIMP}: as stiff as MuJoCo allows); it is soft, "
              "so its accelerations differ a little from the rigid ones (see the check "
              "below): a comparison of time only")
    for r in rows:
        if r.loads_vary:
            print(f"{r.label}: its loads vary in time; MuJoCo's xfrc_applied holds their "
                  "values at t = 0 (the initial state every per-call column evaluates)")
    for r in rows:
        if r.sim_note:
            print(f"† {r.label}: {r.sim_note}")


def print_checks(rows: list[Row]) -> None:
    print(f"\nMuJoCo equivalents at the initial state (mass-centre positions, rotations, "
          f"velocities, accelerations; target ≤ {CHECK_RTOL:g} relative on trees)")
    head = (f"{'system':<17} {'joints':<8} {'pose':>8} {'velocity':>9} {'acc rel':>9} "
            f"{'qacc rel':>9}  result")
    print(head)
    print("-" * len(head))
    for r in rows:
        c = r.check
        if c is None:
            continue
        ok = c.acc <= CHECK_RTOL and c.pose <= 1e-12 and c.velocity <= 1e-9
        q = "-" if math.isnan(c.qacc) else f"{c.qacc:9.1e}"
        res = mark(ok) if c.exact else "soft (time only)"
        print(f"{r.label:<17} {'tree' if c.exact else 'loop‡':<8} {c.pose:8.1e} "
              f"{c.velocity:9.1e} {c.acc:9.1e} {q:>9}  {res}")
    print("acc rel: max |Δ| / max |a| of [a_G, ω̇] in world axes (mj_objectAcceleration); "
          "qacc rel: each link's α = sum of the hinge qacc down a planar chain, the top's "
          "ball-joint qacc = ω̇ in body axes")


# -- time to accuracy ----------------------------------------------------------------------
def mbody_run(model: mbody.Model, t_end: float, rtol: float, atol: float) -> np.ndarray:
    """Mass-centre positions (n, 3) at t_end from one whole `mbody.simulate` call (samples
    at t = 0 and t_end only, so sampling costs next to nothing)."""
    traj = mbody.simulate(model, t_end=t_end, fps=1.0 / t_end, rtol=rtol, atol=atol)
    assert abs(traj.t[-1] - t_end) < 1e-9
    return traj.spatial()[0][-1]


def mujoco_run(m, d, eq: Equivalent, t_end: float) -> np.ndarray:
    """Mass-centre positions (n, 3) after t_end / timestep steps from the initial state,
    stepped in C by mujoco.rollout (in chunks), or by mj_step from Python without it.
    A run MuJoCo flagged as diverging (it then resets the state) gives inf."""
    import mujoco

    if eq.loads_vary:
        raise NotImplementedError("loads of t are not applied step by step here")
    eq.reset(m, d)
    nstep = int(round(t_end / m.opt.timestep))
    assert abs(nstep * m.opt.timestep - t_end) < 1e-9, "the step must divide t_end"
    try:
        from mujoco import rollout
    except ImportError:
        rollout = None
    if rollout is None or eq.xfrc.any():  # rollout would not keep xfrc_applied
        for _ in range(nstep):
            mujoco.mj_step(m, d)
    else:
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, state, spec)
        done = 0
        while done < nstep:
            k = min(20_000, nstep - done)
            states, _ = rollout.rollout(m, d, state, nstep=k)
            state = np.ascontiguousarray(states[0, -1])
            done += k
        mujoco.mj_setState(m, d, state, spec)
    bad = (d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
           + d.warning[mujoco.mjtWarning.mjWARN_BADQPOS].number
           + d.warning[mujoco.mjtWarning.mjWARN_BADQVEL].number)
    mujoco.mj_kinematics(m, d)
    x = d.xipos[eq.body_ids].copy()
    return np.full_like(x, np.inf) if bad or not np.all(np.isfinite(x)) else x


def time_to_reach(points: list[tuple[float, float]], target: float) -> tuple[float, str]:
    """(wall time, bound) to reach `target` error from measured (time, error) points: the
    cheapest run meeting it, log-log interpolated from the cheaper run before it.
    bound '≤' when no interpolation is possible (the cheapest run already meets it, or
    the one before diverged): the time is then an upper bound; (nan, '') when no run
    meets it."""
    pts = sorted(points)
    for k, (t, e) in enumerate(pts):
        if e <= target:
            if k == 0 or not math.isfinite(pts[k - 1][1]):
                return t, "≤"
            t0, e0 = pts[k - 1]  # e0 > target >= e
            s = (math.log(target) - math.log(e0)) / (math.log(max(e, 1e-300)) - math.log(e0))
            return math.exp(math.log(t0) + s * (math.log(t) - math.log(t0))), ""
    return math.nan, ""


def ratio_verdict(tb: float, bb: str, tm: float, bm: str,
                  target: float = ACCURACY_TARGET) -> tuple[str, str]:
    """(ratio text, verdict) for mbody's and the other engine's times to an error, either
    of which may be an upper bound ('≤'): '?' when the bound leaves the target undecided;
    the other engine never reaching the error while mbody does is a PASS."""
    if math.isnan(tb):
        return "-", "-" if math.isnan(tm) else "MISS"
    if math.isnan(tm):
        return "-", "PASS"
    r = tb / tm
    if bb and bm:
        return f"~{r:.2f}", "?"
    if bb:  # the true ratio is at most r
        return f"≤{r:.2f}", "PASS" if r <= target else "?"
    if bm:  # the true ratio is at least r
        return f"≥{r:.2f}", "MISS" if r > target else "?"
    return f"{r:.2f}", mark(r <= target)


FIRST_CALL = """
import sys, time
t0 = time.perf_counter()
import mbody
{load}
t1 = time.perf_counter()
x = mbody.simulate(model, t_end={t_end!r}, fps={fps!r}, rtol={rtol!r}, atol={atol!r})
t2 = time.perf_counter()
mbody.simulate(model, t_end={t_end!r}, fps={fps!r}, rtol={rtol!r}, atol={atol!r})
t3 = time.perf_counter()
print(t2 - t1, t3 - t2)
"""


def first_call(file: str, without_loads: bool, t_end: float, rtol: float, atol: float
               ) -> tuple[float, float]:
    """(first, second) wall time of the whole `mbody.simulate` call in a fresh process
    (the model loaded before either is timed; bytecode cached, as after an install)."""
    import subprocess

    how = ("import yaml\nspec = yaml.safe_load(open({f!r}).read())\nspec.pop('loads', None)"
           "\nmodel = mbody.load(spec)" if without_loads else "model = mbody.load({f!r})")
    code = FIRST_CALL.format(load=how.format(f=str(MODELS / file)), t_end=t_end,
                             fps=1.0 / t_end, rtol=rtol, atol=atol)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT, env=env).stdout.split()
    return float(out[0]), float(out[1])


MUJOCO_FIRST_CALL = """
import sys, time
sys.path.insert(0, {tools!r})
import mujoco
import bench_small as B
mujoco.set_mju_user_warning(lambda text: None)  # a diverged run is shown in the table
model = B.load_without_loads({file!r}) if {without!r} else B.load({file!r})
eq = B.mujoco_equivalent(model, timestep={h!r}, integrator="RK4")
m = mujoco.MjModel.from_xml_string(eq.xml)
d = mujoco.MjData(m)
t1 = time.perf_counter()
B.mujoco_run(m, d, eq, {t_end!r})
t2 = time.perf_counter()
print(t2 - t1)
"""


def mujoco_first_call(file: str, without_loads: bool, h: float, t_end: float) -> float:
    """Wall time of MuJoCo's first `mujoco_run` in a fresh process (mujoco imported, the
    model compiled and its MjData made before it, as mbody's first call has mbody
    imported and the model loaded): its own start-up (the rollout module, first calls)
    counted, as mbody's is."""
    import subprocess

    code = MUJOCO_FIRST_CALL.format(tools=str(Path(__file__).resolve().parent), file=file,
                                    without=without_loads, h=h, t_end=t_end)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT, env=env).stdout.split()
    return float(out[-1])


def accuracy(label: str, file: str, quick: bool, repeat: int, first_runs: int) -> None:
    import mujoco

    without = label in WITHOUT_LOADS
    model = load_without_loads(file) if without else load(file)
    t_end = T_SIM
    eq = mujoco_equivalent(model, integrator="RK4")
    check = check_equivalent(model, eq)
    print(f"\ntime to accuracy: {label} ({file}{', its loads left out' if without else ''}), "
          f"t = {t_end:g} s; error = max over bodies of |x_G − x_G,ref| (m)")
    print(f"  MuJoCo equivalent at t = 0: accelerations agree to {check.acc:.1e} relative, "
          f"qacc conversion to {check.qacc:.1e}: {mark(check.acc <= CHECK_RTOL)} "
          f"(≤ {CHECK_RTOL:g})")
    ref_tol = (1e-13, 1e-14)
    x_ref = mbody_run(model, t_end, *ref_tol)
    rtols = [1e-3, 1e-4, 1e-6, 1e-8, 1e-10] if quick else \
        [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
    # steps that divide t_end; the coarse ones bracket the 1e-4 target on slow systems
    steps = [5e-2, 1e-2, 2e-3, 5e-4, 1e-4] if quick else \
        [5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5]
    mbody_run(model, 0.1, 1e-6, 1e-8)  # warm
    mb, first = [], []
    for rtol in rtols:
        wall, x = best_once(lambda r=rtol: mbody_run(model, t_end, r, r * 1e-2), repeat)
        mb.append((rtol, wall, float(np.abs(x - x_ref).max())))
        first.append(statistics.median(first_call(file, without, t_end, rtol, rtol * 1e-2)[0]
                                       for _ in range(first_runs)))
    mj, mj_first = [], []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda text: None)  # a diverged run is shown in the table
    try:
        for h in steps:
            m = mujoco.MjModel.from_xml_string(
                mujoco_equivalent(model, timestep=h, integrator="RK4").xml)
            d = mujoco.MjData(m)
            mujoco_run(m, d, eq, 10 * h)  # warm (the first rollout call sets itself up)
            wall, x = best_once(lambda m=m, d=d: mujoco_run(m, d, eq, t_end), repeat)
            mj.append((h, wall, float(np.abs(x - x_ref).max()), int(round(t_end / h))))
            mj_first.append(statistics.median(mujoco_first_call(file, without, h, t_end)
                                              for _ in range(first_runs)))
    finally:
        mujoco.set_mju_user_warning(previous)
    close = min((e, h) for h, _, e, _ in mj)
    print(f"  reference: mbody DOP853 rtol {ref_tol[0]:g}, atol {ref_tol[1]:g}; the closest "
          f"MuJoCo RK4 run (h = {close[1]:g} s) ends {close[0]:.1e} m from it")
    gap = " " * 8
    print(f"  {'mbody DOP853':<37}{gap}MuJoCo RK4")
    print(f"  {'rtol':>7} {'first s':>8} {'wall s':>8} {'error m':>9}{gap}{'h s':>7} "
          f"{'steps':>8} {'first s':>8} {'wall s':>8} {'error m':>9}")
    for k in range(max(len(mb), len(mj))):
        left = (f"  {mb[k][0]:7.0e} {first[k]:8.4f} {mb[k][1]:8.4f} {mb[k][2]:9.1e}"
                if k < len(mb) else " " * 37)
        right = ""
        if k < len(mj):
            err = f"{mj[k][2]:9.1e}" if math.isfinite(mj[k][2]) else f"{'diverged':>9}"
            right = f"{mj[k][0]:7.0e} {mj[k][3]:8d} {mj_first[k]:8.4f} {mj[k][1]:8.4f} {err}"
        print(left + gap + right)
    print(f"  wall s: best of {repeat} later calls in this process; first s: the first call "
          f"in a fresh process (mbody imported and the model loaded before it), the median of "
          f"{first_runs} such processes (one process's first call varies by a fifth); mbody: one "
          f"whole simulate() call (samples at 0 and {t_end:g} s only), atol = rtol / 100; "
          "MuJoCo: from mj_resetData, stepped in C by mujoco.rollout; its first s: the "
          "first call in a fresh process (mujoco imported, the model compiled before it), "
          f"the median of {first_runs}")
    print(f"  {'error ≤':>9} {'mbody s':>11} {'MuJoCo s':>9} {'ratio':>7}  "
          f"≤{ACCURACY_TARGET:g}×   {'first s':>11} {'ratio':>7}  ≤{ACCURACY_TARGET:g}×"
          f"   {'MuJoCo first s':>14} {'first/first':>11}")
    for target in (1e-4, 1e-6, 1e-8):
        tb, bb = time_to_reach([(w, e) for _, w, e in mb], target)
        tf, bf = time_to_reach([(f, e) for f, (_, _, e) in zip(first, mb, strict=True)],
                               target)
        tm, bm = time_to_reach([(w, e) for _, w, e, _ in mj], target)
        text, verdict = ratio_verdict(tb, bb, tm, bm)
        ftext, fverdict = ratio_verdict(tf, bf, tm, bm)
        tmf, bmf = time_to_reach([(f, e) for f, (_, _, e, _) in zip(mj_first, mj,
                                                                   strict=True)], target)
        fftext, _ = ratio_verdict(tf, bf, tmf, bmf)
        print(f"  {target:9.0e} {fmt(tb, bb):>11} {fmt(tm, bm):>9} {text:>7}  {verdict:<5}"
              f"{fmt(tf, bf):>11} {ftext:>7}  {fverdict:<5}{fmt(tmf, bmf):>14} {fftext:>11}",
              flush=True)
    print("  time to an error: log-log interpolation between the two runs around it "
          "(≤: an upper bound, the cheapest run or the one after a diverged run; "
          "ratio = mbody / MuJoCo; ?: the bound leaves the target undecided). The "
          "verdicts compare both of mbody's calls with MuJoCo's later calls; first/first, "
          "mbody's first call over MuJoCo's own, is for context")


def fmt(t: float, b: str) -> str:
    return "not reached" if math.isnan(t) else f"{b}{t:.4f}"


# -- Exudyn: the open double pendulum as a minimal-coordinate tree --------------------------
def exudyn_double_pendulum(rtol: float, atol: float, t_end: float):
    """(wall s of SolveDynamic, mass-centre positions (2, 3) at t_end) of the shipped
    double pendulum as Exudyn's kinematic tree (two revolute joints about z, joint
    angles relative to the parent link) integrated by its DOPRI5 with automatic steps."""
    import exudyn as exu
    from exudyn.robotics import Robot, RobotBase, RobotLink, RobotTool

    model = load("double_pendulum.yaml")
    L = 0.5
    m, Izz = float(model.mass[0]), float(model.J[0][2, 2])
    inertia = np.diag([Izz, 1e-4, Izz])  # a rod along its link's y axis
    robot = Robot(gravity=[0, -9.81, 0], base=RobotBase(), tool=RobotTool(),
                  referenceConfiguration=[])
    for i in range(2):
        pre = np.eye(4)
        if i:
            pre[1, 3] = -L
        robot.AddLink(RobotLink(m, [0, -L / 2, 0], inertia, jointType="Rz", preHT=pre))
    angles = [math.radians(30.0), math.radians(15.0)]  # absolute 30 and 45 deg
    robot.referenceConfiguration = angles
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    robot.CreateKinematicTree(mbs)
    mbs.Assemble()
    st = exu.SimulationSettings()
    ti = st.timeIntegration
    ti.endTime = t_end
    ti.numberOfSteps = 10  # with automatic steps: the largest step is endTime / this
    ti.automaticStepSize = True
    ti.absoluteTolerance = atol
    ti.relativeTolerance = rtol
    ti.verboseMode = 0
    st.solution.file.write = False
    st.show.computationTime = False
    st.show.statistics = False
    t0 = time.perf_counter()
    mbs.SolveDynamic(st, solverType=exu.DynamicSolverType.DOPRI5)
    wall = time.perf_counter() - t0
    q = np.array(mbs.systemData.GetODE2Coordinates()) + np.array(angles)
    a1, a2 = q[0], q[0] + q[1]
    G1 = L / 2 * np.array([math.sin(a1), -math.cos(a1), 0.0])
    G2 = L * np.array([math.sin(a1), -math.cos(a1), 0.0]) \
        + L / 2 * np.array([math.sin(a2), -math.cos(a2), 0.0])
    return wall, np.stack((G1, G2))


def exudyn_accuracy(quick: bool, repeat: int) -> None:
    try:
        import exudyn
    except ImportError:
        print("\nExudyn: not installed (pip install -e '.[bench]')")
        return
    t_end = T_SIM
    model = load("double_pendulum.yaml")
    x_ref = mbody_run(model, t_end, 1e-13, 1e-14)
    print(f"\ntime to accuracy: the open double pendulum against Exudyn {exudyn.__version__}'s "
          f"kinematic tree (minimal coordinates, DOPRI5), t = {t_end:g} s; reference: mbody "
          "DOP853 rtol 1e-13")
    rtols = [1e-4, 1e-6, 1e-8, 1e-10] if quick else \
        [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11]
    exudyn_double_pendulum(1e-6, 1e-8, 0.1)  # warm
    mb, ex = [], []
    for rtol in rtols:
        wall, x = best_once(lambda r=rtol: mbody_run(model, t_end, r, r * 1e-2), repeat)
        mb.append((rtol, wall, float(np.abs(x - x_ref).max())))
        runs = [exudyn_double_pendulum(rtol, rtol * 1e-2, t_end) for _ in range(repeat)]
        wall_x, x_x = min(runs, key=lambda r: r[0])
        ex.append((rtol, wall_x, float(np.abs(x_x[:, :2] - x_ref[:, :2]).max())))
    print(f"  {'rtol':>7} {'mbody s':>9} {'error m':>9}   {'Exudyn s':>9} {'error m':>9}")
    for (r, wb, eb), (_, wx, ee) in zip(mb, ex, strict=True):
        print(f"  {r:7.0e} {wb:9.4f} {eb:9.1e}   {wx:9.4f} {ee:9.1e}")
    print(f"  wall s: best of {repeat}; mbody: one whole simulate() call; Exudyn: "
          "SolveDynamic alone (the model built before), atol = rtol / 100 for both")
    print(f"  {'error ≤':>9} {'mbody s':>11} {'Exudyn s':>11} {'ratio':>7}  "
          f"≤{EXUDYN_TARGET:g}×")
    for target in (1e-4, 1e-6, 1e-8):
        tb, bb = time_to_reach([(w, e) for _, w, e in mb], target)
        tx, bx = time_to_reach([(w, e) for _, w, e in ex], target)
        text, verdict = ratio_verdict(tb, bb, tx, bx, EXUDYN_TARGET)
        print(f"  {target:9.0e} {fmt(tb, bb):>11} {fmt(tx, bx):>11} {text:>7}  {verdict}",
              flush=True)


def run(quick: bool, repeat: int, sim_limit: float, accuracy_runs: bool,
        first_runs: int = 5) -> None:
    try:
        import mujoco

        have_mj = True
        version = mujoco.__version__
    except ImportError:
        have_mj, version = False, "not importable"
    import scipy

    print(f"mbody {mbody.__version__} (compiled core: mbody.kernel._core), numpy "
          f"{np.__version__}, scipy {scipy.__version__}, MuJoCo {version}, Python "
          f"{sys.version.split()[0]}")
    rows = [measure(label, file, repeat, sim_limit, have_mj) for label, file in SYSTEMS]
    print_table(rows, repeat)
    if have_mj:
        print_checks(rows)
    if have_mj and accuracy_runs:
        files = dict(SYSTEMS)
        for label in ACCURACY:
            accuracy(label, files[label], quick, 1 if quick else min(repeat, 3), first_runs)
    if accuracy_runs:
        exudyn_accuracy(quick, 1 if quick else min(repeat, 3))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true",
                   help="fewer repeats and a shorter accuracy sweep (under a minute)")
    p.add_argument("--repeat", type=int, help="timed runs per entry, best kept (default 7; 3 "
                   "with --quick)")
    p.add_argument("--sim-limit", type=float, default=30.0, metavar="S",
                   help="wall seconds allowed for one 10 s simulation (default 30), "
                   "through simulate(max_steps=...) when simulate takes it")
    p.add_argument("--no-accuracy", action="store_true", help="skip the time-to-accuracy part")
    p.add_argument("--first-runs", type=int, metavar="N",
                   help="fresh processes timed for each first call, the median kept (default "
                   "5; 3 with --quick)")
    a = p.parse_args(argv)
    repeat = max(1, a.repeat or (3 if a.quick else 7))
    run(a.quick, repeat, a.sim_limit, not a.no_accuracy,
        max(1, a.first_runs or (3 if a.quick else 5)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
