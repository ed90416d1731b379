"""`Trajectory`: the motion of every body over time (what `simulate` returns).

Arrays have a leading time axis K and a body axis n, as in the contract (section 6):

    t: (K,) s
    position: (K, n, d) mass centres, world frame, m (d = 2 planar, 3 spatial)
    velocity: (K, n, d) mass-centre velocities, world frame, m/s
    orientation: spatial (K, n, 4) unit quaternions W_R_B, w first; planar (K, n) angles, rad
    angular_velocity: spatial (K, n, 3) body axes, rad/s; planar (K, n), rad/s
    reactions: (K, m) reaction values by `reaction_labels` (empty when none are tracked)

A trajectory carries what is needed to draw and check it without the model file: body
names, masses, inertia tensors (body axes, about the mass centres), shapes and colours,
gravity, and the model's YAML text when it came from a file. `save` writes one ``.npz``
file (format tag ``mbody-trajectory``, version `FORMAT_VERSION`); `Trajectory.load`
reads it back and raises `TrajectoryFileError` for anything else. Every kind of run
samples at t_start + k / fps (`sample_times`, and `last_sample_warning` when the last
sample falls short of t_end).

    T = ½ Σ m vᵀv + ½ Σ ωᵀ J ω          (kinetic energy)
    H = Σ (x × m v + W_R_B J ω)          (angular momentum about the world origin)
"""

from __future__ import annotations

import functools
import json
import math
import numbers
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody import conventions as cv
from mbody.errors import (
    Issue,
    MbodyError,
    ModelError,
    TrajectoryFileError,
    option_name,
    real_number,
    wrong_type,
)
from mbody.loading import loads
from mbody.model.model import State, count
from mbody.model.records import BodyRecords
from mbody.util.budget import checked_max_bytes
from mbody.util.formatting import number, size_text
from mbody.util.frozen import Frozen
from mbody.util.spatial import planar_quat

if TYPE_CHECKING:
    from mbody.util.npzfile import Member, NpzArchive

FORMAT = "mbody-trajectory"
FORMAT_VERSION = 1
"""Version of the .npz layout; `load` refuses files written by a newer layout."""
AT_LEAST_ONE_SAMPLE = "a run holds at least one sample"
"""Why a trajectory without samples is refused (`Trajectory.need_samples`, `load`)."""
NAME_BYTES = 1024
"""Bytes of the read budget per name a run file may hold (its body names, its reaction
labels): 1 Mi names at the default 1 GiB, more than a model file of the default size has
keys and values (`mbody.model.loader.MAX_NODES`), so more than any such model has bodies
or reaction components. Each name read becomes a Python text of some 60 bytes beyond its
characters (where the file spends 4 bytes a character): the two lists take at most an
eighth of the budget in memory beyond it. ``--max-bytes`` raises both."""

MAX_SAMPLES = 10_000_000
"""Samples at most in one run (memory: the states and solves of every sample are kept)."""


def sample_times(t_end: float, fps: float, t_start: float = 0.0) -> np.ndarray:
    """The sample times t_start, t_start + 1/fps, ... up to t_end (a last sample 1e-9 of
    a step short of t_end counts: t_end * fps need not be a whole number in floats)."""
    if not (math.isfinite(t_end) and math.isfinite(fps) and fps > 0 and t_end > t_start):
        raise MbodyError(f"a kinematic run needs t_end > {t_start:g} s and fps > 0, got "
                         f"t_end {t_end!r}, fps {fps!r}")
    steps = (t_end - t_start) * fps + 1e-9  # a float: compared before it is an int
    if not steps + 1 <= MAX_SAMPLES:
        many = number(steps + 1) if math.isfinite(steps) else "more than 1e308"
        raise MbodyError(f"{many} samples ({number(t_end - t_start)} s at {number(fps)} fps) "
                         f"is more than {number(MAX_SAMPLES)}; lower {option_name('fps')} or "
                         f"{option_name('t_end')}")
    return t_start + np.arange(int(math.floor(steps)) + 1) / fps


def last_sample_warning(t_end: float, fps: float, t_start: float = 0.0) -> str | None:
    """The warning of a run whose last sample falls short of `t_end`: the samples are at
    t_start + k / fps, and (t_end - t_start) · fps is not a whole number (to within the
    rounding `sample_times` allows); None when it is, the usual case."""
    span = t_end - t_start
    x = span * fps
    whole = math.floor(x + 1e-9)
    if x - whole <= 1e-9 * max(1.0, x):
        return None
    last = t_start + whole / fps
    return (f"the last sample is at t = {last:.6g} s, short of t_end = {t_end:g} s: samples "
            f"are every 1/fps = {1 / fps:.6g} s, and {'(t_end - t_start)' if t_start else 't_end'}"
            f" * fps = {x:.6g} is not a whole number; for a sample at t_end, use fps = "
            f"{math.ceil(x) / span:.6g} (or a multiple of it) or t_end = "
            f"{t_start + math.ceil(x) / fps:.6g}")


_ARRAYS = ("t", "position", "velocity", "orientation", "angular_velocity", "reactions",
           "mass", "inertia", "gravity")
_TEXTS = ("model_name", "model_file", "model_yaml")
_SERIES = "series/"


class StoredModelError(ModelError):
    """The model text a run carries (`Trajectory.model_yaml`), or a value set on it, is
    not a valid model. The lines are the stored text's, which need not be the model
    file's: the message says whose they are.

    Parameters
    ----------
    issues : sequence of Issue
        Every problem, located in the stored text.
    traj : Trajectory
        The run (its `run_file` and `model_file` are named).
    """

    def __init__(self, issues: Sequence[Issue], traj: Trajectory):
        run = traj.run_file or "the run"
        self.where = f"the model stored in {run}" + (
            f" (the text of {traj.model_file} when the run was made, not the file now)"
            if traj.model_file and not traj.model_file.startswith("<") else "")
        super().__init__(issues)

    def _text(self) -> str:
        lines = [f"{'line ' + str(i.line) + ', column ' + str(i.column) + ': ' if i.line else ''}"
                 f"{i.key + ': ' if i.key else ''}{i.message}" + (f" ({i.hint})" if i.hint else "")
                 for i in self.issues[:self.SHOWN]]
        more = len(self.issues) - self.SHOWN
        if more > 0:
            lines.append(f"... and {more} more")
        return f"{self.where} is not a valid model:\n" + "\n".join(lines)


@dataclass(eq=False, init=False, repr=False)  # __init__ and __repr__ below; Frozen
class Trajectory(Frozen):
    """The motion of every body over time, as `simulate` returns it.

    Arrays have a leading time axis of K samples and a body axis of n bodies (file order);
    d = 2 for a planar model, 3 for a spatial one. ``len(trajectory)`` is K.

    Parameters
    ----------
    t : (K,) array
        Sample times (s).
    position : (K, n, d) array
        Mass centres, world frame (m).
    velocity : (K, n, d) array
        Mass-centre velocities, world frame (m/s).
    orientation : (K, n, 4) or (K, n) array
        Spatial: unit quaternions W_R_B, w first; planar: angles about z (rad), unwrapped.
    angular_velocity : (K, n, 3) or (K, n) array
        Spatial: body axes (rad/s); planar: about z (rad/s).
    body_names : tuple of str
        The bodies' names, in file order.
    dimension : int
        2 (planar) or 3 (spatial).
    model_name : str
        The model's name.
    model_file : str
        The model file's path as given (empty when the model did not come from a file).
    reaction_labels : tuple of str
        Labels of the reaction series in `reactions`.
    reactions : (K, m) array
        Reaction values by `reaction_labels` (N; N m); empty when none are tracked. Each
        component along its joint frame, or, when ``info["reaction_axes"]`` is
        ``"world"``, each joint's force and moment on its child in world axes
        (`mbody.simulate.axes`).
    info : dict
        Run facts: integrator, tolerances, energy/momentum/constraint drift, and under
        ``"warnings"`` what looked wrong.
    mass : (n,) array or None
        Masses (kg).
    inertia : (n, 3, 3) array or None
        Inertia tensors, body axes, about the mass centres (kg m^2).
    shapes : tuple of dict or None
        Each body's `shape` as in the model file (None when not given).
    colors : tuple of str or None
        Each body's colour as in the model file (None when not given).
    gravity : (3,) array
        Gravity, world axes (m/s^2).
    model_yaml : str
        The model file's text (empty when the model did not come from a file).
    series : dict of str to array
        Per-sample quantities computed during the run, e.g. ``'energy'`` (K,),
        ``'potential'`` (K,).
    run_file : str
        The run file this trajectory was read from (`load`); '' for one made by a run or
        in code. Not saved: it says where a message's model text came from.
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    orientation: np.ndarray
    angular_velocity: np.ndarray
    body_names: tuple[str, ...]
    dimension: int
    model_name: str = ""
    model_file: str = ""
    reaction_labels: tuple[str, ...] = ()
    reactions: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    info: dict = field(default_factory=dict)
    mass: np.ndarray | None = None
    inertia: np.ndarray | None = None
    shapes: tuple[dict | None, ...] = ()
    colors: tuple[str | None, ...] = ()
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    model_yaml: str = ""
    series: dict[str, np.ndarray] = field(default_factory=dict)
    run_file: str = ""

    def __init__(self, t: np.ndarray, position: np.ndarray, velocity: np.ndarray,
                 orientation: np.ndarray, angular_velocity: np.ndarray,
                 body_names: tuple[str, ...], dimension: int, model_name: str = "",
                 model_file: str = "", reaction_labels: tuple[str, ...] = (),
                 reactions: np.ndarray | None = None, info: dict | None = None,
                 mass: np.ndarray | None = None, inertia: np.ndarray | None = None,
                 shapes: tuple[dict | None, ...] = (), colors: tuple[str | None, ...] = (),
                 gravity: np.ndarray | None = None, model_yaml: str = "",
                 series: dict[str, np.ndarray] | None = None, run_file: str = "") -> None:
        # The dataclass's own __init__ would be the same (the fields in this order, those
        # left out at their defaults; None: the field's default_factory), but it is
        # compiled from its source when the class is made: 0.3 ms of every process that
        # simulates, where this one is read from the bytecode cache. Frozen: the fields
        # go into __dict__ directly, as object.__setattr__ would put them.
        self.__dict__.update({
            "t": t, "position": position, "velocity": velocity, "orientation": orientation,
            "angular_velocity": angular_velocity, "body_names": body_names,
            "dimension": dimension, "model_name": model_name, "model_file": model_file,
            "reaction_labels": reaction_labels,
            "reactions": np.zeros((0, 0)) if reactions is None else reactions,
            "info": {} if info is None else info, "mass": mass, "inertia": inertia,
            "shapes": shapes, "colors": colors,
            "gravity": np.zeros(3) if gravity is None else gravity,
            "model_yaml": model_yaml, "series": {} if series is None else series,
            "run_file": run_file})

    @property
    def n(self) -> int:
        """The number of bodies."""
        return len(self.body_names)

    def __len__(self) -> int:
        return len(self.t)

    def state(self, k: int) -> State:
        """The `State` (internal spatial form) at sample k.

        Parameters
        ----------
        k : int
            The sample's index (0 .. K - 1; negative counts from the end). A time is
            `state_at`'s.

        Returns
        -------
        State
            Positions, orientations and velocities at ``t[k]``, spatial arrays (planar
            ones in the x-y plane, turning about z).

        Raises
        ------
        IndexError
            `k` outside 0 .. K - 1 (the message gives the range).
        mbody.errors.MbodyTypeError
            `k` is not a whole number (a `TypeError` too; for a float, the message points
            to `state_at`).
        """
        K = len(self.t)
        if isinstance(k, bool) or not isinstance(k, numbers.Integral):
            hint = (f"for the sample nearest a time in seconds, use .state_at({k!r})"
                    if isinstance(k, numbers.Real) and not isinstance(k, bool) else "")
            raise wrong_type("k", f"a sample's index, a whole number 0..{K - 1}", k, hint)
        if not -K <= k < K:
            raise IndexError(f"sample {k} is out of range: the run has {count(K, 'sample')}"
                             + (f", 0..{K - 1} (negative counts from the end)" if K else ""))
        if self.dimension == cv.PLANAR:
            return State.planar(self.position[k], self.orientation[k], self.velocity[k],
                                self.angular_velocity[k], float(self.t[k]))
        return State(self.position[k], self.orientation[k], self.velocity[k],
                     self.angular_velocity[k], float(self.t[k]))

    def need_samples(self) -> int:
        """K, the number of samples, for a reader that draws, exports or sums from them.

        Returns
        -------
        int
            K >= 1.

        Raises
        ------
        mbody.MbodyError
            The trajectory holds no samples: one made in code (`load` refuses a file that
            holds none).
        """
        K = len(self.t)
        if K == 0:
            raise MbodyError(f"the trajectory holds no samples ({AT_LEAST_ONE_SAMPLE})")
        return K

    def nearest_sample(self, time: float) -> int:
        """The index of the sample nearest `time` (s), within the run's span.

        Parameters
        ----------
        time : float
            A time in seconds, between the first and the last sample's.

        Returns
        -------
        int
            The index k of the sample whose ``t[k]`` is nearest (0 .. K - 1).

        Raises
        ------
        mbody.MbodyError
            The run holds no samples, or `time` lies outside [t[0], t[-1]] (by more than
            rounding).
        """
        time = real_number(time, "time", "a time in seconds")
        self.need_samples()
        t = np.asarray(self.t, dtype=float)
        span = max(abs(t[-1]), abs(t[0]), 1.0) * 1e-9
        if not (t[0] - span <= time <= t[-1] + span):
            raise MbodyError(f"time {time:g} s is outside the trajectory's span "
                             f"[{t[0]:g}, {t[-1]:g}] s")
        return int(np.argmin(np.abs(t - time)))

    def state_at(self, time: float) -> State:
        """The `State` at the sample nearest `time` (s): a stored sample, never an
        interpolation between two (it satisfies the equations and joints as well as the
        run did).

        Parameters
        ----------
        time : float
            A time in seconds, between the first and the last sample's.

        Returns
        -------
        State
            ``state(nearest_sample(time))``: its ``t`` says which sample it is.

        Raises
        ------
        mbody.MbodyError
            `time` outside the run's span, or not a number.
        """
        return self.state(self.nearest_sample(time))

    @classmethod
    def from_states(cls, t: np.ndarray, pos3: np.ndarray, quat: np.ndarray, vel3: np.ndarray,
                    omega3: np.ndarray, *, body_names: tuple[str, ...], dimension: int,
                    **kw) -> Trajectory:
        """Build from internal spatial arrays (K, n, 3|4); planar ones are reduced.

        Parameters
        ----------
        t : (K,) array
            Sample times (s).
        pos3 : (K, n, 3) array
            Mass centres, world frame (m).
        quat : (K, n, 4) array
            Unit quaternions W_R_B, w first.
        vel3 : (K, n, 3) array
            Mass-centre velocities, world frame (m/s).
        omega3 : (K, n, 3) array
            Angular velocities, body axes (rad/s).
        body_names : tuple of str
            The bodies' names, in file order.
        dimension : int
            2 (planar: x, y, the angle about z unwrapped over time, ω_z are kept) or 3.
        **kw
            The other fields of `Trajectory` (``reactions``, ``info``, ``mass``...).

        Returns
        -------
        Trajectory
        """
        if dimension == cv.PLANAR:
            ang = 2.0 * np.arctan2(quat[..., 3], quat[..., 0])
            return cls(t, pos3[..., :2], vel3[..., :2], np.unwrap(ang, axis=0),
                       omega3[..., 2], body_names, dimension, **kw)
        return cls(t, pos3, vel3, quat, omega3, body_names, dimension, **kw)

    # -- internal spatial form ---------------------------------------------------------
    def spatial(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The motion as spatial arrays, whatever the model's dimension.

        Returns
        -------
        tuple of 4 arrays
            (position (K, n, 3) world (m), quaternion W_R_B (K, n, 4) w first, velocity
            (K, n, 3) world (m/s), ω (K, n, 3) body axes (rad/s)); planar motion padded
            with z = 0 and turning about z.
        """
        if self.dimension == cv.SPATIAL:
            return self.position, self.orientation, self.velocity, self.angular_velocity
        K, n = self.orientation.shape
        pad = np.zeros((K, n, 1))
        om = np.zeros((K, n, 3))
        om[..., 2] = self.angular_velocity
        return (np.concatenate((self.position, pad), axis=2), planar_quat(self.orientation),
                np.concatenate((self.velocity, pad), axis=2), om)

    def _need_inertia(self) -> tuple[np.ndarray, np.ndarray]:
        if self.mass is None or self.inertia is None:
            raise TrajectoryFileError("this trajectory carries no masses and inertias")
        return self.mass, self.inertia

    # -- mechanics ---------------------------------------------------------------------
    def __repr__(self) -> str:  # the dataclass's would print every array
        t = self.t
        span = f"t = {t[0]:g} .. {t[-1]:g} s" if len(t) else "no samples"
        return (f"<Trajectory of {self.model_name or 'a model'!r}: "
                f"{count(self.n, 'body', 'bodies')}, {count(len(t), 'sample')}, {span}, "
                f"{count(len(self.reaction_labels), 'reaction series', 'reaction series')}; "
                ".state(k), .kinetic_energy(), .save(path)>")

    def _repr_html_(self) -> str:  # notebook display: the run's facts and its plots
        from mbody.present.rich import trajectory_html  # a display hook (tools/check_imports.py)

        return trajectory_html(self)

    def kinetic_energy(self, per_body: bool = False) -> np.ndarray:
        """T = ½ m vᵀv + ½ ωᵀ J ω.

        Parameters
        ----------
        per_body : bool
            Return each body's energy rather than the total.

        Returns
        -------
        (K,) or (K, n) array
            The kinetic energy at every sample (J): total, or per body with `per_body`.

        Raises
        ------
        TrajectoryFileError
            The trajectory carries no masses and inertias.
        """
        m, J = self._need_inertia()
        _, _, v, w = self.spatial()
        T = 0.5 * m * (v * v).sum(axis=2) + 0.5 * (w * body_matvec(J, w)).sum(axis=2)
        return T if per_body else T.sum(axis=1)

    def spin_angular_momentum(self) -> np.ndarray:
        """Σ W_R_B J ω: the bodies' angular momenta about their own mass centres.

        Returns
        -------
        (K, 3) array
            The sum over bodies at every sample, world axes (kg m^2/s).
        """
        m, J = self._need_inertia()
        _, q, _, w = self.spatial()
        return rotate(q, body_matvec(J, w)).sum(axis=1)

    def angular_momentum(self) -> np.ndarray:
        """H = Σ (x × m v + W_R_B J ω): angular momentum about the world origin.

        Returns
        -------
        (K, 3) array
            H at every sample, world axes (kg m^2/s).
        """
        m, _ = self._need_inertia()
        x, _, v, _ = self.spatial()
        orbital = cross(x, m[:, None] * v).sum(axis=1)
        return orbital + self.spin_angular_momentum()

    def model(self):
        """Rebuild the `Model` from the YAML text stored with the run, with the values
        that were set on it (``info["model_values"]``: `Model.with_values`, ``--set``)
        set again: the model the run integrated (as `mbody.loads` reads the text: at its
        assembled pose, with the joint frames taken there).

        Returns
        -------
        Model

        Raises
        ------
        TrajectoryFileError
            The trajectory carries no YAML text (its model was built in code).
        StoredModelError
            The text, or a value set on it, is not a valid model (a `ModelError` whose
            message says that the text is the one stored in the run, not the file).
        """
        if not self.model_yaml:
            raise TrajectoryFileError("this trajectory does not carry its model's YAML text "
                                      "(the model was built in code, not read from a file, "
                                      "a text or a dictionary)")
        try:
            model = loads(self.model_yaml, self.model_file or "<trajectory>")
            for path, value in self.info.get("model_values", ()):
                # one at a time, as set: each setting reads the text again with every value
                # before it, so a later value of a path wins as it did
                model = model.with_values({path: value})
        except ModelError as exc:  # never the file's lines: the file may say otherwise
            raise StoredModelError(exc.issues, self) from None
        return model

    # -- files -------------------------------------------------------------------------
    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write one .npz file atomically (temp file + rename).

        Parameters
        ----------
        path : str or os.PathLike
            The file to write (replaced if it exists).

        Returns
        -------
        pathlib.Path
            `path`.
        """
        data: dict[str, Any] = {
            "format": np.array(FORMAT), "version": np.array(FORMAT_VERSION),
            "dimension": np.array(self.dimension),
            "body_names": np.array(self.body_names, dtype=str),
            "reaction_labels": np.array(self.reaction_labels, dtype=str),
            "shapes": np.array(json.dumps(list(self.shapes))),
            "colors": np.array(json.dumps(list(self.colors))),
            "info": np.array(json.dumps(_jsonable(self.info))),
        }
        for k in _ARRAYS:
            v = getattr(self, k)
            if v is not None:
                data[k] = np.asarray(v, dtype=float)
        for k in _TEXTS:
            data[k] = np.array(getattr(self, k))
        for k, v in self.series.items():
            data[_SERIES + k] = np.asarray(v, dtype=float)
        # imported here, as the reader's and the model writer's modules below: a run
        # needs none of them, and a fresh process's first run pays for every module it
        # imports (issue 24)
        from mbody.util.atomic import atomic_path

        with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, **data)
        return Path(path)

    @classmethod
    def load(cls, path: str | os.PathLike[str], *, max_bytes: int | None = None
             ) -> Trajectory:
        """Read a file written by `save`, checking it as input that may be hostile (a run
        from someone else): what it holds is checked before anything is inflated, and
        every value a reader relies on before it is returned.

        Parameters
        ----------
        path : str or os.PathLike
            A trajectory ``.npz`` file (format ``mbody-trajectory``, version at most
            `FORMAT_VERSION`).
        max_bytes : int, optional
            The most data read, inflated (default `mbody.util.budget.DATA_BYTES`, 1 GiB,
            or the command line's ``--max-bytes``); a file that holds more is refused
            before any of it is inflated.

        Returns
        -------
        Trajectory
            With `run_file` set to `path`.

        Raises
        ------
        TrajectoryFileError
            Names the file and what is wrong: no such file, another format, a newer
            version, missing entries, shapes that disagree, times that are not finite or
            do not increase, states that are not finite, a damaged archive (a header that
            does not fit its size, JSON nested too deeply), more data than `max_bytes`.
        """
        max_bytes = checked_max_bytes(max_bytes)  # the argument's fault, before the file's
        name = str(path)
        p = Path(path)
        if not p.exists():
            raise TrajectoryFileError(f"{name}: no such file")
        if p.is_dir():
            raise TrajectoryFileError(f"{name}: is a directory, expected a trajectory .npz file")
        if not p.is_file():  # opening a pipe would wait for a writer
            raise TrajectoryFileError(f"{name}: not a regular file (a device or a pipe), "
                                      "expected a trajectory .npz file")
        try:
            with open(p, "rb") as fh:
                head = fh.read(4)
        except OSError as exc:
            raise TrajectoryFileError(f"{name}: cannot read the file: {exc.strerror}") from None
        if head != b"PK\x03\x04":
            kind = ("a YAML model file? run 'mbody simulate MODEL -o run.npz' first"
                    if p.suffix in (".yaml", ".yml") else "not a .npz archive")
            raise TrajectoryFileError(f"{name}: not an mbody trajectory file ({kind})")
        from mbody.util.npzfile import NpzArchive

        with NpzArchive(p, "trajectory file", max_bytes=max_bytes, error=TrajectoryFileError,
                        more=_MORE) as z:
            fields = _read_run(z)
        return cls(**fields, run_file=name)

_MORE = "--max-bytes N on the command line, or Trajectory.load(path, max_bytes=N), reads more"
_NEEDED = ("t", "position", "velocity", "orientation", "angular_velocity", "dimension",
           "body_names")
_STATE = ("position", "velocity", "orientation", "angular_velocity")
_NUMBER = "a number"
_TEXT = "a text"
_INFO_KINDS = {
    **dict.fromkeys(("integrator", "angular_momentum_kind", "energy_not_conserved",
                     "momentum_not_conserved", "angular_momentum_not_conserved"), _TEXT),
    **dict.fromkeys(("rtol", "atol", "fps", "t_end", "energy_initial", "energy_drift",
                     "momentum_drift", "angular_momentum_drift"), _NUMBER),
    **dict.fromkeys(("momentum_initial", "angular_momentum_initial"), "3 numbers"),
    "warnings": "a list of texts", "reaction_axes": "'joint' or 'world'",
    "drivers": "a list of drivers, each with a name, joint, kind and effort (texts)",
    "model_values": "a list of [path, value] pairs, each path a text",
}
"""The kind of each ``info`` entry that a reader of runs formats or walks (`plot`, the
notebook's table, `animate`, `in_world_axes`); other entries are kept as they are."""


def _read_run(z: NpzArchive) -> dict[str, Any]:
    """The fields of the run in the archive `z`, every entry checked before it is used:
    the format tag and version, the entries there, the arrays' shapes against each other
    and their kinds (from the headers, before any array is inflated), then their values
    (finite; times increasing) and the JSON entries (bounded nesting, their kinds)."""
    name = z.name
    if "format" not in z:
        raise TrajectoryFileError(
            f"{name}: a .npz archive, but not an mbody trajectory (it has no "
            f"'format' entry; entries: {', '.join(sorted(z.files)[:8])})")
    fmt = _text(z, "format")
    if fmt != FORMAT:
        raise TrajectoryFileError(f"{name}: a '{fmt}' file, not an mbody trajectory "
                                  f"('{FORMAT}')")
    version = _whole(z, "version") if "version" in z else -1
    if version > FORMAT_VERSION or version < 1:
        raise TrajectoryFileError(
            f"{name}: trajectory format version {version}; this mbody reads version "
            f"{FORMAT_VERSION}" + (" (upgrade mbody)" if version > FORMAT_VERSION else ""))
    missing = [k for k in _NEEDED if k not in z]
    if missing:
        raise TrajectoryFileError(f"{name}: incomplete trajectory, missing "
                                  f"{', '.join(missing)}")
    dim = _whole(z, "dimension")
    if dim not in (cv.PLANAR, cv.SPATIAL):
        raise TrajectoryFileError(f"{name}: dimension {dim}, expected 2 or 3")
    body_names = _labels(z, "body_names")
    labels = _labels(z, "reaction_labels") if "reaction_labels" in z else ()
    series = [k for k in z.files if k.startswith(_SERIES)]
    _check_shapes(z, len(body_names), dim, len(labels), series)
    arrays = {k: np.asarray(z.read(k), dtype=float) for k in (*_ARRAYS, *series) if k in z}
    _check_finite(name, arrays, body_names)
    K = len(arrays["t"])
    return {
        "t": arrays["t"], **{k: arrays[k] for k in _STATE}, "body_names": body_names,
        "dimension": dim, "reaction_labels": labels,
        "reactions": arrays.get("reactions", np.zeros((K, 0))),
        "info": _json(z, "info", dict, _info_problem) if "info" in z else {},
        "mass": arrays.get("mass"), "inertia": arrays.get("inertia"),
        "shapes": tuple(_json(z, "shapes", list, _appearance_problem(len(body_names), dict)))
        if "shapes" in z else (),
        "colors": tuple(_json(z, "colors", list, _appearance_problem(len(body_names), str)))
        if "colors" in z else (),
        "gravity": arrays.get("gravity", np.zeros(3)),
        "series": {k[len(_SERIES):]: arrays[k] for k in series},
        **{k: _text(z, k) for k in _TEXTS if k in z},
    }


def _text(z: NpzArchive, key: str) -> str:
    """Entry `key`: one text (a 0-d string array), as `save` writes it."""
    m = z.members[key]
    if m.shape != () or m.dtype.kind != "U":
        raise z.damaged(f"'{key}' holds {_kind(m)}, expected one text")
    return str(z.read(key))


def _whole(z: NpzArchive, key: str) -> int:
    """Entry `key`: one whole number (a 0-d integer array), as `save` writes it."""
    m = z.members[key]
    if m.shape != () or m.dtype.kind not in "iu":
        raise z.damaged(f"'{key}' holds {_kind(m)}, expected one whole number")
    return int(z.read(key))


def _labels(z: NpzArchive, key: str) -> tuple[str, ...]:
    """Entry `key`: a list of names (a 1-d string array), as `save` writes it, of at most
    one name per `NAME_BYTES` of the budget (from its header, before it is read)."""
    m = z.members[key]
    if len(m.shape) != 1 or m.dtype.kind != "U":
        raise z.damaged(f"'{key}' holds {_kind(m)}, expected a list of names")
    most = z.limit // NAME_BYTES
    if m.shape[0] > most:
        raise TrajectoryFileError(
            f"{z.name}: '{key}' holds {m.shape[0]:,} names; at most {most:,} are read, one "
            f"per KiB of the budget of {size_text(z.limit)} ({_MORE})")
    return tuple(z.read(key).tolist())


def _kind(m: Member) -> str:
    """'(61, 1, 2) float64 values': what a member holds, from its header."""
    return f"{m.shape} {m.dtype} values" if m.shape else f"one {m.dtype} value"


def _check_shapes(z: NpzArchive, n: int, dim: int, m: int, series: list[str]) -> None:
    """The arrays' shapes agree with each other and with the names (a file edited by
    hand, cut short, or made to claim more than it holds), and they hold numbers: from
    their headers, before any is inflated."""
    name = z.name
    t = z.members["t"]
    if len(t.shape) != 1:
        raise TrajectoryFileError(f"{name}: 't' has shape {t.shape}, expected (K,): one "
                                  "time per sample")
    K = t.shape[0]
    if K == 0:  # every reader draws, exports or sums from a sample
        raise TrajectoryFileError(f"{name}: damaged trajectory file: 't' holds no samples "
                                  f"({AT_LEAST_ONE_SAMPLE})")
    d = 2 if dim == cv.PLANAR else 3
    want = {"position": (K, n, d), "velocity": (K, n, d),
            "orientation": (K, n) if d == 2 else (K, n, 4),
            "angular_velocity": (K, n) if d == 2 else (K, n, 3),
            "mass": (n,), "inertia": (n, 3, 3), "gravity": (3,)}
    for k, shape in want.items():
        if k in z and z.shape(k) != shape:
            raise TrajectoryFileError(f"{name}: '{k}' has shape {z.shape(k)}, expected "
                                      f"{shape} (K = {K} samples, n = {n} bodies)")
    if "reactions" in z:
        got = z.shape("reactions")
        if got != (K, m) and not (m == 0 and len(got) == 2 and 0 in got):
            raise TrajectoryFileError(f"{name}: 'reactions' has shape {got}, expected "
                                      f"{(K, m)} (K = {K} samples, {m} reaction labels)")
    for k in series:
        got = z.shape(k)
        if not got or got[0] != K or (k == _SERIES + "angular_momentum" and got != (K, 3)):
            expected = "(K, 3)" if k == _SERIES + "angular_momentum" else "(K, ...)"
            raise TrajectoryFileError(f"{name}: '{k}' has shape {got}, expected {expected}: "
                                      f"one value per sample (K = {K} samples)")
    for k in (*_ARRAYS, *series):
        if k in z and z.members[k].dtype.kind not in "fiu":
            raise z.damaged(f"'{k}' holds {_kind(z.members[k])}, expected numbers")


def _check_finite(name: str, arrays: dict[str, np.ndarray], body_names: tuple[str, ...]
                  ) -> None:
    """Times finite and increasing; states, masses, inertias and gravity finite: every
    reader divides by time steps, fits a camera around the positions, sums energies."""
    t = arrays["t"]
    bad = np.flatnonzero(~np.isfinite(t))
    if len(bad):
        raise TrajectoryFileError(f"{name}: damaged trajectory file: 't' holds {t[bad[0]]} at "
                                  f"sample {bad[0]} (a run's times are finite numbers)")
    back = np.flatnonzero(np.diff(t) <= 0)
    if len(back):
        k = int(back[0])
        raise TrajectoryFileError(f"{name}: damaged trajectory file: the times 't' do not "
                                  f"increase: sample {k + 1} is at t = {t[k + 1]:g} s, after "
                                  f"t = {t[k]:g} s at sample {k}")
    for key in (*_STATE, "mass", "inertia", "gravity"):
        a = arrays.get(key)
        if a is None or np.isfinite(a).all():
            continue
        at = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        if key in _STATE:
            where = f"at sample {at[0]} (t = {t[at[0]]:g} s), body {body_names[at[1]]!r}"
        elif key == "gravity":
            where = f"in component {at[0]}"
        else:
            where = f"for body {body_names[at[0]]!r}"
        raise TrajectoryFileError(f"{name}: damaged trajectory file: '{key}' holds {a[at]} "
                                  f"{where} (a run's values are finite numbers)")


def _json(z: NpzArchive, key: str, kind: type, problem: Any) -> Any:
    """Entry `key`: JSON text (nesting bounded: `jsontext.loads`) of a `kind` value that
    `problem(value)` finds nothing wrong with."""
    from mbody.util import jsontext

    try:
        value = jsontext.loads(_text(z, key))
    except ValueError as exc:
        raise z.damaged(f"'{key}' is not JSON that mbody reads: {exc}") from None
    if not isinstance(value, kind):
        raise z.damaged(f"'{key}' holds a JSON {type(value).__name__}, expected "
                        f"{'an object' if kind is dict else 'a list'}")
    wrong = problem(value)
    if wrong:
        raise z.damaged(f"'{key}': {wrong}")
    return value


def _appearance_problem(n: int, kind: type) -> Any:
    """A check of the `shapes` or `colors` list: one entry per body (or none), each null
    or a `kind`."""
    def problem(items: list) -> str:
        if len(items) not in (0, n):
            return f"{len(items)} entries for {n} bodies"
        wrong = [i for i, v in enumerate(items) if v is not None and not isinstance(v, kind)]
        return (f"entry {wrong[0]} is {items[wrong[0]]!r}, expected null or "
                f"{'an object' if kind is dict else 'a text'}") if wrong else ""
    return problem


def _info_problem(info: dict) -> str:
    """What is wrong with the run's `info`: the first entry a reader uses that is not of
    its kind (`_INFO_KINDS`), or ''."""
    def number(v: Any) -> bool:  # JSON's true and false are Python ints, not numbers here
        return isinstance(v, int | float) and not isinstance(v, bool)

    def text_pair(v: Any) -> bool:
        return isinstance(v, list) and len(v) == 2 and isinstance(v[0], str)

    def driver(v: Any) -> bool:
        return isinstance(v, dict) and all(isinstance(v.get(k), str)
                                           for k in ("name", "joint", "kind", "effort"))

    fits = {_TEXT: lambda v: isinstance(v, str), _NUMBER: number,
            "3 numbers": lambda v: isinstance(v, list) and len(v) == 3
            and all(map(number, v)),
            "a list of texts": lambda v: isinstance(v, list)
            and all(isinstance(w, str) for w in v),
            "'joint' or 'world'": lambda v: v in ("joint", "world"),
            _INFO_KINDS["drivers"]: lambda v: isinstance(v, list) and all(map(driver, v)),
            _INFO_KINDS["model_values"]: lambda v: isinstance(v, list)
            and all(map(text_pair, v))}
    for key, kind in _INFO_KINDS.items():
        if key in info and not fits[kind](info[key]):
            return f"its entry {key!r} is {_short(info[key])}, expected {kind}"
    return ""


def _short(value: Any) -> str:
    """A JSON value in at most 60 characters, for a message."""
    text = json.dumps(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    return x


def model_text(model) -> str:
    """The model as mbody YAML text, what a trajectory keeps so that it can be drawn,
    checked and rebuilt (`Trajectory.model`) without the file: the text it was read from
    (a YAML file, or a text given to `loads`; its line ends read as a text file reads them;
    kept even if the file has gone since), the YAML form of its document (a dictionary, an
    MJCF or URDF file: `mbody.model.yaml_write`), or a large file's text as it is now; ''
    for a model built in code. The values set on the model since it was read are not in
    it: `model_values` lists them."""
    source = getattr(model, "source", None)
    if source is not None and source.text is not None:
        # neither read nor looked up again: a read, or even a stat, costs as much as the
        # rest of a short run's bookkeeping
        return _text_lines(source.text)
    if source is not None and source.document is not None:
        from mbody.model.yaml_write import dump_document

        return dump_document(source.document.data, source=source.file)
    if not model.file or model.file.startswith("<"):
        return ""
    p = Path(model.file)
    try:
        return p.read_text(encoding="utf-8") if p.is_file() else ""
    except (OSError, UnicodeDecodeError):
        return ""


def appearance(model) -> tuple[tuple[dict | None, ...], tuple[str | None, ...]]:
    """(shapes, colors): each body's drawing shape and colour as the file gives them (None:
    the default), in body order, what a trajectory keeps to be drawn without the file."""
    if isinstance(model.bodies, BodyRecords):  # a file's model: no record made per body
        return model.bodies.shapes, model.bodies.colors
    bodies = [model.bodies[b] for b in model.body_names]
    return tuple(b.shape for b in bodies), tuple(b.color for b in bodies)


def model_values(model) -> list[list[Any]]:
    """The values set on the model since it was read (`Model.with_values`, ``--set``), in
    order, as [path, value] pairs: what `Trajectory.model` sets again on the kept text
    (``info["model_values"]``)."""
    source = getattr(model, "source", None)
    return [[path, value] for path, value in source.values] if source is not None else []


@functools.lru_cache(maxsize=16)
def _text_lines(text: str) -> str:
    """`text` with its line ends read as a text file reads them (\\r\\n and \\r as \\n),
    worked out once per text: every run of a model keeps it."""
    return text.replace("\r\n", "\n").replace("\r", "\n")


def body_matvec(J: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(K, n, 3) J_i w_ki for each body's (n, 3, 3) tensor J_i (matmul broadcast over K)."""
    return (J @ w[..., None])[..., 0]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b over the last axis, as np.cross gives it, a few times faster on many short
    arrays (np.cross moves axes and checks shapes on every call)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0), axis=-1)


def rotate(q: np.ndarray, u: np.ndarray) -> np.ndarray:
    """W_R_B u for unit quaternions q (..., 4) [w, x, y, z]: u + 2 w (v × u) + 2 v × (v × u),
    v the vector part (the rotation matrix never formed)."""
    v = q[..., 1:]
    c = cross(v, u)
    return u + 2.0 * (q[..., :1] * c + cross(v, c))


def keep_planar_angles(Y: np.ndarray, n: int) -> None:
    """Set the planar angles carried in the packed samples `Y` (K, 14 n: the core's layout,
    θ after [x | q | v | ω]) to their quaternions' own angles, each on the branch of the
    carried angle (which counts the turns a quaternion cannot). The core's projections
    and Newton steps turn q and leave θ where the step put it: the stored angle would
    then break the joints the stored q keeps (by 1e-10 rad over a long run, by most of a
    step when a kinematic run's samples are far apart)."""
    q = Y[:, 3 * n:7 * n].reshape(len(Y), n, 4)
    theta = Y[:, 13 * n:]
    theta += np.remainder(2.0 * np.arctan2(q[..., 3], q[..., 0]) - theta + np.pi,
                          2.0 * np.pi) - np.pi
