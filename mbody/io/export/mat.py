"""The MATLAB .mat export: the `flat_arrays` names, M and G (and the world-axes map T when
asked for) as MATLAB sparse matrices, vectors as columns (``M*vdot + b``), label lists as
cell columns and the conventions also as a struct. scipy.io is imported when a .mat file
is written or read, not before: it is slow to import and most runs never touch MATLAB
files."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from mbody.io.export.assembly import COLUMN_TEXT, ExportedAssembly, build, flat_arrays


def _cell(values: Iterable[Any]) -> np.ndarray:
    """A MATLAB cell column of strings (an n x 1 cellstr).

    MATLAB and Octave index it with ``strcmp(S.coordinates, 'rod.x')``;
    ``scipy.io.loadmat(path, simplify_cells=True)`` returns it as an array of str (a list
    of one label squeezed to that str), plain ``loadmat`` as nested 1 x 1 arrays. A char
    matrix would pad its rows with spaces in every reader, so labels stay cells.
    """
    items = [str(v) for v in values]
    out = np.empty((len(items), 1), dtype=object)
    for i, v in enumerate(items):
        out[i, 0] = v
    return out


def write(exp: ExportedAssembly, path: Path) -> None:
    """Write `exp` to `path` as a compressed MATLAB 5 file (not atomic by itself).

    Parameters
    ----------
    exp
        The export to write.
    path
        The file to write; scipy would add ``.mat`` to a name without it.
    """
    import scipy.io

    arrs = flat_arrays(exp)
    for k in ("coordinates", "reactions", "body_names", "world_reactions",
              *(f"column_{k}" for k in COLUMN_TEXT[1:])):
        if k in arrs:
            arrs[k] = _cell(arrs[k])
    arrs["M"], arrs["G"] = exp.M, exp.G
    if exp.T is not None:  # world = T * lambda
        arrs["T"] = exp.T
    # The conventions also as a MATLAB struct (lists as cells) for people reading it there.
    arrs["conventions"] = {k: (_cell(v) if isinstance(v, list) else v)
                           for k, v in exp.conventions.items()}
    scipy.io.savemat(path, arrs, oned_as="column", do_compression=True)


def read(path: Path) -> ExportedAssembly:
    """The `ExportedAssembly` stored in the .mat file `path`."""
    import scipy.io

    data = scipy.io.loadmat(path, simplify_cells=False)

    def unstr(v: Any) -> str:
        v = np.asarray(v)
        return str(v.ravel()[0]) if v.size else ""

    def get(k: str) -> Any:
        v = data[k]
        if isinstance(v, np.ndarray) and v.dtype == object:  # a cell column of strings
            return [unstr(x) for x in v.ravel()]
        if isinstance(v, np.ndarray) and v.dtype.kind == "U":
            return unstr(v)
        v = np.asarray(v)
        # MATLAB has no scalars: these three come back as 1x1 matrices
        return v.ravel()[0] if v.size == 1 and k in ("version", "dimension", "t") else v

    return build(path, get, data["M"], data["G"], data.get("T"))
