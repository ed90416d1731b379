"""The state to export when it comes from a simulation: a stored trajectory sample, never
an interpolation between two."""

from __future__ import annotations

import os

from mbody.equations.assemble import Assembly, assemble
from mbody.errors import MbodyError
from mbody.model.model import Model, State
from mbody.simulate.trajectory import Trajectory


def state_at(traj: Trajectory, time: float | None) -> tuple[State, int]:
    """The trajectory's sample nearest to `time` (default: its last sample) and its index.

    No interpolation: a stored sample is a state the integrator produced, so it satisfies
    the equations and constraints as well as the run did (`Trajectory.state_at`). Raises
    `MbodyError` when `time` lies outside the trajectory's time span.
    """
    if time is None:
        if len(traj.t) == 0:
            raise MbodyError("the trajectory holds no samples")
        k = len(traj.t) - 1
    else:
        k = traj.nearest_sample(time)
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

