"""One model with some of its values varied: every case packed for the compiled core
without reading and checking the whole file again for each.

A model is packed once into a structure (kernel.h's int array I, the unknowns and their
band order) and its values (the float array F). Setting values by path (`Model.with_values`)
usually changes F only: a mass, a length, a driver's speed. A `Family` reads each
distinct (path, value) once, in full (the file's rules, the assembly at t = 0: a *probe*),
and records which entries of F, of the file's state and of the `extras` each path
touches. A case with several values set is then composed from its probes, each path's
entries from its own probe, bit for bit what a model read with all of them gives, when
the paths act on separate entries.

That is checked, not assumed: paths whose entries overlap (a body's mass and its shape
both set its inertia), a value that changes the structure (a driver's law that becomes
another program), or another generic rank of the joints, and the case is built in full
instead (`Model.with_values`); and `cases` builds one composed case of every call in full
and compares it bit for bit, falling back to full builds for all of them if it differs.
Every value is checked by the file's rules (its probe); a combination is checked as a
whole when it is built in full.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mbody.equations.pack import pack_model
from mbody.equations.workspace import workspace
from mbody.errors import MbodyError
from mbody.model.model import Model
from mbody.model.values import plain


@dataclass(frozen=True, eq=False)
class Packed:
    """A model packed for the core: F, I, the file's state (the full packed state y,
    before the assembly at t = 0), `extras` and the generic ranks of its two solves."""

    F: np.ndarray
    I: np.ndarray
    start: np.ndarray
    extras: np.ndarray
    ranks: tuple[int, int]

    def same_structure(self, other: Packed) -> bool:
        return (self.ranks == other.ranks and len(self.F) == len(other.F)
                and np.array_equal(self.I, other.I))


@dataclass(frozen=True, eq=False)
class Case:
    """One case of a family.

    F, start, extras: its packed values (`Packed`'s), or None when it failed. model: the
    model built in full when it has a structure of its own (then F is its own F, to be
    used with that model's workspace), else None. error: why its values were refused.
    """

    F: np.ndarray | None = None
    start: np.ndarray | None = None
    extras: np.ndarray | None = None
    model: Model | None = None
    error: str | None = None

    @property
    def shared(self) -> bool:
        """Evaluated with the family's structure (an F row of its model)."""
        return self.F is not None and self.model is None


def extras_of(model: Model) -> np.ndarray:
    """Numbers the runs need besides F: each driver's rate at t = 0, f'(0) (rad/s or
    m/s; the rate of a ``speed`` driver)."""
    drivers = model.drivers
    if drivers is None:
        return np.zeros(0)
    return np.array([float(law[1](0.0)) for law in drivers.laws])


def pack(model: Model) -> Packed:
    """`model` packed (`Packed`)."""
    F, I = pack_model(model)
    ws = workspace(model)
    start = ws.state_vector(model.file_state if model.file_state is not None
                            else model.initial)
    ranks = (int(ws.solver(ws.file_unknowns).generic_rank),
             int(ws.solver(ws.unknowns({})).generic_rank))
    return Packed(F, I, start, extras_of(model), ranks)


def _key(value: Any) -> str:
    """A value's identity among a path's values (as the file would hold it)."""
    return repr(plain(value))


class Family:
    """`model` with the values at `paths` varied (module doc).

    Parameters
    ----------
    model : Model
        The model every case changes (read from a file or a dictionary: `with_values`).
    paths : sequence of str
        The paths the cases set (``bodies.rod.mass``...).
    """

    def __init__(self, model: Model, paths: Sequence[str]):
        self.model = model
        self.paths = tuple(paths)
        self.base = pack(model)
        self._probes: dict[tuple[str, str], Packed | str] = {}
        self._touched = {p: (np.zeros(len(self.base.F), bool),
                             np.zeros(len(self.base.start), bool),
                             np.zeros(len(self.base.extras), bool)) for p in self.paths}
        self.separable = True
        """False once composing has been seen to differ from a full build (then every
        case is built in full)."""

    def probe(self, path: str, value: Any) -> Packed | str:
        """The model with only `path` set to `value`, packed; or the message refusing it."""
        key = (path, _key(value))
        got = self._probes.get(key)
        if got is None:
            try:
                got = pack(self.model.with_values({path: value}))
            except MbodyError as exc:
                got = str(exc)
            if isinstance(got, Packed) and got.same_structure(self.base):
                F, s, e = self._touched[path]
                F |= got.F != self.base.F
                s |= got.start != self.base.start
                e |= got.extras != self.base.extras
            self._probes[key] = got
        return got

    def _overlap(self, paths: Sequence[str]) -> bool:
        """Whether two of `paths` touch a common entry (then they may not act apart)."""
        for part in range(3):
            seen = np.zeros(len(self._touched[paths[0]][part]), dtype=np.int64)
            for p in paths:
                seen += self._touched[p][part]
            if (seen > 1).any():
                return True
        return False

    def _full(self, values: Mapping[str, Any]) -> Case:
        try:
            model = self.model.with_values(values)
            got = pack(model)
        except MbodyError as exc:
            return Case(error=str(exc))
        if got.same_structure(self.base):
            return Case(got.F, got.start, got.extras)
        return Case(got.F, got.start, got.extras, model=model)

    def _composed(self, values: Mapping[str, Any]) -> Case | None:
        """The case composed from its probes, or None when it must be built in full."""
        F, start, extras = self.base.F.copy(), self.base.start.copy(), self.base.extras.copy()
        for path, value in values.items():
            got = self.probe(path, value)
            if isinstance(got, str):
                return Case(error=got)
            if not got.same_structure(self.base):
                return None
            tF, ts, te = self._touched[path]
            F[tF], start[ts], extras[te] = got.F[tF], got.start[ts], got.extras[te]
        return Case(F, start, extras)

    def case(self, values: Mapping[str, Any]) -> Case:
        """One case: composed from its probes when its paths act apart, else built in full.

        Parameters
        ----------
        values : mapping of str to value
            Path -> value, paths among `paths`.

        Returns
        -------
        Case
        """
        unknown = [p for p in values if p not in self._touched]
        if unknown:
            raise MbodyError(f"{unknown[0]!r} is not one of this family's paths "
                             f"({', '.join(self.paths)})")
        if not self.separable:
            return self._full(values)
        for path, value in values.items():
            self.probe(path, value)
        if len(values) > 1 and self._overlap(list(values)):
            return self._full(values)
        got = self._composed(values)
        return self._full(values) if got is None else got

    def cases(self, values: Sequence[Mapping[str, Any]]) -> list[Case]:
        """Every case of `values`; one case composed of several probes is also built in
        full and compared bit for bit (F, the file's state, extras), and if it differs
        every case is built in full from then on.

        Parameters
        ----------
        values : sequence of mappings of str to value
            One per case.

        Returns
        -------
        list of Case
        """
        out = [self.case(v) for v in values]
        if self.separable:
            for v, c in zip(values, out, strict=True):
                if c.shared and len(v) > 1:
                    full = self._full(v)
                    same = (full.shared and full.F is not None and full.start is not None
                            and full.extras is not None and c.F is not None
                            and c.start is not None and c.extras is not None
                            and np.array_equal(full.F, c.F)
                            and np.array_equal(full.start, c.start)
                            and np.array_equal(full.extras, c.extras))
                    if not same:
                        self.separable = False
                        return [self._full(v) for v in values]
                    break
        return out
