"""What to animate: a (trajectory, model) pair from a Trajectory, a Model or a file."""

from __future__ import annotations

import os
from pathlib import Path

import mbody
from mbody.errors import MbodyError, option_name
from mbody.loading import load as load_model
from mbody.model.model import Model
from mbody.simulate.trajectory import Trajectory

Source = Trajectory | Model | str | os.PathLike[str]
"""What `resolve` (and `mbody.animate`) accept."""


def resolve(source: Source, model: Model | str | os.PathLike[str] | None = None, *,
            t_end: float | None = None, fps: float | None = None
            ) -> tuple[Trajectory, Model]:
    """(trajectory, model) from a Trajectory, a Model, or a path to a model or run file.

    A model is simulated first (`mbody.simulate` with its defaults unless `t_end`/`fps`
    are given); a trajectory's model comes from `model`, else from the file it names.

    Parameters
    ----------
    source : Trajectory, Model or path
        The motion, a model to simulate, or a model (.yaml) or run (.npz) file.
    model : Model or path, optional
        The model of a trajectory (default: the one a run file carries or names).
    t_end, fps : float, optional
        Passed to `mbody.simulate` when `source` is a model.

    Returns
    -------
    (Trajectory, Model)
        The motion and the model it was computed from.
    """
    if isinstance(model, str | os.PathLike):
        model = load_model(model)
    if isinstance(source, str | os.PathLike):
        path = Path(source)
        if not path.is_file():
            raise MbodyError(f"{path}: no such file")
        if is_run_file(path):
            source = _load_trajectory(path)
            if model is None:
                model = _model_of(source, path)
        else:
            source = load_model(path)
    if isinstance(source, Model):
        model = source
        source = _simulate(source, t_end, fps)
    if not isinstance(source, Trajectory):
        raise MbodyError(f"cannot animate a {type(source).__name__}: give a Trajectory, a "
                         "Model, or the path of a model (.yaml) or run (.npz) file")
    if model is None:
        raise MbodyError("give the model the trajectory was computed from (model=...)")
    return source, model


def is_run_file(path: str | os.PathLike[str]) -> bool:
    """Whether the file at `path` is a run (.npz: a zip archive, whatever its name)
    rather than a model."""
    with open(path, "rb") as fh:
        return fh.read(4) == b"PK\x03\x04" or Path(path).suffix.lower() == ".npz"


def _load_trajectory(path: Path) -> Trajectory:
    return Trajectory.load(path)  # TrajectoryFileError (an MbodyError) names the problem


def _model_of(traj: Trajectory, path: Path) -> Model:
    """The run's model: from the YAML text it carries, else from the file it names. The
    run may come from someone else: a file it names that is not a model is refused
    without a word of its content (the model reader would quote the text it stumbles
    on, the first line of any file the run names)."""

    if getattr(traj, "model_yaml", ""):
        return traj.model()  # StoredModelError names the run, not the file it names
    if not traj.model_file:
        raise MbodyError(f"{path} does not say which model it came from: pass {_model()}")
    for where in (Path(traj.model_file), path.parent / traj.model_file):
        if where.is_file():
            try:
                return load_model(where)
            except MbodyError:
                raise MbodyError(
                    f"{path} carries no model text, and the file it names as its model, "
                    f"{str(where)!r}, is not a model mbody reads ('mbody check {where}' "
                    f"says why): pass {_model()}") from None
    raise MbodyError(f"{path} was computed from {traj.model_file}, which is not found: "
                     f"pass {_model()}")


def _model() -> str:
    """The argument that gives a run's model, as the caller names it."""
    return option_name("model", "mbody.load(path)", "MODEL")


def _simulate(model: Model, t_end: float | None, fps: float | None) -> Trajectory:

    sim = getattr(mbody, "simulate", None)
    if sim is None:
        raise MbodyError("this mbody cannot simulate yet: animate a saved trajectory")
    kw = {k: v for k, v in (("t_end", t_end), ("fps", fps)) if v is not None}
    return sim(model, **kw)
