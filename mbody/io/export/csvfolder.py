"""The CSV export: a folder of six labelled tables (seven with the world-axes map), for
spreadsheets and anything else that reads CSV.

| file | header |
| --- | --- |
| M.csv, G.csv | ``coordinate`` then the column labels (dense), or ``row, column, value`` |
| T.csv | ``world`` then the reaction labels (dense), or triplets; only with the map |
| vectors.csv | `VECTORS` |
| columns.csv | `COLUMNS` (one line per reaction column) |
| bodies.csv | `BODIES` (one line per body) |
| info.csv | ``key, value`` (values JSON-encoded) |

The reader finds every column by its header name, never by its position: a table whose
columns were reordered, or that gained columns (a spreadsheet's notes), reads the same. A
missing column is an `MbodyError` naming the file and the column. The rows and columns of
M.csv and G.csv are matched to vectors.csv and columns.csv by their labels too; the rows
of T.csv to the labels info.csv lists under ``world_reactions``.
"""

from __future__ import annotations

import csv
import io
import json
import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from mbody.equations.assemble import Assembly
from mbody.errors import MbodyError
from mbody.io.export.assembly import (
    FORMAT,
    MORE,
    VERSION,
    ExportedAssembly,
    as_export,
    build,
    check_format,
)
from mbody.model.arguments import KnownValues
from mbody.util import jsontext
from mbody.util.atomic import atomic_folder
from mbody.util.budget import TEXT_BYTES, byte_limit
from mbody.util.npzfile import over_budget, read_text

CSV_DENSE_LIMIT = 1_000_000
"""M.csv and G.csv are labelled dense tables up to this many cells, else triplets."""

VECTORS = ("coordinate", "b", "Q")
"""Header of vectors.csv."""
COLUMNS = ("label", "joint", "type", "parent", "child", "component", "kind",
           "frame_x", "frame_y", "frame_z", "point_x", "point_y", "point_z", "known",
           "gamma", "phi", "sign")
"""Header of columns.csv; `known` is empty when the reaction is unknown."""
BODIES = ("name", "mass", *(f"J{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)),
          "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "w1", "w2", "w3")
"""Header of bodies.csv: inertia J (body axes), position, quaternion, velocity, ω."""
TRIPLETS = ("row", "column", "value")
"""Header of M.csv and G.csv beyond `CSV_DENSE_LIMIT` cells."""
FILES = ("info.csv", "vectors.csv", "columns.csv", "bodies.csv", "M.csv", "G.csv")
MAP_FILE = "T.csv"
"""The world-axes map's table, written with the six when the export holds it."""

# columns.csv text fields -> the `flat_arrays` names `build` reads
_COLUMN_TEXT = {"joint": "column_joint", "type": "column_type", "parent": "column_parent",
                "child": "column_child", "component": "column_component",
                "kind": "column_kind", "sign": "column_sign"}
_INFO_KEYS = ("format", "version", "model", "model_file", "dimension", "t", "state_source")


# -- writing --------------------------------------------------------------------------------
def write_csv(asm: Assembly | ExportedAssembly, folder: str | os.PathLike[str],
              known: KnownValues | None = None, axes: str = "joint") -> Path:
    """Write the export as CSV tables in `folder` (created if needed), atomically.

    Parameters
    ----------
    asm
        An assembly (exported here) or an export.
    folder
        The folder to write M.csv, G.csv, vectors.csv, columns.csv, bodies.csv and
        info.csv into (and T.csv when the export holds the world-axes map); other files
        in it are left alone.
    known
        Reaction values to record as known, with an `Assembly` (numbers, or expressions
        of t taken at its state's time: `Assembly.reaction_values`).
    axes
        "world": add the world-axes map T (with an `Assembly`; an export has its own).

    Returns
    -------
    Path
        `folder`.

    Notes
    -----
    All six files are written to a temporary folder and moved in only when every one is
    complete (`mbody.util.atomic.atomic_folder`).
    """
    exp = as_export(asm, known, axes)
    with atomic_folder(folder) as tmp:
        for name, rows in _tables(exp).items():
            with open(tmp / name, "w", newline="", encoding="utf-8") as fh:
                csv.writer(fh, lineterminator="\n").writerows(rows)
    return Path(folder)


def _matrix_rows(A: sp.csc_matrix, rows: Sequence[str], cols: Sequence[str],
                 corner: str = "coordinate") -> Iterator[list[Any]]:
    """M.csv, G.csv or T.csv line by line (a generator: a large matrix is never all text);
    `corner` heads the column of row labels in a dense table."""
    if A.shape[0] * A.shape[1] <= CSV_DENSE_LIMIT:
        yield [corner, *cols]
        for label, r in zip(rows, A.toarray().tolist(), strict=True):
            yield [label, *r]
    else:
        yield list(TRIPLETS)
        C = A.tocoo()
        for i, j, v in zip(C.row.tolist(), C.col.tolist(), C.data.tolist(), strict=True):
            yield [rows[i], cols[j], v]


def _tables(exp: ExportedAssembly) -> dict[str, Any]:
    """File name -> its rows (header first); floats as Python floats, whose repr is exact."""
    st, c = exp.state, exp.columns
    info: list[list[Any]] = [
        ["key", "value"], ["format", json.dumps(FORMAT)], ["version", json.dumps(VERSION)],
        ["model", json.dumps(exp.model)], ["model_file", json.dumps(exp.file)],
        ["dimension", json.dumps(exp.dimension)], ["t", json.dumps(exp.t)],
        ["state_source", json.dumps(exp.state_source)]]
    info += [[f"conventions.{k}", json.dumps(v)] for k, v in exp.conventions.items()]
    if exp.T is not None:
        info.append(["world_reactions", json.dumps(exp.world_reactions)])
    vectors: list[list[Any]] = [list(VECTORS)] + [
        [lab, b, q] for lab, b, q in zip(exp.coordinates, exp.b.tolist(), exp.Q.tolist(),
                                         strict=True)]
    columns: list[list[Any]] = [list(COLUMNS)] + [
        [str(c.labels[i]), str(c.joint[i]), str(c.type[i]), str(c.parent[i]),
         str(c.child[i]), str(c.component[i]), str(c.kind[i]), *c.W_e[i].tolist(),
         *c.W_P[i].tolist(), "" if np.isnan(c.known[i]) else float(c.known[i]),
         float(c.gamma[i]), float(c.phi[i]), str(c.sign[i])]
        for i in range(len(c))]
    bodies: list[list[Any]] = [list(BODIES)] + [
        [n, float(exp.masses[i]), *exp.inertias[i].ravel().tolist(),
         *st.position[i].tolist(), *st.quaternion[i].tolist(), *st.velocity[i].tolist(),
         *st.omega[i].tolist()] for i, n in enumerate(exp.body_names)]
    tables: dict[str, Any] = {
        "info.csv": info, "vectors.csv": vectors, "columns.csv": columns, "bodies.csv": bodies,
        "M.csv": _matrix_rows(exp.M, exp.coordinates, exp.coordinates),
        "G.csv": _matrix_rows(exp.G, exp.coordinates, exp.reactions)}
    if exp.T is not None:
        tables[MAP_FILE] = _matrix_rows(exp.T, exp.world_reactions, exp.reactions, "world")
    return tables


# -- reading --------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Table:
    """One CSV file: its header and data rows (blank lines dropped), each row as long as
    the header; `lines` holds each row's line number in the file, for messages."""

    path: Path
    header: list[str]
    rows: list[list[str]]
    lines: list[int]

    def index(self, name: str) -> int:
        """The position of the column headed `name`."""
        try:
            return self.header.index(name)
        except ValueError:
            raise MbodyError(f"{self.path}: no column {name!r} (its header has "
                             f"{', '.join(map(repr, self.header)) or 'nothing'})") from None

    def text(self, name: str) -> list[str]:
        k = self.index(name)
        return [r[k] for r in self.rows]

    def floats(self, *names: str, empty: float | None = None) -> np.ndarray:
        """(rows, len(names)) numbers of the named columns; an empty cell is `empty`
        when given (else an error)."""
        out = np.empty((len(self.rows), len(names)))
        for j, name in enumerate(names):
            k = self.index(name)
            for i, r in enumerate(self.rows):
                cell = r[k].strip()
                if cell == "" and empty is not None:
                    out[i, j] = empty
                    continue
                try:
                    out[i, j] = float(cell)
                except ValueError:
                    raise MbodyError(f"{self.path}, line {self.lines[i]}, column {name!r}: "
                                     f"{r[k]!r} is not a number") from None
        return out


def _table(path: Path, max_bytes: int | None = None) -> _Table:
    if not path.is_file():
        raise MbodyError(f"{path}: no such file (a CSV export is a folder holding "
                         f"{', '.join(FILES)})")
    rows = csv.reader(io.StringIO(read_text(path, max_bytes, MORE), newline=""))
    try:
        numbered = [(k, r) for k, r in enumerate(rows, start=1) if r]
    except csv.Error as exc:
        # read from text split into lines, the csv module has one complaint left: a cell
        # over its field size limit (a process-wide setting, left as it is)
        limit = csv.field_size_limit()
        problem = (f"a cell longer than {limit:,} characters, the most a cell is read"
                   if "limit" in str(exc) else f"not CSV that mbody reads ({exc})")
        raise MbodyError(f"{path}, line {rows.line_num}: {problem}") from None
    if not numbered:
        raise MbodyError(f"{path}: empty (expected a header line)")
    header = numbered[0][1]
    twice = sorted({h for h in header if header.count(h) > 1})
    if twice:
        raise MbodyError(f"{path}: the header names {', '.join(map(repr, twice))} more "
                         "than once")
    for k, r in numbered[1:]:
        if len(r) != len(header):
            raise MbodyError(f"{path}, line {k}: {len(r)} cells, but the header has "
                             f"{len(header)}")
    return _Table(path, header, [r for _, r in numbered[1:]], [k for k, _ in numbered[1:]])


def _matrix(t: _Table, rows: list[str], cols: list[str], what: str,
            corner: str = "coordinate", rows_from: str = "vectors.csv") -> sp.csc_matrix:
    """M, G or T from its table, rows and columns placed by their labels (`rows` from
    `rows_from`, `cols` from vectors.csv or columns.csv, as `what` says; `corner` heads
    the row labels of a dense table)."""
    ri = {s: i for i, s in enumerate(rows)}
    ci = {s: j for j, s in enumerate(cols)}
    shape = (len(rows), len(cols))
    if corner not in t.header and set(TRIPLETS) <= set(t.header):
        r, c = [], []
        for lab_r, lab_c, k in zip(t.text("row"), t.text("column"), t.lines, strict=True):
            if lab_r not in ri or lab_c not in ci:
                raise MbodyError(f"{t.path}, line {k}: ({lab_r!r}, {lab_c!r}) is not a row "
                                 f"of {rows_from} and a column of {what}")
            r.append(ri[lab_r])
            c.append(ci[lab_c])
        return sp.csc_matrix((t.floats("value")[:, 0], (r, c)), shape=shape)
    labels = t.text(corner)
    # every other header is a column label: an unknown one means the tables disagree
    extra = [h for h in t.header if h != corner and h not in ci]
    missing = [c for c in cols if c not in t.header]
    if extra or missing or sorted(labels) != sorted(rows) or len(set(labels)) != len(labels):
        raise MbodyError(f"{t.path}: its labels do not match {rows_from} and {what}"
                         + (f" (columns not there: {', '.join(map(repr, extra))})"
                            if extra else "")
                         + (f" (no column {', '.join(map(repr, missing))})"
                            if missing else ""))
    A = np.zeros(shape)
    A[[ri[s] for s in labels]] = t.floats(*cols)
    return sp.csc_matrix(A)


def read(folder: Path, max_bytes: int | None = None) -> ExportedAssembly:
    """The `ExportedAssembly` stored in the CSV folder `folder`.

    Every column is found by its header name (see the module's docstring). The files
    hold at most `max_bytes` of text in all (default `mbody.util.budget.TEXT_BYTES`),
    refused before any is read.

    Raises
    ------
    MbodyError
        For a missing file, a missing column (naming the file and the column), a cell that
        is not a number, or tables whose labels disagree.
    """
    limit = byte_limit(max_bytes, TEXT_BYTES)
    files = [folder / f for f in (*FILES, MAP_FILE) if (folder / f).is_file()]
    holds = sum(f.stat().st_size for f in files)
    if holds > limit:
        raise MbodyError(over_budget(str(folder), holds, holds, limit, MORE))
    info_t = _table(folder / "info.csv", limit)
    keys, values = info_t.text("key"), info_t.text("value")
    info = {}
    for k, v, line in zip(keys, values, info_t.lines, strict=True):
        try:
            info[k] = jsontext.loads(v)
        except ValueError as exc:
            raise MbodyError(f"{info_t.path}, line {line}: the value of {k!r} is not JSON "
                             f"that mbody reads: {exc}") from None
    for key in _INFO_KEYS:
        if key not in info:
            raise MbodyError(f"{info_t.path}: no {key!r} entry in its 'key' column")
    check_format(info_t.path, str(info["format"]), int(info["version"]))
    conventions = {k.split(".", 1)[1]: v for k, v in info.items()
                   if k.startswith("conventions.")}
    vectors = _table(folder / "vectors.csv", limit)
    cols = _table(folder / "columns.csv", limit)
    bodies = _table(folder / "bodies.csv", limit)
    coordinates, reactions = vectors.text("coordinate"), cols.text("label")
    flat: dict[str, Any] = {k: info[k] for k in _INFO_KEYS}
    flat.update({
        "conventions_json": json.dumps(conventions), "coordinates": coordinates,
        "reactions": reactions, "b": vectors.floats("b"), "Q": vectors.floats("Q"),
        "body_names": bodies.text("name"), "masses": bodies.floats("mass"),
        "inertias": bodies.floats(*BODIES[2:11]),
        "position": bodies.floats("x", "y", "z"),
        "quaternion": bodies.floats("qw", "qx", "qy", "qz"),
        "velocity": bodies.floats("vx", "vy", "vz"),
        "omega": bodies.floats("w1", "w2", "w3"),
        "column_frame": cols.floats("frame_x", "frame_y", "frame_z"),
        "column_point": cols.floats("point_x", "point_y", "point_z"),
        "column_known": cols.floats("known", empty=np.nan),
        "column_gamma": cols.floats("gamma"), "column_phi": cols.floats("phi"),
    })
    for head, name in _COLUMN_TEXT.items():
        flat[name] = cols.text(head)
    M = _matrix(_table(folder / "M.csv", limit), coordinates, coordinates, "vectors.csv")
    G = _matrix(_table(folder / "G.csv", limit), coordinates, reactions, "columns.csv")
    T = None
    if "world_reactions" in info:  # the world-axes map, written when asked for
        world = [str(s) for s in info["world_reactions"]]
        flat["world_reactions"] = world
        T = _matrix(_table(folder / MAP_FILE, limit), world, reactions, "columns.csv", "world",
                    "info.csv's world_reactions")
    return build(folder, flat.__getitem__, M, G, T)
