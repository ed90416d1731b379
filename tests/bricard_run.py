"""mbody's run of Bricard's mechanism (models/bricard.yaml), and what the tests and
tools/bench_bricard.py read from it.

`run` drives the compiled core as `mbody.simulate` does: the core's DOP853
(`mbody.kernel.dop853`) on the core's derivative, the state projected onto the joints
after every accepted step (positions by Gauss-Newton, velocities mass-orthogonal) with a
fresh derivative after a move, samples at k / fps from the step's dense output, each
projected too. It stands in for `mbody.simulate` while that moves onto the core
(issue 23); once it has, `run` is `mbody.simulate(model, t_end, fps, rtol=..., atol=...)`.

The joints' errors at the samples (`joint_errors`) are measured here from the benchmark's
geometry (tests/bricard_reference.py), not by mbody.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from bricard_reference import AXES, POINTS, RODS

import mbody
from mbody.equations.workspace import workspace
from mbody.kernel import _core
from mbody.kernel.dop853 import DOP853

MODEL = Path(__file__).resolve().parent.parent / "models" / "bricard.yaml"
REFRESH = 1e-2
"""A projection that moves the state by more than this many atol refreshes the next
step's first derivative (as `mbody.simulate`)."""
ROBUST_BELOW = 1e-2
"""Geometric ratio below which the projection takes the null-space route (as simulate)."""


def rotation(q: np.ndarray) -> np.ndarray:
    """W_R_B (..., 3, 3) of unit quaternions [w, x, y, z] (..., 4)."""
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack((
        np.stack((1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)), -1),
        np.stack((2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)), -1),
        np.stack((2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)), -1),
    ), -2)


@dataclass
class Run:
    """Samples at `t` (K,): mass centres `x` (K, 5, 3) world, rotations `R` (K, 5, 3, 3),
    velocities `v` (K, 5, 3) world, angular velocities `w` (K, 5, 3) body axes; the run's
    figures."""

    t: np.ndarray
    x: np.ndarray
    R: np.ndarray
    v: np.ndarray
    w: np.ndarray
    steps: int
    evaluations: int
    rejected: int
    wall: float
    largest_move: float
    """The largest move of a projection after a step (m or rad; m/s or rad/s)."""
    start_move: float
    """How far the projection moved the initial state."""


def state_vector(model: mbody.Model, state: mbody.State | None = None) -> np.ndarray:
    return workspace(model).state_vector(model.initial if state is None else state)


def run(model: mbody.Model, t_end: float = 10.0, fps: float = 60.0, *, rtol: float,
        atol: float, initial: mbody.State | None = None) -> Run:
    """Integrate from `initial` (default the file's state) to t_end; samples at k / fps."""
    ws = workspace(model)
    unknowns = ws.file_unknowns
    solver = ws.solver(unknowns)
    lam, n = unknowns.lam, model.n

    def f(t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty_like(y)
        code = solver.derivative(t, y, lam, 0.0, out)
        if code:  # the core found a motion without mass: what `solve` would report
            raise mbody.MbodyError(f"derivative failed at t = {t}: code {code}")
        return out

    info = np.empty(_core.PROJECT_INFO)
    moves = [0.0]

    def project(t: float, y: np.ndarray) -> list[float]:
        solver.project(t, y, 3, ROBUST_BELOW, 0, info)
        if info[_core.PR_SINGULAR]:
            raise mbody.MbodyError(f"the projection failed at t = {t}")
        move = max(info[_core.PR_STEP], info[_core.PR_VELOCITY])
        moves[0] = max(moves[0], move)
        return [move, 0.0, 0.0, 0.0]

    y0 = state_vector(model, initial)
    start = time.perf_counter()
    start_move = project(0.0, y0)[0]
    moves[0] = 0.0
    K = int(np.floor(t_end * fps + 1e-9)) + 1
    t = np.arange(K) / fps
    Y = np.empty((K, len(y0)))
    Y[0] = y0
    sol = DOP853(f, 0.0, y0, t_end, rtol=rtol, atol=atol, project=project, refresh=REFRESH)
    k = 1
    while sol.status == "running":
        sol.step()
        j = int(np.searchsorted(t, sol.t, side="right"))
        if j > k:
            Y[k:j] = sol.dense(t[k:j])
            for i in range(k, j):
                solver.project(float(t[i]), Y[i], 3, ROBUST_BELOW, 0, info)
            k = j
    wall = time.perf_counter() - start
    if sol.status != "finished":
        raise mbody.MbodyError(f"the run stopped at t = {sol.t}: {sol.status}")
    q = Y[:, 3 * n:7 * n].reshape(K, n, 4)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return Run(t, Y[:, :3 * n].reshape(K, n, 3), rotation(q),
               Y[:, 7 * n:10 * n].reshape(K, n, 3), Y[:, 10 * n:13 * n].reshape(K, n, 3),
               sol.steps, sol.nfev, sol.rejected, wall, moves[0], start_move)


def body_point(model: mbody.Model, body: int, world: np.ndarray) -> np.ndarray:
    """A point of `body` given by where it is in the file's pose: its body-frame vector."""
    R0 = rotation(model.initial.quaternion[body])
    return R0.T @ (np.asarray(world, float) - model.initial.position[body])


def p3(model: mbody.Model, r: Run) -> np.ndarray:
    """The benchmark's point P3 (joint B, carried by rod2) at the samples (K, 3)."""
    local = body_point(model, 1, POINTS[2])
    return r.x[:, 1] + r.R[:, 1] @ local


def energy(model: mbody.Model, r: Run) -> np.ndarray:
    """T + V at the samples (K,) (J): V = -Σ m g·x."""
    m = np.asarray(model.mass)
    J = np.asarray(model.J)
    T = 0.5 * np.einsum("i,kia,kia->k", m, r.v, r.v) \
        + 0.5 * np.einsum("kia,iab,kib->k", r.w, J, r.w)
    V = -np.einsum("i,kia,a->k", m, r.x, np.asarray(model.gravity))
    return T + V


def joint_errors(model: mbody.Model, r: Run) -> tuple[float, float]:
    """The joints' largest position error (m: the joint point as each of its two bodies
    carries it) and axis error (rad: the sine of the angle between the two bodies'
    copies of the joint axis) over the samples; the joints and their bodies from the
    benchmark (joint j between rod j and rod j + 1, ground before rod1 and after rod5)."""
    K = len(r.t)
    point_err, axis_err = 0.0, 0.0
    for j in range(6):
        ends = []
        for body in (j - 1, j if j < RODS else -1):  # -1: ground
            if body < 0:
                ends.append((np.broadcast_to(POINTS[j], (K, 3)),
                             np.broadcast_to(AXES[j], (K, 3))))
                continue
            R0 = rotation(model.initial.quaternion[body])
            local_p = R0.T @ (POINTS[j] - model.initial.position[body])
            local_e = R0.T @ AXES[j]
            ends.append((r.x[:, body] + r.R[:, body] @ local_p, r.R[:, body] @ local_e))
        (pa, ea), (pb, eb) = ends
        point_err = max(point_err, float(np.abs(pa - pb).max()))
        axis_err = max(axis_err, float(np.linalg.norm(np.cross(ea, eb), axis=-1).max()))
    return point_err, axis_err
