"""A kinematic run: a driven mechanism's motion over time, and what it takes.

A mechanism whose drivers leave it no freedom (as many independent drivers as degrees of
freedom) is moved by its drivers alone: at each sample time the positions that close
every joint and driver (Newton's method from the previous sample carried forward, so
the run stays on the branch of the file's pose), the velocities and accelerations the
constraints then impose, and the reactions and drivers' efforts that take them, from
the Newton-Euler equations (kinetostatics, or inverse dynamics). Nothing is integrated.
The whole run is one call of the compiled core (`mbody.kernel`: kinematic.c).

The drivers' work is checked against the energy: with every joint ideal (its solved
reactions do no work), dT/dt = Σ effort · f′ + Σ Q · v over the bodies (Q the applied
loads, gravity and springs included), so T(t) − T(0) equals the work of the drivers
and of Q; the run reports both sides and their difference (a cubic quadrature over the
samples, `_cumulative`: its error is of order (ω Δt)⁴, ω the fastest rate).

    traj = kinematic_run(model, t_end=0.1, fps=3600)      # a Trajectory
    traj.reactions[:, traj.reaction_labels.index("motor.M")]
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from mbody import conventions as cv
from mbody.conventions import check_axes
from mbody.equations.joints import reaction_columns
from mbody.equations.solution import singular_mass_error
from mbody.equations.workspace import workspace
from mbody.errors import MbodyError, did_you_mean, real_number, wrong_type
from mbody.kernel import _core
from mbody.model.arguments import checked_model
from mbody.model.checks import MAX_MAGNITUDE
from mbody.model.model import Model
from mbody.simulate.axes import world_series
from mbody.simulate.peaks import record_peaks, steady_rate
from mbody.simulate.trajectory import (
    Trajectory,
    appearance,
    keep_planar_angles,
    last_sample_warning,
    model_text,
    model_values,
    sample_times,
)
from mbody.solve.kinematics import (
    CLOSE_RTOL,
    KinematicsError,
    _cannot_close,
    _size,
    _state,
    require_fully_driven,
)
from mbody.util.spatial import quat_to_matrix

MAX_NEWTON = 60
"""Newton steps at most at one sample (one or two from the previous sample's Taylor
step; more only near a dead centre)."""
ROUNDING_UNITS = 8.0
"""Rounding units of the largest driver's coordinate a Newton step may stay at
(`newton_tolerance`): the last step of a closed loop is about one of them."""
BodyPoints = Mapping[str, tuple[str, Sequence[float]] | str]
"""name -> (body, point in the body's axes from its mass centre, m), or the command line's
``"BODY:X,Y[,Z]"`` text for the same: points to follow."""
POINTS_FORM = ("a mapping name -> (body, [x, y(, z)]) or name -> 'body:x,y(,z)', such as "
               "{'P': ('coupler', [0.1, 0.05])}")
"""What `kinematic_run`'s ``points`` takes, in words (its error messages)."""


def kinematic_run(model: Model, t_end: float, fps: float, *, t_start: float = 0.0,
                  points: BodyPoints | None = None, axes: str = "joint") -> Trajectory:
    """The motion the drivers impose over [t_start, t_end], sampled at `fps`, with the
    reactions and drivers' efforts at each sample (module doc).

    Parameters
    ----------
    model : Model
        A fully driven mechanism: its drivers leave it no freedom (`freedom` is 0).
    t_end, fps : float
        The last time (s) and the samples per second.
    t_start : float
        The first sample's time (s).
    points : mapping, optional
        Body points to follow, name -> (body, [x, y(, z)] in its axes from its mass
        centre, m), or name -> ``"body:x,y(,z)"`` (the form of the command line's
        ``--point NAME=BODY:X,Y``): their world positions go into
        ``series['point:<name>']`` (K, d). Checked before the run.
    axes : {"joint", "world"}
        The reactions' axes (`mbody.equations.world`).

    Returns
    -------
    Trajectory
        Every body's motion; `reactions` by `reaction_labels` (the drivers' efforts
        among them); ``info`` with the Newton steps, the energy check and the peaks,
        and under ``info["warnings"]`` samples too sparse for those peaks
        (`mbody.simulate.peaks.sampling_warning`), or a last sample short of `t_end`
        (`last_sample_warning`).

    Raises
    ------
    MbodyError
        The mechanism is not fully driven (its free coordinates need integrating:
        `mbody.simulate`); a point names no body, or has the wrong number of coordinates
        (`mbody.errors.MbodyTypeError`, a `TypeError` too, when `points` or an entry is
        of another form).
    KinematicsError
        At a sample where the loops cannot close (a dead centre, links that cannot
        reach): its time, the drivers' values and the distance left.
    """
    if not isinstance(model, Model):
        model = checked_model(model)
    t_end = real_number(t_end, "t_end", "a number of seconds")
    fps = real_number(fps, "fps", "a positive number of samples per second")
    t_start = real_number(t_start, "t_start", "a number of seconds")
    if not math.isfinite(t_start):  # else sample_times would blame t_end
        raise MbodyError(f"t_start must be a finite number of seconds, got {t_start:g}")
    check_axes(axes)
    t = sample_times(t_end, fps, t_start)
    require_fully_driven(model)
    followed = body_points(model, points)
    ws = workspace(model)
    unknowns = ws.file_unknowns
    plan = ws.solve_plan(unknowns)
    K, S = len(t), ws.state_size
    L = plan.o_info + _core.INFO
    Y = np.empty((K, S))
    OUT = np.empty((K, L))
    energy = np.empty((K, 3))
    info = np.empty(_core.KR_INFO)
    y = ws.state_vector(model.initial.replace(t=float(t[0])))
    tol = newton_tolerance(model, t)
    done = plan.solver.kinematic_run(t, y, unknowns.lam, MAX_NEWTON, tol, Y, OUT, energy,
                                     info)
    if done < K:
        _failed(model, float(t[done]), y, info)
    traj = _trajectory(model, t, Y, OUT, energy, plan, info, followed, axes, fps)
    short = last_sample_warning(t_end, fps, t_start)
    if short:
        traj.info["warnings"].insert(0, short)
    return traj


def carry(model: Model, t_from: np.ndarray, Y_from: np.ndarray, t_to: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """Each state ``Y_from[k]`` (the core's layout: a run's sample, `sample_states`) at
    ``t_from[k]`` carried to ``t_to[k]`` as `kinematic_run` carries a sample to the next:
    the Taylor step along its velocities and accelerations, Newton's method until every
    joint and driver closes at ``t_to[k]`` (on the sample's branch), then the solve there.
    Exact at ``t_to[k]``, not an interpolation; best from the sample just before it.

    Returns
    -------
    (Y, lam)
        (K, state size) the states at ``t_to``, (K, m) the reactions and drivers' efforts
        there in joint axes (``model.reactions`` order).

    Raises
    ------
    KinematicsError
        The loops cannot close at one of the times (as `kinematic_run`).
    """
    ws = workspace(model)
    unknowns = ws.file_unknowns
    plan = ws.solve_plan(unknowns)
    K, S, m = len(t_to), ws.state_size, len(model.reactions)
    if np.any(np.asarray(t_to) < np.asarray(t_from)):
        raise MbodyError("carry: every time to carry to must be at or after its sample's")
    Y = np.empty((K, S))
    lam = np.empty((K, m))
    two_Y, two_out = np.empty((2, S)), np.empty((2, plan.o_info + _core.INFO))
    energy, info = np.empty((2, 3)), np.empty(_core.KR_INFO)
    for k in range(K):
        # the core takes increasing times: at the sample itself, Newton there alone
        t = (np.array([t_from[k], t_to[k]], dtype=float) if t_to[k] > t_from[k]
             else np.array([t_to[k]], dtype=float))
        y = np.array(Y_from[k], dtype=float)
        done = plan.solver.kinematic_run(t, y, unknowns.lam, MAX_NEWTON,
                                         newton_tolerance(model, t), two_Y[:len(t)],
                                         two_out[:len(t)], energy[:len(t)], info)
        if done < len(t):
            _failed(model, float(t[done]), y, info)
        Y[k] = two_Y[len(t) - 1]
        lam[k] = two_out[len(t) - 1, plan.o_lam:plan.o_lam + m]
    if model.dimension == cv.PLANAR:
        keep_planar_angles(Y, model.n)
    return Y, lam


def newton_tolerance(model: Model, t: np.ndarray) -> float:
    """The Newton step below which a sample's positions are closed, over a run at the
    times `t`: `CLOSE_RTOL` of the model's size, or a few rounding units of the largest
    driver's coordinate when that is larger. A driver's angle of many turns (380 rad
    after 6 s at 600 rpm) is known to its rounding, 5.7e-14 rad there, so its law's
    residual q - f(t), and the last step, cannot go below that: a smaller tolerance would
    never be met."""
    tol = CLOSE_RTOL * _size(model)
    d = model.drivers
    if d is None or not len(d.names):
        return tol
    reach = max(float(np.abs(np.asarray(law[0](t), dtype=float)).max(initial=0.0))
                for law in d.laws)
    return max(tol, ROUNDING_UNITS * float(np.finfo(float).eps) * reach)


def _failed(model: Model, t: float, y: np.ndarray, info: np.ndarray) -> None:
    if info[_core.KR_SINGULAR]:
        code = int(info[_core.KR_SINGULAR]) - 1
        raise singular_mass_error(model, code // 6, code % 6)
    if not np.isfinite(y).all():
        raise KinematicsError(f"the position analysis at t = {t:g} s diverged (a value is "
                              "not a number): a driver may be past a dead centre")
    cols = reaction_columns(model, _state(model, y, t))
    size = _size(model)
    scale = np.where(model.reaction_table.is_moment, 1.0, size)
    bad = np.flatnonzero(np.abs(cols.phi) > 1e3 * CLOSE_RTOL * scale)
    if not len(bad):
        bad = np.argsort(-np.abs(cols.phi / scale))[:1]
    raise KinematicsError(_cannot_close(model, t, cols.phi, bad, float(info[_core.KR_STEP])))


def _trajectory(model: Model, t: np.ndarray, Y: np.ndarray, OUT: np.ndarray,
                energy: np.ndarray, plan, info: np.ndarray,
                points: dict[str, tuple[int, np.ndarray]], axes: str, fps: float
                ) -> Trajectory:
    K, n = len(t), model.n
    planar = model.dimension == cv.PLANAR
    x = Y[:, :3 * n].reshape(K, n, 3)
    q = Y[:, 3 * n:7 * n].reshape(K, n, 4)
    v = Y[:, 7 * n:10 * n].reshape(K, n, 3)
    w = Y[:, 10 * n:13 * n].reshape(K, n, 3)
    if planar:  # the Newton steps turn q, not the angle carried beside it
        keep_planar_angles(Y, n)
    m = len(model.reactions)
    lam = OUT[:, plan.o_lam:plan.o_lam + m]
    stats = OUT[:, plan.o_info:]
    labels: tuple[str, ...] = tuple(model.reactions)
    values = lam
    if axes == "world":
        labels, values = world_series(model, t, Y, lam)
    pose = ((x[..., :2], v[..., :2], Y[:, 13 * n:], w[..., 2]) if planar else (x, v, q, w))
    run_info = {
        "integrator": "none (kinematic run: every sample's positions by Newton's method)",
        "t_end": float(t[-1]), "fps": fps,
        "samples": K, "steps": 0, "evaluations": K,
        "newton_steps": int(info[_core.KR_NEWTON]),
        "newton_steps_most": int(info[_core.KR_WORST]),
        "reaction_axes": axes, "kinematic": True,
        "backward_error": float(stats[:, _core.ST_BERR].max(initial=0.0)),
        "redundant": int((stats[:, _core.ST_MU] - stats[:, _core.ST_RANK]).max(initial=0)),
    }
    shapes, colors = appearance(model)
    traj = Trajectory(
        t, *pose, body_names=model.body_names, dimension=model.dimension,
        model_name=model.name, model_file=model.file, reaction_labels=labels,
        reactions=values, info=run_info, mass=np.array(model.mass),
        inertia=np.array(model.J),
        shapes=shapes, colors=colors, gravity=np.array(model.gravity), model_yaml=model_text(model))
    values_set = model_values(model)
    if values_set:  # what Trajectory.model sets again on the text it carries
        run_info["model_values"] = values_set
    traj.series.update(_body_points(x, q, points, model.dimension))
    traj.series.update(driver_series(model, t))
    run_info["drivers"] = driver_facts(model)
    acc6 = np.zeros((K, n, 6))
    acc = OUT[:, :plan.N].reshape(K, n, -1)
    acc6[..., [0, 1, 5] if planar else slice(None)] = acc
    series, balance = energy_balance(model, traj, Y, acc6, lam, energy)
    traj.series.update(series)
    run_info.update(balance)
    run_info["warnings"] = []
    record_peaks(model, traj)
    return traj


def driven_figures(model: Model, traj: Trajectory, Y: np.ndarray, lam: np.ndarray,
                   unknowns) -> None:
    """What a run of a model with drivers adds to `traj` (integrated by `mbody.simulate`:
    a partly driven mechanism): each driver's coordinate, its facts, the energy check
    (`energy_balance`, the accelerations and energy terms at the samples from one call of
    the core) and the peaks, with the warning of samples too sparse for them
    (`record_peaks`: among ``info["warnings"]``). `Y` (K, state size) the samples, `lam`
    (K, m) the reactions."""
    ws = workspace(model)
    t = traj.t
    K, n = len(t), model.n
    plan = ws.solve_plan(unknowns)
    acc = np.empty((K, plan.N))
    energy = np.empty((K, 3))
    plan.solver.energy_samples(t, np.ascontiguousarray(Y), unknowns.lam, acc, energy)
    acc6 = np.zeros((K, n, 6))
    acc6[..., [0, 1, 5] if model.dimension == cv.PLANAR else slice(None)] = \
        acc.reshape(K, n, -1)
    traj.series.update(driver_series(model, t))
    traj.info["drivers"] = driver_facts(model)
    series, balance = energy_balance(model, traj, Y, acc6, lam, energy)
    for key in ("driver_power", "driver_work", "load_power", "load_work"):
        traj.series[key] = series[key]
    traj.info.update({k: v for k, v in balance.items() if k != "energy_initial"})
    record_peaks(model, traj)


def driver_series(model: Model, t: np.ndarray) -> dict[str, np.ndarray]:
    """'driver:<name>' -> (K,) each driver's coordinate at the times t (its law: rad for
    an angle, m for a displacement)."""
    d = model.drivers
    if d is None:
        return {}
    return {f"driver:{name}": np.asarray(law[0](t), dtype=float)
            for name, law in zip(d.names, d.laws, strict=True)}


def driver_facts(model: Model) -> list[dict]:
    """What a saved run says of each driver: name, joint, 'angle' or 'displacement', the
    label of its effort."""
    d = model.drivers
    if d is None:
        return []
    joints = model.joints
    return [{"name": name, "joint": joints[int(j)].name,
             "kind": "angle" if c == "M" else "displacement", "effort": f"{name}.{c}"}
            for name, j, c in zip(d.names, d.joint.tolist(), d.component, strict=True)]


def body_points(model: Model, points: object) -> dict[str, tuple[int, np.ndarray]]:
    """`kinematic_run`'s `points` checked against `model`, before the run: name -> (the
    body's index, (3,) point in its axes from its mass centre, m).

    Raises
    ------
    MbodyError
        A point on no body of the model (with a did-you-mean), or not d finite numbers.
    mbody.errors.MbodyTypeError
        `points` is not a mapping, or an entry neither (body, coordinates) nor text.
    """
    if points is None:
        return {}
    if not isinstance(points, Mapping):
        raise wrong_type("points", POINTS_FORM, points)
    d = model.dimension
    out: dict[str, tuple[int, np.ndarray]] = {}
    for name, entry in points.items():
        where = f"points[{name!r}]"
        if isinstance(entry, str):
            body, coords = body_point(entry, where)
        elif (isinstance(entry, Sequence) and len(entry) == 2 and isinstance(entry[0], str)
              and isinstance(entry[1], Sequence | np.ndarray)
              and not isinstance(entry[1], str)):
            body, coords = entry[0], list(entry[1])
        else:
            raise wrong_type(where, "(body, [x, y(, z)]) or 'body:x,y(,z)'", entry)
        if body not in model.bodies:
            hint = did_you_mean(body, list(model.body_names))
            raise MbodyError(f"point {name!r}: no body {body!r} in this model"
                             + (f"; {hint}" if hint else ""))
        try:
            r = np.array(coords, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            r = np.full(0, np.nan)
        if len(r) != d or not np.isfinite(r).all():
            raise MbodyError(f"point {name!r}: expected {d} finite coordinates in the body's "
                             f"axes, got {list(coords)!r}")
        if np.abs(r).max() > MAX_MAGNITUDE:
            raise MbodyError(f"point {name!r}: expected coordinates of magnitude at most "
                             f"{MAX_MAGNITUDE:g} m, as a model file's, got {list(coords)!r}")
        out[str(name)] = (model.bodies[body].index, np.concatenate((r, np.zeros(3 - d))))
    return out


def body_point(text: str, where: str) -> tuple[str, list[float]]:
    """``"coupler:0.1,0.05"`` -> ``("coupler", [0.1, 0.05])``: a body point as the command
    line's ``--point NAME=BODY:X,Y[,Z]`` writes it after the name; `where` names it in
    messages."""
    body, sep, coords = text.partition(":")
    if not (sep and body.strip()):
        raise MbodyError(f"{where}: expected BODY:X,Y[,Z] (for example coupler:0.1,0.05), "
                         f"got {text!r}")
    try:
        xs = [float(c) for c in coords.split(",")]
    except ValueError:
        raise MbodyError(f"{where}: {coords!r} is not a list of numbers (X,Y or X,Y,Z)"
                         ) from None
    return body.strip(), xs


def _body_points(x: np.ndarray, q: np.ndarray, points: dict[str, tuple[int, np.ndarray]],
                 d: int) -> dict[str, np.ndarray]:
    """'point:<name>' -> (K, d) world positions of the body points `body_points` checked."""
    out: dict[str, np.ndarray] = {}
    for name, (i, r) in points.items():
        R = quat_to_matrix(q[:, i])  # (K, 3, 3)
        out[f"point:{name}"] = (x[:, i] + R @ r)[:, :d]
    return out


def energy_balance(model: Model, traj: Trajectory, Y: np.ndarray, acc6: np.ndarray,
                   lam: np.ndarray, energy: np.ndarray) -> tuple[dict[str, np.ndarray], dict]:
    """The drivers' work against the energy (module doc): series 'kinetic_energy',
    'potential_energy', 'energy', 'driver_power', 'load_power', 'driver_work',
    'load_work' (K,); the run's totals; and the power balance at every sample,
    P_drivers + P_loads = d(T + V)/dt with dT/dt = Σ m v·a + ωᵀ J ω̇ (body axes) and
    dV/dt = −Σ m g·v + Σ k (L − L0) L′ from the solved accelerations (`acc6`, (K, n, 6):
    a_G world, ω̇ body axes): its largest relative residual.

    A mechanism that does not move (a driver at 0 rpm) has every power zero: what is
    computed is rounding of velocities of 1e-29 m/s, and its ratio to the largest of them
    says nothing. When no body moves over the run by more than the position analysis
    resolves (`CLOSE_RTOL` of the model's size, or rad), ``at_rest`` is True and both
    residuals are 0: the balance holds trivially.

    `energy` (K, 3) is the core's per sample: Q · v (every load on the bodies at their mass
    centres, gravity and springs included), the springs' elastic energy and its rate. The
    applied loads' power is Q · v less gravity's, Σ m g · v, and the springs' elastic
    part: what is not in V (forces, couples, dampers)."""
    t = traj.t
    K, n = len(t), model.n
    T = traj.kinetic_energy()
    mass = np.asarray(model.mass, dtype=float)
    g = np.asarray(model.gravity, dtype=float)
    J = np.asarray(model.J, dtype=float)
    d = model.drivers
    k = len(d.names) if d is not None else 0
    rates = (np.stack([law[1](t) for law in d.laws], axis=1)  # f′(t), (K, k)
             if k and d is not None else np.zeros((K, 0)))
    P_drive = (lam[:, lam.shape[1] - k:] * rates).sum(axis=1) if k else np.zeros(K)
    x = Y[:, :3 * n].reshape(K, n, 3)
    v = Y[:, 7 * n:10 * n].reshape(K, n, 3)
    w = Y[:, 10 * n:13 * n].reshape(K, n, 3)
    gravity_power = (v @ g) @ mass  # (K,) Σ m g · v
    V = -(x @ g) @ mass + energy[:, 1]
    dV = -gravity_power + energy[:, 2]
    P_loads = energy[:, 0] - gravity_power + energy[:, 2]
    Jw_dot = (J[None] @ acc6[..., 3:, None])[..., 0]
    dT = (mass * (v * acc6[..., :3]).sum(axis=2)).sum(axis=1) + (w * Jw_dot).sum(axis=(1, 2))
    dE = dT + dV
    power = max(float(np.abs(P_drive).max(initial=0.0)),
                float(np.abs(P_loads).max(initial=0.0)), float(np.abs(dE).max(initial=0.0)),
                1e-300)
    power_residual = float(np.abs(P_drive + P_loads - dE).max(initial=0.0)) / power
    span = float(t[-1] - t[0]) if K > 1 else math.inf  # one sample: at rest only if still
    at_rest = (float(np.abs(v).max(initial=0.0)) * span <= CLOSE_RTOL * _size(model)
               and float(np.abs(w).max(initial=0.0)) * span <= CLOSE_RTOL)
    W_drive = _cumulative(P_drive, t)
    W_loads = _cumulative(P_loads, t)
    E = T + V
    residual = W_drive[-1] + W_loads[-1] - (E[-1] - E[0])
    scale = max(float(np.abs(W_drive).max(initial=0.0)),
                float(np.abs(W_loads).max(initial=0.0)),
                float(np.abs(E - E[0]).max(initial=0.0)), 1e-300)
    series = {"kinetic_energy": T, "potential_energy": V, "energy": E,
              "driver_power": P_drive, "driver_work": W_drive, "load_power": P_loads,
              "load_work": W_loads}
    return series, {
        "driver_work": float(W_drive[-1]), "load_work": float(W_loads[-1]),
        "energy_change": float(E[-1] - E[0]),
        "energy_balance_residual": 0.0 if at_rest else float(abs(residual) / scale),
        "power_balance_residual": 0.0 if at_rest else power_residual,
        "at_rest": at_rest,
        "energy_initial": float(E[0]),
    }


def _cumulative(f: np.ndarray, t: np.ndarray) -> np.ndarray:
    """∫ f dt from t[0] to each sample. On equal steps h each interval is the integral of
    the cubic through its two samples and their outer neighbours,
    h (−f₋₁ + 13 f₀ + 13 f₁ − f₂) / 24 (error O(h⁵) an interval), the first and last by
    the quadratic through three samples, h (5 f₀ + 8 f₁ − f₂) / 12; unequal steps (a last
    sample clamped to t_end) by trapezoids."""
    K = len(t)
    out = np.zeros(K)
    if K < 2:
        return out
    h = np.diff(t)
    if K < 4 or np.ptp(h) > 1e-9 * h[0]:
        out[1:] = np.cumsum(0.5 * (f[1:] + f[:-1]) * h)
        return out
    step = float(h.mean())
    part = np.empty(K - 1)
    part[1:-1] = (-f[:-3] + 13.0 * f[1:-2] + 13.0 * f[2:-1] - f[3:]) * (step / 24.0)
    part[0] = (5.0 * f[0] + 8.0 * f[1] - f[2]) * (step / 12.0)
    part[-1] = (5.0 * f[-1] + 8.0 * f[-2] - f[-3]) * (step / 12.0)
    out[1:] = np.cumsum(part)
    return out


def revolution(model: Model) -> float | None:
    """The time of one revolution (s) of the first driver when it turns at a constant rate
    (a `speed` driver, or an angle law of constant slope), else None."""
    d = model.drivers
    if d is None or not len(d.names) or d.component[0] != "M":
        return None
    w = steady_rate(d.laws[0][1], np.array([0.0, 0.37, 1.1, 7.3]))
    return None if w is None else 2.0 * math.pi / abs(w)


SAMPLES_A_TURN = 360
"""A run's default samples a revolution of a first driver turning at a constant rate: one
a degree (its peaks then read within 0.004 % of a sine's: `mbody.simulate.peaks`)."""
DEFAULT_SPAN, DEFAULT_FPS = 1.0, 100.0
"""A run's default span (s) and samples per second when no driver turns at a constant
rate."""


def default_fps(turn: float | None) -> float:
    """A kinematic run's samples a second by default: `SAMPLES_A_TURN` a revolution of the
    first driver when it turns at a constant rate, a revolution `turn` s long
    (`revolution`), else `DEFAULT_FPS`. What ``mbody kinematics`` takes without --fps
    (`default_sampling`), and a sweep's ``--run kinematics`` without --steps, for each
    case at its own rate."""
    return SAMPLES_A_TURN / turn if turn else DEFAULT_FPS


def default_sampling(model: Model) -> tuple[float, float]:
    """(span, fps): what a kinematic run of `model` covers by default (`mbody kinematics`
    without --t-end and --fps, `kinematic_at` without a run): one revolution of the first
    driver at `SAMPLES_A_TURN` samples when it turns at a constant rate, else
    `DEFAULT_SPAN` at `DEFAULT_FPS` (`default_fps`)."""
    turn = revolution(model)
    return (turn or DEFAULT_SPAN, default_fps(turn))


def summary(traj: Trajectory, path: str | None = None) -> str:
    """A kinematic run in a few lines: the samples, Newton's work, each reaction's and
    effort's peak (with the first driver's coordinate then), and the energy check."""
    i = traj.info
    lines = [f"kinematic run of {traj.model_name!r}: {i['samples']} samples, t = "
             f"{float(traj.t[0]):g} .. {i['t_end']:g} s"
             + (f" at {i['fps']:g} per second" if i["fps"] else "")
             + f"; {i['newton_steps']} Newton steps (at most {i['newton_steps_most']} at a "
             f"sample); largest relative backward error {i['backward_error']:.1e}"]
    if i.get("redundant"):
        lines.append(f"warning: {i['redundant']} redundant constraint(s): the reactions they "
                     "share are the minimum-norm ones")
    lines += driven_lines(traj)
    lines.extend(f"warning: {w}" for w in i.get("warnings", ()))
    if path:
        lines.append(f"saved {path}")
    return "\n".join(lines)


def driven_lines(traj: Trajectory) -> list[str]:
    """The peaks table and the energy check of a run with drivers (none without)."""
    i = traj.info
    lines: list[str] = []
    peaks = i.get("peaks") or []
    if peaks:
        drv = peaks[0].get("driver")
        axes = ("world axes" if i.get("reaction_axes") == "world" else
                "joint-frame components")
        lines.append(f"peaks over the run (largest magnitude; {axes}"
                     + (f"; {drv}'s coordinate at that time" if drv else "") + "):")
        big = max(abs(p["value"]) for p in peaks)
        rows = [[p["label"], f"0 {p['unit']}", "throughout"] + ([""] if drv else [])
                if _shown(p["value"], big) == "0" else
                [p["label"], f"{p['value']:.6g} {p['unit']}", f"t = {p['t']:.6g} s"]
                + ([f"{drv} = {p['driver_value']:.6g} {p['driver_unit']}"] if drv else [])
                for p in peaks]
        widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
        lines += ["  " + "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip()
                  for r in rows]
    if "driver_work" not in i:
        return lines
    if i.get("at_rest"):
        lines.append(f"energy check: every power is zero (no body moves by more than "
                     f"{CLOSE_RTOL:g} of the mechanism's size over the run), so the drivers' "
                     "power plus the applied loads' equals d(T + V)/dt trivially, and so "
                     "does their work")
        return lines
    work = max(abs(i["driver_work"]), abs(i["load_work"]), abs(i["energy_change"]))
    lines.append(f"energy check: the drivers' power plus the applied loads' equals "
                 f"d(T + V)/dt at every sample to {i['power_balance_residual']:.1e} of the "
                 f"largest power; over the run the drivers' work "
                 f"{_shown(i['driver_work'], work)} J + "
                 f"the loads' {_shown(i['load_work'], work)} J = the change of T + V "
                 f"{_shown(i['energy_change'], work)} J to "
                 f"{i['energy_balance_residual']:.1e} "
                 "(cubic quadrature over the samples)")
    return lines


def _shown(x: float, scale: float) -> str:
    """x to 6 significant digits, 0 when it is rounding beside `scale` (below 1e-12 of
    it): the figure then reads the same on every machine."""
    return "0" if abs(x) <= 1e-12 * scale else f"{x:.6g}"
