"""The JSON export: one document that validates against the schema shipped with the package
(`schema()`, mbody/data/assembly.schema.json); sparse matrices as sorted 0-based
``row, col, value`` triplets, one object per reaction column and per body; the world-axes
map, when asked for, under ``world`` (its labels and T as triplets). Floats are
written by `json` with the shortest repr that reads back exactly; a number that is not
finite is written as null (`mbody.util.jsontext`: strict JSON)."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from mbody import conventions as cv
from mbody import joint_types
from mbody.errors import MbodyError
from mbody.io.export.assembly import (
    COLUMN_TEXT,
    FORMAT,
    VERSION,
    ExportedAssembly,
    build,
    check_format,
    check_map,
    check_shape,
)
from mbody.util import jsontext
from mbody.util.npzfile import read_text


def _triplets(A: sp.csc_matrix) -> dict[str, Any]:
    """CSC as triplets, sorted by column then row (the CSC order itself)."""
    col = np.repeat(np.arange(A.shape[1]), np.diff(A.indptr))
    return {"shape": list(A.shape), "row": A.indices.tolist(), "col": col.tolist(),
            "value": A.data.tolist()}


def to_json(exp: ExportedAssembly) -> dict[str, Any]:
    """The JSON document (validates against `schema()`)."""
    st = exp.state
    bodies = [{"name": n, "mass": float(exp.masses[i]), "inertia": exp.inertias[i].tolist(),
               "position": st.position[i].tolist(), "quaternion": st.quaternion[i].tolist(),
               "velocity": st.velocity[i].tolist(), "omega": st.omega[i].tolist()}
              for i, n in enumerate(exp.body_names)]
    doc: dict[str, Any] = {
        "format": FORMAT, "version": VERSION,
        "model": {"name": exp.model, "file": exp.file, "dimension": exp.dimension},
        "state": {"t": exp.t, "source": exp.state_source},
        "conventions": exp.conventions,
        "coordinates": exp.coordinates, "reactions": exp.reactions,
        "bodies": bodies, "columns": exp.columns.records(),
        "M": _triplets(exp.M), "b": exp.b.tolist(), "Q": exp.Q.tolist(), "G": _triplets(exp.G),
    }
    if exp.T is not None:
        doc["world"] = {"reactions": exp.world_reactions, "T": _triplets(exp.T)}
    return doc


def write(exp: ExportedAssembly, path: Path) -> None:
    """Write `to_json(exp)` to `path`, UTF-8 (not atomic by itself).

    Parameters
    ----------
    exp
        The export to write.
    path
        The file to write.
    """
    with open(path, "w", encoding="utf-8") as fh:
        jsontext.dump(to_json(exp), fh, indent=1)


def schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of the JSON export, shipped with the package, with
    the joint types and reaction components the registry holds (`mbody.joint_types`: a
    new type's exports validate without editing the schema file)."""
    text = resources.files("mbody").joinpath("data/assembly.schema.json").read_text("utf-8")
    out: dict[str, Any] = json.loads(text)
    column = out["properties"]["columns"]["items"]["properties"]
    column["type"]["enum"] = list(dict.fromkeys(
        name for d in (cv.PLANAR, cv.SPATIAL) for name in joint_types.type_names(d)))
    column["component"]["enum"] = list(joint_types.COMPONENT_NAMES)
    column["kind"]["enum"] = [joint_types.FORCE, joint_types.MOMENT, joint_types.WRENCH]
    return out


def read(path: Path, max_bytes: int | None = None) -> ExportedAssembly:
    """The `ExportedAssembly` stored in the JSON file `path`: at most `max_bytes` of text
    (default `mbody.util.budget.TEXT_BYTES`), refused before it is read; its nesting
    bounded before it is parsed (`mbody.util.jsontext.loads`)."""
    d = jsontext.loads(read_text(path, max_bytes))
    if not isinstance(d, dict):
        raise MbodyError(f"{path}: not an mbody export (not a JSON object)")
    check_format(path, str(d.get("format")), int(d.get("version", 0)))
    return from_json(d, path)


def from_json(d: dict[str, Any], path: Path | str = "<json>") -> ExportedAssembly:
    """An `ExportedAssembly` from the JSON document `to_json` produces.

    Parameters
    ----------
    d
        The parsed document.
    path
        Where it came from, for messages.
    """
    bodies, cols = d["bodies"], d["columns"]
    flat: dict[str, Any] = {
        "format": d["format"], "version": d["version"], "model": d["model"]["name"],
        "model_file": d["model"]["file"], "dimension": d["model"]["dimension"],
        "t": d["state"]["t"], "state_source": d["state"]["source"],
        "conventions_json": json.dumps(d["conventions"]),
        "coordinates": d["coordinates"], "reactions": d["reactions"],
        "body_names": [b["name"] for b in bodies], "masses": [b["mass"] for b in bodies],
        "inertias": [b["inertia"] for b in bodies] or np.zeros((0, 3, 3)),
        "b": d["b"], "Q": d["Q"],
        "column_frame": [c["frame"] for c in cols] or np.zeros((0, 3)),
        "column_point": [c["point"] for c in cols] or np.zeros((0, 3)),
        "column_known": [np.nan if c["known"] is None else c["known"] for c in cols],
        "column_gamma": [c["gamma"] for c in cols], "column_phi": [c["phi"] for c in cols],
    }
    for k in ("position", "quaternion", "velocity", "omega"):
        flat[k] = [b[k] for b in bodies] or np.zeros((0, 4 if k == "quaternion" else 3))
    for k in COLUMN_TEXT[1:]:
        flat[f"column_{k}"] = [c[k] for c in cols]

    def mat(t: dict[str, Any], shape: tuple[int, ...]) -> sp.csc_matrix:
        # made after its shape is checked against the labels: the column pointers alone
        # take 8 bytes per column a file claims
        return sp.csc_matrix((t["value"], (t["row"], t["col"])), shape=shape)

    def shape(t: dict[str, Any]) -> tuple[int, ...]:
        return tuple(int(k) for k in t["shape"])

    N, m = len(d["coordinates"]), len(d["reactions"])
    check_shape(Path(path), "M", shape(d["M"]), (N, N), "the coordinates by the coordinates")
    check_shape(Path(path), "G", shape(d["G"]), (N, m), "the coordinates by the reactions")
    world = d.get("world")
    T = None
    if world is not None:
        flat["world_reactions"] = world["reactions"]
        check_map(Path(path), shape(world["T"]), len(world["reactions"]), m)
        T = mat(world["T"], shape(world["T"]))
    M = mat(d["M"], shape(d["M"]))
    return build(Path(path), flat.__getitem__, M, mat(d["G"], shape(d["G"])), T)

