"""What a solve returns: `Solution` (accelerations, every reaction value, what the solve
found) and the reaction values as a read-only mapping; the names of the compiled core's
solve routes; the error for a motion that carries no mass.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from mbody.errors import MbodyError, closest, did_you_mean, not_found
from mbody.model.model import count
from mbody.model.reprs import name_list


class ReactionValues(Mapping):
    """label -> value of every reaction component (N, or N m for moments), a read-only
    view of one array in the order of `Assembly.reactions` (made lazily: a chain of
    10 000 links has 30 000 of them). `array` is that array, read-only.

    `values` is kept as given; `array` is a read-only view of it, made when first asked
    for (marking an array read-only costs a quarter of a microsecond, a twentieth of a
    small model's whole solve), so whoever makes one must not write into `values` after.
    """

    def __init__(self, labels: list[str], index: dict[str, int], values: np.ndarray):
        self._labels, self._index, self._values = labels, index, values
        self._array: np.ndarray | None = None

    @property
    def array(self) -> np.ndarray:
        """The values in the order of the labels (N; N m), read-only."""
        out = self._array
        if out is None:
            out = self._values.view()
            out.flags.writeable = False
            self._array = out
        return out

    def __getitem__(self, label: str) -> float:
        try:
            return float(self._values[self._index[label]])
        except (KeyError, TypeError):
            raise not_found("reaction component", label, self._labels, "components") from None

    def __contains__(self, label: object) -> bool:  # a Mapping's would make the message
        return isinstance(label, str) and label in self._index

    def get(self, label: str, default: Any = None) -> Any:
        i = self._index.get(label) if isinstance(label, str) else None
        return default if i is None else float(self._values[i])

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
    axes : str
        ``joint``: `reactions` are the joint-frame components; ``world``: each joint's
        force and moment in world axes (`mbody.equations.world`).
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
    axes: str = "joint"

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
            raise KeyError(self._not_a_coordinate(label)) from None

    def _not_a_coordinate(self, label: object) -> str:
        """What `label` is instead, when not a coordinate: a reaction component (read from
        `reactions`), close to a coordinate or to a reaction component, or neither."""
        said = f"no coordinate {label!r}"
        if not isinstance(label, str):
            return f"{said}: a coordinate's label is text, such as {self.coordinates[0]!r}" \
                if self.coordinates else said
        if label in self.reactions:
            return (f"{said}: it is a reaction component, read as "
                    f"sol.reactions[{label!r}]")
        hint = did_you_mean(label, self.coordinates)
        if hint:
            return f"{said}; {hint}"
        close = closest(label, self.reactions)
        if close is not None:
            return f"{said}; did you mean the reaction component sol.reactions[{close!r}]?"
        return f"{said} (the coordinates: {name_list(self.coordinates)})"

    def __repr__(self) -> str:  # the dataclass's would print every value
        return (f"<Solution: {count(len(self.coordinates), 'acceleration')}, "
                f"{count(len(self.reactions), 'reaction component')} ({len(self.solved)} solved)"
                + (f", {len(self.warnings)} warning(s)" if self.warnings else "")
                + "; sol[label], .as_dict(), .reactions, .warnings>")

    def _repr_html_(self) -> str:  # notebook display: accelerations and reactions by body
        from mbody.present.rich import solution_html  # a display hook (tools/check_imports.py)

        return solution_html(self)


METHODS = (
    "banded Cholesky of the Schur complement",
    "null-space solve on the joints' geometry (SVD of the scaled G_U)",
    "pivoted Cholesky of the Schur complement, minimum-norm reactions (redundant "
    "constraints)",
)
"""How the compiled core solved, by its route (info slot ST_PATH of `mbody.kernel`)."""


def singular_mass_error(model, body: int, row: int) -> MbodyError:
    """The error for a motion the joints allow that carries no mass or inertia."""
    names = getattr(model, "body_names", None)
    name = names[body] if names is not None else f"#{body}"
    what = (f"translation along world {'xyz'[row]}" if row < 3
            else f"rotation about its body {'xyz'[row - 3]} axis")
    return MbodyError(f"the accelerations are not unique: body {name!r} has no mass or "
                      f"inertia for the {what}, and no joint constrains that motion; give "
                      "it mass or inertia there, or a joint that holds it")


_NEW, _SET = object.__new__, object.__setattr__


def solution_fields(coordinates: list[str], solved: tuple[str, ...]) -> dict[str, object]:
    """The fields of a plain solve's `Solution` (full rank, nothing broken, no condition)
    that do not change from one state to the next, in field order: what `plain_solution`
    completes."""
    return {"coordinates": coordinates, "accelerations": None, "reactions": None,
            "solved": solved, "not_unique": (), "residual": None, "condition": None,
            "method": METHODS[0], "broken_joints": (), "redundant": 0, "axes": "joint"}


def plain_solution(fields: dict[str, object], accelerations: np.ndarray,
                   reactions: Mapping[str, float], residual: float, method: str,
                   not_unique: tuple[str, ...] = (), redundant: int = 0) -> Solution:
    """`Solution` of a plain solve (nothing broken, no condition asked for) from its
    constant `fields` (`solution_fields`): the solve's hot path, a dictionary's copy and
    a few entries (a fifth of a microsecond; the keyword call of `solution` takes twice
    that). Equal to the dataclass's own."""
    obj = _NEW(Solution)
    d = obj.__dict__
    d.update(fields)
    d["accelerations"], d["reactions"] = accelerations, reactions
    d["residual"], d["method"] = residual, method
    if redundant:
        d["not_unique"], d["redundant"] = not_unique, redundant
    return obj


def solution(coordinates: list[str], accelerations: np.ndarray,
             reactions: Mapping[str, float], solved: tuple[str, ...] = (),
             not_unique: tuple[str, ...] = (), residual: float | None = None,
             condition: float | None = None, method: str = "block-diagonal M",
             broken_joints: tuple[str, ...] = (), redundant: int = 0,
             axes: str = "joint") -> Solution:
    """`Solution(...)` with the same arguments, made without the frozen dataclass's
    __init__ (an object.__setattr__ per field: a microsecond of a five-microsecond solve);
    still frozen, equal to one made the usual way (tests/test_reprs.py holds the fields
    the same)."""
    obj = _NEW(Solution)
    _SET(obj, "__dict__", {
        "coordinates": coordinates, "accelerations": accelerations, "reactions": reactions,
        "solved": solved, "not_unique": not_unique, "residual": residual,
        "condition": condition, "method": method, "broken_joints": broken_joints,
        "redundant": redundant, "axes": axes})
    return obj
