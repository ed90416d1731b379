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
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from mbody import conventions as cv
from mbody.equations.pack import pack_model, pack_unknowns
from mbody.kernel import _core

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


class Workspace:
    """A model packed for the compiled core, and the core's objects for it (module doc).

    core: the core's model (`mbody.kernel._core.Model`): loads, columns of G, φ, γ, Gᵀv.
    `solver(unknowns)` gives the core's `Unknowns` for one set of unknown components
    (solve, derivative, projection), made once per set.
    """

    def __init__(self, model: Model):
        self.model = model
        self.planar = model.dimension == cv.PLANAR
        F, I = pack_model(model)
        self.core = _core.Model(F, I, self.planar)
        self._solvers: dict[bytes, _core.Unknowns] = {}
        self._lock = threading.Lock()

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
        return Unknowns(mask, np.flatnonzero(mask), lam, mask.tobytes())

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
        """The core's `Unknowns` for this set (its S's band order and scratch), made once."""
        out = self._solvers.get(unknowns.key)
        if out is None:
            with self._lock:
                out = self._solvers.get(unknowns.key)
                if out is None:
                    out = _core.Unknowns(self.core, pack_unknowns(self.model, unknowns.U))
                    self._solvers[unknowns.key] = out
        return out

    # -- states ---------------------------------------------------------------------------
    def pack_state(self, state: State) -> np.ndarray:
        """[x | q | v | ω] flat (13 n,), a fresh C array (the core's state layout, less the
        planar angles, which evaluations do not read)."""
        return np.concatenate((state.position.ravel(), state.quaternion.ravel(),
                               state.velocity.ravel(), state.omega.ravel()))


_WORKSPACES: weakref.WeakKeyDictionary[Model, Workspace] = weakref.WeakKeyDictionary()
_LOCK = threading.Lock()


def workspace(model: Model) -> Workspace:
    """The model's `Workspace`, made on first use and kept while the model lives."""
    ws = _WORKSPACES.get(model)
    if ws is None:
        with _LOCK:
            ws = _WORKSPACES.get(model)
            if ws is None:
                ws = Workspace(model)
                _WORKSPACES[model] = ws
    return ws
