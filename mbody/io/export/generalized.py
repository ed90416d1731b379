"""The equations in generalized coordinates exported with their labels: npz, .mat, JSON.

    write_generalized(asm.generalized(), "lagrange.npz")    # or .mat, .json

What every format holds (the same names): ``coordinates`` (labels of q, the rows and
columns of M, the rows of f), ``units``, ``quasi`` (1 for a quasi-velocity), ``q``,
``qdot``, ``M``, ``f``, ``body_coordinates`` (the rows of T, v_e and a0: the stacked
equations' coordinates), ``T``, ``v_e``, ``a0`` (v = T q' + v_e, v' = T q'' + a0),
``efforts`` and ``effort_rows`` (a chosen driver's effort and the coordinate it acts on),
``held`` (the reaction components held as constraints), ``model``, ``model_file``, ``t``,
``equation`` ("M q'' = f (+ efforts on their rows)"). Written atomically.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody.errors import MbodyError
from mbody.io.export.assembly import MORE, text_array
from mbody.io.export.mat import checked
from mbody.util import jsontext
from mbody.util.atomic import atomic_path
from mbody.util.npzfile import NpzArchive, read_text

if TYPE_CHECKING:
    from mbody.equations.generalized import Generalized

SUFFIXES = (".npz", ".mat", ".json")
EQUATION = "M q'' = f + efforts (each effort on its row); v = T q' + v_e; v' = T q'' + a0"


def generalized_data(g: Generalized) -> dict[str, Any]:
    """The export's fields (module doc) as Python and numpy values."""
    cs = g.coordinate_set
    efforts = list(g.efforts)
    rows = [cs.labels.index(c) for c in g.efforts.values()]
    held = [r for r, h in zip(g.model.reactions, cs.held.mask, strict=True) if h]
    return {
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
    every declared size checked before anything is inflated, nesting bounded."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        with NpzArchive(path, "export file", max_bytes=max_bytes, more=MORE,
                        damage="not a readable mbody export") as z:
            out: dict[str, Any] = {k: z.read(k) for k in z.files}
        for k in _TEXT:
            out[k] = [str(x) for x in out[k]]
        for k in ("model", "model_file", "equation"):
            out[k] = str(out[k])
        out["t"] = float(out["t"])
        return out
    if suffix == ".mat":
        import scipy.io  # slow to import: only for .mat files

        raw = scipy.io.loadmat(checked(path, max_bytes), simplify_cells=True)
        out = {k: v for k, v in raw.items() if not k.startswith("__")}
        for k in _TEXT:
            v = out.get(k, [])
            out[k] = [str(v)] if isinstance(v, str) else [str(x) for x in np.atleast_1d(v)]
        out["effort_rows"] = (np.atleast_1d(out["effort_rows"]) - 1).astype(int).tolist()
        return out
    doc = jsontext.loads(read_text(path, max_bytes, MORE))
    for k in ("q", "qdot", "M", "f", "T", "v_e", "a0"):
        doc[k] = np.asarray(doc[k], float)
    return doc
