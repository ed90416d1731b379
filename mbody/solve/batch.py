"""Many states at once: one model solved at K states in one call of the compiled core
(`mbody.kernel`: ``Unknowns.solve_many``, a loop over the states inside C writing a (K, ...)
output), and at many values of the same structure (a `mbody.solve.family.Family`: each
case's packed F given with the states, the structure and its unknowns packed once).

    sols = mbody.solve_many(model, states)                       # one model, K states
    sols = mbody.solve_many(model, values=[{"bodies.rod.mass": m} for m in masses])

Each state's numbers are those of ``mbody.assemble(model, state).solve()`` (the same C
function on the same input: tests compare them), with the file's known reaction values.
`Evaluator` is the layer the sweep uses: the packed arrays in, the core's outputs out.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mbody.equations.solution import METHODS, ReactionValues, Solution, singular_mass_error
from mbody.equations.workspace import workspace
from mbody.errors import MbodyError, MbodyTypeError, not_found, wrong_type
from mbody.kernel import _core
from mbody.model.arguments import checked_model, checked_state
from mbody.model.model import Model, State
from mbody.solve.family import Family
from mbody.solve.kinematics import CLOSE_RTOL, NEWTON_STEPS, _size

ROBUST_BELOW = 1e-2
"""The geometric ratio below which a kinematic step takes the null-space route (as
`mbody.solve.kinematics.kinematics`)."""
CLOSED = 1e3 * CLOSE_RTOL
"""A kinematic analysis whose largest position error (relative to the model's size;
angles absolute) is above this has not closed its loops (`kinematics`' own test)."""


class Evaluator:
    """A model's compiled solves for packed states in bulk.

    `solve` gives the core's solve output of each state (``_core.solve_layout``); with
    ``F`` and ``rows``, state k is evaluated with the values F[rows[k]] of a model of the
    same structure (`Family`). `kinematics` moves states onto every joint and driver.

    Parameters
    ----------
    model : Model
        The model (its file's known reaction values are the solves' given values).
    """

    def __init__(self, model: Model):
        self.model = model
        ws = self.ws = workspace(model)
        self.unknowns = ws.file_unknowns
        self.plan = ws.solve_plan(self.unknowns)
        self.every = ws.solver(ws.unknowns({}))
        self.N, self.o_lam, self.o_info = self.plan.N, self.plan.o_lam, self.plan.o_info
        self.width = self.o_info + _core.INFO
        self.m = len(model.reactions)
        self.size = _size(model)
        self.phi_scale = np.ascontiguousarray(
            np.where(model.reaction_table.is_moment, 1.0, self.size), dtype=float)
        self.state_size = ws.state_size
        self.fully_driven = int(self.every.generic_rank) == len(model.coordinates)
        """The joints and drivers fix every motion: positions and velocities follow from
        them alone (not from masses or loads)."""
        drivers = model.drivers
        self.needs_assembly = bool(len(model.reactions)) and (
            (drivers is not None and len(drivers) > 0)
            or bool(model.joint_table.body_points.any()))
        """`mbody.load` moves the bodies onto their joints at t = 0 (`assembled`)."""

    def solve(self, t: np.ndarray, Y: np.ndarray, F: np.ndarray | None = None,
              rows: np.ndarray | None = None, states: np.ndarray | None = None,
              out: np.ndarray | None = None) -> np.ndarray:
        """(K, width) the core's solve output at each state (t (K,), Y (K, 13 n or the
        full state size); with `states` (K,), state k is Y[states[k]]); into `out`'s
        first K rows when given (a buffer kept between calls)."""
        t = np.ascontiguousarray(t, dtype=float)
        if out is None or len(out) < len(t):
            out = np.empty((len(t), self.width))
        out = out[:len(t)]
        self.plan.solver.solve_many(t, np.ascontiguousarray(Y, dtype=float),
                                    self.unknowns.lam, out, _f(F), _rows(rows),
                                    _rows(states))
        return out

    def peaks(self, t: np.ndarray, Y: np.ndarray, states: np.ndarray, segment: int,
              F: np.ndarray | None = None, rows: np.ndarray | None = None) -> np.ndarray:
        """The solves of `solve` folded per segment of `segment` consecutive states:
        (K / segment, m + 1) the largest |value| of each reaction component over the
        segment, then the first singular code of its states (0: none). States as `solve`
        with `states` (Y[states[k]])."""
        out = np.empty((len(t) // segment, self.m + 1))
        self.plan.solver.peaks_many(np.ascontiguousarray(t, dtype=float),
                                    np.ascontiguousarray(Y, dtype=float),
                                    self.unknowns.lam, out, _f(F), _rows(rows),
                                    np.ascontiguousarray(states, dtype=np.int64), segment)
        return out

    def kinematics(self, t: np.ndarray, Y: np.ndarray, F: np.ndarray | None = None,
                   rows: np.ndarray | None = None, chain: np.ndarray | None = None, *,
                   fast: bool = False, predict: bool = False) -> np.ndarray:
        """Move each row of Y (K, full state size; C-contiguous, in place) onto every joint
        and driver at t[k] (`mbody.solve.kinematics.kinematics`: fast=False takes its steps
        exactly; fast=True, for a fully driven mechanism, Newton steps to the position
        then one velocity projection). chain (K,): 1 where a row starts from the previous
        row's result (moved along its velocities when `predict`). Returns (K, KN_INFO):
        steps, the largest position error (relative), singular code, the last step."""
        if not (Y.flags.c_contiguous and Y.dtype == float):
            raise ValueError("Y: expected a C-contiguous float64 array")
        t = np.ascontiguousarray(t, dtype=float)
        info = np.empty((len(t), _core.KN_INFO))
        settings = np.array([NEWTON_STEPS, CLOSE_RTOL * self.size, CLOSE_RTOL, ROBUST_BELOW,
                             float(fast), float(predict)])
        ch = None if chain is None else np.ascontiguousarray(chain, dtype=np.int64)
        self.every.kinematics_many(t, Y, _f(F), _rows(rows), ch, self.phi_scale, settings,
                                   info)
        return info

    def assemble(self, starts: np.ndarray, F: np.ndarray | None = None,
                 rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The states at t = 0 that `mbody.load` gives (`assembled`): starts (C, full
        state size), the file's states. Returns (the states, whether each closed)."""
        Y = np.array(starts, dtype=float, order="C", copy=True)
        if not self.needs_assembly:
            return Y, np.ones(len(Y), dtype=bool)
        info = self.kinematics(np.zeros(len(Y)), Y, F, rows)
        return Y, closed(info)

    def solution(self, out: np.ndarray, t: float = 0.0) -> Solution:
        """One state's `Solution` from its row of `solve`'s output (as
        `mbody.equations.assemble.solve_state` makes it)."""
        model = self.model
        acc = out[:self.N] if self.plan.rows is None else out[:self.N][self.plan.rows]
        m = self.m
        lam = out[self.o_lam:self.o_lam + m].copy()
        reactions = ReactionValues(model.reactions, model.reaction_index, lam)
        mu = len(self.unknowns.U)
        if not mu:
            return Solution(model.coordinates, acc.copy(), reactions)
        info = out[self.o_info:]
        if info[_core.ST_SINGULAR]:
            code = int(info[_core.ST_SINGULAR]) - 1
            raise singular_mass_error(model, code // 6, code % 6)
        rank = int(info[_core.ST_RANK])
        flags = out[self.o_lam + 2 * m:self.o_info]
        not_unique = tuple(model.reactions[i] for i in np.flatnonzero(flags)) if rank < mu \
            else ()
        return Solution(model.coordinates, acc.copy(), reactions, self.plan.labels,
                        not_unique, float(info[_core.ST_BERR]), None,
                        METHODS[int(info[_core.ST_PATH])], (), mu - rank)


def closed(info: np.ndarray) -> np.ndarray:
    """(K,) whether each row of `Evaluator.kinematics` closed every joint and driver."""
    return (info[:, _core.KN_SINGULAR] == 0) & (info[:, _core.KN_ERROR] <= CLOSED)


def _f(F: np.ndarray | None) -> np.ndarray | None:
    return None if F is None else np.ascontiguousarray(F, dtype=float)


def _rows(rows: np.ndarray | None) -> np.ndarray | None:
    return None if rows is None else np.ascontiguousarray(rows, dtype=np.int64)


@dataclass(frozen=True)
class Solutions:
    """The solves of one model at K states (what `solve_many` returns).

    Parameters
    ----------
    coordinates : list of str
        The acceleration labels (``Assembly.coordinates``).
    reactions : list of str
        The reaction labels (``Assembly.reactions``), the columns of `values`.
    t : (K,) array
        Each state's time (s).
    accelerations : (K, N) array
        v̇ per state, in the order of `coordinates` (m/s², rad/s²); NaN where it failed.
    values : (K, m) array
        Every reaction value per state, given or solved (N; N m); NaN where it failed.
    residual : (K,) array
        The relative backward error of each constrained solve (0 when nothing was solved).
    redundant : (K,) int array
        Redundant constraints at each state (their reactions are not unique).
    broken : (K,) int array
        Enforced constraints each state breaks (it is off its joints).
    errors : tuple of (str or None)
        Why a state has no solution (values refused, a motion without mass), else None.
    """

    coordinates: list[str]
    reactions: list[str]
    t: np.ndarray
    accelerations: np.ndarray
    values: np.ndarray
    residual: np.ndarray
    redundant: np.ndarray
    broken: np.ndarray
    errors: tuple[str | None, ...]

    def __len__(self) -> int:
        return len(self.t)

    def reaction(self, label: str) -> np.ndarray:
        """(K,) one reaction component at every state.

        Parameters
        ----------
        label : str
            A reaction label (``A.Fx``, ``motor.M``).

        Returns
        -------
        (K,) array
        """
        if label not in self.reactions:
            raise not_found("reaction", label, self.reactions, "reactions")
        return self.values[:, self.reactions.index(label)]

    def __repr__(self) -> str:
        bad = sum(e is not None for e in self.errors)
        return (f"<Solutions at {len(self)} states: {len(self.coordinates)} accelerations, "
                f"{len(self.reactions)} reaction components each"
                + (f", {bad} failed" if bad else "") + "; .accelerations, .values, "
                ".reaction(label), .errors>")


def solve_many(model: Model, states: Sequence[State] | State | None = None, *,
               values: Sequence[Mapping[str, Any]] | None = None) -> Solutions:
    """Accelerations and reactions of `model` at many states, in one call of the core.

    Parameters
    ----------
    model : Model
        The model.
    states : sequence of State, or State, optional
        Where to solve (each at its own ``t``). Default: the model's initial state, or,
        with `values`, each case's own initial state (as `mbody.load` would give it).
    values : sequence of mappings, optional
        One set of values per case (``{"bodies.rod.mass": 2.0}``: `Model.with_values`'
        paths): each state solved with its case's values; states and values pair up
        (or one state serves every case). Cases of the same structure share it: their
        values are packed without reading the file again (`mbody.solve.family`).

    Returns
    -------
    Solutions
        Per state: the accelerations and every reaction value, as
        ``mbody.assemble(case_model, state).solve()`` gives them (joint-frame axes).

    Raises
    ------
    MbodyError
        States and values of different lengths; a state of another model's size or with
        values that are not finite (`mbody.model.arguments.checked_state`, naming it as
        ``states[k]``).
    mbody.errors.MbodyTypeError
        `states` of the wrong type; `values` not a list of mappings (one mapping alone
        is one case: ``values=[{...}]``).
    """
    if not isinstance(model, Model):
        model = checked_model(model)
    if isinstance(states, State):
        states = [states]
    elif states is not None and not isinstance(states, Sequence):
        raise MbodyTypeError(f"states must be a State or a sequence of them, got "
                             f"{type(states).__name__}")
    if values is None:
        ev = Evaluator(model)
        states = [model.initial] if states is None else list(states)
        t, Y = _packed(ev, states)
        return _solutions(ev, t, ev.solve(t, Y), [None] * len(t))
    values = case_values(values)
    if states is not None and len(states) not in (1, len(values)):
        raise MbodyError(f"{len(states)} states for {len(values)} sets of values: give one "
                         "state, or one per set")
    paths = list(dict.fromkeys(p for v in values for p in v))
    family = Family(model, paths)
    cases = family.cases(values)
    ev = Evaluator(model)
    K = len(values)
    out = np.full((K, ev.width), np.nan)
    t = np.zeros(K)
    errors: list[str | None] = [c.error for c in cases]
    shared = [k for k, c in enumerate(cases) if c.shared]
    if shared:
        F = np.stack([cases[k].F for k in shared])  # type: ignore[misc]
        rows = np.arange(len(shared))
        if states is None:
            Y, ok = ev.assemble(np.stack([cases[k].start for k in shared]),  # type: ignore[misc]
                                F, rows)
            for j in np.flatnonzero(~ok):
                errors[shared[j]] = _not_assembled(model, values[shared[j]])
            tk = np.zeros(len(shared))
        else:
            tk, Y = _packed(ev, [states[k if len(states) > 1 else 0] for k in shared])
        out[shared] = ev.solve(tk, Y, F, rows)
        t[shared] = tk
    for k, c in enumerate(cases):
        if c.model is None:
            continue
        own = Evaluator(c.model)  # a structure of its own
        if own.width != ev.width:
            errors[k] = ("these values change the model's sizes (bodies, reaction "
                         "components); solve it on its own: model.with_values(...)")
            continue
        st = [c.model.initial] if states is None else [states[k if len(states) > 1 else 0]]
        tk, Y = _packed(own, st)
        out[k] = own.solve(tk, Y)[0]
        t[k] = tk[0]
    for k, e in enumerate(errors):
        if e is not None:
            out[k] = np.nan
    return _solutions(ev, t, out, errors)


def case_values(values: object) -> list[dict[str, Any]]:
    """`solve_many`'s `values` as a list of dicts, one per case; `MbodyTypeError` naming
    the argument (or the case) that is not what it takes."""
    form = "a list of mappings, one per case (path -> value)"
    if isinstance(values, Mapping):
        raise wrong_type("values", form, values, "for one case, a list of one: values=[{...}]")
    if isinstance(values, str | bytes) or not isinstance(values, Iterable):
        raise wrong_type("values", form, values)
    out = []
    for k, v in enumerate(values):
        if not isinstance(v, Mapping):
            raise wrong_type(f"values[{k}]", "a mapping path -> value, such as "
                             "{'bodies.rod.mass': 2.0}", v)
        out.append(dict(v))
    return out


def _not_assembled(model: Model, values: Mapping[str, Any]) -> str:
    """The message of a case whose joints do not close at t = 0: `mbody.load`'s own."""
    try:
        model.with_values(values)
    except MbodyError as exc:
        return str(exc)
    return "the joints and drivers do not close at t = 0 with these values"


def _packed(ev: Evaluator, states: Sequence[State]) -> tuple[np.ndarray, np.ndarray]:
    n = ev.model.n
    for k, s in enumerate(states):
        checked_state(ev.model, s, f"states[{k}]")
    Y = np.stack([ev.ws.pack_state(s) for s in states]) if states else np.zeros((0, 13 * n))
    return np.array([float(s.t) for s in states]), Y


def _solutions(ev: Evaluator, t: np.ndarray, out: np.ndarray,
               errors: list[str | None]) -> Solutions:
    model = ev.model
    acc = out[:, :ev.N]
    if ev.plan.rows is not None:
        acc = acc[:, ev.plan.rows]
    info = out[:, ev.o_info:]
    errors = list(errors)
    for k in np.flatnonzero(np.nan_to_num(info[:, _core.ST_SINGULAR]) > 0):
        if errors[k] is None:
            code = int(info[k, _core.ST_SINGULAR]) - 1
            errors[k] = str(singular_mass_error(model, code // 6, code % 6))
    mu = len(ev.unknowns.U)
    rank = np.nan_to_num(info[:, _core.ST_RANK], nan=mu)
    return Solutions(model.coordinates, model.reactions, t, acc.copy(),
                     out[:, ev.o_lam:ev.o_lam + ev.m].copy(),
                     np.nan_to_num(info[:, _core.ST_BERR]),
                     (mu - rank).astype(int) if mu else np.zeros(len(t), int),
                     np.nan_to_num(info[:, _core.ST_BROKEN]).astype(int), tuple(errors))


