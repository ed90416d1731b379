"""A run's reactions in world axes (docs/reactions.md, "In world axes").

A run stores each joint's reaction components along its joint frame, as the solver gives
them, unless it is asked for world axes (``simulate(..., axes="world")``,
``kinematic_run(..., axes="world")``). `mbody.equations.world` sums one state's
components into each joint's force and moment on its child in world x, y, z; here that
is done at every sample of a run: each component's direction at each sampled state from
the compiled core, then the one sum vectorised over the samples. A run saved in joint
axes is converted afterwards with the model it carries (`in_world_axes`).

    traj = simulate(model, 2.0, 100)          # joint-frame components
    world = in_world_axes(traj)               # the same run, reactions in world axes
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from mbody import conventions as cv
from mbody.equations.workspace import workspace
from mbody.equations.world import world_reaction_series
from mbody.errors import MbodyError, TrajectoryFileError
from mbody.model.model import Model
from mbody.simulate.peaks import peaks
from mbody.simulate.trajectory import Trajectory


def reaction_directions(model: Model, t: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """(K, m) x 3: each reaction component's unit direction (world axes) at each sampled
    state, `Y` (K, state size) in the core's layout at the times `t` (K,)."""
    ws = workspace(model)
    m = len(model.reactions)
    K = len(t)
    W_e = np.empty((K, m, 3))
    c6, p6, W_P = np.empty((m, 6)), np.empty((m, 6)), np.empty((m, 3))
    gamma, phi, gtv = np.empty(m), np.empty(m), np.empty(m)
    Y = np.ascontiguousarray(Y, dtype=float)
    for k in range(K):  # one core call a sample: the columns at that state
        ws.core.columns(float(t[k]), Y[k], c6, p6, W_e[k], W_P, gamma, phi, gtv)
    return W_e


def world_series(model: Model, t: np.ndarray, Y: np.ndarray, lam: np.ndarray
                 ) -> tuple[tuple[str, ...], np.ndarray]:
    """The world-axes labels and their values (K, p) at the sampled states `Y` (K, state
    size, the core's layout) at the times `t`, from the joint-frame values `lam` (K, m,
    in ``model.reactions`` order): `mbody.equations.world.world_reaction_series`."""
    return world_reaction_series(model, reaction_directions(model, t, Y),
                                 np.asarray(lam, dtype=float).reshape(len(t), -1))


def sample_states(model: Model, traj: Trajectory) -> np.ndarray:
    """(K, state size) the run's samples in the core's layout [x | q | v | ω | θ (planar)]
    (`mbody.equations.workspace.Workspace.state_vector`, for every sample at once)."""
    x, q, v, w = traj.spatial()
    K, n = len(traj.t), traj.n
    parts = [x.reshape(K, -1), q.reshape(K, -1), v.reshape(K, -1), w.reshape(K, -1)]
    if traj.dimension == cv.PLANAR:
        parts.append(np.asarray(traj.orientation, dtype=float).reshape(K, n))
    Y = np.concatenate(parts, axis=1) if K else np.zeros((0, workspace(model).state_size))
    if Y.shape[1] != workspace(model).state_size:
        raise MbodyError(f"the run's {n} bodies do not fit the model {model.name!r} "
                         f"({model.n} bodies)")
    return Y


def in_world_axes(traj: Trajectory, model: Model | None = None) -> Trajectory:
    """The run with its reactions in world axes: each joint's force and moment on its
    child along world x, y, z at every sample (labels ``<joint>.Fx`` ... as
    ``Assembly.solve(axes="world")`` gives them), the drivers' efforts kept; its peaks
    recomputed. A run already in world axes, or one that stores no reactions, is returned
    as it is.

    Parameters
    ----------
    traj : Trajectory
        A run whose reactions are in joint axes (``info["reaction_axes"]`` "joint" or
        absent: every run saved before world axes existed).
    model : Model, optional
        The run's model (default: the one it carries, `Trajectory.model`).

    Returns
    -------
    Trajectory
        The same run (its arrays shared, not copied) with `reactions` and
        `reaction_labels` in world axes, ``info["reaction_axes"]`` "world".

    Raises
    ------
    MbodyError
        The run does not carry its model and none is given, or its reactions are not the
        model's (another model, or a run whose reactions were not all stored).
    """
    if traj.info.get("reaction_axes", "joint") == "world" or not len(traj.reaction_labels) \
            or np.asarray(traj.reactions).shape[1:] != (len(traj.reaction_labels),):
        return traj
    if model is None:
        again = "run it again with --axes world (axes='world')"
        if Path(traj.model_file).suffix.lower() in (".xml", ".urdf", ".mjcf"):
            raise MbodyError(
                f"the run of {traj.model_name!r} was made from {traj.model_file}, an "
                "imported model: turning its reactions into world axes needs the model "
                "(the joints' directions at each sample), which a run carries for mbody "
                f"YAML files only; {again}, or pass the model (in_world_axes(traj, model))")
        try:
            model = traj.model()
        except TrajectoryFileError:
            raise MbodyError(
                f"the run of {traj.model_name!r} does not carry its model's text, which "
                "turning its reactions into world axes needs (the joints' directions at "
                f"each sample); {again}") from None
    if tuple(model.reactions) != tuple(traj.reaction_labels) or \
            tuple(model.body_names) != tuple(traj.body_names):
        raise MbodyError(f"the run's reactions ({', '.join(traj.reaction_labels[:4])}...) are "
                         f"not those of the model {model.name!r}: give the model the run "
                         "was made from")
    labels, values = world_series(model, traj.t, sample_states(model, traj), traj.reactions)
    info = dict(traj.info)
    info["reaction_axes"] = "world"
    out = dataclasses.replace(traj, reaction_labels=labels, reactions=values, info=info,
                              series=dict(traj.series))
    if "peaks" in info:
        info["peaks"] = peaks(model, out)
    return out
