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

from mbody import conventions as cv
from mbody.equations.pack import pack_model
from mbody.equations.workspace import workspace
from mbody.errors import MbodyError
from mbody.kernel import _core
from mbody.model.model import Model, State
from mbody.model.values import plain
from mbody.solve.kinematics import assembled, placed


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


def state_vector(model: Model, state: State) -> np.ndarray:
    """The full packed state (`Workspace.state_vector`), without making a workspace."""
    parts = [state.position.ravel(), state.quaternion.ravel(), state.velocity.ravel(),
             state.omega.ravel()]
    if model.dimension == cv.PLANAR:
        q = state.quaternion
        parts.append(2.0 * np.arctan2(q[:, 3], q[:, 0]))
    return np.concatenate(parts)


def pack(model: Model, like: Packed | None = None) -> Packed:
    """`model` packed (`Packed`). With `like` (a model of the same structure whose joints
    and pose are the same: only masses, loads or laws differ) its generic ranks are
    `like`'s: they depend on the joints' geometry alone, and finding them takes a few
    kinematic steps."""
    F, I = pack_model(model)
    start = state_vector(model, model.file_state if model.file_state is not None
                         else model.initial)
    if like is not None and _same_geometry(model, F, I, start, like):
        ranks = like.ranks
    else:
        ws = workspace(model)
        ranks = (int(ws.solver(ws.file_unknowns).generic_rank),
                 int(ws.solver(ws.unknowns({})).generic_rank))
    return Packed(F, I, start, extras_of(model), ranks)


def _same_geometry(model: Model, F: np.ndarray, I: np.ndarray, start: np.ndarray,
                   like: Packed) -> bool:
    """The same structure, joints (F's joints block) and pose (the file's positions and
    attitudes) as `like`: everything the joints' generic rank, and whether the drivers
    are independent of the joints, depend on."""
    if len(F) != len(like.F) or not np.array_equal(I, like.I):
        return False
    n, nj = model.n, len(model.joint_table.names)
    k, s = len(model.forces.names), len(model.springs.names)
    lo = 3 + _core.BODY_W * n + _core.LOAD_W * k + _core.SPRING_W * s
    hi = lo + _core.JOINT_W * nj
    return (np.array_equal(F[lo:hi], like.F[lo:hi])
            and np.array_equal(start[:7 * n], like.start[:7 * n]))


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
        self._shared: dict[tuple[str, str], bool] = {}  # probe of the base's structure
        self._touched = {p: (np.zeros(len(self.base.F), bool),
                             np.zeros(len(self.base.start), bool),
                             np.zeros(len(self.base.extras), bool)) for p in self.paths}
        self._overlaps: dict[tuple[str, ...], bool] = {}  # cleared when a set grows
        self.separable = True
        """False once composing has been seen to differ from a full build (then every
        case is built in full)."""

    def probe(self, path: str, value: Any) -> Packed | str:
        """The model with only `path` set to `value`, packed; or the message refusing it."""
        key = (path, _key(value))
        got = self._probes.get(key)
        if got is None:
            try:
                got = self._probe_model({path: value})
            except MbodyError as exc:
                got = str(exc)
            shared = isinstance(got, Packed) and got.same_structure(self.base)
            if isinstance(got, Packed) and shared:
                F, s, e = self._touched[path]
                grew = False
                for mask, new in ((F, got.F != self.base.F),
                                  (s, got.start != self.base.start),
                                  (e, got.extras != self.base.extras)):
                    if (new & ~mask).any():
                        mask |= new
                        grew = True
                if grew:
                    self._overlaps.clear()
            self._probes[key] = got
            self._shared[key] = shared
        return got

    def _probe_model(self, values: Mapping[str, Any]) -> Packed:
        """The model with `values` set, read and checked in full, packed. Its last step
        is `Model.with_values`' assembly at t = 0, which checks that the drivers are
        independent of the joints, moves the bodies (the state packed is the file's all
        the same: the core assembles a case itself) and takes the joint frames at the
        assembled pose (`mbody.model.build.frames_at`): those are packed. When the joints
        and the pose are the base's, the check says nothing new and is skipped
        (`mbody.solve.kinematics.placed`); the frames are still taken, since the
        assembled pose depends on the masses and the drivers' values too. Any problem the
        step finds refuses the value."""
        model = self.model.edited(values)
        got = pack(model, self.base)
        finish = model.source.finish if model.source is not None else None
        if finish is None:
            return got
        if got.ranks is self.base.ranks and finish is assembled:  # the base's geometry
            return pack(placed(model), self.base)
        return pack(finish(model), self.base)

    def _overlap(self, paths: Sequence[str]) -> bool:
        """Whether two of `paths` touch a common entry (then they may not act apart)."""
        key = tuple(paths)
        got = self._overlaps.get(key)
        if got is None:
            got = self._overlaps[key] = self._overlap_now(paths)
        return got

    def _overlap_now(self, paths: Sequence[str]) -> bool:
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
            got = pack(model, self.base)
        except MbodyError as exc:
            return Case(error=str(exc))
        if got.same_structure(self.base):
            return Case(got.F, got.start, got.extras)
        return Case(got.F, got.start, got.extras, model=model)

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
        return self.cases([values])[0]

    def cases(self, values: Sequence[Mapping[str, Any]]) -> list[Case]:
        """Every case of `values` (as `case`, the composing done for all of them at
        once); one case composed of several probes is also read in full and compared bit
        for bit (F, the file's state, extras), and if it differs every case is built in
        full from then on.

        Parameters
        ----------
        values : sequence of mappings of str to value
            One per case.

        Returns
        -------
        list of Case
        """
        out: list[Case | None] = [None] * len(values)
        groups: dict[tuple[str, ...], list[int]] = {}
        for k, v in enumerate(values):
            unknown = [p for p in v if p not in self._touched]
            if unknown:
                raise MbodyError(f"{unknown[0]!r} is not one of this family's paths "
                                 f"({', '.join(self.paths)})")
            if not self.separable:
                out[k] = self._full(v)
                continue
            keys = [(p, _key(x)) for p, x in v.items()]
            for pk, x in zip(keys, v.values(), strict=True):
                if pk not in self._probes:
                    self.probe(pk[0], x)
            refused = next((self._probes[pk] for pk in keys
                            if isinstance(self._probes[pk], str)), None)
            if refused is not None:
                out[k] = Case(error=refused)  # type: ignore[arg-type]
            elif not all(self._shared[pk] for pk in keys) or (
                    len(v) > 1 and self._overlap(list(v))):
                out[k] = self._full(v)
            else:
                groups.setdefault(tuple(v), []).append(k)
        for paths, ks in groups.items():
            F = np.repeat(self.base.F[None], len(ks), axis=0)
            start = np.repeat(self.base.start[None], len(ks), axis=0)
            extras = np.repeat(self.base.extras[None], len(ks), axis=0)
            for p in paths:
                probes = [self._probes[(p, _key(values[k][p]))] for k in ks]
                tF, ts, te = self._touched[p]
                for whole, mask, part in ((F, tF, "F"), (start, ts, "start"),
                                          (extras, te, "extras")):
                    if mask.any():
                        whole[:, mask] = np.stack([getattr(q, part)[mask] for q in probes])
            for i, k in enumerate(ks):
                out[k] = Case(F[i], start[i], extras[i])
        cases: list[Case] = out  # type: ignore[assignment]
        if self.separable:
            for v, c in zip(values, cases, strict=True):
                if c.shared and len(v) > 1:
                    full = self._checked(v)
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
        return cases

    def _checked(self, values: Mapping[str, Any]) -> Case:
        """A case read afresh to check a composed one: `Model.edited` and packed (its
        F, file state and extras are those of `Model.with_values`, whose last step moves
        the bodies and packs nothing new; taken too when the joints or pose differ from
        the base's, to check the drivers)."""
        try:
            got = self._probe_model(values)
        except MbodyError as exc:
            return Case(error=str(exc))
        return Case(got.F, got.start, got.extras) if got.same_structure(self.base) \
            else Case(got.F, got.start, got.extras, model=self.model.with_values(values))

