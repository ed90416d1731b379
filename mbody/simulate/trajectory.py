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
file (format tag ``mbody-trajectory``, version
`mbody.simulate.run_file.FORMAT_VERSION`); `Trajectory.load` reads it back and raises
`TrajectoryFileError` for anything else. Runs sample at t_start + k / fps
(`sample_times`; `last_sample_warning` when the last sample falls short of t_end).

    T = ½ Σ m vᵀv + ½ Σ ωᵀ J ω          (kinetic energy)
    H = Σ (x × m v + W_R_B J ω)          (angular momentum about the world origin)
"""

from __future__ import annotations

import functools
import math
import numbers
import os
from collections.abc import Sequence
from dataclasses import field
from pathlib import Path
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody.errors import (
    AT_LEAST_ONE_SAMPLE,
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
from mbody.util.formatting import number
from mbody.util.frozen import Frozen, dataclass_on_first_look
from mbody.util.spatial import planar_quat

MAX_SAMPLES = 10_000_000
"""Samples at most in one run (memory: the states and solves of every sample are kept)."""


def sample_times(t_end: float, fps: float, t_start: float = 0.0) -> np.ndarray:
    """The sample times t_start, t_start + 1/fps, ... up to t_end (a last sample 1e-9 of
    a step short of t_end counts: t_end * fps need not be a whole number in floats)."""
    if not (math.isfinite(t_end) and math.isfinite(fps) and fps > 0 and t_end > t_start):
        raise MbodyError(f"a run needs t_end > {t_start:g} s and fps > 0, got "
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


@dataclass_on_first_look(eq=False, init=False, repr=False)  # __init__ and __repr__ below; Frozen
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
        from mbody.simulate.run_file import write_run  # deferred: only saving needs it

        return write_run(self, path)

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
            `mbody.simulate.run_file.FORMAT_VERSION`).
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
        from mbody.simulate.run_file import read_run  # deferred: only loading needs it

        return cls(**read_run(path, max_bytes), run_file=str(path))


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
