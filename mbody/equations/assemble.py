"""``assemble(model, state) -> Assembly``: the stacked Newton-Euler equations

    M v̇ + b = Q + G λ

with, per body in file order, Newton rows (world axes) then Euler rows (body axes).
M is block diagonal and constant in body axes, so the assembly keeps its blocks (the
model's masses and inertia tensors) and builds the sparse matrix only when asked for.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping, Sequence
from functools import cached_property
from typing import TYPE_CHECKING, TypeVar

import numpy as np

from mbody import conventions as cv
from mbody.equations.constraints import ConstraintJacobian
from mbody.equations.fbd import body_equations
from mbody.equations.generalized import Generalized, generalized
from mbody.equations.joints import ReactionColumns, g_matrix, joint_errors, reaction_columns
from mbody.equations.loads import AppliedLoads, wrench_parts
from mbody.equations.solution import (
    INCONSISTENT,
    METHODS,
    ReactionValues,
    Solution,
    plain_solution,
    singular_mass_error,
    solution,
)
from mbody.equations.symbolic import SymbolicEquations, assembly_symbolic
from mbody.equations.workspace import (
    NOT_UNIQUE_KEPT,
    SolvePlan,
    Unknowns,
    Workspace,
    workspace,
)
from mbody.equations.world import world_reactions
from mbody.errors import MbodyError, not_found
from mbody.kernel import _core
from mbody.model.arguments import KnownValues, checked_model, checked_state, known_at
from mbody.model.model import Model, State, count

if TYPE_CHECKING:
    import scipy.sparse as sp

    from mbody.equations.fbd import BodyEquations

__all__ = ["INCONSISTENT", "Assembly", "ReactionValues", "Solution", "assemble", "mass_matrix",
           "singular_mass_error", "solve_state"]


def _select(model: Model, a6: np.ndarray) -> np.ndarray:
    """(n, 6) per-body rows -> flat stacked vector in the model's coordinates."""
    if model.dimension == cv.SPATIAL:
        return _strip(model, a6.reshape(-1))
    return _strip(model, a6[:, cv.PLANAR_SELECT].reshape(-1))


def _strip(model: Model, full: np.ndarray) -> np.ndarray:
    """The solver's uniform rows (`all_coordinates`) -> the model's `coordinates` (a
    particle's rotation rows, which carry nothing, dropped)."""
    return full[model.rows] if model.has_particles else full


def mass_matrix(model: Model) -> sp.spmatrix:
    """Block-diagonal M as a BSR matrix over the (n, 6, 6) (planar (n, 3, 3)) blocks.

    Built from index arrays (block i at block row and column i), never from a list of
    per-body matrices; `Assembly.M` builds it only when first asked for.
    """
    import scipy.sparse as sp

    n = model.n
    k = model.rows_per_body
    blocks = np.zeros((n, k, k))
    if model.dimension == cv.PLANAR:
        blocks[:, 0, 0] = blocks[:, 1, 1] = model.mass
        blocks[:, 2, 2] = model.J[:, 2, 2]
    else:
        blocks[:, [0, 1, 2], [0, 1, 2]] = model.mass[:, None]
        blocks[:, 3:, 3:] = model.J
    M = sp.bsr_matrix((blocks, np.arange(n), np.arange(n + 1)), shape=(n * k, n * k))
    if model.has_particles:  # a particle's rows are its translations only
        M = M.tocsr()[model.rows][:, model.rows]
    return M


class Assembly:
    """The stacked equations of a model at one state.

    M: (N, N) sparse block-diagonal mass matrix; b: (N,) gyroscopic vector; Q: (N,)
    applied generalised forces; G: (N, m) sparse reaction coupling. N = 3 n (planar) or
    6 n (spatial); m = number of reaction unknowns. `coordinates` labels the rows,
    `reactions` the columns of G. `bodies[name]` gives one body's free-body data and
    its Newton-Euler pair. Made by `assemble`; nothing is computed until asked for.

    Parameters
    ----------
    model : Model
        The model whose equations these are.
    state : State
        The state they are written at: positions, orientations, velocities and the time
        (load values and known reactions that vary in time are taken at ``state.t``).
    """

    def __init__(self, model: Model, state: State):
        self.model = model
        self.state = state

    def __repr__(self) -> str:
        model = self.model
        unknown = len(workspace(model).unknowns_at(self.state.t).U) if model.reactions else 0
        return (f"<Assembly of {model.name!r} at t = {self.state.t:g} s: "
                f"{count(model.n, 'body', 'bodies')}, "
                f"{count(len(model.reactions), 'reaction component')} ({unknown} unknown); "
                ".solve(), .bodies[name], .M, .b, .Q, .G>")

    @cached_property
    def _loads_and_b6(self) -> tuple[AppliedLoads, np.ndarray]:
        """Q and b per body from the compiled core: (AppliedLoads with Q6 (6, n) rows
        [W_F; B_M], b6 (n, 6) [0; ω × J ω]) (planar: b = 0)."""
        Q6, b6 = wrench_parts(self.model, self.state)
        if self.model.dimension == cv.PLANAR:
            b6[:] = 0.0  # a planar body turns about its principal axis z: ω × J ω = 0
        return AppliedLoads(self.model, self.state, Q6.T), b6

    @property
    def loads(self) -> AppliedLoads:
        """Net applied loads per body (and, for diagrams, each load's contribution)."""
        return self._loads_and_b6[0]

    @property
    def _Q6(self) -> np.ndarray:
        return self._loads_and_b6[0].Q6.T

    @property
    def _b6(self) -> np.ndarray:
        return self._loads_and_b6[1]

    # -- the stacked system ------------------------------------------------------------
    @property
    def coordinates(self) -> list[str]:
        """Row labels of M, b, Q and G, body by body (``rod.x``, ``rod.w1``...)."""
        return self.model.coordinates

    @property
    def reactions(self) -> list[str]:
        """Column labels of G: every reaction component (``A.Fx``...), known or not."""
        return self.model.reactions

    @property
    def known(self) -> dict[str, float]:
        """Reaction values given in the model file."""
        return dict(self.model.known_reactions)

    # M, b, Q and G cannot be written to: `solve` and `generalized` work from the model and
    # state, not from these arrays, so an edit in place would change what an export of
    # this assembly holds but not its solution (a "what if" goes through `known=` or
    # `Model.with_values`)
    @cached_property
    def M(self) -> sp.spmatrix:
        """(N, N) block-diagonal mass matrix, sparse: m I (kg), then J (body axes, kg m^2).
        Read-only."""
        return _readonly(mass_matrix(self.model))

    @cached_property
    def b(self) -> np.ndarray:
        """(N,) gyroscopic vector: 0 on Newton rows, ω × J ω on Euler rows (N m).
        Read-only."""
        return _readonly(_select(self.model, self._b6))

    @cached_property
    def Q(self) -> np.ndarray:
        """(N,) applied generalised forces: net force (world axes, N), moment about G (body
        axes, N m). Read-only."""
        return _readonly(_select(self.model, self._Q6))

    @cached_property
    def columns(self) -> ReactionColumns:
        """Each reaction component's direction, point and per-body wrench at this state."""
        return reaction_columns(self.model, self.state)

    @cached_property
    def G(self) -> sp.csc_matrix:
        """(N, m) sparse reaction coupling: column c is the wrench of reaction c per unit.
        Read-only."""
        G = g_matrix(self.model, self.columns)
        return _readonly(G[self.model.rows] if self.model.has_particles else G)

    def jacobian(self) -> ConstraintJacobian:
        """The constraint Jacobian Gᵀ (m x N) with labelled rows and columns, plus γ and φ.

        Returns
        -------
        ConstraintJacobian
            Gᵀ (sparse CSR) with rows labelled by `reactions` and columns by `coordinates`;
            γ, the acceleration-level right-hand side, and φ, the position-level errors.
        """
        cols = self.columns
        return ConstraintJacobian(self.G.T.tocsr(), list(self.reactions),
                                  list(self.coordinates), cols.gamma, cols.phi)

    @property
    def shape(self) -> dict[str, tuple[int, ...]]:
        """The shapes of M, b, Q and G by name, without building them."""
        N, m = len(self.coordinates), len(self.reactions)
        return {"M": (N, N), "b": (N,), "Q": (N,), "G": (N, m)}

    # -- per body ----------------------------------------------------------------------
    @cached_property
    def bodies(self) -> Mapping[str, BodyEquations]:
        """name -> `BodyEquations` (free body and Newton-Euler pair), built on first access."""
        return _LazyBodies(self, body_equations)

    def symbolic(self, bodies: list[str] | None = None) -> SymbolicEquations:
        """Every body's Newton-Euler pair with symbols instead of numbers (m, I_G or I_1,
        w_1, loads by name, reaction labels), as text and LaTeX; needs sympy.

        Parameters
        ----------
        bodies : list of str, optional
            Only these bodies (default: all, in stacking order).

        Returns
        -------
        SymbolicEquations
            ``text()``, ``latex()``, ``document()``; each body's ``evaluate()`` gives back
            its rows of M, b, Q and G (see `mbody.equations.symbolic`).
        """
        return assembly_symbolic(self, bodies)

    def generalized(self, coordinates: Sequence[str] | None = None,
                    known: KnownValues | None = None, *,
                    progress: bool = False) -> Generalized:
        """The equations in generalized coordinates, ``M_q q'' = f_q``: these equations
        multiplied by Tᵀ, where v = T q' + v_e, which removes the reactions
        (`mbody.equations.generalized`).

        Parameters
        ----------
        coordinates : sequence of str, optional
            One coordinate per degree of freedom by label (``O.angle``, ``P.displacement``,
            a body's ``rod.theta``...); default: each driver's coordinate, a spanning
            tree's joint coordinates, then a free body's own.
        known : mapping of str to float or str, optional
            Reaction values applied as loads (their joints not held), added to the file's:
            numbers, or expressions of t as text taken at ``state.t`` (`reaction_values`).
        progress : bool
            Say on standard error what is being computed, once it has taken a second
            (`mbody.util.progress`).

        Returns
        -------
        Generalized
            ``M``, ``f``, ``T``, ``q``, ``qdot``, ``accelerations()``, ``symbolic()``.
        """
        return generalized(self.model, self.state, coordinates, known, progress=progress)

    # -- solving -----------------------------------------------------------------------
    def reaction_values(self, known: KnownValues | None = None) -> dict[str, float]:
        """The file's known reaction values updated with `known`; labels are checked.

        Parameters
        ----------
        known : mapping of str to float or str, optional
            Reaction values (N; N m) by label, overriding or adding to the file's: numbers,
            or expressions of t as text (``"2*t"``, docs/expressions.md), taken at
            ``state.t`` as the file's are.

        Returns
        -------
        dict of str to float
            label -> value of every known reaction component, at ``state.t``.

        Raises
        ------
        MbodyError
            `known` is not a mapping (`MbodyTypeError`), a label is not a reaction
            component of the model, or a value is not a finite number or an expression
            finite at ``state.t``.
        """
        if known is None:
            return self.model.known_reactions_at(self.state.t)
        return known_at(self.model, known, self.state.t)

    def solve(self, known: KnownValues | None = None, *,
              condition: bool = False, axes: str = "joint") -> Solution:
        """Accelerations, and the reactions not given (from the file or `known`).

        With every reaction known (or none): v̇ = M⁻¹ (Q + G λ − b). Otherwise the
        Newton-Euler pairs and the joint constraints are solved together,
        ``M v̇ − G_U λ_U = Q − b + G_K λ_K``, ``G_Uᵀ v̇ = γ_U`` (the compiled core: `solve_state`);
        the joints of known components are not enforced.

        Parameters
        ----------
        known : mapping of str to float or str, optional
            Reaction values (N; N m) by label, added to the file's; the rest are solved.
            A value is a finite number, or an expression of t as text (``"2*t"``), taken
            at ``state.t`` (`reaction_values`).
        condition : bool
            Also compute the 1-norm condition number of the Schur complement Gᵀ M⁻¹ G
            (`Solution.condition`).
        axes : {"joint", "world"}
            The axes of the reactions returned: each joint's frame (components as labelled,
            the default), or world axes (each joint's force and moment on its child,
            ``A.Fx, A.Fy...`` along world x, y, z: `mbody.equations.world`).

        Returns
        -------
        Solution
            The accelerations in the order of `coordinates`, every reaction value, and
            what the solve found (redundant or broken constraints, backward error).
        """
        ws = workspace(self.model)
        if not known and axes == "joint":  # the usual call: the file's unknowns
            return _solve(ws, ws.file_plan, self.model, self.state, ws.file_unknowns,
                          condition, self._columns)
        if axes not in ("joint", "world"):
            raise MbodyError(f"axes must be 'joint' or 'world', got {axes!r}")
        unknowns = (ws.unknowns(self.reaction_values(known)) if known
                    else ws.unknowns_at(self.state.t))
        sol = _solve(ws, ws.solve_plan(unknowns), self.model, self.state, unknowns,
                     condition, self._columns)
        if axes == "world":
            sol = dataclasses.replace(sol, reactions=world_reactions(
                self.model, self.columns, sol.reactions), axes="world")
        return sol

    def _columns(self) -> ReactionColumns:  # what solve_state asks for when it needs them
        return self.columns

    def _repr_html_(self) -> str:  # notebook display: each body's free body and pair
        from mbody.present.rich import assembly_html  # a display hook (tools/check_imports.py)

        return assembly_html(self)

    def _repr_latex_(self) -> str:  # the stacked system as display math
        from mbody.present.rich import assembly_latex  # a display hook (tools/check_imports.py)

        return assembly_latex(self)


class _LazyBodies(Mapping[str, "BodyEquations"]):
    """name -> BodyEquations, built on first access (presentation, not the hot path)."""

    def __init__(self, asm: Assembly, build: Callable[[Assembly, int], BodyEquations]):
        self._asm, self._build = asm, build
        self._cache: dict[str, BodyEquations] = {}

    def __getitem__(self, name: str) -> BodyEquations:
        if name not in self._cache:
            if name not in self._asm.model.index:
                raise not_found("body named", name, self._asm.model.body_names, "bodies")
            self._cache[name] = self._build(self._asm, self._asm.model.index[name])
        return self._cache[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._asm.model.body_names)

    def __len__(self) -> int:
        return self._asm.model.n

    def __repr__(self) -> str:  # a Mapping's default names only its class
        names = list(self._asm.model.body_names)
        shown = ", ".join(repr(b) for b in names[:6]) + (", ..." if len(names) > 6 else "")
        return f"<bodies of {self._asm.model.name!r}: {shown}; [name] -> BodyEquations>"


def solve_state(model: Model, state: State, unknowns: Unknowns, *, condition: bool = False,
                columns: Callable[[], ReactionColumns] | None = None) -> Solution:
    """The accelerations and the unknown reactions at `state`, by the compiled core:
    ``M v̇ − G_U λ_U = Q − b + G_K λ_K``, ``G_Uᵀ v̇ = γ_U`` (the Schur complement
    S = G_Uᵀ M⁻¹ G_U by banded Cholesky; exactly redundant joints by a pivoted Cholesky
    with the minimum-norm reactions; near a singular position the null-space solve on
    the joints' geometry). `columns` gives the reaction columns at `state` when a broken
    joint must be described or a large S's condition estimated (made only then)."""
    ws = workspace(model)
    return _solve(ws, ws.solve_plan(unknowns), model, state, unknowns, condition, columns)


def _solve(ws: Workspace, plan: SolvePlan, model: Model, state: State, unknowns: Unknowns,
           condition: bool, columns: Callable[[], ReactionColumns] | None) -> Solution:
    """`solve_state` with the workspace and the plan in hand. The hot path of every small
    solve: each line costs a tenth of a microsecond or so, so the plain case (full rank,
    nothing broken, no condition asked for) reads what it needs from the plan and builds
    the `Solution` from the plan's constant fields."""
    (solver, N, o_lam, o_info, labels, rows, size, m, mu, reactions, index, fields,
     patterns) = plan
    out = np.empty(size)
    info = solver.solve(state.t, ws.pack_state(state), unknowns.lam, out)
    acc = out[:N] if rows is None else out[:N][rows]
    values = ReactionValues(reactions, index, out[o_lam:o_lam + m])
    if not mu:
        return solution(model.coordinates, acc, values)
    rank, berr, n_broken, _, path, singular = info
    if singular:
        code = singular - 1
        raise singular_mass_error(model, code // 6, code % 6)
    if not n_broken and not condition:
        if rank == mu:
            return plain_solution(fields, acc, values, berr, METHODS[path])
        key = out[o_lam + 2 * m:o_info].tobytes()  # the not-unique flags
        shared = patterns.get(key)
        if shared is None:
            shared = tuple(reactions[i] for i in np.flatnonzero(out[o_lam + 2 * m:o_info]))
            if len(patterns) < NOT_UNIQUE_KEPT:
                patterns[key] = shared
        return plain_solution(fields, acc, values, berr, METHODS[path], shared,
                              mu - rank)
    broken: tuple[str, ...] = ()
    if n_broken > 0:  # rare: describe the broken joints
        cols = columns() if columns is not None else reaction_columns(model, state)
        broken = tuple(joint_errors(model, state, cols, unknowns.mask,
                                    gtv=out[o_lam + m:o_lam + 2 * m]))
    not_unique: tuple[str, ...] = ()
    if rank < mu:
        flags = out[o_lam + 2 * m:o_info]
        not_unique = tuple(reactions[i] for i in np.flatnonzero(flags))
    cond = None
    if condition:
        cond = _condition(model, state, unknowns, solver, ws.pack_state(state), rank,
                          columns)
    return solution(model.coordinates, acc, values, solved=labels, not_unique=not_unique,
                    residual=berr, condition=cond, method=METHODS[path],
                    broken_joints=broken, redundant=mu - rank)


DENSE_CONDITION = 200
"""Up to this many unknown components the condition of S is computed from S itself
(formed dense by the core, inverted: O(mu³), 2 s at 2000); above, estimated (Hager and
Higham's 1-norm estimator on the sparse S and its LU factors, M⁻¹ G made block by block:
linear in the bodies; on chains of 100 to 8000 links it gave the exact figure to 6
digits)."""


def _condition(model: Model, state: State, unknowns: Unknowns, solver: _core.Unknowns,
               y: np.ndarray, rank: int, columns: Callable[[], ReactionColumns] | None
               ) -> float:
    """The 1-norm condition number of S = G_Uᵀ M⁻¹ G_U (inf when redundant constraints
    make it singular)."""
    mu = len(unknowns.U)
    if rank < mu:
        return float("inf")
    if mu <= DENSE_CONDITION:
        S = np.empty((mu, mu))
        solver.schur(float(state.t), y, S)
        return float(np.linalg.cond(S, 1))
    import scipy.sparse.linalg as spla

    cols = columns() if columns is not None else reaction_columns(model, state)
    G = g_matrix(model, cols).tocsc()[:, unknowns.U]  # the model's uniform rows
    # M is block diagonal: M⁻¹ G has G's pattern, made in O(nnz)
    Minv_G = (mass_inverse(model) @ G).tocsc()
    if model.has_particles:  # a particle's rows are its translations only
        G, Minv_G = G[model.rows], Minv_G[model.rows]
    S = (G.T @ Minv_G).tocsc()
    lu = spla.splu(S)
    inverse = spla.LinearOperator(S.shape, matvec=lu.solve,
                                  rmatvec=lambda r: lu.solve(r, trans="T"), dtype=float)
    return float(spla.onenormest(S) * spla.onenormest(inverse))


def mass_inverse(model: Model) -> sp.bsr_matrix:
    """M⁻¹ over the uniform rows, block by block: 1/m on the translations, J⁻¹ (planar
    1/J_zz) on the rotations; 0 on a particle's rotations, which are not among the rows
    (`Model.rows`) that M⁻¹ G is taken on."""
    import scipy.sparse as sp

    n, k = model.n, model.rows_per_body
    blocks = np.zeros((n, k, k))
    body = ~np.asarray(model.particle, dtype=bool)
    if model.dimension == cv.PLANAR:
        blocks[:, 0, 0] = blocks[:, 1, 1] = 1.0 / model.mass
        blocks[body, 2, 2] = 1.0 / model.J[body, 2, 2]
    else:
        blocks[:, [0, 1, 2], [0, 1, 2]] = (1.0 / model.mass)[:, None]
        blocks[body, 3:, 3:] = np.linalg.inv(model.J[body])
    return sp.bsr_matrix((blocks, np.arange(n), np.arange(n + 1)), shape=(n * k, n * k))


def assemble(model: Model, state: State | None = None) -> Assembly:
    """The stacked Newton-Euler equations of `model` at `state` (default: its initial state).

    Nothing is computed until asked for: `solve()`, `Q`, `b`, `G`, `M`, `bodies`.

    Parameters
    ----------
    model : Model
        The model, from `load` or `loads` (a file's path is refused: read it with
        ``mbody.load(path)`` first, so that one model serves many calls).
    state : State, optional
        Positions, orientations, velocities and time to write the equations at (default
        ``model.initial``, the file's initial state).

    Returns
    -------
    Assembly
        The equations ``M v̇ + b = Q + G λ`` at that state.

    Raises
    ------
    MbodyError
        `model` is not a `Model`, or `state` not a `State` (`MbodyTypeError`, also a
        `TypeError`); a state of another number of bodies, or with values that are not
        finite (`mbody.model.arguments.checked_state`).
    """
    if not isinstance(model, Model):
        model = checked_model(model)
    if state is None:
        return Assembly(model, model.initial)
    return Assembly(model, checked_state(model, state, "state"))


_Array = TypeVar("_Array")


def _readonly(a: _Array) -> _Array:
    """`a` with its numbers (a compressed sparse matrix's data and structure) made
    read-only."""
    parts = (a,) if isinstance(a, np.ndarray) else (a.data, a.indices, a.indptr)  # type: ignore[attr-defined]
    for part in parts:
        part.flags.writeable = False
    return a
