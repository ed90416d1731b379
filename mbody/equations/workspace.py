"""What evaluating a model needs, made once per model and kept apart from it.

As Pinocchio keeps a robot's `Model` (what it is) apart from its `Data` (scratch and
results of evaluations), a `Model` here holds only what the file says, and its
`Workspace` holds the model packed for the compiled core (`mbody.kernel`,
`mbody.equations.pack`): the core's model object, and per set of unknown reaction
components the core's `Unknowns` with its scratch memory. Every evaluation goes through
the one compiled core, whatever the model's size and however many calls came before.

`workspace(model)` makes it on first use and keeps it while the model lives (a weak
reference: it goes with the model).
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from mbody import conventions as cv
from mbody.equations.pack import pack_model, pack_unknowns
from mbody.equations.solution import solution_fields
from mbody.kernel import _core
from mbody.util.spatial import quaternion_rate

if TYPE_CHECKING:
    from mbody.model.model import Model, State


@dataclass(frozen=True, eq=False)
class Unknowns:
    """A set of unknown reaction components and the given values of the others.

    mask: (m,) True where unknown; U: (mu,) their columns (the order of the solve);
    lam: (m,) the given values, 0 on the unknown components; key: bytes of mask.
    """

    mask: np.ndarray
    U: np.ndarray
    lam: np.ndarray
    key: bytes

    @property
    def every(self) -> bool:
        """Every component is unknown (no masked copies needed)."""
        return len(self.U) == len(self.mask)

    def labels(self, labels: list[str]) -> tuple[str, ...]:
        """The unknown components' labels, in label order (`labels` = model.reactions)."""
        if self.every:
            return tuple(labels)
        return tuple(map(labels.__getitem__, self.U.tolist()))


class SolvePlan(NamedTuple):
    """One set of unknowns' solve, laid out: the core's solver; where `Unknowns.solve`
    writes (N accelerations, λ at o_lam, info at o_info); the unknowns' labels; the rows
    a model with particles keeps (None: all); and what every solve with them reads
    besides the state, looked up once: the length of the output (size), the number of
    reaction components (m) and of unknown ones (mu), the model's reaction labels and
    their index, the constant fields of a plain solve's `Solution` (`fields`:
    `mbody.equations.solution.solution_fields`), and the labels of the components that
    redundant constraints leave undetermined, by the core's flags (bytes; filled as met,
    up to `NOT_UNIQUE_KEPT` patterns: a mechanism redundant by its structure has one)."""

    solver: _core.Unknowns
    N: int
    o_lam: int
    o_info: int
    labels: tuple[str, ...]
    rows: np.ndarray | None
    size: int
    m: int
    mu: int
    reactions: list[str]
    reaction_index: dict[str, int]
    fields: dict[str, object]
    not_unique: dict[bytes, tuple[str, ...]]


NOT_UNIQUE_KEPT = 64
"""Patterns of not-unique reactions a plan keeps (`SolvePlan.not_unique`)."""


class Workspace:
    """A model packed for the compiled core, and the core's objects for it (module doc).

    core: the core's model (`mbody.kernel._core.Model`): loads, columns of G, φ, γ, Gᵀv.
    `solver(unknowns)` gives the core's `Unknowns` for one set of unknown components
    (solve, derivative, projection), made once per set; `memo` keeps what other layers
    derive from the model once (the same life: a model is frozen).
    """

    def __init__(self, model: Model, gone: Callable[[weakref.ref], object] | None = None):
        # the workspace goes with the model, not after; `gone` is called when it does
        self._model = weakref.ref(model, gone)
        self.planar = model.dimension == cv.PLANAR
        F, I = pack_model(model)
        self.core = _core.Model(F, I, self.planar)
        self._solvers: dict[bytes, _core.Unknowns] = {}
        self._plans: dict[bytes, SolvePlan] = {}
        self._lock = threading.Lock()
        self.memo: dict[object, object] = {}
        """Facts other layers derive from the model alone, kept while it lives (a
        simulation's conservation reasons, its initial joint errors...): keys are the
        deriving module's own tuples, values never handed out to be changed."""

    @property
    def model(self) -> Model:
        model = self._model()
        if model is None:  # pragma: no cover - a workspace is reached through its model
            raise ReferenceError("the workspace's model is gone")
        return model

    def __repr__(self) -> str:
        return (f"<Workspace of {self.model.name!r}: {len(self._solvers)} set(s) of unknowns "
                "prepared; .core, .solver(unknowns)>")

    @property
    def state_size(self) -> int:
        """Length of the packed state y (`mbody.kernel`'s layout)."""
        return int(self.core.state_size)

    # -- unknown reactions ----------------------------------------------------------------
    def unknowns(self, given: Mapping[str, float]) -> Unknowns:
        """The components not in `given` (label -> value, labels already checked)."""
        model = self.model
        m = len(model.reaction_table.labels)
        mask = np.ones(m, dtype=bool)
        lam = np.zeros(m)
        index = model.reaction_index
        for label, v in given.items():  # the given values are few
            k = index[label]
            mask[k], lam[k] = False, float(v)
        return Unknowns(mask, mask.nonzero()[0], lam, mask.tobytes())

    @cached_property
    def file_unknowns(self) -> Unknowns:
        """`unknowns` of the file's known values (those varying in t are set by the core
        at each time: their entries of lam here are their t = 0 values)."""
        return self.unknowns(self.model.known_reactions)

    def unknowns_at(self, t: float, extra: Mapping[str, float] | None = None) -> Unknowns:
        """The file's known values at time t (the core evaluates those that vary), updated
        with `extra`."""
        if not extra:
            return self.file_unknowns
        given = self.model.known_reactions_at(t)
        given.update(extra)
        return self.unknowns(given)

    def solver(self, unknowns: Unknowns) -> _core.Unknowns:
        """The core's `Unknowns` for this set (its S's band order and scratch, and the rank
        its constraints have at the mechanism's generic configurations), made once."""
        out = self._solvers.get(unknowns.key)
        if out is None:
            with self._lock:
                out = self._solvers.get(unknowns.key)
                if out is None:
                    out = _core.Unknowns(self.core, pack_unknowns(self.model, unknowns.U))
                    out.set_generic_rank(self._generic_rank(unknowns, out))
                    self._solvers[unknowns.key] = out
        return out

    def solve_plan(self, unknowns: Unknowns) -> SolvePlan:
        """What one solve with these unknowns needs besides the state (made once)."""
        plan = self._plans.get(unknowns.key)
        if plan is None:
            model = self.model
            m = len(unknowns.mask)
            N, o_lam, o_info = _core.solve_layout(model.n, m, self.planar)
            labels = unknowns.labels(model.reactions)
            plan = SolvePlan(self.solver(unknowns), N, o_lam, o_info, labels,
                             model.rows if model.has_particles else None,
                             o_info + _core.INFO, m, len(unknowns.U), model.reactions,
                             model.reaction_index, solution_fields(model.coordinates, labels),
                             {})
            self._plans[unknowns.key] = plan
        return plan

    @cached_property
    def file_plan(self) -> SolvePlan:
        """`solve_plan` of `file_unknowns` (a solve without extra known values)."""
        return self.solve_plan(self.file_unknowns)

    def _generic_rank(self, unknowns: Unknowns, solver: _core.Unknowns) -> int:
        """The rank of G_U at the mechanism's generic configurations, decided on its
        geometry: the rank at the file's pose and, when that is short of full, at a
        second assembled configuration a small step along a motion the joints allow (a
        random one: generic with probability one); the larger. A mechanism redundant at
        every configuration (Bricard's) keeps its deficiency there; one that is singular
        only at its file's pose (a four-bar chain drawn flat) does not."""
        mu = len(unknowns.U)
        y0 = self.state_vector(self.model.initial)
        r0 = self._rank_at(solver, unknowns, y0)
        if r0 >= mu:
            return mu
        n = self.model.n
        rng = np.random.default_rng(0)
        info = np.empty(_core.PROJECT_INFO)
        y = y0.copy()
        y[7 * n:13 * n] = rng.standard_normal(6 * n)  # a random motion ...
        if self.planar:
            y[7 * n:10 * n].reshape(n, 3)[:, 2] = 0.0
            y[10 * n:13 * n].reshape(n, 3)[:, :2] = 0.0
        solver.project(0.0, y, 0, 0.0, 1, info)  # ... the joints allow (velocities only)
        v, w = y[7 * n:10 * n].reshape(n, 3), y[10 * n:13 * n].reshape(n, 3)
        speed = max(float(np.abs(v).max()), float(np.abs(w).max()) * self._size(), 1e-300)
        dt = 1e-3 * self._size() / speed  # a step of a thousandth of the model's size
        y1 = y0.copy()
        y1[:3 * n] += dt * v.ravel()
        q = y1[3 * n:7 * n].reshape(n, 4)
        q += dt * quaternion_rate(q, w)
        q /= np.linalg.norm(q, axis=1, keepdims=True)
        if self.planar:
            y1[13 * n:] += dt * w[:, 2]
        solver.project(0.0, y1, 10, 0.0, 1, info)  # back onto the joints
        if info[_core.PR_SINGULAR]:
            return r0
        return max(r0, self._rank_at(solver, unknowns, y1))

    def _rank_at(self, solver: _core.Unknowns, unknowns: Unknowns, y: np.ndarray) -> int:
        info = self._solve_info(solver, unknowns, 0.0, y)
        if info[_core.ST_SINGULAR]:
            return len(unknowns.U)  # no rank to learn from here: assume none lost
        return int(info[_core.ST_RANK])

    def _solve_info(self, solver: _core.Unknowns, unknowns: Unknowns, t: float,
                    y: np.ndarray) -> np.ndarray:
        """The info slots (``_core.ST_*``) of the core's solve at (t, y)."""
        _, _, o_info = _core.solve_layout(self.model.n, len(unknowns.mask), self.planar)
        out = np.empty(o_info + _core.INFO)
        solver.solve(t, y, unknowns.lam, out)
        return out[o_info:]

    def breaks_joints(self, state: State) -> bool:
        """Whether `state` may break a joint the file's unknown reactions enforce: the
        core's count of the components past `mbody.equations.joints.JOINT_TOL` (its
        scales never larger than `joint_errors`'s, so False means that `joint_errors`
        finds none; True asks it to describe them)."""
        unknowns = self.file_unknowns
        info = self._solve_info(self.solver(unknowns), unknowns, float(state.t),
                                self.state_vector(state))
        return bool(info[_core.ST_BROKEN] > 0)

    def _size(self) -> float:
        """The model's length scale: the spread of its mass centres and joint points."""
        model = self.model
        pts = np.concatenate((model.initial.position, model.joint_table.B_r_child))
        return max(float(np.ptp(pts, axis=0).max()) if len(pts) else 0.0, 1e-3)

    # -- states ---------------------------------------------------------------------------
    def state_vector(self, state: State) -> np.ndarray:
        """The full packed state a simulation integrates: [x | q | v | ω | θ (planar)]."""
        parts = [state.position.ravel(), state.quaternion.ravel(), state.velocity.ravel(),
                 state.omega.ravel()]
        if self.planar:
            q = state.quaternion
            parts.append(2.0 * np.arctan2(q[:, 3], q[:, 0]))
        return np.concatenate(parts)

    def pack_state(self, state: State) -> np.ndarray:
        """[x | q | v | ω] flat (13 n,), a C array (the core's state layout, less the planar
        angles, which evaluations do not read). Kept with a state whose arrays are all
        read-only (a model's initial state): it cannot change, so it is packed once."""
        packed = state.__dict__.get("_packed")
        if packed is not None:
            return packed
        y = np.concatenate((state.position.ravel(), state.quaternion.ravel(),
                            state.velocity.ravel(), state.omega.ravel()))
        if not (state.position.flags.writeable or state.quaternion.flags.writeable
                or state.velocity.flags.writeable or state.omega.flags.writeable):
            y.flags.writeable = False
            state.__dict__["_packed"] = y  # a frozen dataclass: its __dict__ holds caches
        return y


_WORKSPACES: dict[int, Workspace] = {}
"""id(model) -> its workspace; an entry goes with its model (the callback of the
workspace's weak reference to it: a weakref.finalize would do the same, but its first use
in a process imports atexit). A plain dict: a lookup per evaluation, where a
WeakKeyDictionary's costs a microsecond."""
_LOCK = threading.Lock()


def workspace(model: Model) -> Workspace:
    """The model's `Workspace`, made on first use and kept while the model lives."""
    ws = _WORKSPACES.get(id(model))
    if ws is None or ws._model() is not model:
        with _LOCK:
            ws = _WORKSPACES.get(id(model))
            if ws is None or ws._model() is not model:
                key = id(model)
                ws = Workspace(model, lambda _: _WORKSPACES.pop(key, None))
                _WORKSPACES[key] = ws
    return ws
