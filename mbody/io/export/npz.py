"""The npz export: numpy arrays under the `flat_arrays` names, each sparse matrix (M, G, and
the world-axes map T when asked for) as its CSC arrays (``M_data, M_indices, M_indptr,
M_shape``) so that one scipy call rebuilds it without mbody, and labels as plain string
arrays (no pickling)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from mbody.errors import MbodyError
from mbody.io.export.assembly import (
    MORE,
    ExportedAssembly,
    build,
    check_format,
    flat_arrays,
    text_array,
)
from mbody.util.npzfile import NpzArchive


def write(exp: ExportedAssembly, path: Path) -> None:
    """Write `exp` to `path` as a compressed npz (not atomic: `write_export` makes it so).

    Parameters
    ----------
    exp
        The export to write.
    path
        The file to write (numpy adds no suffix: the file handle is given).
    """
    arrs = flat_arrays(exp)
    for k in ("coordinates", "reactions", "body_names", "world_reactions"):
        if k in arrs:
            arrs[k] = text_array(arrs[k])
    for name in ("M", "G", "T"):
        A = getattr(exp, name)
        if A is None:  # no world-axes map asked for
            continue
        arrs.update({f"{name}_data": A.data, f"{name}_indices": A.indices,
                     f"{name}_indptr": A.indptr, f"{name}_shape": np.array(A.shape)})
    arrays: dict[str, Any] = {k: np.asarray(v) for k, v in arrs.items()}
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)


def read(path: Path, max_bytes: int | None = None) -> ExportedAssembly:
    """The `ExportedAssembly` stored in the npz file `path` (never unpickles anything;
    every member's size checked before any is inflated, at most `max_bytes` in all:
    `mbody.util.npzfile`)."""
    with NpzArchive(path, "export file", max_bytes=max_bytes, more=MORE,
                    damage="not a readable mbody export") as z:
        data = {k: z.read(k) for k in z.files}

    def get(k: str) -> Any:
        v = data[k]
        return v.item() if v.ndim == 0 else v

    def mat(name: str) -> sp.csc_matrix:
        return sp.csc_matrix((data[f"{name}_data"], data[f"{name}_indices"],
                              data[f"{name}_indptr"]), shape=tuple(data[f"{name}_shape"]))

    if "format" not in data:
        raise MbodyError(f"{path}: a .npz archive, but not an mbody export (it has no "
                         f"'format' entry; entries: {', '.join(sorted(data)[:8])})")
    # the tag before the matrices: a saved run (another mbody .npz) is named as such
    check_format(path, str(get("format")), int(get("version")) if "version" in data else 0)
    return build(path, get, mat("M"), mat("G"), mat("T") if "T_data" in data else None)
