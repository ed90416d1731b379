"""The equations of motion in generalized coordinates, ``M_q q'' = f_q``, by projection of
the per-body Newton-Euler equations ``M v' + b = Q + G λ``.

With the coordinates' rate rows A (`mbody.equations.coordinates`) and the held joints' Gᵀ,
the velocity transformation T solves ``[Gᵀ; Aᵀ] T = [0; I]`` (and v_e the drivers' part,
a0 the acceleration at q'' = 0):

    v = T q' + v_e,     v' = T q'' + a0

Multiplying the Newton-Euler equations by Tᵀ removes the reactions (``Tᵀ G = (Gᵀ T)ᵀ =
0``: the joints' forces do no work on the motions the joints allow) and leaves one
equation per coordinate:

    M_q = Tᵀ M T,        f_q = Tᵀ (Q − b − M a0)

(plus the known reactions' work, and a chosen driver's effort on its own coordinate).
Everything is computed by the compiled core in one call (kernel.h, ``mb_generalized``).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from mbody.equations.coordinates import CoordinateSet, columns, coordinate_set
from mbody.equations.workspace import workspace
from mbody.errors import MbodyError, option_name
from mbody.kernel import _core
from mbody.model.arguments import KnownValues, checked_state, known_at
from mbody.model.model import Model, State
from mbody.util.progress import Progress, progress_of

if TYPE_CHECKING:
    from mbody.equations.symbolic.lagrange import SymbolicLagrange

SINGULAR_RTOL = 1e-10
"""The coordinates do not determine the motion at a state when the smallest diagonal
entry of the QR factor of [Gᵀ; Aᵀ] (columns scaled to unit length) is below this fraction
of the largest."""


class CoordinatesSingularError(MbodyError):
    """The generalized coordinates do not determine the motion at this state (a singular
    position for them: a rocker at its dead centre, a ball joint's rates are fine)."""


@dataclass(frozen=True, eq=False)
class Generalized:
    """``M q'' = f`` in generalized coordinates at one state (module doc).

    Parameters
    ----------
    model : Model
        The model.
    state : State
        Where the equations are written.
    coordinate_set : CoordinateSet
        The coordinates and what is held.
    q : (k,) array
        The coordinates' values (rad, m; NaN for a quasi-velocity).
    qdot : (k,) array
        Their rates (rad/s, m/s), A v of the state's velocities.
    M : (k, k) array
        Generalized mass, symmetric positive definite (kg m^2, kg, kg m).
    f : (k,) array
        Generalized forces: the loads' and the velocity terms' (N m, N).
    T : (N, k) array
        v = T q' + v_e; rows labelled by `Model.coordinates`.
    v_e : (N,) array
        The drivers' part of the velocity (0 without held drivers).
    a0 : (N,) array
        The bodies' accelerations at q'' = 0 (velocity terms, drivers' laws).
    f_scale : (k,) array
        The magnitude of the terms each generalized force is made of: what "f = 0" is
        measured against, and its rounding (a pendulum hanging straight down has f = 0
        from terms of size m g L). Per group of body rows (translations, rotations): the
        largest entry of T's column times the sum of |Q|, |b|, |G_K λ_K| and |M a0|.
    rank : float
        Smallest over largest pivot of the projection's QR (1 well determined, 0 singular).
    residual : float
        How far the state is off its joints, as the least-squares residual of the
        projection (0 on them).
    warnings : tuple of str
        What looked wrong (a state off its joints).
    """

    model: Model
    state: State
    coordinate_set: CoordinateSet
    q: np.ndarray
    qdot: np.ndarray
    M: np.ndarray
    f: np.ndarray
    T: np.ndarray
    v_e: np.ndarray
    a0: np.ndarray
    f_scale: np.ndarray
    rank: float
    residual: float
    warnings: tuple[str, ...] = field(default_factory=tuple)

    @property
    def coordinates(self) -> list[str]:
        """The coordinates' labels (``O.angle``, ``P.displacement``, ``S.w1``...)."""
        return self.coordinate_set.labels

    @property
    def units(self) -> list[str]:
        """Each coordinate's unit (``rad``, ``m``)."""
        return [c.unit for c in self.coordinate_set.items]

    @property
    def quasi(self) -> np.ndarray:
        """(k,) True for a quasi-velocity (no coordinate value; its rate is what counts)."""
        return self.coordinate_set.quasi

    @property
    def efforts(self) -> dict[str, str]:
        """A driver's effort label -> the coordinate it acts on (as a generalized force:
        ``M q'' = f + effort`` on that row)."""
        labels = self.coordinates
        return {e: labels[k] for e, k in self.coordinate_set.efforts}

    @property
    def body_coordinates(self) -> list[str]:
        """The row labels of T, v_e and a0: the stacked equations' coordinates."""
        return self.model.coordinates

    def accelerations(self, efforts: Mapping[str, float] | None = None) -> np.ndarray:
        """q'' = M⁻¹ (f + the drivers' efforts given).

        Parameters
        ----------
        efforts : mapping of str to float, optional
            A chosen driver's effort (N m or N) by label; absent ones are 0.

        Returns
        -------
        (k,) array
        """
        rhs = self.f + self.effort_vector(efforts)
        return np.linalg.solve(self.M, rhs)

    def effort_vector(self, efforts: Mapping[str, float] | None = None) -> np.ndarray:
        """The generalized forces of the drivers' efforts (each on its coordinate).

        Parameters
        ----------
        efforts : mapping of str to float, optional
            A chosen driver's effort (N m or N) by label.

        Returns
        -------
        (k,) array
        """
        out = np.zeros(len(self.f))
        index = dict(self.coordinate_set.efforts)
        for label, v in (efforts or {}).items():
            if label not in index:
                raise MbodyError(f"{label!r} is not the effort of a driver whose coordinate "
                                 f"is chosen (those: {', '.join(index) or 'none'})")
            out[index[label]] += float(v)
        return out

    def body_accelerations(self, qddot: np.ndarray) -> np.ndarray:
        """v' = T q'' + a0: the bodies' accelerations (rows as `body_coordinates`).

        Parameters
        ----------
        qddot : (k,) array
            The coordinates' accelerations.

        Returns
        -------
        (N,) array
        """
        return self.T @ np.asarray(qddot, dtype=float) + self.a0

    def velocities(self, qdot: np.ndarray | None = None) -> np.ndarray:
        """v = T q' + v_e (rows as `body_coordinates`).

        Parameters
        ----------
        qdot : (k,) array, optional
            The coordinates' rates (default: the state's).

        Returns
        -------
        (N,) array
        """
        return self.T @ (self.qdot if qdot is None else np.asarray(qdot, float)) + self.v_e

    @cached_property
    def forces(self) -> dict[str, np.ndarray]:
        """The generalized forces by what makes them: ``gravity``, each applied load and
        spring by name, ``known reactions``, and ``velocity terms`` (the rest of f: the
        gyroscopic terms and the centripetal and Coriolis accelerations, Tᵀ(−b − M a0),
        with the drivers' laws). Their sum is `f`."""
        model, T = self.model, self.T
        cols = columns(model)
        n = model.n
        state = self.consistent_state
        ws = workspace(model)
        y = ws.pack_state(state)
        out: dict[str, np.ndarray] = {}
        if np.any(model.gravity):
            g6 = np.zeros((n, 6))
            g6[:, :3] = model.mass[:, None] * model.gravity
            out["gravity"] = T.T @ g6.reshape(-1)[cols]
        k, s = len(model.forces.names), len(model.springs.names)
        if k + s:
            rows = np.empty((k + 2 * s, 7))
            ws.core.load_wrenches(float(state.t), y, rows)
            names = list(model.forces.names) + [nm for nm in model.springs.names
                                                for _ in range(2)]
            where = np.full(6 * n, -1)  # a body's components -> their rows of T
            where[cols] = np.arange(len(cols))
            for name, row in zip(names, rows, strict=True):
                b = int(row[0])
                if b < 0:
                    continue
                # the load's wrench is on one body: T's rows of that body alone
                at = where[6 * b:6 * b + 6]
                on = at >= 0
                out[name] = out.get(name, 0.0) + T[at[on]].T @ row[1:][on]
        rest = self.f - sum(out.values(), np.zeros(len(self.f)))
        out["velocity terms"] = rest
        return out

    @cached_property
    def consistent_state(self) -> State:
        """The state with its velocities v = T q' + v_e (those the equations use)."""
        return state_with_velocities(self.model, self.state, self.velocities())

    def symbolic(self, progress: bool | Progress = False) -> SymbolicLagrange:
        """M(q) and f(q, q') in symbols, for a planar tree (needs sympy): see
        `mbody.equations.symbolic.lagrange`.

        Parameters
        ----------
        progress : bool or Progress
            Say on standard error which rows are being made, once it has taken a second
            (`mbody.util.progress`): sympy takes seconds for ten coordinates.

        Returns
        -------
        SymbolicLagrange
            ``M``, ``f`` (sympy matrices), ``evaluate(q, qdot)``; printed, the equations.
        """
        from mbody.equations.symbolic.lagrange import symbolic_lagrange  # sympy: slow

        with progress_of(progress, f"symbolic {self.model.name}") as bar:
            return symbolic_lagrange(self.model, self.coordinate_set, bar)

    def __repr__(self) -> str:
        k = len(self.f)
        return (f"<Generalized equations of {self.model.name!r} at t = {self.state.t:g} s: "
                f"{k} coordinate{'s' if k != 1 else ''} ({', '.join(self.coordinates[:6])}"
                f"{', ...' if k > 6 else ''}); .M, .f, .T, .accelerations()>")

    def _repr_pretty_(self, p, cycle: bool) -> None:  # IPython shows the text table
        from mbody.present.lagrange import generalized_text  # a display hook

        p.text(generalized_text(self))

    def _repr_latex_(self) -> str:
        from mbody.present.lagrange import generalized_latex  # a display hook

        return "$$" + generalized_latex(self) + "$$"


def state_with_velocities(model: Model, state: State, v: np.ndarray) -> State:
    """`state` with the stacked velocity `v` (rows as `Model.coordinates`)."""
    cols = columns(model)
    full = np.zeros(6 * model.n)
    full[cols] = v
    six = full.reshape(model.n, 6)
    return state.replace(velocity=six[:, :3].copy(), omega=six[:, 3:].copy())


@functools.lru_cache(maxsize=256)
def layout(N: int, k: int) -> tuple[int, ...]:
    """Offsets of T, v_e, a0, M, f, q, q', f_scale, info and the end in the core's
    output."""
    o = [0, N * k]
    o.append(o[-1] + N)      # a0
    o.append(o[-1] + N)      # M
    o.append(o[-1] + k * k)  # f
    o.append(o[-1] + k)      # q
    o.append(o[-1] + k)      # q'
    o.append(o[-1] + k)      # f_scale
    o.append(o[-1] + k)      # info
    o.append(o[-1] + _core.GENERALIZED_INFO)
    return tuple(o)


def generalized(model: Model, state: State | None = None,
                coordinates: Sequence[str] | None = None,
                known: KnownValues | None = None, *,
                progress: bool | Progress = False) -> Generalized:
    """The equations of `model` in generalized coordinates at `state` (module doc).

    Parameters
    ----------
    model : Model
        The model.
    state : State, optional
        Default: the model's initial state.
    coordinates : sequence of str, optional
        The coordinates by label (one per degree of freedom); default: drivers'
        coordinates, then a spanning tree's joint coordinates, then free bodies' own
        (`mbody.equations.coordinates`).
    known : mapping of str to float or str, optional
        Reaction values to apply as loads (their joints are then not held), added to the
        file's: finite numbers, or expressions of t as text taken at ``state.t``
        (`mbody.model.arguments.known_at`).
    progress : bool or Progress
        Say on standard error what is being computed once it has taken a second (a
        model of a thousand bodies takes seconds): tqdm bars (`mbody.util.progress`), or
        the steps on a `Progress` of the caller's.

    Returns
    -------
    Generalized

    Raises
    ------
    MbodyError
        Unknown or dependent coordinates; `CoordinatesSingularError` when they do not
        determine the motion at this state; a `state` or `known` that is not what it
        should be (`mbody.model.arguments`).
    """
    state = model.initial if state is None else checked_state(model, state, "state")
    given = known_at(model, known, state.t) if known else None
    if progress is False:  # the usual call: no bars to set up (a small model's takes µs)
        return evaluate(model, state, coordinate_set(model, coordinates, given))
    with progress_of(progress, f"generalized {model.name}") as bar:
        bar.step("choosing the coordinates")
        cs = coordinate_set(model, coordinates, given)
        bar.step(f"projecting the equations: T ({len(cs.cols)} x {len(cs)}), M, f")
        return evaluate(model, state, cs)


def evaluate(model: Model, state: State, cs: CoordinateSet,
             qdot: np.ndarray | None = None) -> Generalized:
    """`Generalized` at `state` for the coordinate set `cs` (rates `qdot`, default the
    state's)."""
    ws = workspace(model)
    out = np.empty(layout(len(cs.cols), len(cs))[-1])
    ws.solver(cs.held).generalized(
        float(state.t), ws.pack_state(state), cs.held.lam, cs.Iq, cs.cols,
        None if qdot is None else np.ascontiguousarray(qdot, dtype=float), out)
    return from_output(model, state, cs, out)


def checked(model: Model, state: State, cs: CoordinateSet, out: np.ndarray
            ) -> tuple[float, float, tuple[str, ...]]:
    """(pivot ratio, residual, warnings) of the core's output (`layout`); raises
    `CoordinatesSingularError` when the coordinates do not determine the motion."""
    o = layout(len(cs.cols), len(cs))
    rank = float(out[o[8] + _core.GI_RANK])
    if not rank > SINGULAR_RTOL:
        raise CoordinatesSingularError(
            f"the coordinates {', '.join(cs.labels)} do not determine the motion of "
            f"'{model.name}' at t = {state.t:g} s (a singular position for them: pivot "
            f"ratio {rank:.1e}); choose others with {option_name('coordinates', '[...]')}")
    residual = float(out[o[8] + _core.GI_RESIDUAL])
    warnings: tuple[str, ...] = ()
    if residual > 1e-6:
        warnings = (f"the state is off its joints (least-squares residual {residual:.2g} of "
                    "the projection): the equations are those of the nearest motion",)
    return rank, residual, warnings


def from_output(model: Model, state: State, cs: CoordinateSet, out: np.ndarray
                ) -> Generalized:
    """`Generalized` from the core's output (`layout`)."""
    N, k = len(cs.cols), len(cs)
    o = layout(N, k)
    rank, residual, warnings = checked(model, state, cs, out)
    return Generalized(model, state, cs, cs.values(out[o[5]:o[6]]), out[o[6]:o[7]],
                       out[o[3]:o[4]].reshape(k, k), out[o[4]:o[5]],
                       out[:o[1]].reshape(N, k), out[o[1]:o[2]], out[o[2]:o[3]],
                       out[o[7]:o[8]], rank, residual, warnings)
