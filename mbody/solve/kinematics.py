"""Kinematic analysis: the positions and velocities that close every joint and driver.

A mechanism with drivers (joint coordinates prescribed in time) is moved by them; one
whose joint points are given on each body (``at: [[parent point], [child point]]``) has
a file pose that need only be close. Both need the configuration where every constraint
holds at a time t:

    φ(q, t) = 0          (position: Newton–Raphson from a start, on its branch)
    Gᵀ v = f′(t)          (velocity: the smallest change of kinetic energy that keeps them)

Each Newton step is the compiled core's coordinate projection (`mbody.kernel`,
project.c): M Δ − G μ = 0, Gᵀ Δ = −φ, the least move in the kinetic metric, so the
solution found is the one nearest the start (the file's pose, or the previous instant's
solution along a run: its branch). The accelerations follow from the constraint
equations with the forces, `mbody.assemble(model, state).solve()`: for a fully driven
mechanism they are the motion the drivers impose, and the reactions with the drivers'
efforts are what it takes (kinetostatics). Whether the drivers leave any freedom, the
degrees of freedom of the joints and drivers together, is `freedom` (`fully_driven`: none
left, so a run is kinematic).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from mbody.equations.joints import g_block, reaction_columns
from mbody.equations.workspace import workspace
from mbody.errors import Issue, MbodyError, ModelError
from mbody.kernel import _core
from mbody.model.arguments import checked_model, checked_state
from mbody.model.build import frames_at
from mbody.model.model import Model, State

NEWTON_STEPS = 60
"""Newton steps at most (one is usually enough from an integrator's step; a few from a
file's rough pose; more only near a dead centre, where the steps shrink)."""
CLOSE_RTOL = 1e-12
"""The joints hold when every position error is below this, relative to the model's
size (angles: absolute, rad)."""


class KinematicsError(MbodyError):
    """The joints and drivers cannot all hold at a time: a loop that cannot close (a
    driver past a dead centre, links too short), named with its distance left."""


class AssemblyError(ModelError, KinematicsError):
    """A model file whose joints and drivers cannot all close at t = 0 (`mbody.load`): a
    problem of the file (a `ModelError`, located at its first driver's entry when it has
    drivers), and a `KinematicsError`."""


def kinematics(model: Model, t: float = 0.0, *, start: State | None = None) -> State:
    """The positions and velocities that close every joint and driver at time `t`.

    Parameters
    ----------
    model : Model
        The model, with its drivers (if any).
    t : float
        Time (s): the drivers' laws are taken there.
    start : State, optional
        Where Newton's method starts (default: the file's state); its branch is the one
        found, and its velocities are the ones kept as far as the joints allow.

    Returns
    -------
    State
        At time `t`: every joint and driver holds at position and velocity level.

    Raises
    ------
    MbodyError
        `t` is not a finite number; a `model` or `start` that is not one of this model
        (`mbody.model.arguments`).
    KinematicsError
        The loops cannot close at `t` (which joints, the drivers' values, the distance
        left).
    """
    given = t
    try:
        t = float(t)
    except (TypeError, ValueError):
        t = math.nan  # refused below, with what was given
    if not math.isfinite(t):
        raise MbodyError(f"t must be a finite number of seconds (the time the drivers' "
                         f"laws are taken at), got {given!r}")
    if not isinstance(model, Model):
        model = checked_model(model)
    ws = workspace(model)
    state = model.initial if start is None else checked_state(model, start, "start")
    unknowns = ws.unknowns({})  # every joint and driver holds
    solver = ws.solver(unknowns)
    y = ws.state_vector(state.replace(t=t))
    info = np.empty(_core.PROJECT_INFO)
    size = _size(model)
    moved = np.inf
    for _ in range(NEWTON_STEPS):
        solver.project(t, y, 1, 1e-2, 0, info)
        if info[_core.PR_SINGULAR]:
            code = int(info[_core.PR_SINGULAR]) - 1
            body = model.body_names[code // 6]
            raise KinematicsError(f"the position analysis at t = {t:g} s cannot move body "
                                  f"{body!r}: its motion carries no mass")
        moved = float(info[_core.PR_STEP])
        if moved <= CLOSE_RTOL * size:
            break
    out = _state(model, y, t)
    cols = reaction_columns(model, out)
    scale = np.where(model.reaction_table.is_moment, 1.0, size)
    bad = np.flatnonzero(np.abs(cols.phi) > 1e3 * CLOSE_RTOL * scale)
    if len(bad) or not np.isfinite(y).all():
        raise KinematicsError(_cannot_close(model, t, cols.phi, bad, moved))
    return out


def _state(model: Model, y: np.ndarray, t: float) -> State:
    n = model.n
    q = y[3 * n:7 * n].reshape(n, 4)
    return State(y[:3 * n].reshape(n, 3).copy(), q / np.linalg.norm(q, axis=1)[:, None],
                 y[7 * n:10 * n].reshape(n, 3).copy(), y[10 * n:13 * n].reshape(n, 3).copy(),
                 float(t))


def _size(model: Model) -> float:
    """The model's length scale: the spread of its mass centres, its joints' arms."""
    pts = model.initial.position
    spread = float(np.ptp(pts, axis=0).max()) if model.n > 1 else 0.0
    arms = float(np.abs(model.joint_table.B_r_child).max()) if len(model.joints) else 0.0
    return max(spread, arms, 1e-3)


def _cannot_close(model: Model, t: float, phi: np.ndarray, bad: np.ndarray,
                  step: float) -> str:
    rt = model.reaction_table
    labels = rt.labels
    worst = bad[np.argsort(-np.abs(phi[bad]))][:6]
    left = ", ".join(f"{labels[k]} {phi[k]:.3g} {'rad' if rt.is_moment[k] else 'm'}"
                     for k in worst)
    drivers = model.drivers
    at = ""
    if drivers is not None and len(drivers):
        # an angle in degrees, as every other kinematics output gives it (review R7-14)
        values = [f"{name} = {math.degrees(float(law[0](t))):.6g} deg" if c == "M" else
                  f"{name} = {float(law[0](t)):.6g} m"
                  for name, law, c in zip(drivers.names, drivers.laws, drivers.component,
                                          strict=True)]
        at = f" with {', '.join(values)}"
    return (f"the joints cannot all close at t = {t:g} s{at}: the distance left is {left}"
            f" (Newton's last step {step:.3g}); a driver may be past a dead centre, or the "
            "links cannot reach")


def check_drivers(model: Model) -> None:
    """Refuse more drivers than the mechanism has degrees of freedom, or a driver of a
    motion the joints already fix: each driver must add one independent constraint to
    the joints' (a `ModelError` at the drivers' entries in the file)."""
    drivers = model.drivers
    if drivers is None or not len(drivers):
        return
    m = len(model.reactions)
    k = len(drivers)
    if m > 3000:  # a dense rank test would be slow: trust the file
        return
    G = np.asarray(mbody_assembly_G(model))
    joints = np.linalg.matrix_rank(G[:, :m - k], tol=None) if m > k else 0
    every = np.linalg.matrix_rank(G, tol=None)
    if every - joints == k:
        return
    dof = len(model.coordinates) - joints
    if k > dof:
        line, col = drivers.where[dof] if dof < k else drivers.where[-1]
        raise ModelError([Issue(model.file, line, col, f"drivers[{dof}]",
                                f"{k} drivers for {dof} degree(s) of freedom: the joints "
                                f"leave the mechanism {dof} way(s) to move, and each driver "
                                "prescribes one",
                                f"keep at most {dof} driver(s); the others' coordinates "
                                "follow from the joints")])
    line, col = drivers.where[-1]
    raise ModelError([Issue(model.file, line, col, f"drivers[{k - 1}]",
                            f"driver '{drivers.names[-1]}' adds no independent constraint: "
                            "its coordinate is already fixed by the joints and the other "
                            "drivers", "drive another joint, or remove it")])


def mbody_assembly_G(model: Model) -> np.ndarray:
    """G at the file's pose, dense (rows: every body's rows; a particle's turning rows are
    zero), without scipy: `mbody check` of a driven model loads no heavy module."""
    cols = reaction_columns(model, model.initial)
    return g_block(model, cols, np.arange(model.n), np.arange(len(model.reactions)))


def assembled(model: Model) -> Model:
    """The model with its initial state moved onto its joints and drivers at t = 0 when
    the file asks for it: joint points given on each body, or drivers (whose laws at 0
    may differ from the file's pose). Otherwise `model` itself: a model written with
    world joint points is where the file puts it (`check` warns when it breaks a joint).
    The file's own state is kept as `model.file_state`; the joint frames are the
    contract's rule at the assembled pose (`mbody.model.build.frames_at`)."""
    if not _assembles(model):
        return model
    check_drivers(model)
    return placed(model)


def _assembles(model: Model) -> bool:
    """Whether `mbody.load` assembles `model` (`assembled`)."""
    return ((model.drivers is not None and len(model.drivers) > 0)
            or bool(model.joint_table.body_points.any())) and bool(len(model.reactions))


def placed(model: Model) -> Model:
    """`assembled` without its check that each driver adds an independent constraint (a
    caller that knows it: `mbody.solve.family`, for a model whose joints and file pose
    are those of one already checked)."""
    if not _assembles(model):
        return model
    try:
        state = kinematics(model, 0.0)
    except KinematicsError as exc:
        drivers = model.drivers
        if drivers is not None and len(drivers):
            (line, col), key = drivers.where[0], "drivers[0]"
        else:
            (line, col), key = (0, 0), "joints"
        raise AssemblyError([Issue(
            model.file, line, col, key, str(exc),
            "check the joints' points on each body and the drivers' values at t = 0")]
        ) from None
    joints, table = frames_at(model.joints, model.reaction_table, model.dimension,
                              model.initial, state, CLOSE_RTOL)
    return dataclasses.replace(model, initial=state, file_state=model.initial, joints=joints,
                               reaction_table=table)


def freedom(model: Model) -> int:
    """The degrees of freedom the joints and drivers leave (the model's coordinates less
    the generic rank of the enforced constraints): 0 for a fully driven mechanism."""
    ws = workspace(model)
    solver = ws.solver(ws.file_unknowns)
    return len(model.coordinates) - int(solver.generic_rank)


def fully_driven(model: Model) -> bool:
    """The model has drivers and they leave it no freedom (`freedom` is 0)."""
    d = model.drivers
    return d is not None and len(d.names) > 0 and freedom(model) == 0


def require_fully_driven(model: Model) -> None:
    """Refuse (`MbodyError`) a mechanism whose drivers leave degrees of freedom: their
    motion follows from the forces, and only an integration (`mbody.simulate`) finds it."""
    free = freedom(model)
    if free:
        d = model.drivers
        have = len(d.names) if d is not None else 0
        raise MbodyError(f"{model.name!r} is not fully driven: its {have} driver(s) leave "
                         f"{free} degree(s) of freedom, whose motion follows from the "
                         "forces; integrate it with mbody simulate (mbody.simulate), which "
                         "follows the drivers and integrates the rest")
