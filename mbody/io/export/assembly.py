"""The in-memory export and what every format shares: `ExportedAssembly` (``M v̇ + b = Q +
G λ`` at one state with its labels), `exported` (collect it from an `Assembly`), the flat
named arrays of npz and .mat (`flat_arrays`) and the one constructor every reader ends in
(`build`), which checks the format tag and version.

Each format's module (`npz`, `mat`, `jsonfile`, `csvfolder`) holds its writer and its
reader and maps the file to and from these names; nothing here knows a file format.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import scipy.sparse as sp

from mbody import conventions as cv
from mbody import joint_types
from mbody.conventions import check_axes
from mbody.equations.assemble import Assembly, Solution
from mbody.equations.pack import pack_columns_model, pack_unknowns_of
from mbody.equations.solution import METHODS, singular_mass_error
from mbody.equations.world import world_map
from mbody.errors import MbodyError, not_found, wrong_type
from mbody.kernel import _core
from mbody.model.arguments import KnownValues
from mbody.model.model import Model, State
from mbody.simulate.run_file import FORMAT as TRAJECTORY_FORMAT
from mbody.util import jsontext
from mbody.util.formatting import number

FORMAT = "mbody-export"
"""The format tag every export carries; a reader refuses any other."""
GENERALIZED_FORMAT = "mbody-generalized"
"""The format tag of an export of the equations in generalized coordinates (`mbody
lagrange -o`, `mbody.io.export.generalized`): named here, where a reader of the other
exports tells it apart."""
VERSION = 2
"""The newest export layout this mbody writes and reads. Version 2 added the world-axes
map (`ExportedAssembly.T`, written when asked for); version 1 files read as before."""

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
                raise not_found("reaction column", i, [str(x) for x in self.labels],
                                "reaction columns")
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
        """Every column as `__getitem__` gives it, in column order."""
        return [self[i] for i in range(len(self))]


@dataclass(frozen=True, eq=False)
class ExportedAssembly:
    """``M v̇ + b = Q + G λ`` at one state, with its labels: what every export holds.

    Parameters
    ----------
    model, file
        The model's name and the file it was loaded from.
    dimension
        2 (planar) or 3 (spatial).
    state_source
        Where `state` came from (the initial state, or a trajectory sample).
    conventions
        `mbody.conventions.conventions` of the dimension: equation, row order, frames...
    coordinates
        (N,) row labels, e.g. ``"rod.x"``.
    reactions
        (m,) column labels of G, e.g. ``"O.Fx"``.
    columns
        Per-column joint data (`Columns`).
    body_names
        (n,) body names.
    masses
        (n,) kg.
    inertias
        (n, 3, 3) kg m^2, body axes about the mass centre (planar: I_G is entry [2, 2]).
    state
        The `State` the matrices were taken at (positions world, quaternions w first,
        velocities world, ω body axes; planar bodies in the x-y plane).
    M
        (N, N) scipy CSC mass matrix.
    b, Q
        (N,) gyroscopic and applied-force vectors.
    G
        (N, m) scipy CSC reaction coupling.
    world_reactions
        (p,) labels of the reactions in world axes (``O.Fx``...: each joint's force and
        moment on its child along world x, y, z, then the drivers' efforts;
        `mbody.equations.world`), when the export holds the map `T`; else empty.
    T
        (p, m) scipy CSC map from the joint-frame values λ (the columns of G, in the order
        of `reactions`) to the world-axes ones at this state, world = T λ; None when the
        export was not asked for world axes (``exported(asm, axes="world")``, ``mbody
        export --axes world``).
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
    world_reactions: list[str] = field(default_factory=list)
    T: sp.csc_matrix | None = None

    @property
    def t(self) -> float:
        """The time of the exported state (s)."""
        return float(self.state.t)

    @property
    def known(self) -> dict[str, float]:
        """The reaction values stored as known, by label (unknown ones are NaN on file)."""
        return {str(k): float(v) for k, v in zip(self.columns.labels, self.columns.known,
                                                  strict=True) if not np.isnan(v)}

    @property
    def shape(self) -> dict[str, tuple[int, ...]]:
        """The shape of M, b, Q, G (and T when the export holds it)."""
        N, m = len(self.coordinates), len(self.reactions)
        out: dict[str, tuple[int, ...]] = {"M": (N, N), "b": (N,), "Q": (N,), "G": (N, m)}
        if self.T is not None:
            out["T"] = (len(self.world_reactions), m)
        return out

    def __repr__(self) -> str:  # the dataclass's would print every matrix
        N, m = len(self.coordinates), len(self.reactions)
        world = "" if self.T is None else f", T {len(self.world_reactions)}x{m}"
        return (f"<ExportedAssembly of {self.model!r}: M {N}x{N}, G {N}x{m}{world}; state: "
                f"{self.state_source}; .solve(), .columns>")

    def solve(self, known: Mapping[str, float] | None = None, *,
              axes: str = "joint") -> Solution:
        """Accelerations, and the reaction components not given (stored values or `known`).

        Parameters
        ----------
        known
            Reaction values by label, added to (or replacing) the stored known values.
        axes
            The axes of the reactions returned: "joint" (the columns of G) or "world"
            (``T λ``, labelled by `world_reactions`: needs an export holding `T`).

        Returns
        -------
        Solution
            Accelerations aligned with `coordinates`, and every reaction's value.

        Raises
        ------
        MbodyError
            For a label of `known` that is no reaction of this export, or world axes asked
            of an export without `T`.

        Notes
        -----
        All known: v̇ = M⁻¹ (Q + G λ − b). Otherwise, with U the unknown components,
        ``[[M, −G_U], [G_Uᵀ, 0]] [v̇; λ_U] = [Q − b + G_K λ_K; γ_U]`` (the joints of the
        given components are not enforced), solved by the same constrained solver as
        `mbody.Assembly.solve` (the compiled core's, with the stored columns of G given
        to it), from the stored matrices alone: redundant constraints give the
        minimum-norm reactions, named.
        """
        check_axes(axes)
        if axes == "world" and self.T is None:
            raise MbodyError("this export holds no world-axes map (T): export the model "
                             "again with --axes world (exported(asm, axes='world'))")
        sol = self._solve(known)
        if axes == "world":
            assert self.T is not None
            lam = np.array([sol.reactions[r] for r in self.reactions], dtype=float)
            world = self.T @ lam
            sol = dataclasses.replace(sol, reactions=dict(zip(
                self.world_reactions, world.tolist(), strict=True)), axes="world")
        return sol

    def _solve(self, known: Mapping[str, float] | None) -> Solution:
        """The joint-frame solve (`solve`'s notes)."""
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
        U = np.flatnonzero(mask)
        mu = len(U)
        F, I = pack_columns_model(bodies.mass, bodies.J, bodies.J_inv, t.parent, t.child)
        core = _core.Model(F, I, self.dimension == cv.PLANAR)
        solver = _core.Unknowns(core, pack_unknowns_of(t.child, t.parent, bodies.n, U))
        out = np.empty(6 * bodies.n + 2 * mu + _core.INFO)
        solver.solve_given(r6, np.ascontiguousarray(cols.child6),
                           np.ascontiguousarray(cols.parent6),
                           np.ascontiguousarray(self.columns.gamma[U]), out)
        acc6 = out[:6 * bodies.n]
        info = out[6 * bodies.n + 2 * mu:]
        coords = list(self.coordinates)
        if info[_core.ST_SINGULAR]:
            code = int(info[_core.ST_SINGULAR]) - 1
            raise singular_mass_error(SimpleNamespace(body_names=self.body_names),
                                      code // 6, code % 6)
        lam[U] = out[6 * bodies.n:6 * bodies.n + mu]
        if not mu:
            return Solution(coords, acc6[rows],
                            dict(zip(self.reactions, lam.tolist(), strict=True)))
        flags = out[6 * bodies.n + mu:6 * bodies.n + 2 * mu]
        solved = tuple(self.reactions[k] for k in U.tolist())
        rank = int(info[_core.ST_RANK])
        return Solution(coords, acc6[rows],
                        dict(zip(self.reactions, lam.tolist(), strict=True)), solved,
                        tuple(self.reactions[k] for k, f in zip(U.tolist(), flags, strict=True)
                              if f and rank < mu),
                        float(info[_core.ST_BERR]), None, METHODS[int(info[_core.ST_PATH])],
                        (), mu - rank)

    def differences(self, other: ExportedAssembly) -> list[str]:
        """What differs from `other`, bit for bit.

        Parameters
        ----------
        other
            The export to compare with.

        Returns
        -------
        list of str
            The names of the fields that differ (``"M"``, ``"state.position"``,
            ``"columns.W_e"``...); empty when the two are identical.
        """
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
            if not _same_sparse(getattr(self, k), getattr(other, k)):
                out.append(k)
        for k in (*COLUMN_TEXT, "W_e", "W_P", "known", "gamma", "phi"):
            if not _same(getattr(self.columns, k), getattr(other.columns, k)):
                out.append(f"columns.{k}")
        if self.world_reactions != other.world_reactions:
            out.append("world_reactions")
        if (self.T is None) != (other.T is None) or (
                self.T is not None and other.T is not None and not _same_sparse(self.T, other.T)):
            out.append("T")
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


def _same_sparse(a: sp.csc_matrix, b: sp.csc_matrix) -> bool:
    return a.shape == b.shape and _same(a.data, b.data) and _same(a.indices, b.indices) \
        and _same(a.indptr, b.indptr)


def _canonical(A: sp.spmatrix) -> sp.csc_matrix:
    """CSC with sorted indices and no stored zeros: one representation per matrix."""
    C = sp.csc_matrix(A, dtype=float, copy=True)
    C.eliminate_zeros()
    C.sum_duplicates()
    C.sort_indices()
    C.indices = C.indices.astype(np.int64)
    C.indptr = C.indptr.astype(np.int64)
    return C


def text_array(values: Sequence[str]) -> np.ndarray:
    """(k,) numpy strings; an empty list still gives a string array (not float64)."""
    return np.array(values, dtype=str) if values else np.zeros(0, dtype="<U1")


def exported(asm: Assembly, known: KnownValues | None = None,
             state_source: str = "", axes: str = "joint") -> ExportedAssembly:
    """Collect the matrices, labels and per-column joint data of `asm` for export.

    Per column c with joint j: W_e[c] is the component's axis in world axes at
    `asm.state` (the joint frame is fixed to the parent), W_P[c] the joint point; + acts
    on j's child, − on its parent.

    Parameters
    ----------
    asm
        The assembly at the state to export.
    known
        Reaction values added to the model file's (labels are checked): numbers, or
        expressions of t as text taken at the state's time (`Assembly.reaction_values`).
    state_source
        Where the state came from; by default the model's initial state.
    axes
        "world" adds the map T from the joint-frame values to the world-axes ones at the
        state (`ExportedAssembly.T`, `mbody.equations.world.world_map`); "joint" (the
        default) leaves it out.

    Returns
    -------
    ExportedAssembly
        What every export format writes.

    Raises
    ------
    mbody.errors.MbodyTypeError
        `asm` is not an `Assembly` (a `Model` is assembled first: ``mbody.assemble(model)``).
    """
    if not isinstance(asm, Assembly):
        raise _not_an_assembly(asm, "an Assembly (mbody.assemble(model))")
    model: Model = asm.model
    values = asm.reaction_values(known)
    t = model.reaction_table
    cols = asm.columns
    jt = np.array([[j.name, j.type, j.parent, j.child] for j in model.joints],
                  dtype=str).reshape(-1, 4)
    per = jt[t.joint] if len(t.labels) else np.zeros((0, 4), dtype="<U1")
    labels = list(t.labels)
    component = [lab.split(".", 1)[1] for lab in labels]
    kind = np.array([joint_types.what(c) for c in component], dtype=str)
    sign = [f"+{lab} acts on {c} at the joint point, -{lab} on {p}"
            for lab, p, c in zip(labels, per[:, 2], per[:, 3], strict=True)]
    columns = Columns(
        text_array(labels), per[:, 0], per[:, 1], per[:, 2], per[:, 3], text_array(component),
        kind.astype(str) if len(labels) else np.zeros(0, dtype="<U1"), text_array(sign),
        np.array(cols.W_e, dtype=float).reshape(-1, 3),
        np.array(cols.W_P, dtype=float).reshape(-1, 3),
        np.array([values.get(lab, np.nan) for lab in labels], dtype=float),
        np.array(cols.gamma, dtype=float).reshape(-1),
        np.array(cols.phi, dtype=float).reshape(-1),
    )
    check_axes(axes)
    world: tuple[str, ...] = ()
    T = None
    if axes == "world":
        world, T = world_map(model, np.asarray(cols.W_e, dtype=float).reshape(-1, 3))
        T = _canonical(T)
    st = asm.state
    state = State(np.array(st.position, dtype=float), np.array(st.quaternion, dtype=float),
                  np.array(st.velocity, dtype=float), np.array(st.omega, dtype=float),
                  float(st.t))
    return ExportedAssembly(
        model=model.name, file=model.file, dimension=model.dimension,
        state_source=state_source or f"the model's initial state (t = {st.t:g} s)",
        conventions=cv.conventions(model.dimension),
        coordinates=list(asm.coordinates), reactions=labels, columns=columns,
        body_names=list(model.body_names), masses=np.array(model.mass, dtype=float),
        inertias=np.array(model.J, dtype=float), state=state,
        M=_canonical(asm.M), b=np.array(asm.b, dtype=float), Q=np.array(asm.Q, dtype=float),
        G=_canonical(asm.G), world_reactions=list(world), T=T,
    )


def as_export(obj: Assembly | ExportedAssembly, known: KnownValues | None = None,
              axes: str = "joint") -> ExportedAssembly:
    """`obj` itself when already exported, else ``exported(obj, known, axes=axes)``;
    `mbody.errors.MbodyTypeError` for anything else."""
    if isinstance(obj, ExportedAssembly):
        return obj
    if not isinstance(obj, Assembly):
        raise _not_an_assembly(obj, "an Assembly (mbody.assemble(model)) or an "
                               "ExportedAssembly (mbody.load_export(path))")
    return exported(obj, known, axes=axes)


def _not_an_assembly(obj: object, expected: str) -> MbodyError:
    """The error of an export asked of something else: how to get an assembly of it."""
    hint = ("assemble the model first: mbody.assemble(model), or "
            "mbody.assemble(model, state) at another state" if isinstance(obj, Model)
            else "load and assemble the model first: mbody.assemble(mbody.load(path))"
            if isinstance(obj, str | os.PathLike) else "")
    return wrong_type("asm", expected, obj, hint)


def flat_arrays(exp: ExportedAssembly) -> dict[str, Any]:
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
    if exp.T is not None:  # the map itself is each format's to write, as M and G are
        out["world_reactions"] = exp.world_reactions
    return out


MORE = "mbody.load_export(path, max_bytes=N) reads more"
"""How a larger export is read, for the readers' messages (`mbody.util.npzfile`)."""


@contextmanager
def unreadable(path: Path, what: str = "mbody export") -> Iterator[None]:
    """Within the block, reading the file `path`: an error that is not an `MbodyError`
    (an entry missing or of another kind, text that is not JSON, a file that cannot be
    read) becomes one naming the file, "not a readable `what`", and what went wrong."""
    try:
        yield
    except MbodyError:
        raise
    except (OSError, ValueError, KeyError, IndexError, TypeError) as exc:
        raise MbodyError(f"{path}: not a readable {what} ({type(exc).__name__}: {exc})"
                         ) from None


def check_shape(path: Path, what: str, shape: tuple[int, ...], want: tuple[int, int],
                of: str) -> None:
    """Refuse a matrix whose shape does not fit its labels (`of` says which), before it is
    built: a file's shape is a claim (a sparse matrix of 10^12 columns needs 8 TB for its
    column pointers alone)."""
    if tuple(shape) != want:
        raise MbodyError(f"{path}: {what} is {' x '.join(map(str, shape))}; expected "
                         f"{want[0]} x {want[1]} ({of})")


def check_sparse(path: Path | str, what: str, A: Any) -> None:
    """Refuse a sparse matrix read from a file whose structure is not one: its index
    arrays not whole numbers, a row index outside the matrix, column pointers that go
    back. scipy's compiled routines (`eliminate_zeros`, conversions, products) index
    memory with them unchecked: a crafted row index crashed the process (review R3).
    Anything else (a dense array) passes.

    Raises
    ------
    MbodyError
        Naming the file and the matrix `what`.
    """
    if not (sp.issparse(A) and A.format in ("csc", "csr")):
        return
    try:
        if A.indices.dtype.kind not in "iu" or A.indptr.dtype.kind not in "iu":
            raise ValueError(f"its index arrays hold {A.indices.dtype} and {A.indptr.dtype} "
                             "values, expected whole numbers")
        A.check_format(full_check=True)
    except ValueError as exc:
        raise MbodyError(f"{path}: the sparse matrix {what} is damaged ({exc})") from None


def check_map(path: Path, shape: tuple[int, ...], world: int, m: int) -> None:
    """Refuse a world-axes map T whose shape is not its `world` labels by the `m`
    reactions (a reader calls it before it makes T from a file's triplets, too)."""
    if tuple(shape) != (world, m):
        raise MbodyError(f"{path}: the world-axes map T is {'x'.join(map(str, shape))}; "
                         f"expected {world}x{m} (its labels by the reactions)")


def check_format(path: Path, fmt: str, version: int) -> None:
    """Refuse a file of another format (a saved run: how to read or export it), or of a
    newer layout than this mbody reads."""
    if fmt == TRAJECTORY_FORMAT:
        raise MbodyError(f"{path}: an mbody trajectory (a run saved by simulate or "
                         "kinematics), not an export; read it with mbody.Trajectory.load("
                         "path), or export one of its samples: mbody export MODEL --state "
                         "RUN --time T")
    if fmt == GENERALIZED_FORMAT:
        raise MbodyError(f"{path}: an export of the equations in generalized coordinates "
                         "(mbody lagrange -o), not of the stacked ones; read it with "
                         "mbody.io.export.generalized.read_generalized(path)")
    if fmt != FORMAT:
        raise MbodyError(f"{path}: not an mbody export (format {fmt!r})")
    if version > VERSION:
        raise MbodyError(f"{path}: export format version {number(version)} is newer than "
                         f"this mbody reads ({VERSION}); upgrade mbody")


def build(path: Path, get: Callable[[str], Any], M: sp.spmatrix | np.ndarray,
          G: sp.spmatrix | np.ndarray, T: sp.spmatrix | np.ndarray | None = None
          ) -> ExportedAssembly:
    """An `ExportedAssembly` from a reader's view of a file.

    Parameters
    ----------
    path
        The file or folder read (for messages).
    get
        ``get(name)`` returns the value stored under a `flat_arrays` name (scalars as
        scalars, label lists as sequences of strings, numbers as array-likes).
    M, G
        The two matrices, in any sparse or dense form (stored canonically as CSC).
    T
        The world-axes map when the file holds one (version 2 on; its labels under
        ``world_reactions``), else None (every version 1 file).

    Raises
    ------
    MbodyError
        When the format tag is not `FORMAT` or the version is newer than `VERSION`, or
        the map's shape does not fit its labels and the reactions.
    """
    version = int(get("version"))
    check_format(path, str(get("format")), version)
    for what, A in (("M", M), ("G", G), ("T", T)):
        check_sparse(path, what, A)
    n = len(get("body_names"))
    m = len(get("reactions"))
    N = len(get("coordinates"))
    check_shape(path, "M", M.shape, (N, N), "the coordinates by the coordinates")
    check_shape(path, "G", G.shape, (N, m), "the coordinates by the reactions")
    world: list[str] = []
    if T is not None:
        if version < 2:
            raise MbodyError(f"{path}: a version {version} export holds no world-axes map, "
                             "yet this one has one (an edited file?)")
        world = [str(s) for s in get("world_reactions")]
        check_map(path, tuple(T.shape), len(world), m)

    def vec(name: str, *shape: int) -> np.ndarray:
        return np.asarray(get(name), dtype=float).reshape(shape)

    def txt(name: str) -> np.ndarray:
        return text_array([str(s) for s in get(name)])

    columns = Columns(txt("reactions"), txt("column_joint"), txt("column_type"),
                      txt("column_parent"), txt("column_child"), txt("column_component"),
                      txt("column_kind"), txt("column_sign"),
                      vec("column_frame", m, 3), vec("column_point", m, 3),
                      vec("column_known", m), vec("column_gamma", m), vec("column_phi", m))
    state = State(vec("position", n, 3), vec("quaternion", n, 4), vec("velocity", n, 3),
                  vec("omega", n, 3), float(get("t")))
    return ExportedAssembly(
        model=str(get("model")), file=str(get("model_file")), dimension=int(get("dimension")),
        state_source=str(get("state_source")),
        conventions=jsontext.loads(str(get("conventions_json"))),
        coordinates=[str(s) for s in get("coordinates")],
        reactions=[str(s) for s in get("reactions")], columns=columns,
        body_names=[str(s) for s in get("body_names")], masses=vec("masses", n),
        inertias=vec("inertias", n, 3, 3), state=state,
        M=_canonical(M), b=vec("b", N), Q=vec("Q", N), G=_canonical(G),
        world_reactions=world, T=None if T is None else _canonical(T))


