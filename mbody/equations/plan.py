"""One evaluation plan per model: everything that depends only on the model, made once,
and the choice of the path that evaluates a state.

`model.plan` (a `ModelPlan`, built on first use and kept with the model) owns:

- the numpy kernels' layout for the per-body loads and gyroscopic terms (`kernels`) and
  the load sums for the current load values (`load_frame`);
- the reaction columns' model constants (`reaction_constants`);
- per set of unknown reaction components: which they are, the given values of the others
  (`unknowns`), the per-body block plan of large solves (`block_plan`) and the packed
  structure the compiled path uses;
- the packed model for the compiled path (`mbody.solve.compiled`), and the decision to use it.

Two paths evaluate a state, with the same formulas:

- the numpy path (`mbody.equations.kernels`, `mbody.equations.joints`,
  `mbody.equations.constraints`, `mbody.solve.kkt`): vectorised over bodies, for large
  models and one-off evaluations;
- the compiled path (`mbody.solve.compiled`, numba): one call per state for models of up to
  `COMPILED_MAX_BODIES` bodies, used once a plan has been evaluated `JIT_AFTER` times
  (or at once by `simulate`). Importing numba and loading its cached machine code takes
  a few tenths of a second, more than a one-off solve costs, so `mbody solve` and
  friends never pay it.

Environment: ``MBODY_JIT=0`` turns the compiled path off, ``MBODY_JIT=1`` uses it from
the first evaluation (tests compare the two paths this way).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from mbody.equations.joints import reaction_constants
from mbody.equations.kernels import build_frame, build_plan

if TYPE_CHECKING:
    from mbody.equations.kernels import LoadFrame, Plan
    from mbody.model.model import Model, State
    from mbody.solve.blockplan import BlockPlan

COMPILED_MAX_BODIES = 200
"""Largest model (bodies) evaluated by the compiled path; larger ones are the numpy
kernels' (vectorised, cache-blocked) business."""
JIT_AFTER = 8
"""In automatic mode, a plan switches to the compiled path after this many evaluations."""


def _mode(text: str) -> str:
    v = text.strip().lower()
    return {"0": "off", "off": "off", "no": "off", "false": "off",
            "1": "on", "on": "on", "yes": "on", "true": "on"}.get(v, "auto")


JIT = _mode(os.environ.get("MBODY_JIT", "auto"))
"""'auto', 'on' or 'off': when the compiled path is used (MBODY_JIT; see `set_jit`)."""


def set_jit(mode: str) -> str:
    """Set the compiled path's mode ('auto', 'on' or 'off'); returns the previous one."""
    global JIT
    previous, JIT = JIT, _mode(mode)
    return previous


_compiled_module = None
_compiled_lock = threading.Lock()


def compiled():
    """The `mbody.solve.compiled` module (importing numba), or None when numba is unavailable."""
    global _compiled_module
    if _compiled_module is None:
        with _compiled_lock:
            if _compiled_module is None:
                try:
                    from mbody.solve import compiled as mod
                except ImportError:  # numba missing or broken: the numpy path serves
                    mod = False
                _compiled_module = mod
    return _compiled_module or None


class LoadProgram(NamedTuple):
    """The loads as the compiled path evaluates them at any time, in the order of the
    arguments of `mbody.solve.compiled.set_loads` (and `rk_run`): the constant values,
    then the time-varying entries (`mbody.model.expressions.ProgramTable`, empty when
    every load is constant)."""

    base: np.ndarray  # (k, 3) float: the load values, constant entries in place
    rows: np.ndarray
    cols: np.ndarray
    which: np.ndarray
    starts: np.ndarray
    codes: np.ndarray
    numbers: np.ndarray


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


class ModelPlan:
    """What the hot paths need of one model, computed once (see the module docstring)."""

    def __init__(self, model: Model):
        self.model = model
        self.evaluations = 0
        self._lock = threading.Lock()
        self._frame: LoadFrame | None = None
        self._blocks: dict[bytes, BlockPlan | None] = {}
        self._packed_unknowns: dict[bytes, np.ndarray] = {}

    # -- the numpy path's model data ------------------------------------------------------------
    @cached_property
    def kernels(self) -> Plan:
        """The per-body kernels' layout (`mbody.equations.kernels.Plan`)."""

        return build_plan(self.model)

    def load_frame(self, t: float) -> LoadFrame:
        """The load sums for ``model.forces.vector_at(t)``, rebuilt only when that array
        is another one (constant loads: never)."""

        vec = self.model.forces.vector_at(t)
        frame = self._frame
        if frame is None or frame.vector is not vec:
            frame = build_frame(self.model, self.kernels, vec)
            self._frame = frame  # keeps `vec` alive, so its identity stays meaningful
        return frame

    @cached_property
    def reaction_constants(self):
        """Per reaction component, what its column of G needs of the model only."""

        return reaction_constants(self.model)

    def block_plan(self, unknowns: Unknowns) -> BlockPlan | None:
        """The per-body block plan of large constrained solves for these unknowns."""
        if unknowns.key not in self._blocks:
            from mbody.solve.blockplan import make_plan

            self._blocks[unknowns.key] = make_plan(self.model, unknowns.U)
        return self._blocks[unknowns.key]

    # -- unknown reactions ----------------------------------------------------------------------
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
        return Unknowns(mask, np.flatnonzero(mask), lam, mask.tobytes())

    @cached_property
    def file_unknowns(self) -> Unknowns | None:
        """`unknowns` of the file's known values when none varies in time (else None)."""
        if self.model.known_expressions:
            return None
        return self.unknowns(self.model.known_reactions)

    def unknowns_at(self, t: float, extra: Mapping[str, float] | None = None) -> Unknowns:
        """The file's known values at time t, updated with `extra`."""
        if not extra and self.file_unknowns is not None:
            return self.file_unknowns
        given = self.model.known_reactions_at(t)
        if extra:
            given.update(extra)
        return self.unknowns(given)

    # -- the compiled path ----------------------------------------------------------------------
    def use_compiled(self, calls: int = 1) -> bool:
        """Whether to evaluate through `mbody.solve.compiled` (counting `calls` evaluations)."""
        self.evaluations += calls
        mode = JIT
        if mode == "off" or self.model.n > COMPILED_MAX_BODIES or self.model.n == 0:
            return False
        if mode == "auto" and self.evaluations < JIT_AFTER:
            return False
        return compiled() is not None

    @cached_property
    def packed(self) -> tuple[np.ndarray, np.ndarray]:
        """(F, I): the model as the compiled path reads it (`mbody.solve.compiled.pack_model`)."""
        return compiled().pack_model(self.model)

    @cached_property
    def constant_loads(self) -> np.ndarray:
        """A writable copy of the constant load values (one compiled signature for all)."""
        return np.array(self.model.forces.vector, dtype=float)

    def load_values(self, t: float) -> np.ndarray:
        """(k, 3) load values at time t, as the compiled path takes them."""
        ft = self.model.forces
        return self.constant_loads if ft.varying is None else ft.vector_at(t)

    @cached_property
    def load_program(self) -> LoadProgram:
        """The loads as the compiled path evaluates them at any time (`LoadProgram`)."""
        varying = self.model.forces.varying
        if varying is not None:
            p = varying.program
            return LoadProgram(self.constant_loads, p.rows, p.cols, p.which, p.starts,
                               p.codes, p.numbers)
        none = np.zeros(0, dtype=np.int64)
        return LoadProgram(self.constant_loads, rows=none, cols=none, which=none,
                           starts=np.zeros(1, dtype=np.int64), codes=none,
                           numbers=np.zeros(0))

    def packed_unknowns(self, unknowns: Unknowns) -> np.ndarray:
        """The compiled path's structure of these unknowns (ordered for a narrow band)."""
        out = self._packed_unknowns.get(unknowns.key)
        if out is None:
            U = unknowns.U
            if len(U) > 64:  # order for a narrow band of S (small ones: any order is fine)
                U = U[_band_order(self.model, U)]
            out = compiled().pack_unknowns(self.model, U)
            with self._lock:
                self._packed_unknowns[unknowns.key] = out
        return out

    def pack_state(self, state: State) -> np.ndarray:
        """[x | q | v | ω] flat (13 n,), a fresh C array (one compiled signature)."""
        return np.concatenate((state.position.ravel(), state.quaternion.ravel(),
                               state.velocity.ravel(), state.omega.ravel()))


def _band_order(model: Model, U: np.ndarray) -> np.ndarray:
    """A reverse Cuthill-McKee order of the unknown components (coupled when they act on a
    common body), so that S = G_Uᵀ M⁻¹ G_U has a narrow band."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    rt = model.reaction_table
    mu = len(U)
    body = np.concatenate((rt.child[U], rt.parent[U]))
    comp = np.concatenate((np.arange(mu), np.arange(mu)))
    keep = body >= 0
    B = sp.csr_matrix((np.ones(int(keep.sum())), (comp[keep], body[keep])),
                      shape=(mu, model.n))
    pattern = (B @ B.T).tocsr()
    return reverse_cuthill_mckee(pattern, symmetric_mode=True)
