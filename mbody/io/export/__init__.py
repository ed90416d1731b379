"""Self-describing exports of ``M v̇ + b = Q + G λ``: npz, MATLAB .mat, JSON and CSV.

Every export holds the stacked matrices at one state together with what is needed to
read them without mbody: the coordinate label of every row, the reaction label of every
column of G and, per column, its joint, joint type, parent, child, component, direction
(the joint-frame axis in world axes at that state), joint point and sign rule; the body
masses, inertia tensors and state; and the conventions (`mbody.conventions.conventions`).
Asked for world axes (``exported(asm, axes="world")``), an export also holds the map T
from the joint-frame reaction values λ to the world-axes ones, world = T λ, with their
labels (``O.Fx``...: each joint's force and moment on its child along world x, y, z).

    exp = exported(asm)                 # an `ExportedAssembly` (in memory)
    write_export(asm, "eqs.npz")        # or .mat / .json; write_csv(asm, "eqs_csv/")
    back = load_export("eqs.npz")       # the same `ExportedAssembly`, bit for bit

The package: `assembly` (the in-memory export and what every format shares), one module
per format holding its writer and its reader together (`npz`, `mat`, `jsonfile`,
`csvfolder`), `sample` (the state at a trajectory sample), and here the choice of format
by suffix. Floats are written so that they read back exactly.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

from mbody.equations.assemble import Assembly
from mbody.errors import MbodyError
from mbody.io.export import csvfolder, jsonfile, mat, npz
from mbody.io.export.assembly import (
    COLUMN_TEXT,
    FORMAT,
    VERSION,
    Columns,
    ExportedAssembly,
    as_export,
    exported,
    unreadable,
)
from mbody.io.export.csvfolder import CSV_DENSE_LIMIT, write_csv
from mbody.io.export.jsonfile import from_json, schema, to_json
from mbody.io.export.sample import assembly_from_trajectory, state_at
from mbody.model.arguments import KnownValues
from mbody.util.atomic import atomic_path
from mbody.util.budget import checked_max_bytes

__all__ = [
    "COLUMN_TEXT", "CSV_DENSE_LIMIT", "FORMAT", "SUFFIXES", "VERSION", "Columns",
    "ExportedAssembly", "assembly_from_trajectory", "exported", "from_json", "load_export",
    "schema", "state_at", "to_json", "write_csv", "write_export",
]

SUFFIXES = {".npz": "npz", ".mat": "mat", ".json": "json"}
"""File suffix -> format; a CSV export is a folder (`write_csv`)."""


def _module(fmt: str) -> ModuleType:
    # looked up at each call, so that a format's `write`/`read` patched on its own module
    # (as the tests do to simulate a full disk) is the one used
    return {"npz": npz, "mat": mat, "json": jsonfile}[fmt]


def write_export(asm: Assembly | ExportedAssembly, path: str | os.PathLike[str],
                 known: KnownValues | None = None, axes: str = "joint") -> Path:
    """Write an export whose format follows the suffix of `path`, atomically.

    Parameters
    ----------
    asm
        An assembly (exported here) or an export.
    path
        A file name ending in .npz, .mat or .json.
    known
        Reaction values to record as known, with an `Assembly` (numbers, or expressions
        of t taken at its state's time: `Assembly.reaction_values`).
    axes
        "world": add the map T from the joint-frame reaction values to the world-axes
        ones (`ExportedAssembly.T`), with an `Assembly` (an export has its own).

    Returns
    -------
    Path
        `path`.

    Raises
    ------
    MbodyError
        For another suffix; `mbody.errors.OutputError` when the file cannot be written
        (nothing is left behind, and an existing file is unchanged);
        `mbody.errors.MbodyTypeError` when `asm` is neither (a `Model` is assembled
        first: ``write_export(mbody.assemble(model), path)``).
    """
    path = Path(path)
    fmt = SUFFIXES.get(path.suffix.lower())
    if fmt is None:
        raise MbodyError(f"{path}: unknown export format {path.suffix or '(no suffix)'!r}; "
                         "use a name ending in .npz, .mat or .json, or --csv DIR")
    exp = as_export(asm, known, axes)
    with atomic_path(path) as tmp:
        _module(fmt).write(exp, tmp)
    return path


def load_export(path: str | os.PathLike[str], *, max_bytes: int | None = None
                ) -> ExportedAssembly:
    """Reload any export (.npz, .mat, .json file, or a CSV folder) as an `ExportedAssembly`.

    The file is read as input that may be hostile (an export from someone else): its
    size, what it declares and its nesting are checked before it is inflated or parsed.

    Parameters
    ----------
    path
        The file, or the folder `write_csv` wrote.
    max_bytes
        The most data read: an npz or .mat file's arrays once inflated (default 1 GiB,
        `mbody.util.budget.DATA_BYTES`), a JSON file's or CSV folder's text (default
        32 MiB, `TEXT_BYTES`); a larger export is refused before it is read.

    Returns
    -------
    ExportedAssembly
        The export, bit for bit as written.

    Raises
    ------
    MbodyError
        For a missing, unreadable, foreign or damaged file, or one over `max_bytes`; a
        `max_bytes` that is not a whole number of bytes, at least 1.
    """
    max_bytes = checked_max_bytes(max_bytes)  # the argument's fault, not the file's
    path = Path(path)
    reader: Callable[[Path, int | None], ExportedAssembly]
    if path.is_dir():
        reader = csvfolder.read
    else:
        fmt = SUFFIXES.get(path.suffix.lower())
        if fmt is None:
            raise MbodyError(f"{path}: not an mbody export (expected .npz, .mat, .json or a "
                             "CSV folder)")
        if not path.exists():
            raise MbodyError(f"{path}: no such file")
        reader = _module(fmt).read
    with unreadable(path):
        return reader(path, max_bytes)
