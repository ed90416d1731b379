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
reads it back and raises `TrajectoryFileError` for anything else.

    T = ½ Σ m vᵀv + ½ Σ ωᵀ J ω          (kinetic energy)
    H = Σ (x × m v + W_R_B J ω)          (angular momentum about the world origin)
"""

from __future__ import annotations

import json
import os
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody.equations.spatial import matvec, planar_quat, quat_to_matrix
from mbody.errors import TrajectoryFileError
from mbody.io.atomic import atomic_path
from mbody.model.model import State, count, loads

FORMAT = "mbody-trajectory"
FORMAT_VERSION = 1
"""Version of the .npz layout; `load` refuses files written by a newer layout."""

_ARRAYS = ("t", "position", "velocity", "orientation", "angular_velocity", "reactions",
           "mass", "inertia", "gravity")
_TEXTS = ("model_name", "model_file", "model_yaml")
_SERIES = "series/"


@dataclass(frozen=True, eq=False)
class Trajectory:
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
    """Run facts: integrator, tolerances, energy/momentum/constraint drift."""
    mass: np.ndarray | None = None
    """(n,) kg."""
    inertia: np.ndarray | None = None
    """(n, 3, 3) inertia tensors, body axes, about the mass centres, kg m^2."""
    shapes: tuple[dict | None, ...] = ()
    """Each body's `shape` as in the model file (None when not given)."""
    colors: tuple[str | None, ...] = ()
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """(3,) world, m/s^2."""
    model_yaml: str = ""
    """The model file's text (empty when the model did not come from a file)."""
    series: dict[str, np.ndarray] = field(default_factory=dict)
    """Per-sample quantities computed during the run, e.g. 'energy' (K,), 'potential' (K,)."""

    @property
    def n(self) -> int:
        return len(self.body_names)

    def __len__(self) -> int:
        return len(self.t)

    def state(self, k: int) -> State:
        """The `State` (internal spatial form) at sample k."""
        if self.dimension == cv.PLANAR:
            return State.planar(self.position[k], self.orientation[k], self.velocity[k],
                                self.angular_velocity[k], float(self.t[k]))
        return State(self.position[k], self.orientation[k], self.velocity[k],
                     self.angular_velocity[k], float(self.t[k]))

    @classmethod
    def from_states(cls, t: np.ndarray, pos3: np.ndarray, quat: np.ndarray, vel3: np.ndarray,
                    omega3: np.ndarray, *, body_names: tuple[str, ...], dimension: int,
                    **kw) -> Trajectory:
        """Build from internal spatial arrays (K, n, 3|4); planar ones are reduced."""
        if dimension == cv.PLANAR:
            ang = 2.0 * np.arctan2(quat[..., 3], quat[..., 0])
            return cls(t, pos3[..., :2], vel3[..., :2], np.unwrap(ang, axis=0),
                       omega3[..., 2], body_names, dimension, **kw)
        return cls(t, pos3, vel3, quat, omega3, body_names, dimension, **kw)

    # -- internal spatial form ---------------------------------------------------------
    def spatial(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(position (K,n,3), quaternion (K,n,4), velocity (K,n,3), ω body (K,n,3))."""
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

    def kinetic_energy(self, per_body: bool = False) -> np.ndarray:
        """T = ½ m vᵀv + ½ ωᵀ J ω: (K,) total, or (K, n) with `per_body`."""
        m, J = self._need_inertia()
        _, _, v, w = self.spatial()
        T = 0.5 * m * np.einsum("kni,kni->kn", v, v) \
            + 0.5 * np.einsum("kni,kni->kn", w, matvec(J, w))
        return T if per_body else T.sum(axis=1)

    def spin_angular_momentum(self) -> np.ndarray:
        """Σ W_R_B J ω: (K, 3) world axes, the bodies' momenta about their mass centres."""
        m, J = self._need_inertia()
        _, q, _, w = self.spatial()
        return matvec(quat_to_matrix(q), matvec(J, w)).sum(axis=1)

    def angular_momentum(self) -> np.ndarray:
        """H = Σ (x × m v + W_R_B J ω): (K, 3) world axes, about the world origin."""
        m, _ = self._need_inertia()
        x, _, v, _ = self.spatial()
        orbital = np.cross(x, m[:, None] * v).sum(axis=1)
        return orbital + self.spin_angular_momentum()

    def model(self):
        """Rebuild the `Model` from the YAML text stored with the run."""

        if not self.model_yaml:
            raise TrajectoryFileError("this trajectory does not carry its model's YAML text "
                                      "(the model did not come from a file)")
        return loads(self.model_yaml, self.model_file or "<trajectory>")

    # -- files -------------------------------------------------------------------------
    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write one .npz file atomically (temp file + rename); returns the path."""

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
        with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, **data)
        return Path(path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Trajectory:
        """Read a file written by `save`; `TrajectoryFileError` names what is wrong."""
        name = str(path)
        p = Path(path)
        if not p.exists():
            raise TrajectoryFileError(f"{name}: no such file")
        if p.is_dir():
            raise TrajectoryFileError(f"{name}: is a directory, expected a trajectory .npz file")
        try:
            with open(p, "rb") as fh:
                head = fh.read(4)
        except OSError as exc:
            raise TrajectoryFileError(f"{name}: cannot read the file: {exc.strerror}") from None
        if head != b"PK\x03\x04":
            kind = ("a YAML model file? run 'mbody simulate MODEL -o run.npz' first"
                    if p.suffix in (".yaml", ".yml") else "not a .npz archive")
            raise TrajectoryFileError(f"{name}: not an mbody trajectory file ({kind})")
        try:
            # Open the file here: np.load leaves its own handle open when the zip is bad.
            with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as z:
                files = set(z.files)
                if "format" not in files:
                    raise TrajectoryFileError(
                        f"{name}: a .npz archive, but not an mbody trajectory (it has no "
                        f"'format' entry; entries: {', '.join(sorted(files)[:8])})")
                fmt = str(z["format"])
                if fmt != FORMAT:
                    raise TrajectoryFileError(f"{name}: a '{fmt}' file, not an mbody "
                                              f"trajectory ('{FORMAT}')")
                version = int(z["version"]) if "version" in files else -1
                if version > FORMAT_VERSION or version < 1:
                    raise TrajectoryFileError(
                        f"{name}: trajectory format version {version}; this mbody reads "
                        f"version {FORMAT_VERSION}" + (" (upgrade mbody)"
                                                       if version > FORMAT_VERSION else ""))
                missing = [k for k in ("t", "position", "velocity", "orientation",
                                       "angular_velocity", "dimension", "body_names")
                           if k not in files]
                if missing:
                    raise TrajectoryFileError(f"{name}: incomplete trajectory, missing "
                                              f"{', '.join(missing)}")
                arrays = {k: z[k] for k in _ARRAYS if k in files}
                texts = {k: str(z[k]) for k in _TEXTS if k in files}
                series = {k[len(_SERIES):]: z[k] for k in files if k.startswith(_SERIES)}
                traj = cls(
                    t=arrays["t"], position=arrays["position"], velocity=arrays["velocity"],
                    orientation=arrays["orientation"],
                    angular_velocity=arrays["angular_velocity"],
                    body_names=tuple(str(s) for s in z["body_names"]),
                    dimension=int(z["dimension"]),
                    reaction_labels=tuple(str(s) for s in z["reaction_labels"])
                    if "reaction_labels" in files else (),
                    reactions=arrays.get("reactions", np.zeros((len(arrays["t"]), 0))),
                    info=json.loads(str(z["info"])) if "info" in files else {},
                    mass=arrays.get("mass"), inertia=arrays.get("inertia"),
                    shapes=tuple(json.loads(str(z["shapes"]))) if "shapes" in files else (),
                    colors=tuple(json.loads(str(z["colors"]))) if "colors" in files else (),
                    gravity=arrays.get("gravity", np.zeros(3)),
                    series=series, **texts)
        except TrajectoryFileError:
            raise
        except (zipfile.BadZipFile, zlib.error, EOFError, ValueError, OSError, KeyError,
                TypeError, json.JSONDecodeError) as exc:
            raise TrajectoryFileError(f"{name}: damaged or truncated trajectory file "
                                      f"({type(exc).__name__}: {exc})") from None
        traj._check(name)
        return traj

    def _check(self, name: str) -> None:
        """Shapes agree with each other (a file edited by hand or cut short)."""
        K, n, dim = len(self.t), self.n, self.dimension
        d = 2 if dim == cv.PLANAR else 3
        want = {"position": (K, n, d), "velocity": (K, n, d),
                "orientation": (K, n) if d == 2 else (K, n, 4),
                "angular_velocity": (K, n) if d == 2 else (K, n, 3)}
        if dim not in (cv.PLANAR, cv.SPATIAL):
            raise TrajectoryFileError(f"{name}: dimension {dim}, expected 2 or 3")
        for k, shape in want.items():
            if getattr(self, k).shape != shape:
                raise TrajectoryFileError(f"{name}: '{k}' has shape {getattr(self, k).shape}, "
                                          f"expected {shape} (K = {K} samples, n = {n} bodies)")
        if self.mass is not None and self.mass.shape != (n,):
            raise TrajectoryFileError(f"{name}: 'mass' has shape {self.mass.shape}, expected "
                                      f"({n},)")
        if self.inertia is not None and self.inertia.shape != (n, 3, 3):
            raise TrajectoryFileError(f"{name}: 'inertia' has shape {self.inertia.shape}, "
                                      f"expected ({n}, 3, 3)")


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
