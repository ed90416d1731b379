"""The equations in generalized coordinates exported with their labels: npz, .mat, JSON.

    write_generalized(asm.generalized(), "lagrange.npz")    # or .mat, .json

What every format holds (the same names): ``coordinates`` (labels of q, the rows and
columns of M, the rows of f), ``units``, ``quasi`` (1 for a quasi-velocity), ``q``,
``qdot``, ``M``, ``f``, ``body_coordinates`` (the rows of T, v_e and a0: the stacked
equations' coordinates), ``T``, ``v_e``, ``a0`` (v = T q' + v_e, v' = T q'' + a0),
``efforts`` and ``effort_rows`` (a chosen driver's effort and the coordinate it acts on),
``held`` (the reaction components held as constraints), ``model``, ``model_file``, ``t``,
``equation`` ("M q'' = f (+ efforts on their rows)"), and the tag ``format``
("mbody-generalized") with its ``version`` (files written before the tag have neither,
and read as before). Written atomically; read back (`read_generalized`) as input that
may be hostile, as `mbody.load_export` reads the other exports.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody.errors import MbodyError
from mbody.io.export.assembly import FORMAT as EXPORT_FORMAT
from mbody.io.export.assembly import (
    GENERALIZED_FORMAT,
    MORE,
    TRAJECTORY_FORMAT,
    text_array,
    unreadable,
)
from mbody.io.export.mat import load as load_mat
from mbody.util import jsontext
from mbody.util.atomic import atomic_path
from mbody.util.budget import checked_max_bytes
from mbody.util.npzfile import NpzArchive, read_text

if TYPE_CHECKING:
    from mbody.equations.generalized import Generalized

SUFFIXES = (".npz", ".mat", ".json")
EQUATION = "M q'' = f + efforts (each effort on its row); v = T q' + v_e; v' = T q'' + a0"
VERSION = 1
"""The layout this mbody writes and reads (tagged ``format``: `GENERALIZED_FORMAT`)."""


def generalized_data(g: Generalized) -> dict[str, Any]:
    """The export's fields (module doc) as Python and numpy values."""
    cs = g.coordinate_set
    efforts = list(g.efforts)
    rows = [cs.labels.index(c) for c in g.efforts.values()]
    held = [r for r, h in zip(g.model.reactions, cs.held.mask, strict=True) if h]
    return {
        "format": GENERALIZED_FORMAT, "version": VERSION,
        "model": g.model.name, "model_file": g.model.file or "", "t": float(g.state.t),
        "equation": EQUATION,
        "coordinates": list(g.coordinates), "units": list(g.units),
        "quasi": [int(x) for x in cs.quasi],
        "q": np.asarray(g.q, float), "qdot": np.asarray(g.qdot, float),
        "M": np.asarray(g.M, float), "f": np.asarray(g.f, float),
        "body_coordinates": list(g.body_coordinates), "T": np.asarray(g.T, float),
        "v_e": np.asarray(g.v_e, float), "a0": np.asarray(g.a0, float),
        "efforts": efforts, "effort_rows": rows, "held": held,
    }


def _cell(values: list[str]) -> np.ndarray:
    """A MATLAB cell column of strings."""
    out = np.empty((len(values), 1), dtype=object)
    for i, v in enumerate(values):
        out[i, 0] = str(v)
    return out


_TEXT = ("coordinates", "units", "body_coordinates", "efforts", "held")


def write_generalized(g: Generalized, path: str | os.PathLike[str]) -> Path:
    """Write the export; the format follows the suffix (.npz, .mat or .json).

    Raises
    ------
    MbodyError
        For another suffix; `mbody.errors.OutputError` when the file cannot be written
        (nothing is left behind).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise MbodyError(f"{path}: unknown export format {path.suffix or '(no suffix)'!r}; "
                         "use a name ending in .npz, .mat or .json")
    data = generalized_data(g)
    with atomic_path(path) as tmp:
        if suffix == ".npz":
            arrays: dict[str, Any] = {k: (text_array(v) if k in _TEXT else np.asarray(v))
                                      for k, v in data.items()}
            with open(tmp, "wb") as fh:
                np.savez_compressed(fh, **arrays)
        elif suffix == ".mat":
            import scipy.io  # slow to import: only for .mat files

            mat = {k: (_cell(v) if k in _TEXT else v) for k, v in data.items()}
            mat["effort_rows"] = np.asarray(data["effort_rows"], float) + 1  # 1-based
            mat["quasi"] = np.asarray(data["quasi"], float)
            scipy.io.savemat(tmp, mat, oned_as="column", do_compression=True)
        else:
            doc = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in data.items()}
            with open(tmp, "w", encoding="utf-8") as fh:
                json.dump(doc, fh, indent=1)
                fh.write("\n")
    return path


def read_generalized(path: str | os.PathLike[str], max_bytes: int | None = None
                     ) -> dict[str, Any]:
    """An export read back: the fields of `generalized_data` (labels as lists of str,
    matrices as arrays; .mat effort rows back to 0-based). Read as `mbody.load_export`
    reads a file, as input that may be hostile: at most `max_bytes` (an npz or .mat
    file's arrays once inflated, default 1 GiB; a JSON file's text, default 32 MiB),
    every declared size checked before anything is inflated, nesting bounded; the format
    tag checked before the fields are read.

    Raises
    ------
    MbodyError
        Naming the file and what is wrong: no such file, another suffix, another kind
        of file (a saved run, an export of the stacked equations), a newer version, a
        missing entry, a damaged file, more than `max_bytes`; a `max_bytes` that is not a
        whole number of bytes, at least 1.
    """
    max_bytes = checked_max_bytes(max_bytes)  # the argument's fault, not the file's
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise MbodyError(f"{path}: not an export of the generalized equations (expected "
                         "a name ending in .npz, .mat or .json)")
    if not path.exists():
        raise MbodyError(f"{path}: no such file")
    with unreadable(path, "export of the generalized equations"):
        if suffix == ".npz":
            out = _read_npz(path, max_bytes)
        elif suffix == ".mat":
            out = _read_mat(path, max_bytes)
        else:
            out = jsontext.loads(read_text(path, max_bytes, MORE))
            if not isinstance(out, dict):
                raise MbodyError(f"{path}: not an export of the generalized equations (a "
                                 f"JSON {type(out).__name__}, expected an object)")
            _check_tag(path, out)
        missing = [k for k in _FIELDS if k not in out]
        if missing:
            raise MbodyError(f"{path}: an export of the generalized equations without "
                             f"{', '.join(map(repr, missing))}")
        for k in _TEXT:
            v = out[k]
            out[k] = [str(v)] if isinstance(v, str) else [str(x) for x in np.atleast_1d(v)]
        for k in ("model", "model_file", "equation"):
            out[k] = str(out[k])
        out["t"] = float(out["t"])
        out["format"] = GENERALIZED_FORMAT  # also for a file written before the tag
        out["version"] = int(np.asarray(out.get("version", VERSION)).ravel()[0])
        for k in _MATRICES:
            out[k] = np.asarray(out[k], float)
        rows = np.asarray(out["effort_rows"], float).ravel() - (1 if suffix == ".mat" else 0)
        out["effort_rows"] = rows.astype(int).tolist()
        return out


_FIELDS = ("coordinates", "units", "quasi", "q", "qdot", "M", "f", "body_coordinates", "T",
           "v_e", "a0", "efforts", "effort_rows", "held", "model", "model_file", "t",
           "equation")
_MATRICES = ("q", "qdot", "M", "f", "T", "v_e", "a0")


def _check_tag(path: Path, data: Any) -> None:
    """Refuse a file that is not an export of the generalized equations (`data`: what it
    holds by name), or a newer one. A file written before the tag has the ``equation``
    entry every version writes."""
    if "format" not in data:
        if "equation" in data:
            return
        raise MbodyError(f"{path}: not an export of the generalized equations (it has no "
                         "'format' entry; mbody lagrange -o writes them)")
    fmt = str(data["format"])
    if fmt == TRAJECTORY_FORMAT:
        raise MbodyError(f"{path}: an mbody trajectory (a run saved by simulate or "
                         "kinematics), not an export of the generalized equations; read it "
                         "with mbody.Trajectory.load(path)")
    if fmt == EXPORT_FORMAT:
        raise MbodyError(f"{path}: an export of the stacked equations (mbody export), not "
                         "of the generalized ones; read it with mbody.load_export(path)")
    if fmt != GENERALIZED_FORMAT:
        raise MbodyError(f"{path}: not an export of the generalized equations (format "
                         f"{fmt!r})")
    version = int(np.asarray(data.get("version", 0)).ravel()[0])
    if version > VERSION:
        raise MbodyError(f"{path}: generalized export version {version} is newer than this "
                         f"mbody reads ({VERSION}); upgrade mbody")


def _read_npz(path: Path, max_bytes: int | None) -> dict[str, Any]:
    """The npz file's entries, its tag read (and checked) before the rest is inflated."""
    with NpzArchive(path, "export file", max_bytes=max_bytes, more=MORE,
                    damage="not a readable mbody export") as z:
        tag = {k: z.read(k) for k in ("format", "version", "equation") if k in z}
        if "format" in tag and (tag["format"].shape != () or tag["format"].dtype.kind != "U"):
            raise z.damaged("'format' is not one text")
        _check_tag(path, tag)
        return {k: z.read(k) for k in z.files}


def _read_mat(path: Path, max_bytes: int | None) -> dict[str, Any]:
    """The .mat file's variables (`mbody.io.export.mat.load`, cells as lists)."""
    out = {k: v for k, v in load_mat(path, max_bytes, simplify_cells=True).items()
           if not k.startswith("__")}
    _check_tag(path, out)
    return out
