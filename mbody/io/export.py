"""Self-describing exports of ``M v̇ + b = Q + G λ``: npz, MATLAB .mat, JSON and CSV.

Every export holds the stacked matrices at one state together with what is needed to
read them without mbody: the coordinate label of every row, the reaction label of every
column of G and, per column, its joint, joint type, parent, child, component, direction
(the joint-frame axis in world axes at that state), joint point and sign rule; the body
masses, inertia tensors and state; and the conventions (`mbody.conventions.conventions`).

    exp = exported(asm)                 # an `ExportedAssembly` (in memory)
    write_export(asm, "eqs.npz")        # or .mat / .json; write_csv(asm, "eqs_csv/")
    back = load_export("eqs.npz")       # the same `ExportedAssembly`, bit for bit

Storage of the sparse M and G: npz keeps the CSC arrays (``M_data, M_indices, M_indptr,
M_shape``); .mat stores MATLAB sparse matrices; JSON stores sorted triplets
(``row, col, value``); CSV writes labelled dense tables (triplets beyond
`CSV_DENSE_LIMIT` cells). Floats are written so that they read back exactly.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from mbody import conventions as cv
from mbody.equations.assemble import Assembly, Solution, assemble
from mbody.equations.constraints import gamma, phi
from mbody.equations.plan import Unknowns
from mbody.errors import MbodyError
from mbody.io.atomic import _umask, atomic_path
from mbody.model.model import Model, State
from mbody.simulate.trajectory import Trajectory
from mbody.solve.kkt import ConstrainedSystem, block_solve

FORMAT = "mbody-export"
VERSION = 1
SUFFIXES = {".npz": "npz", ".mat": "mat", ".json": "json"}
CSV_DENSE_LIMIT = 1_000_000
"""CSV writes M and G as labelled dense tables up to this many cells, else as triplets."""

COLUMN_TEXT = ("labels", "joint", "type", "parent", "child", "component", "kind", "sign")
"""Text fields of `Columns`, one entry per reaction column (in this order in files)."""


# -- the in-memory export ------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Columns:
    """One entry per column of G (reaction unknown), struct of arrays.

    labels, joint, type, parent, child, component, kind ('force' | 'moment'), sign: (m,)
    text. W_e: (m, 3) the component's direction (its joint-frame axis) in world axes at
    the exported state. W_P: (m, 3) the joint point, world coordinates (m).
    known: (m,) the reaction value when known, NaN when unknown.
    gamma: (m,) γ, the velocity-product terms of each joint constraint, so that a motion
    keeping the joints has Gᵀ v̇ = γ (row c of Gᵀ is column c of G); phi: (m,) the
    position error of each constraint at the state (0 when the joints are assembled).
    """

    labels: np.ndarray
    joint: np.ndarray
    type: np.ndarray
    parent: np.ndarray
    child: np.ndarray
    component: np.ndarray
    kind: np.ndarray
    sign: np.ndarray
    W_e: np.ndarray
    W_P: np.ndarray
    known: np.ndarray
    gamma: np.ndarray
    phi: np.ndarray

    def __len__(self) -> int:
        return len(self.labels)

    def __getitem__(self, i: int | str) -> dict[str, Any]:
        """Column `i` (index or label) as a plain dict (what the JSON file holds)."""
        if isinstance(i, str):
            hits = np.flatnonzero(self.labels == i)
            if not len(hits):
                raise KeyError(f"no reaction column {i!r}")
            i = int(hits[0])
        out: dict[str, Any] = {"label": str(self.labels[i])}
        out.update({k: str(getattr(self, k)[i]) for k in COLUMN_TEXT[1:]})
        out["frame"] = self.W_e[i].tolist()
        out["point"] = self.W_P[i].tolist()
        out["known"] = None if np.isnan(self.known[i]) else float(self.known[i])
        out["gamma"] = float(self.gamma[i])
        out["phi"] = float(self.phi[i])
        return out

    def records(self) -> list[dict[str, Any]]:
        return [self[i] for i in range(len(self))]


@dataclass(frozen=True, eq=False)
class ExportedAssembly:
    """``M v̇ + b = Q + G λ`` at one state, with its labels: what every export holds.

    M: (N, N) and G: (N, m) scipy CSC matrices; b, Q: (N,). coordinates: (N,) row labels;
    reactions: (m,) column labels; columns: per-column joint data (`Columns`).
    body_names: (n,); masses: (n,) kg; inertias: (n, 3, 3) kg m^2, body axes about the
    mass centre (planar: I_G is entry [2, 2]); state: the `State` the matrices were taken
    at (positions world, quaternions w first, velocities world, ω body axes; planar bodies
    in the x-y plane). state_source says where that state came from.
    """

    model: str
    file: str
    dimension: int
    state_source: str
    conventions: dict[str, Any]
    coordinates: list[str]
    reactions: list[str]
    columns: Columns
    body_names: list[str]
    masses: np.ndarray
    inertias: np.ndarray
    state: State
    M: sp.csc_matrix
    b: np.ndarray
    Q: np.ndarray
    G: sp.csc_matrix

    @property
    def t(self) -> float:
        return float(self.state.t)

    @property
    def known(self) -> dict[str, float]:
        return {str(k): float(v) for k, v in zip(self.columns.labels, self.columns.known,
                                                  strict=True) if not np.isnan(v)}

    @property
    def shape(self) -> dict[str, tuple[int, ...]]:
        N, m = len(self.coordinates), len(self.reactions)
        return {"M": (N, N), "b": (N,), "Q": (N,), "G": (N, m)}

    def __repr__(self) -> str:  # the dataclass's would print every matrix
        N, m = len(self.coordinates), len(self.reactions)
        return (f"<ExportedAssembly of {self.model!r}: M {N}x{N}, G {N}x{m}; state: "
                f"{self.state_source}; .solve(), .records()>")

    def solve(self, known: Mapping[str, float] | None = None) -> Solution:
        """Accelerations, and the reaction components not given (stored values or `known`).

        All known: v̇ = M⁻¹ (Q + G λ − b). Otherwise, with U the unknown components,
        ``[[M, −G_U], [G_Uᵀ, 0]] [v̇; λ_U] = [Q − b + G_K λ_K; γ_U]`` (the joints of the
        given components are not enforced), solved by the same constrained solver as
        `mbody.Assembly.solve` (`mbody.kkt.ConstrainedSystem`), from the stored matrices
        alone: redundant constraints give the minimum-norm reactions, named.
        """

        values = self.known
        for label, v in (known or {}).items():
            if label not in self.reactions:
                raise MbodyError(f"no reaction component {label!r} in this export")
            values[label] = float(v)
        lam = np.array([values.get(r, np.nan) for r in self.reactions], dtype=float)
        mask = np.isnan(lam)
        lam[mask] = 0.0
        bodies, cols, rows = _solver_view(self)
        r6 = np.zeros((bodies.n, 6))
        r6.reshape(-1)[rows] = self.Q - self.b
        t = bodies.reaction_table
        for six, body in ((cols.child6, t.child), (cols.parent6, t.parent)):
            on = body >= 0
            np.add.at(r6, body[on], six[on] * lam[on, None])
        unknowns = Unknowns(mask, np.flatnonzero(mask), lam, mask.tobytes())
        coords = list(self.coordinates)
        if not len(unknowns.U):
            acc6 = block_solve(bodies, np.arange(bodies.n), r6)
            return Solution(coords, acc6.reshape(-1)[rows],
                            dict(zip(self.reactions, lam.tolist(), strict=True)))
        system = ConstrainedSystem(bodies, cols, unknowns)
        acc6, lam_U, berr = system.solve_refined(r6, self.columns.gamma[mask])
        lam[mask] = lam_U
        solved = tuple(r for r, k in zip(self.reactions, mask, strict=True) if k)
        return Solution(coords, acc6.reshape(-1)[rows],
                        dict(zip(self.reactions, lam.tolist(), strict=True)), solved,
                        tuple(solved[k] for k in system.fact.redundant if k >= 0), berr,
                        None, system.fact.method, (), system.fact.size - system.fact.rank)

    def differences(self, other: ExportedAssembly) -> list[str]:
        """What differs from `other`, bit for bit ([] when they are identical)."""
        out = []
        for k in ("model", "file", "dimension", "state_source", "conventions", "coordinates",
                  "reactions", "body_names"):
            if getattr(self, k) != getattr(other, k):
                out.append(k)
        for k in ("masses", "inertias", "b", "Q"):
            if not _same(getattr(self, k), getattr(other, k)):
                out.append(k)
        for k in ("position", "quaternion", "velocity", "omega"):
            if not _same(getattr(self.state, k), getattr(other.state, k)):
                out.append(f"state.{k}")
        if self.t != other.t:
            out.append("t")
        for k in ("M", "G"):
            a, b = getattr(self, k), getattr(other, k)
            if a.shape != b.shape or not (_same(a.data, b.data) and _same(a.indices, b.indices)
                                          and _same(a.indptr, b.indptr)):
                out.append(k)
        for k in (*COLUMN_TEXT, "W_e", "W_P", "known", "gamma", "phi"):
            if not _same(getattr(self.columns, k), getattr(other.columns, k)):
                out.append(f"columns.{k}")
        return out


@dataclass(frozen=True)
class _Bodies:
    """What the constrained solver reads of a model, rebuilt from an export's matrices:
    masses (n,), inertia tensors J and J⁻¹ (n, 3, 3), M⁻¹'s diagonal when every J is
    diagonal (minv6), and the reaction columns' child and parent bodies."""

    n: int
    mass: np.ndarray
    J: np.ndarray
    J_inv: np.ndarray
    minv6: np.ndarray | None
    reaction_table: Any
    plan: Any = None


@dataclass(frozen=True)
class _Parents:
    child: np.ndarray
    parent: np.ndarray


@dataclass(frozen=True)
class _Columns:
    child6: np.ndarray
    parent6: np.ndarray


def _solver_view(exp: ExportedAssembly) -> tuple[_Bodies, _Columns, np.ndarray]:
    """(bodies, columns, rows): the export in the solver's per-body six-row form, from M
    and G as stored (so an edited matrix is honoured). rows (N,) places each stored row
    among the 6 n rows (planar [x, y, θ] are rows 0, 1, 5 of a body), read from the
    coordinate labels: a particle has translation rows only (its rotation rows get a
    placeholder inertia, and nothing acts on them)."""
    n = len(exp.body_names)
    index = {name: i for i, name in enumerate(exp.body_names)}
    where = {**{r: k for k, r in enumerate(cv.SPATIAL_ROWS)}, "theta": 5}
    rows = np.array([6 * index[lab.rsplit(".", 1)[0]] + where[lab.rsplit(".", 1)[1]]
                     for lab in exp.coordinates], dtype=np.intp).reshape(-1)
    N6 = 6 * n
    P = sp.csr_matrix((np.ones(len(rows)), (rows, np.arange(len(rows)))),
                      shape=(N6, len(rows)))
    M = (P @ sp.csr_matrix(exp.M) @ P.T).tocsr()
    diag = M.diagonal()
    mass = diag[0::6].copy()
    J = np.zeros((n, 3, 3))
    if exp.dimension == cv.SPATIAL:
        base = np.arange(n) * 6 + 3
        for i in range(3):
            for j in range(3):
                J[:, i, j] = np.asarray(M[base + i, base + j]).ravel()
    else:  # only I_G acts (planar rows); the other two axes are placeholders
        J[:, 0, 0] = J[:, 1, 1] = J[:, 2, 2] = diag[5::6]
    present = np.zeros(N6, dtype=bool)
    present[rows] = True
    particle = ~present.reshape(n, 6)[:, 5]
    J[particle] = mass[particle, None, None] * np.eye(3)  # placeholder, never turned
    J_inv = np.linalg.inv(J) if n else J
    off = J - np.einsum("nii->ni", J)[:, :, None] * np.eye(3)
    minv6 = None
    if not np.any(off):
        minv6 = np.concatenate((np.repeat(1.0 / mass[:, None], 3, axis=1),
                                1.0 / np.einsum("nii->ni", J)), axis=1)
    child = np.array([index[str(c)] for c in exp.columns.child], dtype=np.intp)
    parent = np.array([index.get(str(p), -1) for p in exp.columns.parent], dtype=np.intp)
    m = len(child)
    G = (P @ sp.csc_matrix(exp.G)).tocsc()
    child6, parent6 = np.zeros((m, 6)), np.zeros((m, 6))
    if m:
        col = np.repeat(np.arange(m), 6)
        child6[:] = np.asarray(G[(child[:, None] * 6 + np.arange(6)).ravel(), col]
                               ).reshape(m, 6)
        on = parent >= 0
        if on.any():
            colp = np.repeat(np.arange(m)[on], 6)
            parent6[on] = np.asarray(
                G[(parent[on, None] * 6 + np.arange(6)).ravel(), colp]).reshape(-1, 6)
    bodies = _Bodies(n, mass, J, J_inv, minv6, _Parents(child, parent))
    return bodies, _Columns(child6, parent6), rows


def _same(a: Any, b: Any) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return False
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        return bool(np.array_equal(a.astype(float), b.astype(float), equal_nan=True))
    return bool(np.array_equal(a.astype(str), b.astype(str)))


def _canonical(A: sp.spmatrix) -> sp.csc_matrix:
    """CSC with sorted indices and no stored zeros: one representation per matrix."""
    C = sp.csc_matrix(A, dtype=float, copy=True)
    C.eliminate_zeros()
    C.sum_duplicates()
    C.sort_indices()
    C.indices = C.indices.astype(np.int64)
    C.indptr = C.indptr.astype(np.int64)
    return C


def _text(values: list[str]) -> np.ndarray:
    return np.array(values, dtype=str) if values else np.zeros(0, dtype="<U1")


def exported(asm: Assembly, known: Mapping[str, float] | None = None,
             state_source: str = "") -> ExportedAssembly:
    """Collect the matrices, labels and per-column joint data of `asm` for export.

    `known` adds reaction values to the file's (labels are checked). Per column c with
    joint j: W_e[c] is the component's axis in world axes at `asm.state` (the joint frame
    is fixed to the parent), W_P[c] the joint point; + acts on j's child, − on its parent.
    """
    model: Model = asm.model
    values = asm.reaction_values(known)
    t = model.reaction_table
    cols = asm.columns
    jt = np.array([[j.name, j.type, j.parent, j.child] for j in model.joints],
                  dtype=str).reshape(-1, 4)
    per = jt[t.joint] if len(t.labels) else np.zeros((0, 4), dtype="<U1")
    labels = list(t.labels)
    component = [lab.split(".", 1)[1] for lab in labels]
    kind = np.where(cols.is_moment, "moment", "force")
    sign = [f"+{lab} acts on {c} at the joint point, -{lab} on {p}"
            for lab, p, c in zip(labels, per[:, 2], per[:, 3], strict=True)]
    columns = Columns(
        _text(labels), per[:, 0], per[:, 1], per[:, 2], per[:, 3], _text(component),
        kind.astype(str) if len(labels) else np.zeros(0, dtype="<U1"), _text(sign),
        np.array(cols.W_e, dtype=float).reshape(-1, 3),
        np.array(cols.W_P, dtype=float).reshape(-1, 3),
        np.array([values.get(lab, np.nan) for lab in labels], dtype=float),
        np.array(gamma(model, asm.state, cols), dtype=float).reshape(-1),
        np.array(phi(model, asm.state), dtype=float).reshape(-1),
    )
    st = asm.state
    state = State(*(np.array(getattr(st, k), dtype=float) for k in
                    ("position", "quaternion", "velocity", "omega")), float(st.t))
    return ExportedAssembly(
        model=model.name, file=model.file, dimension=model.dimension,
        state_source=state_source or f"the model's initial state (t = {st.t:g} s)",
        conventions=cv.conventions(model.dimension),
        coordinates=list(asm.coordinates), reactions=labels, columns=columns,
        body_names=list(model.body_names), masses=np.array(model.mass, dtype=float),
        inertias=np.array(model.J, dtype=float), state=state,
        M=_canonical(asm.M), b=np.array(asm.b, dtype=float), Q=np.array(asm.Q, dtype=float),
        G=_canonical(asm.G),
    )


def _as_export(obj: Assembly | ExportedAssembly, known=None) -> ExportedAssembly:
    return obj if isinstance(obj, ExportedAssembly) else exported(obj, known)


# -- a state from a trajectory ---------------------------------------------------------
def state_at(traj, time: float | None) -> tuple[State, int]:
    """The trajectory's sample nearest to `time` (default: its last sample) and its index.

    No interpolation: a stored sample is a state the integrator produced, so it satisfies
    the equations and constraints as well as the run did. Raises `MbodyError` when `time`
    lies outside the trajectory's time span.
    """
    t = np.asarray(traj.t, dtype=float)
    if len(t) == 0:
        raise MbodyError("the trajectory holds no samples")
    if time is None:
        k = len(t) - 1
    else:
        span = max(abs(t[-1]), abs(t[0]), 1.0) * 1e-9
        if not (t[0] - span <= time <= t[-1] + span):
            raise MbodyError(f"time {time:g} s is outside the trajectory's span "
                             f"[{t[0]:g}, {t[-1]:g}] s")
        k = int(np.argmin(np.abs(t - time)))
    return traj.state(k), k


def assembly_from_trajectory(model: Model, path: str | os.PathLike[str],
                             time: float | None = None) -> tuple[Assembly, str]:
    """Assemble `model` at the sample of the trajectory file `path` nearest to `time`."""

    traj = Trajectory.load(path)
    if tuple(traj.body_names) != tuple(model.body_names) or traj.dimension != model.dimension:
        raise MbodyError(f"{path}: this trajectory is of another model (bodies "
                         f"{', '.join(list(traj.body_names)[:5])}..., dimension "
                         f"{traj.dimension}); the model has {', '.join(model.body_names[:5])}"
                         f"..., dimension {model.dimension}")
    state, k = state_at(traj, time)
    asked = "last sample" if time is None else f"nearest to t = {time:g} s"
    src = f"trajectory {path}, sample {k} at t = {float(traj.t[k]):.10g} s ({asked})"
    return assemble(model, state), src


# -- writing ------------------------------------------------------------------------------
def write_export(asm: Assembly | ExportedAssembly, path: str | os.PathLike[str],
                 known: Mapping[str, float] | None = None) -> Path:
    """Write an export; the format follows the suffix (.npz, .mat, .json). Atomic."""
    path = Path(path)
    fmt = SUFFIXES.get(path.suffix.lower())
    if fmt is None:
        raise MbodyError(f"{path}: unknown export format {path.suffix or '(no suffix)'!r}; "
                         "use a name ending in .npz, .mat or .json, or --csv DIR")
    exp = _as_export(asm, known)
    writer = {"npz": _write_npz, "mat": _write_mat, "json": _write_json}[fmt]
    with atomic_path(path) as tmp:
        writer(exp, tmp)
    return path


def _arrays(exp: ExportedAssembly) -> dict[str, Any]:
    """The flat, named arrays shared by npz and .mat (MATLAB-valid names)."""
    c = exp.columns
    out: dict[str, Any] = {
        "format": FORMAT, "version": VERSION, "model": exp.model, "model_file": exp.file,
        "dimension": exp.dimension, "t": exp.t, "state_source": exp.state_source,
        "equation": cv.EQUATION, "conventions_json": json.dumps(exp.conventions),
        "b": exp.b, "Q": exp.Q,
        "coordinates": exp.coordinates, "reactions": exp.reactions,
        "body_names": exp.body_names, "masses": exp.masses, "inertias": exp.inertias,
        "position": exp.state.position, "quaternion": exp.state.quaternion,
        "velocity": exp.state.velocity, "omega": exp.state.omega,
        "column_frame": c.W_e, "column_point": c.W_P, "column_known": c.known,
        "column_gamma": c.gamma, "column_phi": c.phi,
    }
    for k in COLUMN_TEXT[1:]:
        out[f"column_{k}"] = getattr(c, k)
    return out


def _write_npz(exp: ExportedAssembly, path: Path) -> None:
    arrs = _arrays(exp)
    for k in ("coordinates", "reactions", "body_names"):
        arrs[k] = _text(arrs[k])
    for name in ("M", "G"):
        A = getattr(exp, name)
        arrs.update({f"{name}_data": A.data, f"{name}_indices": A.indices,
                     f"{name}_indptr": A.indptr, f"{name}_shape": np.array(A.shape)})
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **{k: np.asarray(v) for k, v in arrs.items()})


def _cell(values) -> np.ndarray:
    """A MATLAB cell column of strings."""
    out = np.empty((len(values), 1), dtype=object)
    for i, v in enumerate(values):
        out[i, 0] = str(v)
    return out


def _write_mat(exp: ExportedAssembly, path: Path) -> None:
    import scipy.io

    arrs = _arrays(exp)
    for k in ("coordinates", "reactions", "body_names", *(f"column_{k}" for k in
                                                          COLUMN_TEXT[1:])):
        arrs[k] = _cell(arrs[k])
    arrs["M"], arrs["G"] = exp.M, exp.G
    # The conventions also as a MATLAB struct (lists as cells) for people reading it there.
    arrs["conventions"] = {k: (_cell(v) if isinstance(v, list) else v)
                           for k, v in exp.conventions.items()}
    scipy.io.savemat(path, arrs, oned_as="column", do_compression=True)


def _triplets(A: sp.csc_matrix) -> dict[str, Any]:
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
    return {
        "format": FORMAT, "version": VERSION,
        "model": {"name": exp.model, "file": exp.file, "dimension": exp.dimension},
        "state": {"t": exp.t, "source": exp.state_source},
        "conventions": exp.conventions,
        "coordinates": exp.coordinates, "reactions": exp.reactions,
        "bodies": bodies, "columns": exp.columns.records(),
        "M": _triplets(exp.M), "b": exp.b.tolist(), "Q": exp.Q.tolist(), "G": _triplets(exp.G),
    }


def _write_json(exp: ExportedAssembly, path: Path) -> None:
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(to_json(exp), fh, indent=1, allow_nan=False, ensure_ascii=False)
        fh.write("\n")


def schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of the JSON export, shipped with the package."""
    text = resources.files("mbody").joinpath("data/assembly.schema.json").read_text("utf-8")
    return json.loads(text)


# -- CSV ----------------------------------------------------------------------------------
def write_csv(asm: Assembly | ExportedAssembly, folder: str | os.PathLike[str],
              known: Mapping[str, float] | None = None) -> Path:
    """Write the export as CSV files in `folder` (created if needed).

    M.csv, G.csv: labelled dense tables (first column the coordinate label, header the
    column labels), or ``row,column,value`` triplets beyond `CSV_DENSE_LIMIT` cells;
    vectors.csv: coordinate, b, Q; columns.csv: one line per reaction column;
    bodies.csv: mass, inertia tensor and state per body; info.csv: model facts and the
    conventions (values JSON-encoded). All files are written to a temporary folder first
    and moved in only when every one is complete.
    """
    exp = _as_export(asm, known)
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise MbodyError(f"{folder}: exists and is not a folder")
    parent = folder.parent if str(folder.parent) else Path(".")
    parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=parent))
    os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp makes 0700; give what mkdir() would
    try:
        for name, rows in _csv_tables(exp).items():
            with open(tmp / name, "w", newline="", encoding="utf-8") as fh:
                csv.writer(fh, lineterminator="\n").writerows(rows)
        if not folder.exists():
            os.replace(tmp, folder)
        else:
            for f in sorted(tmp.iterdir()):
                os.replace(f, folder / f.name)
            tmp.rmdir()
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return folder


def _matrix_rows(A: sp.csc_matrix, rows: list[str], cols: list[str]):
    if A.shape[0] * A.shape[1] <= CSV_DENSE_LIMIT:
        yield ["coordinate", *cols]
        for label, r in zip(rows, A.toarray().tolist(), strict=True):
            yield [label, *r]
    else:
        yield ["row", "column", "value"]
        C = A.tocoo()
        for i, j, v in zip(C.row.tolist(), C.col.tolist(), C.data.tolist(), strict=True):
            yield [rows[i], cols[j], v]


def _csv_tables(exp: ExportedAssembly) -> dict[str, Any]:
    st, c = exp.state, exp.columns
    info = [["key", "value"], ["format", json.dumps(FORMAT)], ["version", json.dumps(VERSION)],
            ["model", json.dumps(exp.model)], ["model_file", json.dumps(exp.file)],
            ["dimension", json.dumps(exp.dimension)], ["t", json.dumps(exp.t)],
            ["state_source", json.dumps(exp.state_source)]]
    info += [[f"conventions.{k}", json.dumps(v)] for k, v in exp.conventions.items()]
    vectors = [["coordinate", "b", "Q"]] + [
        [lab, b, q] for lab, b, q in zip(exp.coordinates, exp.b.tolist(), exp.Q.tolist(),
                                         strict=True)]
    head = ["label", "joint", "type", "parent", "child", "component", "kind",
            "frame_x", "frame_y", "frame_z", "point_x", "point_y", "point_z", "known",
            "gamma", "phi", "sign"]
    columns = [head] + [
        [*(str(getattr(c, k)[i]) for k in COLUMN_TEXT[:-1]), *c.W_e[i].tolist(),
         *c.W_P[i].tolist(), "" if np.isnan(c.known[i]) else float(c.known[i]),
         float(c.gamma[i]), float(c.phi[i]), str(c.sign[i])]
        for i in range(len(c))]
    bhead = ["name", "mass", *(f"J{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)),
             "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "w1", "w2", "w3"]
    bodies = [bhead] + [
        [n, float(exp.masses[i]), *exp.inertias[i].ravel().tolist(),
         *st.position[i].tolist(), *st.quaternion[i].tolist(), *st.velocity[i].tolist(),
         *st.omega[i].tolist()] for i, n in enumerate(exp.body_names)]
    return {"info.csv": info, "vectors.csv": vectors, "columns.csv": columns,
            "bodies.csv": bodies,
            "M.csv": _matrix_rows(exp.M, exp.coordinates, exp.coordinates),
            "G.csv": _matrix_rows(exp.G, exp.coordinates, exp.reactions)}


# -- reading ------------------------------------------------------------------------------
def load_export(path: str | os.PathLike[str]) -> ExportedAssembly:
    """Reload any export (.npz, .mat, .json file, or a CSV folder) as an `ExportedAssembly`.

    Raises `MbodyError` for a missing, unreadable or foreign file.
    """
    path = Path(path)
    if path.is_dir():
        reader = _read_csv
    else:
        fmt = SUFFIXES.get(path.suffix.lower())
        if fmt is None:
            raise MbodyError(f"{path}: not an mbody export (expected .npz, .mat, .json or a "
                             "CSV folder)")
        if not path.exists():
            raise MbodyError(f"{path}: no such file")
        reader = {"npz": _read_npz, "mat": _read_mat, "json": _read_json}[fmt]
    try:
        return reader(path)
    except MbodyError:
        raise
    except (OSError, ValueError, KeyError, IndexError, TypeError) as exc:
        raise MbodyError(f"{path}: not a readable mbody export ({type(exc).__name__}: "
                         f"{exc})") from None


def _check_format(path: Path, fmt: str, version: int) -> None:
    if fmt != FORMAT:
        raise MbodyError(f"{path}: not an mbody export (format {fmt!r})")
    if version > VERSION:
        raise MbodyError(f"{path}: export format version {version} is newer than this mbody "
                         f"reads ({VERSION}); upgrade mbody")


def _build(path: Path, get, M: sp.spmatrix, G: sp.spmatrix) -> ExportedAssembly:
    """Assemble an `ExportedAssembly` from a reader's `get(name)` of the `_arrays` names."""
    _check_format(path, str(get("format")), int(get("version")))
    n = len(get("body_names"))
    m = len(get("reactions"))

    def vec(name, *shape):
        return np.asarray(get(name), dtype=float).reshape(shape)

    def txt(name):
        return np.array([str(s) for s in get(name)], dtype=str) if m else \
            np.zeros(0, dtype="<U1")

    columns = Columns(txt("reactions"), *(txt(f"column_{k}") for k in COLUMN_TEXT[1:]),
                      vec("column_frame", m, 3), vec("column_point", m, 3),
                      vec("column_known", m), vec("column_gamma", m), vec("column_phi", m))
    state = State(vec("position", n, 3), vec("quaternion", n, 4), vec("velocity", n, 3),
                  vec("omega", n, 3), float(get("t")))
    N = len(get("coordinates"))
    return ExportedAssembly(
        model=str(get("model")), file=str(get("model_file")), dimension=int(get("dimension")),
        state_source=str(get("state_source")),
        conventions=json.loads(str(get("conventions_json"))),
        coordinates=[str(s) for s in get("coordinates")],
        reactions=[str(s) for s in get("reactions")], columns=columns,
        body_names=[str(s) for s in get("body_names")], masses=vec("masses", n),
        inertias=vec("inertias", n, 3, 3), state=state,
        M=_canonical(M), b=vec("b", N), Q=vec("Q", N), G=_canonical(G))


def _read_npz(path: Path) -> ExportedAssembly:
    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}

    def get(k):
        v = data[k]
        return v.item() if v.ndim == 0 else v

    def mat(name):
        return sp.csc_matrix((data[f"{name}_data"], data[f"{name}_indices"],
                              data[f"{name}_indptr"]), shape=tuple(data[f"{name}_shape"]))

    return _build(path, get, mat("M"), mat("G"))


def _read_mat(path: Path) -> ExportedAssembly:
    import scipy.io

    data = scipy.io.loadmat(path, simplify_cells=False)

    def unstr(v) -> str:
        v = np.asarray(v)
        return str(v.ravel()[0]) if v.size else ""

    def get(k):
        v = data[k]
        if isinstance(v, np.ndarray) and v.dtype == object:  # a cell column of strings
            return [unstr(x) for x in v.ravel()]
        if isinstance(v, np.ndarray) and v.dtype.kind == "U":
            return unstr(v)
        v = np.asarray(v)
        return v.ravel()[0] if v.size == 1 and k in ("version", "dimension", "t") else v

    return _build(path, get, data["M"], data["G"])


def _read_json(path: Path) -> ExportedAssembly:
    with open(path, encoding="utf-8") as fh:
        d = json.load(fh)
    if not isinstance(d, dict):
        raise MbodyError(f"{path}: not an mbody export (not a JSON object)")
    _check_format(path, str(d.get("format")), int(d.get("version", 0)))
    return from_json(d, path)


def from_json(d: dict[str, Any], path: Path | str = "<json>") -> ExportedAssembly:
    """An `ExportedAssembly` from the JSON document `to_json` produces."""
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

    def mat(t):
        return sp.csc_matrix((t["value"], (t["row"], t["col"])), shape=tuple(t["shape"]))

    return _build(Path(path), flat.__getitem__, mat(d["M"]), mat(d["G"]))


def _read_csv(folder: Path) -> ExportedAssembly:
    def table(name) -> list[list[str]]:
        with open(folder / name, newline="", encoding="utf-8") as fh:
            return list(csv.reader(fh))

    info = {k: json.loads(v) for k, v in table("info.csv")[1:]}
    conventions = {k.split(".", 1)[1]: v for k, v in info.items()
                   if k.startswith("conventions.")}
    vectors = table("vectors.csv")[1:]
    coordinates = [r[0] for r in vectors]
    cols = table("columns.csv")[1:]
    bodies = table("bodies.csv")[1:]
    reactions = [r[0] for r in cols]

    def floats(rows, a, b):
        return np.array([[float(x) for x in r[a:b]] for r in rows], dtype=float).reshape(
            len(rows), b - a)

    def matrix(name, labels):
        rows = table(name)
        shape = (len(coordinates), len(labels))
        if rows and rows[0][:1] == ["row"]:
            ri = {s: i for i, s in enumerate(coordinates)}
            ci = {s: i for i, s in enumerate(labels)}
            r = [ri[x[0]] for x in rows[1:]]
            c = [ci[x[1]] for x in rows[1:]]
            return sp.csc_matrix(([float(x[2]) for x in rows[1:]], (r, c)), shape=shape)
        if rows[0][1:] != labels or [x[0] for x in rows[1:]] != coordinates:
            raise MbodyError(f"{folder / name}: its labels do not match vectors.csv and "
                             "columns.csv")
        return sp.csc_matrix(floats(rows[1:], 1, 1 + len(labels)).reshape(shape))

    flat: dict[str, Any] = dict(info)
    flat.update({
        "conventions_json": json.dumps(conventions), "coordinates": coordinates,
        "reactions": reactions, "b": floats(vectors, 1, 2), "Q": floats(vectors, 2, 3),
        "body_names": [r[0] for r in bodies], "masses": floats(bodies, 1, 2),
        "inertias": floats(bodies, 2, 11), "position": floats(bodies, 11, 14),
        "quaternion": floats(bodies, 14, 18), "velocity": floats(bodies, 18, 21),
        "omega": floats(bodies, 21, 24),
        "column_frame": floats(cols, 7, 10), "column_point": floats(cols, 10, 13),
        "column_known": [np.nan if r[13] == "" else float(r[13]) for r in cols],
        "column_gamma": [float(r[14]) for r in cols], "column_phi": [float(r[15]) for r in cols],
        "column_sign": [r[16] for r in cols],
    })
    for i, k in enumerate(COLUMN_TEXT[1:-1], start=1):
        flat[f"column_{k}"] = [r[i] for r in cols]
    return _build(folder, flat.__getitem__, matrix("M.csv", coordinates),
                  matrix("G.csv", reactions))
