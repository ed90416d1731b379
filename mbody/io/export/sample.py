"""The state to export when it comes from a simulation: a stored trajectory sample, never
an interpolation between two."""

from __future__ import annotations

import os

import numpy as np

from mbody.equations.assemble import Assembly, assemble
from mbody.errors import MbodyError
from mbody.model.model import Model, State
from mbody.simulate.trajectory import Trajectory


def state_at(traj: Trajectory, time: float | None) -> tuple[State, int]:
    """The trajectory's sample nearest to `time` (default: its last sample) and its index.

    No interpolation: a stored sample is a state the integrator produced, so it satisfies
    the equations and constraints as well as the run did. Raises `MbodyError` when `time`
    lies outside the trajectory's time span.
    """
    t = np.asarray(traj.t, dtype=float)
    if len(t) == 0:
        raise MbodyError("the trajectory holds no samples")
    if time is None:
        k = len(t) - 1
    else:
        span = max(abs(t[-1]), abs(t[0]), 1.0) * 1e-9
        if not (t[0] - span <= time <= t[-1] + span):
            raise MbodyError(f"time {time:g} s is outside the trajectory's span "
                             f"[{t[0]:g}, {t[-1]:g}] s")
        k = int(np.argmin(np.abs(t - time)))
    return traj.state(k), k


def assembly_from_trajectory(model: Model, path: str | os.PathLike[str],
                             time: float | None = None) -> tuple[Assembly, str]:
    """Assemble `model` at the sample of the trajectory file `path` nearest to `time`."""

    traj = Trajectory.load(path)
    if tuple(traj.body_names) != tuple(model.body_names) or traj.dimension != model.dimension:
        raise MbodyError(f"{path}: this trajectory is of another model (bodies "
                         f"{', '.join(list(traj.body_names)[:5])}..., dimension "
                         f"{traj.dimension}); the model has {', '.join(model.body_names[:5])}"
                         f"..., dimension {model.dimension}")
    state, k = state_at(traj, time)
    asked = "last sample" if time is None else f"nearest to t = {time:g} s"
    src = f"trajectory {path}, sample {k} at t = {float(traj.t[k]):.10g} s ({asked})"
    return assemble(model, state), src

