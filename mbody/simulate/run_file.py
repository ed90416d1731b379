"""A run's file: what `Trajectory.save` writes and `Trajectory.load` reads, one ``.npz``
archive (format tag `FORMAT`, version `FORMAT_VERSION`) of the trajectory's arrays, its
texts and its facts as JSON. Reading checks it as input that may be hostile (a run from
someone else): what the archive holds is checked before anything is inflated
(`mbody.util.npzfile`), and every value a reader relies on before it is returned.

Kept apart from `mbody.simulate.trajectory`, which every run imports: a run needs none of
this, and a fresh process's first simulate pays for every module it imports (issue 24).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody import conventions as cv
from mbody.errors import AT_LEAST_ONE_SAMPLE, TrajectoryFileError
from mbody.util import jsontext
from mbody.util.atomic import atomic_path
from mbody.util.budget import checked_max_bytes
from mbody.util.formatting import size_text
from mbody.util.npzfile import Member, NpzArchive

if TYPE_CHECKING:
    from mbody.simulate.trajectory import Trajectory

FORMAT = "mbody-trajectory"
FORMAT_VERSION = 1
"""Version of the .npz layout; `load` refuses files written by a newer layout."""
NAME_BYTES = 1024
"""Bytes of the read budget per name a run file may hold (its body names, its reaction
labels): 1 Mi names at the default 1 GiB, more than a model file of the default size has
keys and values (`mbody.model.loader.MAX_NODES`), so more than any such model has bodies
or reaction components. Each name read becomes a Python text of some 60 bytes beyond its
characters (where the file spends 4 bytes a character): the two lists take at most an
eighth of the budget in memory beyond it. ``--max-bytes`` raises both."""

_ARRAYS = ("t", "position", "velocity", "orientation", "angular_velocity", "reactions",
           "mass", "inertia", "gravity")
_TEXTS = ("model_name", "model_file", "model_yaml")
_SERIES = "series/"

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


def write_run(traj: Trajectory, path: str | os.PathLike[str]) -> Path:
    """`traj` into the run file `path` (`Trajectory.save`), atomically: a temporary file
    renamed into place."""
    data: dict[str, Any] = {
        "format": np.array(FORMAT), "version": np.array(FORMAT_VERSION),
        "dimension": np.array(traj.dimension),
        "body_names": np.array(traj.body_names, dtype=str),
        "reaction_labels": np.array(traj.reaction_labels, dtype=str),
        "shapes": np.array(json.dumps(list(traj.shapes))),
        "colors": np.array(json.dumps(list(traj.colors))),
        "info": np.array(json.dumps(_jsonable(traj.info))),
    }
    for k in _ARRAYS:
        v = getattr(traj, k)
        if v is not None:
            data[k] = np.asarray(v, dtype=float)
    for k in _TEXTS:
        data[k] = np.array(getattr(traj, k))
    for k, v in traj.series.items():
        data[_SERIES + k] = np.asarray(v, dtype=float)
    with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **data)
    return Path(path)


def read_run(path: str | os.PathLike[str], max_bytes: int | None) -> dict[str, Any]:
    """The fields of the run in the file `path` (`Trajectory.load`, which documents what is
    refused), every entry checked before it is used; `max_bytes` the most data read,
    inflated (None: the default budget)."""
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
    with NpzArchive(p, "trajectory file", max_bytes=max_bytes, error=TrajectoryFileError,
                    more=_MORE) as z:
        return _fields(z)


def _fields(z: NpzArchive) -> dict[str, Any]:
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


