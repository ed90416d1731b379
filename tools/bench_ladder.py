"""Benchmark: ladders of closed loops at 50 to 500 unknowns, per evaluation, both paths.

    python tools/bench_ladder.py [--quick] [--repeat R] [--sizes 50,100,250,500]

A ladder of N parallelogram loops: N + 1 rungs (length L) hang from ground pins at
x = 0, d, 2d, ..., and N couplers (length d) join the tips of neighbouring rungs. Each
loop shares a rung with the next; with the bodies listed rung, coupler, rung, ... the
Schur complement S = G_Uᵀ M⁻¹ G_U stays banded (half bandwidth 5 planar, 10 spatial).
Three kinds, every reaction component unknown:

- planar: revolute pins everywhere; 2N + 1 bodies, 3N + 1 pins, 6N + 2 unknowns, 1 DOF;
- spatial: the same ladder in space, rungs on revolutes about z, couplers on spherical
  joints at both ends (R-S-S-R loops, independent constraints): 11N + 5 unknowns; each
  coupler may also spin about its own line, which nothing drives;
- spatial-redundant: every joint a revolute about z, as a user would first write it:
  15N + 5 unknowns, 3 of them redundant per loop (S is singular; minimum-norm reactions).

Per kind and size (microseconds per call, best of --repeat, `tools/timing.py`):
``mbody.assemble(model, state).solve()`` and one call of ``mbody.simulate``'s right-hand
side (``mbody.simulate.state_derivative``), on the compiled path (``set_jit('on')``) and
on the numpy path (``set_jit('off')``), with the solver path each took (the solution's
``method``; for the right-hand side, the numpy path's factorisation or the compiled
call) and S's half bandwidth. The state: every rung at 30° from the vertical turning at
1 rad/s (the couplers translate), so the velocity-product terms γ are not zero.

Checked before anything is timed:
- the two paths agree (accelerations and reactions, 1e-10 relative; on the redundant
  kind to 10 cond(S) ε, what rounding leaves of a pseudo-inverse) and Gᵀ v̇ = γ (1e-9
  relative to max(|γ|, ‖Gᵀ‖ |v̇|), infinity norms);
- the accelerations equal the closed form: a parallelogram ladder moves like one
  compound pendulum, every rung at the same angle θ with
  θ̈ = −(g Σ(m_r L/2 + m_c L) / Σ(I_r,pivot + m_c L²)) sin θ, and the couplers translate;
- released from rest, a simulated ladder (the smallest size) follows that pendulum's
  exact motion (θ(t) = 2 asin(k cd(ω t | k²)), k = sin(θ₀/2)) over 2 s, to 1e-7 rad;
- no dense factorisation on the numpy path: numpy's and scipy's dense LAPACK entry
  points are counted during one solve and one right-hand side (the compiled path's is
  named by its `method`);
- BLAS threads: what threadpoolctl sees, the CPU time the process's other threads (BLAS
  workers) used while timing (from /proc; 0 when none ran), and each time again under
  ``threadpool_limits(1)``.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import importlib.util
import math
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
from mbody.equations import plan as mplan  # noqa: E402

L, D, W, G0 = 0.5, 0.3, 0.02, 9.81
"""Rung length, coupler length (pin spacing), bar thickness (m), gravity (m/s²)."""
THETA0, OMEGA0 = math.radians(30.0), 1.0
"""The benchmark state: rungs at 30° from hanging straight down, turning at 1 rad/s."""
KINDS = ("planar", "spatial", "spatial-redundant")
SIZES = (50, 100, 250, 500)


# -- the model -------------------------------------------------------------------------------
def unknowns_per_loop(kind: str) -> tuple[int, int]:
    """(a, b): a ladder of N loops has a N + b unknown reaction components."""
    return {"planar": (6, 2), "spatial": (11, 5), "spatial-redundant": (15, 5)}[kind]


def loops_for(kind: str, unknowns: int) -> int:
    """The number of loops whose ladder has the unknown count nearest `unknowns`."""
    a, b = unknowns_per_loop(kind)
    return max(1, round((unknowns - b) / a))


def masses(n_loops: int) -> tuple[np.ndarray, np.ndarray]:
    """(rung masses (N + 1,), coupler masses (N,)), kg: unequal, so that the reactions
    differ from loop to loop."""
    k = np.arange(n_loops + 1)
    return 1.0 + 0.3 * np.sin(1.3 * k), 0.6 + 0.2 * np.cos(0.7 * k[:-1])


def rung_inertia(m: np.ndarray, kind: str) -> np.ndarray:
    """Each rung's moment of inertia about its mass centre and the pin axis z."""
    if kind == "planar":
        return m * L * L / 12.0  # a slender rod
    return m * (L * L + W * W) / 12.0  # a W x L x W box, about its z axis


def ladder_spec(n_loops: int, kind: str = "planar", theta0: float = THETA0,
                omega0: float = OMEGA0) -> dict:
    """A ladder of `n_loops` parallelogram loops as a model dict (see the module
    docstring), every rung at angle `theta0` from the downward vertical turning at
    `omega0` rad/s, couplers translating. Bodies are listed rung, coupler, rung, ...
    so that neighbours are near in the equations' order."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    planar = kind == "planar"
    mr, mc = masses(n_loops)
    Ir = rung_inertia(mr, kind)
    s, c = math.sin(theta0), math.cos(theta0)
    u = np.array([s, -c, 0.0])  # along a rung, pivot to tip
    tip_v = omega0 * L * np.array([c, s, 0.0])  # ω ẑ × L u

    def vec(a) -> list[float]:
        return [float(x) for x in (a[:2] if planar else a)]

    bodies, joints = [], []
    tip_joint = "revolute" if kind != "spatial" else "spherical"
    for k in range(n_loops + 1):
        pivot = np.array([k * D, 0.0, 0.0])
        rung = {"name": f"r{k}", "mass": float(mr[k]),
                "position": vec(pivot + 0.5 * L * u), "velocity": vec(0.5 * tip_v)}
        if planar:
            rung.update(inertia=float(Ir[k]), angle=theta0, angular_velocity=omega0)
        else:
            ix = float(mr[k] * 2 * W * W / 12.0)  # about the rung's own line (body y)
            rung.update(inertia=[float(Ir[k]), ix, float(Ir[k])],
                        orientation={"euler": [theta0, 0.0, 0.0]},  # yaw about z
                        angular_velocity=[0.0, 0.0, omega0])
        bodies.append(rung)
        pin = {"name": f"p{k}", "type": "revolute", "parent": "ground", "child": f"r{k}",
               "at": vec(pivot)}
        if not planar:
            pin["axis"] = [0.0, 0.0, 1.0]
        joints.append(pin)
        if k == n_loops:
            break
        tip = pivot + L * u
        coupler = {"name": f"c{k}", "mass": float(mc[k]),
                   "position": vec(tip + [0.5 * D, 0.0, 0.0]), "velocity": vec(tip_v)}
        if planar:
            coupler.update(inertia=float(mc[k] * D * D / 12.0))
        else:
            coupler.update(inertia=[float(mc[k] * 2 * W * W / 12.0),
                                    float(mc[k] * (D * D + W * W) / 12.0),
                                    float(mc[k] * (D * D + W * W) / 12.0)])
        bodies.append(coupler)
        for name, parent, child, at in ((f"a{k}", f"r{k}", f"c{k}", tip),
                                        (f"b{k}", f"c{k}", f"r{k + 1}", tip + [D, 0, 0])):
            j = {"name": name, "type": tip_joint, "parent": parent, "child": child,
                 "at": vec(at)}
            if tip_joint == "revolute" and not planar:
                j["axis"] = [0.0, 0.0, 1.0]
            joints.append(j)
    return {"model": f"ladder-{kind}-{n_loops}", "dimension": 2 if planar else 3,
            "gravity": [0.0, -G0] if planar else [0.0, -G0, 0.0], "bodies": bodies,
            "joints": joints}


# -- the closed form: one compound pendulum ---------------------------------------------------
def pendulum(n_loops: int, kind: str) -> tuple[float, float]:
    """(I, K) of the equivalent compound pendulum I θ̈ = −K sin θ: I = Σ rungs' inertia
    about their pins + Σ m_c L² (couplers translate on circles of radius L),
    K = g (Σ m_r L/2 + Σ m_c L)."""
    mr, mc = masses(n_loops)
    inertia = float(np.sum(rung_inertia(mr, kind) + mr * L * L / 4) + np.sum(mc) * L * L)
    return inertia, float(G0 * (np.sum(mr) * L / 2 + np.sum(mc) * L))


def closed_form_accelerations(n_loops: int, kind: str, theta: float = THETA0,
                              omega: float = OMEGA0) -> np.ndarray:
    """The accelerations `solve()` returns, in its coordinate order: planar per body
    [a_x, a_y, α]; spatial [a_G (world), ω̇ (body axes)]."""
    inertia, K = pendulum(n_loops, kind)
    alpha = -K / inertia * math.sin(theta)
    u = np.array([math.sin(theta), -math.cos(theta), 0.0])
    t = np.array([math.cos(theta), math.sin(theta), 0.0])  # ẑ × u
    tip = L * (alpha * t - omega * omega * u)
    rows = []
    for k in range(n_loops + 1):
        rows.append(np.concatenate((0.5 * tip, [0.0, 0.0, alpha])))
        if k < n_loops:
            rows.append(np.concatenate((tip, [0.0, 0.0, 0.0])))
    a = np.array(rows)
    if kind == "planar":
        return a[:, [0, 1, 5]].ravel()
    return a.ravel()  # the body z axes stay along world z: ω̇ body = world


def pendulum_angle(n_loops: int, kind: str, t: np.ndarray, theta0: float) -> np.ndarray:
    """Exact θ(t) of the equivalent pendulum released from rest at theta0:
    sin(θ/2) = k cd(ω t | k²), k = sin(θ₀/2), ω = √(K/I) (Jacobi's elliptic functions)."""
    from scipy.special import ellipj

    inertia, K = pendulum(n_loops, kind)
    k = math.sin(theta0 / 2)
    sn, cn, dn, _ = ellipj(math.sqrt(K / inertia) * np.asarray(t), k * k)
    return 2.0 * np.arcsin(k * cn / dn)


# -- checks ------------------------------------------------------------------------------------
def rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), 1e-300))


def reactions(sol, model) -> np.ndarray:
    arr = getattr(sol.reactions, "array", None)
    return np.asarray(arr if arr is not None else [sol.reactions[r] for r in model.reactions])


def solve_with(model, state, mode: str):
    previous = mplan.set_jit(mode)
    try:
        return mbody.assemble(model, state).solve()
    finally:
        mplan.set_jit(previous)


def condition(model, state) -> float:
    """cond(S) (for a singular S, that of its nonzero part)."""
    from mbody.solve.kkt import RANK_RTOL, ConstrainedSystem

    previous = mplan.set_jit("off")
    try:
        asm = mbody.assemble(model, state)
        sol = asm.solve(condition=True)
        if not sol.redundant:
            return float(sol.condition)
        S = ConstrainedSystem(model, asm.columns, model.plan.file_unknowns).fact._S
        S = S.toarray() if hasattr(S, "toarray") else np.asarray(S)
        w = np.linalg.eigvalsh(0.5 * (S + S.T))
        kept = w[w > RANK_RTOL * w[-1]]
        return float(kept[-1] / kept[0])
    finally:
        mplan.set_jit(previous)


def constraint_residual(model, state, acc: np.ndarray) -> float:
    """|Gᵀ v̇ − γ|∞ / max(|γ|∞, ‖Gᵀ‖∞ |v̇|∞): how far accelerations `acc` (in the
    solution's coordinates) are from holding the joints at acceleration level."""
    asm = mbody.assemble(model, state)
    GT, gamma = asm.G.T.tocsr(), asm.jacobian().gamma
    norm_GT = float(np.max(np.asarray(abs(GT).sum(axis=1))))
    scale = max(float(np.max(np.abs(gamma))), norm_GT * float(np.max(np.abs(acc))), 1e-300)
    return float(np.max(np.abs(GT @ acc - gamma))) / scale


@dataclass
class Check:
    acc: float  # compiled vs numpy, accelerations
    lam: float  # compiled vs numpy, reactions
    constraint: float  # `constraint_residual`, worse path
    closed: float  # accelerations vs the closed form, worse path
    rhs: float  # simulate's right-hand side (the core) vs the numpy solve's accelerations
    tol: float  # 1e-10; with redundant constraints 10 cond(S) ε when larger

    @property
    def ok(self) -> bool:
        return (max(self.acc, self.lam, self.closed, self.rhs) <= self.tol
                and self.constraint <= max(1e-9, self.tol))


def check(model, n_loops: int, kind: str) -> Check:
    state = model.initial
    a, b = solve_with(model, state, "off"), solve_with(model, state, "on")
    gta = max(constraint_residual(model, state, s.accelerations) for s in (a, b))
    exact = closed_form_accelerations(n_loops, kind)
    # Redundant constraints: the pseudo-inverse of S leaves rounding of cond(S) ε.
    tol = 1e-10 if not a.redundant else max(1e-10, 10 * condition(model, state) * 2.2e-16)
    y = initial_y(model)
    f = rhs(model, "on")  # simulate's right-hand side: the compiled core, whatever the mode
    assert f.compiled
    n = model.n
    d = f(0.0, y)[7 * n:13 * n].reshape(2, n, 3)  # v̇ (world), ω̇ (body axes) per body
    acc = (np.stack((d[0, :, 0], d[0, :, 1], d[1, :, 2]), axis=1) if model.dimension == 2
           else np.concatenate((d[0], d[1]), axis=1)).ravel()
    # the state keeps its joints: Baumgarte's terms vanish, the accelerations are the solve's
    return Check(rel(b.accelerations, a.accelerations),
                 rel(reactions(b, model), reactions(a, model)), gta,
                 max(rel(s.accelerations, exact) for s in (a, b)),
                 rel(acc, a.accelerations), tol)


def motion_error(kind: str, n_loops: int, t_end: float = 2.0) -> tuple[float, str]:
    """(largest |θ − θ_exact| over the rungs and samples (rad), evaluation path) of a
    ladder released from rest, simulated at simulate's defaults."""
    model = mbody.load(ladder_spec(n_loops, kind, omega0=0.0))
    traj = mbody.simulate(model, t_end=t_end, fps=50)
    x = traj.spatial()[0]  # (K, n, 3) mass centres
    rungs = np.arange(0, model.n, 2)
    pivots = np.arange(n_loops + 1) * D
    theta = np.arctan2(x[:, rungs, 0] - pivots, -x[:, rungs, 1])
    exact = pendulum_angle(n_loops, kind, traj.t, THETA0)[:, None]
    return float(np.max(np.abs(theta - exact))), traj.info["evaluation_path"]


DENSE = {
    "numpy.linalg": ("cholesky", "eigh", "eigvalsh", "eig", "svd", "inv", "solve", "lstsq",
                     "pinv", "qr"),
    "scipy.linalg": ("cholesky", "cho_factor", "lu_factor", "lu", "solve", "eigh",
                     "eigvalsh", "svd", "inv", "lstsq", "pinvh", "qr", "ldl"),
}


@contextlib.contextmanager
def dense_spy(min_size: int = 7):
    """Count calls of numpy's and scipy's dense LAPACK entry points on matrices of at
    least `min_size` rows (the per-body 3 x 3 and 6 x 6 products are not factorisations
    of S). Yields the list of (function, shape) calls."""
    calls: list[tuple[str, tuple[int, ...]]] = []
    saved = []
    for modname, names in DENSE.items():
        mod = importlib.import_module(modname)
        for name in names:
            fn = getattr(mod, name, None)
            if fn is None:
                continue

            def spy(*args, _fn=fn, _name=f"{modname}.{name}", **kw):
                a = np.asarray(args[0]) if args else None
                if a is not None and a.ndim == 2 and min(a.shape) >= min_size:
                    calls.append((_name, a.shape))
                return _fn(*args, **kw)

            saved.append((mod, name, fn))
            setattr(mod, name, spy)
    try:
        yield calls
    finally:
        for mod, name, fn in saved:
            setattr(mod, name, fn)


# -- timing ------------------------------------------------------------------------------------
def initial_y(model) -> np.ndarray:
    """The state vector exactly as `simulate` builds it ([x | q | v | ω | θ (planar)])."""
    s0 = model.initial
    theta0 = (2.0 * np.arctan2(s0.quaternion[:, 3], s0.quaternion[:, 0])
              if model.dimension == 2 else ())
    return np.concatenate((s0.position.ravel(), s0.quaternion.ravel(), s0.velocity.ravel(),
                           s0.omega.ravel(), theta0))


def rhs(model, mode: str):
    """simulate's right-hand side, on the path `mode` selects ('on' or 'off')."""
    previous = mplan.set_jit(mode)
    try:
        return importlib.import_module("mbody.simulate").state_derivative(model)
    finally:
        mplan.set_jit(previous)


def worker_cpu() -> float:
    """CPU seconds used so far by the process's threads other than this one (BLAS and
    numba workers), from /proc (Linux; nan elsewhere). Clock ticks: 10 ms resolution."""
    import os
    import threading

    try:
        tasks = os.listdir("/proc/self/task")
        tick = os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, AttributeError):
        return math.nan
    me, total = threading.get_native_id(), 0
    for tid in tasks:
        if int(tid) == me:
            continue
        try:
            with open(f"/proc/self/task/{tid}/stat") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
        except OSError:  # the thread ended
            continue
        total += int(fields[11]) + int(fields[12])  # utime, stime
    return total / tick


def timed(funcs: dict, repeat: int) -> tuple[dict[str, float], dict[str, float]]:
    """Per function: (best seconds per call, the other threads' CPU time / wall time
    while it was timed: 0 when no BLAS thread ran, up to 1 per extra busy thread).

    The functions take turns, one `best` run each per round, so that a burst of load
    from other processes on this shared machine spreads over all of them instead of
    spoiling every run of one."""
    out = {key: math.inf for key in funcs}
    cpu = dict.fromkeys(funcs, 0.0)
    wall = dict.fromkeys(funcs, 0.0)
    for fn in funcs.values():
        for _ in range(3):
            fn()
    for _ in range(repeat):
        for key, fn in funcs.items():
            k0, w0 = worker_cpu(), time.perf_counter()
            out[key] = min(out[key], best(fn, 1))
            cpu[key] += worker_cpu() - k0
            wall[key] += time.perf_counter() - w0
    return out, {key: cpu[key] / wall[key] for key in funcs}


@dataclass
class Row:
    kind: str
    loops: int
    bodies: int
    mu: int
    times: dict[str, float]  # solve-jit, solve-np, rhs-jit, rhs-np: s per call
    workers: dict[str, float]  # the same: other threads' CPU time / wall time
    one_thread: dict[str, float]  # the times again under threadpool_limits(1)
    method_jit: str
    method_np: str
    rhs_np: str
    bw_jit: int
    bw_np: int | None
    dense: list
    full_jit: str = ""  # the methods in full
    full_np: str = ""
    full_rhs: str = ""


COLUMNS = ("solve-jit", "solve-np", "rhs-jit", "rhs-np")


def short(method: str) -> str:
    """The solution's `method`, shortened for the table; dense ones in capitals."""
    m = method.lower()
    if "banded" in m:
        return ("banded Cholesky" + (", blocks" if "blocks" in m else "")
                + (", sparse" if m == "banded cholesky of the schur complement" else ""))
    for key, text in (("svd", "DENSE SVD"), ("eigen", "DENSE eigh"),
                      ("pseudo-inverse", "DENSE eigh"), ("dense", "DENSE Cholesky")):
        if key in m:
            return text
    return method


def measure(kind: str, target: int, repeat: int, threads: bool) -> Row:
    """Time one ladder (the kind's size nearest `target` unknowns) on both paths."""
    n_loops = loops_for(kind, target)
    model = mbody.load(ladder_spec(n_loops, kind))
    state = model.initial
    unknowns = model.plan.file_unknowns
    y = initial_y(model)
    funcs = {}
    for mode, tag in (("on", "jit"), ("off", "np")):
        def solve(mode=mode):
            # the path is chosen per call from mbody.equations.plan.JIT (set_jit's global), set
            # here directly: set_jit's parsing would be timed too
            mplan.JIT = mode
            return mbody.assemble(model, state).solve()

        f = rhs(model, mode)  # the path is fixed when the right-hand side is made
        funcs[f"solve-{tag}"] = solve
        funcs[f"rhs-{tag}"] = lambda f=f: f(0.0, y)
    previous = mplan.JIT
    one: dict[str, float] = {}
    try:
        times, workers = timed(funcs, repeat)
        if threads:
            from threadpoolctl import threadpool_limits

            with threadpool_limits(1):
                one = timed(funcs, repeat)[0]
        method_jit = funcs["solve-jit"]().method
        with dense_spy() as calls:
            method_np = funcs["solve-np"]().method
            funcs["rhs-np"]()
        mplan.JIT = "off"  # the numpy right-hand side's factorisation, as it makes it
        system = mbody.assemble(model, state).constrained(unknowns, rate=20.0,
                                                          refine=False)[2]
    finally:
        mplan.JIT = previous
    bp = model.plan.block_plan(unknowns)
    bw_jit = int(model.plan.packed_unknowns(unknowns)[1])
    return Row(kind, n_loops, model.n, len(unknowns.U), times, workers, one, short(method_jit),
               short(method_np), short(system.fact.method), bw_jit,
               bp.bw if bp is not None else None, calls, method_jit, method_np,
               system.fact.method)


def blas_summary() -> str:
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        return "threadpoolctl not installed: BLAS threads not inspected"
    libs = [f"{i['internal_api']} {i['version']} ({Path(i['filepath']).name.split('-')[0]}) "
            f"{i['num_threads']} threads" for i in threadpool_info()]
    return "BLAS: " + "; ".join(libs) if libs else "BLAS: none loaded"


def print_rows(rows: list[Row], repeat: int, threads: bool) -> None:
    print(f"\nµs per call, best of {repeat}; solve = assemble(model, state).solve(); "
          "RHS = simulate's f(t, y)")
    head = (f"{'kind':<17} {'N':>3} {'n':>4} {'mu':>4} | {'solve':>8} {'numpy':>8} | "
            f"{'RHS':>8} {'numpy':>8} | {'bw':>3} {'np':>3} | threads | "
            "path: compiled / numpy solve / numpy RHS")
    print(head)
    print("-" * len(head))
    for r in rows:
        t = r.times
        print(f"{r.kind:<17} {r.loops:>3} {r.bodies:>4} {r.mu:>4} | "
              + " | ".join(f"{t[a] * 1e6:8.1f} {t[b] * 1e6:8.1f}"
                           for a, b in (COLUMNS[:2], COLUMNS[2:]))
              + f" | {r.bw_jit:>3} {r.bw_np if r.bw_np is not None else '-':>3} | "
              f"{max(r.workers.values()):7.2f} | {r.method_jit} / {r.method_np} / {r.rhs_np}")
    print("N loops, n bodies, mu unknown reaction components; bw, np: S's half bandwidth "
          "(compiled order; numpy per-body blocks' order)")
    print("threads: the largest over the four columns of the CPU time of threads other "
          "than the caller's (BLAS workers) / wall time while timing; 0.00: none ran")
    if threads and rows and rows[0].one_thread:
        print("\nthe same under threadpool_limits(1), µs per call (× = default threads / "
              "one thread)")
        head = (f"{'kind':<17} {'mu':>4} | " + " | ".join(
            f"{c:>9} {'×':>5}" for c in ("solve", "numpy", "RHS", "numpy")))
        print(head)
        print("-" * len(head))
        for r in rows:
            print(f"{r.kind:<17} {r.mu:>4} | " + " | ".join(
                f"{r.one_thread[c] * 1e6:9.1f} {r.times[c] / r.one_thread[c]:5.2f}"
                for c in COLUMNS))
    for side, methods in (("compiled", {r.full_jit for r in rows}),
                          ("numpy", {m for r in rows for m in (r.full_np, r.full_rhs)})):
        print(f"{side} paths: " + "; ".join(f"{short(m)} = {m}" for m in sorted(methods)))
    dense = [r for r in rows if r.dense]
    print("\ndense factorisations on the numpy path (calls in one solve + one RHS): "
          + ("" if dense else "none"))
    for r in dense:
        counts: dict[str, int] = {}
        for name, shape in r.dense:
            key = f"{name} {shape[0]}x{shape[1]}"
            counts[key] = counts.get(key, 0) + 1
        print(f"  {r.kind} mu={r.mu}: " + ", ".join(f"{k} ×{c}" for k, c in counts.items()))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="50 and 100 unknowns, 3 repeats")
    p.add_argument("--repeat", type=int, help="timed runs per entry, best kept (default 9)")
    p.add_argument("--sizes", help="unknown counts, comma-separated (default 50,100,250,500)")
    p.add_argument("--kinds", default=",".join(KINDS), help=f"of {', '.join(KINDS)}")
    p.add_argument("--no-threads", action="store_true",
                   help="skip the second timing under threadpool_limits(1)")
    a = p.parse_args(argv)
    repeat = max(1, a.repeat or (3 if a.quick else 9))
    sizes = ([int(s) for s in a.sizes.split(",")] if a.sizes
             else [50, 100] if a.quick else list(SIZES))
    kinds = [k.strip() for k in a.kinds.split(",")]
    bad = [k for k in kinds if k not in KINDS]
    if bad:
        p.error(f"unknown kind(s) {', '.join(bad)}; of {', '.join(KINDS)}")
    threads = not a.no_threads
    if threads and importlib.util.find_spec("threadpoolctl") is None:
        print("threadpoolctl not installed: no timing under threadpool_limits(1)")
        threads = False
    import numba
    import scipy
    import scipy.linalg  # noqa: F401 (its BLAS, for the summary; mbody loads it too)

    print(f"mbody {mbody.__version__}, numpy {np.__version__}, scipy {scipy.__version__}, "
          f"numba {numba.__version__}, Python {sys.version.split()[0]}")
    mbody.assemble(mbody.load(ladder_spec(1, "planar"))).solve()  # imports, first compile
    print(blas_summary())
    fails = 0

    print("\nchecks: compiled vs numpy (accelerations, λ), Gᵀ v̇ = γ (`constraint_residual`), "
          "accelerations vs the closed form, right-hand sides compiled vs numpy")
    for kind in kinds:
        for target in sizes:
            n_loops = loops_for(kind, target)
            model = mbody.load(ladder_spec(n_loops, kind))
            c = check(model, n_loops, kind)
            fails += not c.ok
            print(f"  {kind:<17} N={n_loops:<3} acc {c.acc:7.1e}  λ {c.lam:7.1e}  "
                  f"Gᵀv̇−γ {c.constraint:7.1e}  closed form {c.closed:7.1e}  "
                  f"RHS {c.rhs:7.1e}  (≤ {c.tol:.0e})  {'PASS' if c.ok else 'FAIL'}",
                  flush=True)
    for kind in kinds:
        if kind == "spatial-redundant":
            continue
        n_loops = loops_for(kind, min(sizes))
        err, path = motion_error(kind, n_loops)
        ok = err <= 1e-7
        fails += not ok
        print(f"  {kind} N={n_loops} released from rest, 2 s of simulate() ({path}): "
              f"rung angles vs the exact pendulum {err:.1e} rad  {'PASS' if ok else 'FAIL'}",
              flush=True)

    rows = [measure(kind, target, repeat, threads) for kind in kinds for target in sizes]
    print_rows(rows, repeat, threads)
    return 1 if fails else 0


if __name__ == "__main__":
    raise SystemExit(main())
