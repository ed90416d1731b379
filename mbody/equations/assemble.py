"""``assemble(model, state) -> Assembly``: the stacked Newton-Euler equations

    M v̇ + b = Q + G λ

with, per body in file order, Newton rows (world axes) then Euler rows (body axes).
M is block diagonal and constant in body axes, so the assembly keeps its blocks (the
model's masses and inertia tensors) and builds the sparse matrix only when asked for.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.equations import kernels
from mbody.equations.constraints import ConstraintJacobian, gamma, joint_errors, phi
from mbody.equations.fbd import body_equations
from mbody.equations.joints import (
    ReactionColumns,
    constraint_velocity,
    g_matrix,
    reaction_columns,
    reaction_wrench,
)
from mbody.equations.loads import AppliedLoads
from mbody.equations.plan import Unknowns, compiled
from mbody.equations.spatial import matvec
from mbody.equations.symbolic import SymbolicEquations, assembly_symbolic
from mbody.errors import MbodyError, did_you_mean
from mbody.model.model import Model, State, count
from mbody.solve.kkt import ConstrainedSystem, singular_mass_error

if TYPE_CHECKING:
    import scipy.sparse as sp

    from mbody.equations.constraints import ConstraintJacobian
    from mbody.equations.fbd import BodyEquations


def _select(model: Model, a6: np.ndarray) -> np.ndarray:
    """(n, 6) per-body rows -> flat stacked vector in the model's coordinates."""
    if model.dimension == cv.SPATIAL:
        return _strip(model, a6.reshape(-1))
    return _strip(model, a6[:, cv.PLANAR_SELECT].reshape(-1))


def _strip(model: Model, full: np.ndarray) -> np.ndarray:
    """The solver's uniform rows (`all_coordinates`) -> the model's `coordinates` (a
    particle's rotation rows, which carry nothing, dropped)."""
    return full[model.rows] if model.has_particles else full


def accelerations6(model: Model, rhs6: np.ndarray) -> np.ndarray:
    """Block solve of M v̇ = rhs: (n, 6) -> (n, 6) [a_G (world), ω̇ (body axes)]."""
    out = np.empty_like(rhs6)
    out[:, :3] = rhs6[:, :3] / model.mass[:, None]
    out[:, 3:] = matvec(model.J_inv, rhs6[:, 3:])
    return out


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


class ReactionValues(Mapping):
    """label -> value of every reaction component (N, or N m for moments), a read-only
    view of one array in the order of `Assembly.reactions` (made lazily: a chain of
    10 000 links has 30 000 of them). `array` is that array."""

    def __init__(self, labels: list[str], index: dict[str, int], values: np.ndarray):
        self._labels, self._index, self.array = labels, index, values
        self.array.flags.writeable = False

    def __getitem__(self, label: str) -> float:
        return float(self.array[self._index[label]])

    def __iter__(self):
        return iter(self._labels)

    def __len__(self) -> int:
        return len(self._labels)

    def __repr__(self) -> str:  # a dict's when short; a chain's 30 000 values are not
        full = repr(dict(self)) if len(self) <= 12 else ""
        if full and len(full) < 300:
            return full
        return (f"<ReactionValues: {len(self)} components (N; N m), "
                f"{', '.join(self._labels[:4])}, ...; [label], dict(it), .array>")


INCONSISTENT = 1e-8
"""Relative backward error above which a constrained solve is reported as inconsistent."""


@dataclass(frozen=True)
class Solution:
    """Accelerations (aligned with `coordinates`) and the reaction values used.

    What `Assembly.solve` returns; ``solution["rod.w1"]`` reads one acceleration by its
    coordinate label.

    Parameters
    ----------
    coordinates : list of str
        The row labels, body by body (``Assembly.coordinates``).
    accelerations : (N,) array
        v̇ in the order of `coordinates`. Spatial rows: a_G in world axes (m/s^2), then
        ω̇ in body axes (rad/s^2); planar rows: a_x, a_y (m/s^2), α (rad/s^2).
    reactions : mapping of str to float
        label -> value of every reaction component, given or solved (N; N m).
    solved : tuple of str
        Reaction components solved for (the rest were given).
    not_unique : tuple of str
        Solved components that redundant constraints leave undetermined (minimum norm).
    residual : float or None
        Relative backward error of the constrained solve (None when nothing was solved).
    condition : float or None
        1-norm condition estimate of the Schur complement Gᵀ M⁻¹ G (when asked for).
    method : str
        How the system was solved (``"block-diagonal M"`` when no reaction was unknown).
    broken_joints : tuple of str
        Enforced constraints that the state breaks (φ ≠ 0 or Gᵀ v ≠ 0), as text.
    redundant : int
        Number of redundant constraints (unknown components minus the rank of G_U).
    """

    coordinates: list[str]
    accelerations: np.ndarray
    reactions: Mapping[str, float]
    solved: tuple[str, ...] = ()
    not_unique: tuple[str, ...] = ()
    residual: float | None = None
    condition: float | None = None
    method: str = "block-diagonal M"
    broken_joints: tuple[str, ...] = ()
    redundant: int = 0

    @property
    def warnings(self) -> list[str]:
        """What looks wrong with this solve, as sentences (empty when nothing does)."""
        out = []
        if self.not_unique:
            out.append(f"{self.redundant} redundant constraint(s): the reactions "
                       f"{', '.join(self.not_unique)} share that indeterminacy and are not "
                       "unique; the minimum-norm values are given")
        if self.broken_joints:
            out.append(f"the state breaks joint constraints: {', '.join(self.broken_joints)}"
                       "; the joints hold only from a state that respects them (positions "
                       "and velocities)")
        if self.residual is not None and self.residual > INCONSISTENT:
            out.append(f"the constraints are inconsistent at this state (relative residual "
                       f"{self.residual:.1e}): the joints are not assembled, or the velocities "
                       "break them; the least-squares accelerations are given")
        return out

    def as_dict(self) -> dict[str, float]:
        """The accelerations by coordinate label.

        Returns
        -------
        dict of str to float
            ``{coordinate: acceleration}`` in stacking order (m/s^2 or rad/s^2).
        """
        return dict(zip(self.coordinates, self.accelerations.tolist(), strict=True))

    def __getitem__(self, label: str) -> float:
        try:
            return float(self.accelerations[self.coordinates.index(label)])
        except ValueError:
            raise KeyError(f"no coordinate {label!r}; "
                           f"{did_you_mean(label, self.coordinates)}") from None

    def __repr__(self) -> str:  # the dataclass's would print every value
        return (f"<Solution: {count(len(self.coordinates), 'acceleration')}, "
                f"{count(len(self.reactions), 'reaction component')} ({len(self.solved)} solved)"
                + (f", {len(self.warnings)} warning(s)" if self.warnings else "")
                + "; sol[label], .as_dict(), .reactions, .warnings>")

    def _repr_html_(self) -> str:  # notebook display: accelerations and reactions by body
        from mbody.present.rich import solution_html  # a display hook (tools/check_imports.py)

        return solution_html(self)


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
        unknown = len(model.plan.unknowns_at(self.state.t).U) if model.reactions else 0
        return (f"<Assembly of {model.name!r} at t = {self.state.t:g} s: "
                f"{count(model.n, 'body', 'bodies')}, "
                f"{count(len(model.reactions), 'reaction component')} ({unknown} unknown); "
                ".solve(), .bodies[name], .M, .b, .Q, .G>")

    @cached_property
    def _loads_and_b6(self) -> tuple[AppliedLoads, np.ndarray]:
        """Q and b per body, from the numpy kernels: (AppliedLoads with Q6 (6, n) rows
        [W_F; B_M], b6 (n, 6) [0; ω × J ω]) (planar: b = 0)."""
        model, state = self.model, self.state
        plan = model.plan.kernels
        frame = model.plan.load_frame(state.t)
        sparse = kernels.sparse_wrench(plan, [
            kernels.load_wrenches(model, plan, frame, state),
            kernels.spring_wrenches(model, state)])
        Q6 = np.empty((6, model.n))
        b6 = np.zeros((6, model.n))  # rows 0-2 (Newton) stay 0; planar: all 0
        kernels.loads_and_gyroscopic(plan, frame, state, sparse, Q6,
                                     b6[3:6] if model.dimension == cv.SPATIAL else None)
        # (n, 6) transposed views of the kernels' (6, n) layout
        return AppliedLoads(model, state, Q6), b6.T

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

    @cached_property
    def M(self) -> sp.spmatrix:
        """(N, N) block-diagonal mass matrix, sparse: m I (kg), then J (body axes, kg m^2)."""
        return mass_matrix(self.model)

    @cached_property
    def b(self) -> np.ndarray:
        """(N,) gyroscopic vector: 0 on Newton rows, ω × J ω on Euler rows (N m)."""
        return _select(self.model, self._b6)

    @cached_property
    def Q(self) -> np.ndarray:
        """(N,) applied generalised forces: net force (world axes, N), moment about G (body
        axes, N m)."""
        return _select(self.model, self._Q6)

    @cached_property
    def columns(self) -> ReactionColumns:
        """Each reaction component's direction, point and per-body wrench at this state."""
        return reaction_columns(self.model, self.state)

    @cached_property
    def G(self) -> sp.csc_matrix:
        """(N, m) sparse reaction coupling: column c is the wrench of reaction c per unit."""
        G = g_matrix(self.model, self.columns)
        return G[self.model.rows] if self.model.has_particles else G

    def jacobian(self) -> ConstraintJacobian:
        """The constraint Jacobian Gᵀ (m x N) with labelled rows and columns, plus γ and φ.

        Returns
        -------
        ConstraintJacobian
            Gᵀ (sparse CSR) with rows labelled by `reactions` and columns by `coordinates`;
            γ, the acceleration-level right-hand side, and φ, the position-level errors.
        """
        return ConstraintJacobian(self.G.T.tocsr(), list(self.reactions),
                                  list(self.coordinates),
                                  gamma(self.model, self.state, self.columns),
                                  phi(self.model, self.state))

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

    # -- solving -----------------------------------------------------------------------
    def reaction_values(self, known: Mapping[str, float] | None = None) -> dict[str, float]:
        """The file's known reaction values updated with `known`; labels are checked.

        Parameters
        ----------
        known : mapping of str to float, optional
            Reaction values (N; N m) by label, overriding or adding to the file's.

        Returns
        -------
        dict of str to float
            label -> value of every known reaction component, at ``state.t``.

        Raises
        ------
        MbodyError
            A label of `known` is not a reaction component of the model.
        """
        values = self.model.known_reactions_at(self.state.t)
        labels = self.model.reaction_index
        for label, v in (known or {}).items():
            if label not in labels:
                hint = did_you_mean(label, self.reactions)
                raise MbodyError(f"no reaction component {label!r} in this model"
                                 + (f"; {hint}" if hint else ""))
            values[label] = float(v)
        return values

    def solve(self, known: Mapping[str, float] | None = None, *,
              condition: bool = False) -> Solution:
        """Accelerations, and the reactions not given (from the file or `known`).

        With every reaction known (or none): v̇ = M⁻¹ (Q + G λ − b). Otherwise the
        Newton-Euler pairs and the joint constraints are solved together,
        ``M v̇ − G_U λ_U = Q − b + G_K λ_K``, ``G_Uᵀ v̇ = γ_U`` (see `mbody.solve.kkt`);
        the joints of known components are not enforced.

        Parameters
        ----------
        known : mapping of str to float, optional
            Reaction values (N; N m) by label, added to the file's; the rest are solved.
        condition : bool
            Also estimate the 1-norm condition number of the Schur complement Gᵀ M⁻¹ G
            (`Solution.condition`; takes the numpy path).

        Returns
        -------
        Solution
            The accelerations in the order of `coordinates`, every reaction value, and
            what the solve found (redundant or broken constraints, backward error).
        """
        model = self.model
        plan = model.plan
        unknowns = (plan.unknowns(self.reaction_values(known)) if known
                    else plan.unknowns_at(self.state.t))
        if not condition and plan.use_compiled():
            return self._solve_compiled(unknowns)
        if len(unknowns.U):
            return self._solve_constrained(unknowns, condition)
        lam = unknowns.lam
        extra = None
        if len(lam):  # G λ, summed per body on the kernels' sparse path
            rt, cols = model.reaction_table, self.columns
            extra = kernels.sparse_wrench(plan.kernels, [
                (np.concatenate((rt.child, rt.parent)),
                 np.concatenate((cols.child6 * lam[:, None], cols.parent6 * lam[:, None])))])
        acc6 = np.empty((model.n, 6))
        kernels.solve(plan.kernels, self._Q6.T, self._b6.T[3:6], extra, acc6.T)
        return Solution(self.coordinates, _select(model, acc6),
                        dict(zip(self.reactions, lam.tolist(), strict=True)))

    def _solve_compiled(self, unknowns: Unknowns) -> Solution:
        """The compiled path (`mbody.solve.compiled`), the same solve as `_solve_constrained`."""
        model, plan, state = self.model, self.model.plan, self.state
        C = compiled()
        F, I = plan.packed
        m = len(unknowns.mask)
        N, o_lam, o_info = C.solve_layout(model.n, m, model.dimension == cv.PLANAR)
        out = np.empty(o_info + C.INFO)
        C.solve(F, I, plan.packed_unknowns(unknowns), plan.pack_state(state),
                plan.load_values(state.t), unknowns.lam, model.dimension == cv.PLANAR, out)
        info = out[o_info:]
        labels = self.reactions
        lam = out[o_lam:o_lam + m]
        if not len(unknowns.U):
            return Solution(self.coordinates, _strip(model, out[:N]),
                            dict(zip(labels, lam.tolist(),
                                                                strict=True)))
        if info[C.ST_SINGULAR]:
            code = int(info[C.ST_SINGULAR]) - 1
            raise singular_mass_error(model, code // 6, code % 6)
        broken: tuple[str, ...] = ()
        if info[C.ST_BROKEN] > 0:  # rare: describe the broken joints with the numpy path
            broken = tuple(joint_errors(model, state, self.columns, unknowns.mask,
                                        gtv=out[o_lam + m:o_lam + 2 * m]))
        mu, rank = len(unknowns.U), int(info[C.ST_RANK])
        not_unique: tuple[str, ...] = ()
        if rank < mu:
            flags = out[o_lam + 2 * m:o_info]
            not_unique = tuple(labels[i] for i in np.flatnonzero(flags))
        return Solution(self.coordinates, _strip(model, out[:N]),
                        ReactionValues(labels, model.reaction_index, lam),
                        unknowns.labels(labels), not_unique, float(info[C.ST_BERR]), None,
                        COMPILED_METHODS[int(info[C.ST_PATH])], broken,
                        mu - rank)

    def constrained(self, unknowns: Unknowns, *, rate: float = 0.0, refine: bool = True):
        """The numpy path's constrained solve.

        Parameters
        ----------
        unknowns : Unknowns
            Which reaction components are solved for, and the values λ of the others.
        rate : float
            Baumgarte's α (1/s): > 0 adds his terms to γ (γ − 2 α Gᵀ v − α² φ,
            `mbody.simulate.mechanism`); 0 leaves γ as it is.
        refine : bool
            Make one round of iterative refinement when the backward error asks for it.

        Returns
        -------
        tuple
            (v̇ (n, 6) rows [a_G (world axes, m/s^2), ω̇ (body axes, rad/s^2)], λ (m,) every
            reaction value (N; N m), the `ConstrainedSystem`, the backward error or None
            when `refine` is False).
        """
        model, state, cols = self.model, self.state, self.columns
        lam = unknowns.lam.copy()
        r6 = self._Q6 - self._b6 + reaction_wrench(model, cols, lam)
        system = ConstrainedSystem(model, cols, unknowns)
        g = gamma(model, state, cols)
        stab_U = None
        if rate:
            stab = (-2.0 * rate * constraint_velocity(model, cols, state)
                    - rate * rate * phi(model, state, cols=cols))
            g = g + stab
            stab_U = stab if unknowns.every else stab[unknowns.U]
        g_U = g if unknowns.every else g[unknowns.U]
        berr = None
        if refine:
            acc6, lam_U, berr = system.solve_refined(r6, g_U)
        else:
            acc6, lam_U = system.solve(r6, g_U, stab_U)
        lam[unknowns.U] = lam_U
        return acc6, lam, system, berr

    def _solve_constrained(self, unknowns: Unknowns, condition: bool) -> Solution:

        model = self.model
        acc6, lam, system, berr = self.constrained(unknowns)
        labels = self.reactions
        solved = unknowns.labels(labels)
        return Solution(self.coordinates, _select(model, acc6),
                        ReactionValues(labels, model.reaction_index, lam), solved,
                        tuple(solved[k] for k in system.fact.redundant if k >= 0),
                        berr,
                        system.fact.condition() if condition else None,
                        system.fact.method,
                        tuple(joint_errors(model, self.state, self.columns, unknowns.mask,
                                           gtv=constraint_velocity(model, self.columns,
                                                                   self.state))),
                        system.fact.size - system.fact.rank)

    def _repr_html_(self) -> str:  # notebook display: each body's free body and pair
        from mbody.present.rich import assembly_html  # a display hook (tools/check_imports.py)

        return assembly_html(self)

    def _repr_latex_(self) -> str:  # the stacked system as display math
        from mbody.present.rich import assembly_latex  # a display hook (tools/check_imports.py)

        return assembly_latex(self)


COMPILED_METHOD = "banded Cholesky of the Schur complement (compiled)"
COMPILED_NULL_SPACE = ("null-space solve on the joints' geometry (SVD of the scaled G_U; "
                       "compiled)")
COMPILED_REDUNDANT = ("pivoted Cholesky of the Schur complement, minimum-norm reactions "
                      "(redundant constraints; compiled)")
COMPILED_METHODS = (COMPILED_METHOD, COMPILED_NULL_SPACE, COMPILED_REDUNDANT)
"""The compiled solve's method by its path (info slot ST_PATH)."""


class _LazyBodies(Mapping[str, "BodyEquations"]):
    """name -> BodyEquations, built on first access (presentation, not the hot path)."""

    def __init__(self, asm: Assembly, build: Callable[[Assembly, int], BodyEquations]):
        self._asm, self._build = asm, build
        self._cache: dict[str, BodyEquations] = {}

    def __getitem__(self, name: str) -> BodyEquations:
        if name not in self._cache:
            if name not in self._asm.model.index:
                hint = did_you_mean(name, self._asm.model.body_names)
                raise KeyError(f"no body named {name!r}" + (f"; {hint}" if hint else ""))
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


def assemble(model: Model, state: State | None = None) -> Assembly:
    """The stacked Newton-Euler equations of `model` at `state` (default: its initial state).

    Nothing is computed until asked for: `solve()`, `Q`, `b`, `G`, `M`, `bodies`.

    Parameters
    ----------
    model : Model
        The model, from `load` or `loads`.
    state : State, optional
        Positions, orientations, velocities and time to write the equations at (default
        ``model.initial``, the file's initial state).

    Returns
    -------
    Assembly
        The equations ``M v̇ + b = Q + G λ`` at that state.
    """
    return Assembly(model, model.initial if state is None else state)

