"""The state to export when it comes from a simulation: a stored trajectory sample, never
an interpolation between two."""

from __future__ import annotations

import os

from mbody.equations.assemble import Assembly, assemble
from mbody.errors import MbodyError, wrong_type
from mbody.model.model import Model, State
from mbody.simulate.trajectory import Trajectory


def state_at(traj: Trajectory, time: float | None) -> tuple[State, int]:
    """The trajectory's sample nearest to `time` (default: its last sample) and its index.

    No interpolation: a stored sample is a state the integrator produced, so it satisfies
    the equations and constraints as well as the run did (`Trajectory.state_at`). Raises
    `MbodyError` when `time` lies outside the trajectory's time span.
    """
    if time is None:
        k = traj.need_samples() - 1
    else:
        k = traj.nearest_sample(time)
    return traj.state(k), k


def assembly_from_trajectory(model: Model, run: Trajectory | str | os.PathLike[str],
                             time: float | None = None) -> tuple[Assembly, str]:
    """Assemble `model` at the sample of a run nearest to `time` (default: its last).

    Parameters
    ----------
    model : Model
        The model the run was made of.
    run : Trajectory, str or path
        The run: a `Trajectory` (`mbody.simulate`, `mbody.kinematic_run`) or its ``.npz``
        file (``mbody simulate -o``, `Trajectory.save`).
    time : float, optional
        The time (s) whose nearest sample is taken; default the last sample. A time
        outside the run's span is refused.

    Returns
    -------
    (Assembly, str)
        The assembly at that sample, and where its state came from (the run, the
        sample's index and time), as an export's ``state_source`` records it.
    """
    if isinstance(run, Trajectory):
        traj, where = run, f"the run of {run.model_name or 'a model'!r}"
    elif isinstance(run, str | os.PathLike):
        traj, where = Trajectory.load(run), f"trajectory {run}"
    else:
        raise wrong_type("run", "a Trajectory or the path of its .npz file", run)
    if tuple(traj.body_names) != tuple(model.body_names) or traj.dimension != model.dimension:
        raise MbodyError(f"{where}: this trajectory is of another model (bodies "
                         f"{', '.join(list(traj.body_names)[:5])}..., dimension "
                         f"{traj.dimension}); the model has {', '.join(model.body_names[:5])}"
                         f"..., dimension {model.dimension}")
    state, k = state_at(traj, time)
    asked = "last sample" if time is None else f"nearest to t = {time:g} s"
    src = f"{where}, sample {k} at t = {float(traj.t[k]):.10g} s ({asked})"
    return assemble(model, state), src

