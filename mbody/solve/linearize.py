"""Linearisation about an equilibrium or a steady motion: small oscillations, natural
frequencies, damping ratios, mode shapes and stability.

In generalized coordinates the equations of motion are ``M(q) q'' = f(q, q')``
(`mbody.equations.generalized`). About a state where q'' = 0 — an equilibrium, or a steady
motion whose moving coordinates the equations do not depend on (a spin about a principal
axis: the orientation is then a symmetry and is left out; a gyroscope's precession and
spin angles) — a small motion δq obeys

    M δq'' + D δq' + K δq = 0,      K = −∂f/∂q,  D = −∂f/∂q'

K holds the stiffness of the loads (springs, a load that turns with a body) and the
geometric stiffness of the constraint forces: T changes with q, so Tᵀ Q does even when Q
does not (gravity). A linearisation in the bodies' own coordinates that forgets the
second part (``λ ∂Gᵀ/∂q``) finds no stiffness at all in a pendulum under gravity.
`Linearization.K_geometric` is that part on its own.

Derivatives: f is quadratic in q' (the velocity terms, the gyroscopic terms and dampers'
linear ones), so a central difference in q' is exact up to rounding. In q, central
differences at steps h, h/2 and h/4 (h = 0.01 rad, or 0.01 of the model's size) are
combined by Richardson's extrapolation twice (error O(h⁶)); the error is bounded by the
estimated error of the second-to-last extrapolation (|R₁ − R₂|/15), plus the rounding of f
(10 ε of the magnitude of the terms that make it, `Generalized.f_scale`, times the
projection's condition, over the smallest step). Each perturbed state moves the bodies
along T e_k by their exponential maps: a curve through the state whose tangent is the
coordinate's direction, which is all a derivative at the state needs (the compiled core
evaluates f at all of them in one call, kernel.h: ``mb_linearize``).
"""

from __future__ import annotations

import functools
import weakref
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np

from mbody.equations.coordinates import CoordinateSet, columns, coordinate_set
from mbody.equations.generalized import Generalized, checked, from_output, layout
from mbody.equations.workspace import workspace
from mbody.errors import MbodyError
from mbody.kernel import _core
from mbody.model.arguments import checked_model, checked_state
from mbody.model.model import Model, State
from mbody.solve.configure import move

STEP = 1e-2
"""The largest of the three position steps (rad; times the model's size for lengths)."""
ROUNDING = 10 * np.finfo(float).eps
"""Relative rounding error of one evaluation of f against the terms it is made of
(`Generalized.f_scale`), per unit of the projection's condition (the core divides it by
the pivot ratio of [Gᵀ; Aᵀ]'s QR): a few sums of products and one backward-stable solve
of a system of the model's size."""
STEADY_RTOL = 1e-8
"""A state is steady when every generalized force is below this fraction of the terms
that make it (`Generalized.f_scale`)."""
MOVING_RTOL = 1e-12
"""A coordinate moves when its rate exceeds this fraction of the rates' scale."""

def _mode(eigenvalue: complex, kind: str, frequency: float, damping_ratio: float,
          shape: np.ndarray) -> Mode:
    """`Mode(...)`, made without the frozen dataclass's __init__ (an object.__setattr__ per
    field); equal to one made the usual way."""
    obj = object.__new__(Mode)
    object.__setattr__(obj, "__dict__", {"eigenvalue": eigenvalue, "kind": kind,
                                         "frequency": frequency, "damping_ratio": damping_ratio,
                                         "shape": shape})
    return obj


_ROW = (_core.MODE_RE, _core.MODE_IM, _core.MODE_KIND, _core.MODE_FREQUENCY,
        _core.MODE_DAMPING)
"""Where a mode's eigenvalue (re, im), kind, frequency and damping ratio are in its row."""

_KINDS = {_core.MODE_NEUTRAL: "neutral", _core.MODE_OSCILLATION: "oscillation",
          _core.MODE_GROWTH: "growth", _core.MODE_DECAY: "decay"}

_PARAMS = np.zeros(_core.LINEARIZE_PARAMS)
_PARAMS[[_core.LP_STEP, _core.LP_ROUNDING, _core.LP_STEADY, _core.LP_MOVING]] = (
    STEP, ROUNDING, STEADY_RTOL, MOVING_RTOL)


@dataclass(frozen=True)
class Mode:
    """One mode of the linearised motion.

    Parameters
    ----------
    eigenvalue : complex
        λ (1/s); an oscillation's has Im λ > 0 (its conjugate is the same mode).
    kind : str
        ``oscillation`` (a complex pair), ``growth`` (a real λ > 0), ``decay`` (a real
        λ < 0) or ``neutral`` (λ = 0: a free or cyclic motion).
    frequency : float
        Natural frequency |λ| (rad/s) of an oscillation; NaN otherwise.
    damping_ratio : float
        ζ = −Re λ / |λ| (NaN for a neutral mode).
    shape : (k,) complex array
        The coordinates' amplitudes, the largest 1 (real and positive).
    """

    eigenvalue: complex
    kind: str
    frequency: float
    damping_ratio: float
    shape: np.ndarray

    @property
    def frequency_hz(self) -> float:
        """The natural frequency in Hz."""
        return self.frequency / (2.0 * np.pi)

    @property
    def period(self) -> float:
        """2π/|Im λ| (s) of an oscillation; inf otherwise."""
        w = abs(self.eigenvalue.imag)
        return 2.0 * np.pi / w if w > 0 else float("inf")


class _Offsets(NamedTuple):
    """Where each part of `mb_linearize`'s output starts, for N columns and k
    coordinates (kernel.h)."""

    k: int
    ngen: int      # the generalized equations' part ends; K, K_err, D, D_err (4 k^2) follow
    M: int         # M_q (k x k) in it
    qdot: int      # q' (k) in it
    resid: int     # q'' (k), then the left-out flags (k), then A's slot (4 k^2)
    info: int
    spectrum: int
    modes: int
    oscillations: int  # their frequencies, then their damping ratios
    end: int


@functools.lru_cache(maxsize=256)
def _offsets(N: int, k: int) -> _Offsets:
    gl = layout(N, k)
    kk = k * k
    resid = gl[-1] + 4 * kk
    info = resid + 2 * k + 4 * kk
    spectrum = info + _core.LINEARIZE_INFO
    modes = spectrum + 6 * k + 8 * kk
    oscillations = modes + 12 * k + 4 * kk
    return _Offsets(k, gl[-1], gl[3], gl[6], resid, info, spectrum, modes, oscillations,
                    oscillations + 4 * k)


@dataclass(frozen=True, eq=False)
class Linearization:
    """``M δq'' + D δq' + K δq = 0`` about a state (module doc).

    The compiled core computes it all in one call (kernel.h: ``mb_linearize``): the
    equations there (`generalized`), the differences, A, its spectrum (``mb_spectrum``:
    each eigenvalue's bound from its own left and right vectors) and its modes
    (``mb_modes``). The attributes below are views of that output, made when first read;
    `mbody.linearize` makes it.

    Parameters
    ----------
    model, state : Model, State
        The model and the state linearised about.
    coordinate_set : CoordinateSet
        The coordinates (the driven ones held).
    warnings : tuple of str
        Why the state is not steady, and anything else worth saying.
    _out, _at, _info : array, offsets, list
        The core's output, where its parts start, and its info entries.
    """

    model: Model
    state: State
    coordinate_set: CoordinateSet
    warnings: tuple[str, ...]
    _out: np.ndarray = field(repr=False)
    _at: _Offsets = field(repr=False)
    _info: list[float] = field(repr=False)

    @property
    def steady(self) -> bool:
        """Whether the state is an equilibrium or a steady motion (q'' = 0, and every
        moving coordinate cyclic); otherwise the eigenvalues are those of the tangent system
        at this instant, and `stable` is None."""
        return bool(self._info[_core.LI_STEADY])

    @property
    def tolerance(self) -> float:
        """The most any eigenvalue may be off (1/s): √(‖δA‖ ‖A‖), ‖δA‖ = ‖M⁻¹‖
        (‖δK‖ + ‖δD‖) from the derivatives' error bounds (infinity norms; a double
        eigenvalue, a Jordan block, moves by that much), and at least 1e3 ε ‖A‖. Each
        eigenvalue has its own, smaller bound where it is simple (`eigenvalue_errors`)."""
        return self._info[_core.LI_TOL]

    @property
    def dA(self) -> float:
        """‖δA‖, the bound on A's error (in A's units)."""
        return self._info[_core.LI_DA]

    @cached_property
    def M(self) -> np.ndarray:
        """(k, k) generalized mass."""
        k = self._at.k
        return self._out[self._at.M:self._at.M + k * k].reshape(k, k)

    @cached_property
    def _differences(self) -> np.ndarray:
        k = self._at.k
        return self._out[self._at.ngen:self._at.ngen + 4 * k * k].reshape(4, k, k)

    @property
    def K(self) -> np.ndarray:
        """(k, k) stiffness −∂f/∂q (the loads' and the constraint forces' geometric
        stiffness)."""
        return self._differences[0]

    @property
    def K_error(self) -> np.ndarray:
        """(k, k) bounds on K's errors, entry by entry."""
        return self._differences[1]

    @property
    def D(self) -> np.ndarray:
        """(k, k) damping −∂f/∂q' (with the gyroscopic terms)."""
        return self._differences[2]

    @property
    def D_error(self) -> np.ndarray:
        """(k, k) bounds on D's errors, entry by entry."""
        return self._differences[3]

    @cached_property
    def residual(self) -> np.ndarray:
        """(k,) q'' at the state (0 at an equilibrium or a steady motion)."""
        return self._out[self._at.resid:self._at.resid + self._at.k]

    @cached_property
    def _left(self) -> np.ndarray:
        k, at = self._at.k, self._at.resid + self._at.k
        return self._out[at:at + k] > 0

    @cached_property
    def left_out(self) -> tuple[str, ...]:
        """The symmetries left out of the first-order system: the cyclic coordinates
        that move (the spin of a steady spin, a gyroscope's precession), and the angles of
        quasi-velocities the forces do not depend on (a free body's orientation)."""
        labels = self.coordinate_set.labels
        return tuple(labels[i] for i in np.flatnonzero(self._left))

    @cached_property
    def kept(self) -> np.ndarray:
        """(k',) int: the coordinates whose δq are in the first-order system (the
        others left out)."""
        return np.flatnonzero(~self._left)

    @property
    def _nz(self) -> int:
        return int(self._info[_core.LI_KEPT]) + self._at.k

    @cached_property
    def A(self) -> np.ndarray:
        """(k' + k, k' + k) first-order system ``z' = A z``, z = (δq of the kept
        coordinates, δq'): ``[[0, E], [−M⁻¹ K, −M⁻¹ D]]``."""
        nz, at = self._nz, self._at.resid + 2 * self._at.k
        return self._out[at:at + nz * nz].reshape(nz, nz)

    @cached_property
    def _spectrum_out(self) -> np.ndarray:
        nz = self._nz
        return self._out[self._at.spectrum:self._at.spectrum + 3 * nz + 2 * nz * nz]

    @cached_property
    def _modes_out(self) -> np.ndarray:
        nz = self._nz
        return self._out[self._at.modes:self._at.modes + _core.MODE_W * nz + 2 * nz * self._at.k]

    @cached_property
    def generalized(self) -> Generalized:
        """The equations in generalized coordinates there (the driven coordinates held)."""
        return from_output(self.model, self.state, self.coordinate_set,
                           self._out[:self._at.ngen])

    @property
    def coordinates(self) -> list[str]:
        """The coordinates (the driven ones held)."""
        return self.coordinate_set.labels

    @cached_property
    def _spectrum(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(eigenvalues, unit eigenvectors, error bounds), by real part then imaginary
        part."""
        n, out = len(self.A), self._spectrum_out
        return (out[:2 * n].view(complex), out[2 * n:2 * n + 2 * n * n].view(complex)
                .reshape(n, n), out[2 * n + 2 * n * n:])

    @property
    def eigenvalues(self) -> np.ndarray:
        """The first-order system's eigenvalues (complex, 1/s: rad/s for the imaginary
        parts), by real part then imaginary part."""
        return self._spectrum[0]

    @property
    def eigenvalue_errors(self) -> np.ndarray:
        """A bound on each eigenvalue's error (1/s), in `eigenvalues`' order: κ_i ‖δA‖ for
        a simple one (κ_i its condition ‖x_i‖ ‖y_i‖ / |y_iᴴ x_i|), at most `tolerance`
        (the bound of a double one); at least 1e3 ε ‖A‖."""
        return self._spectrum[2]

    @cached_property
    def modes(self) -> list[Mode]:
        """The modes: oscillations (one per complex pair), growths, decays and neutral
        ones (λ = 0: a free or cyclic motion), neutral first, then by |λ| (kernel.h:
        ``mb_modes``)."""
        m, n, k = int(self._info[_core.LI_MODES]), self._nz, self._at.k
        start = _core.MODE_W * n
        shapes = self._modes_out[start:start + 2 * m * k].view(complex).reshape(m, k)
        re, im, kind, freq, damp = _ROW
        return [_mode(complex(r[re], r[im]), _KINDS[r[kind]], r[freq], r[damp], shape)
                for r, shape in zip(self._mode_rows.tolist(), shapes, strict=True)]

    @property
    def _mode_rows(self) -> np.ndarray:
        """(modes, MODE_W): the modes' rows from the core, in `modes`' order."""
        m = int(self._info[_core.LI_MODES])
        return self._modes_out[:_core.MODE_W * m].reshape(m, _core.MODE_W)

    @property
    def oscillations(self) -> list[Mode]:
        """The oscillatory modes, by natural frequency."""
        return [m for m in self.modes if m.kind == "oscillation"]

    @property
    def frequencies(self) -> np.ndarray:
        """The natural frequencies |λ| of the oscillations (rad/s), ascending."""
        count, at = int(self._info[_core.LI_OSCILLATIONS]), self._at.oscillations
        return self._out[at:at + count]

    @property
    def frequencies_hz(self) -> np.ndarray:
        """The natural frequencies in Hz."""
        return self.frequencies / (2.0 * np.pi)

    @property
    def damping_ratios(self) -> np.ndarray:
        """ζ of each oscillation, in the order of `frequencies`."""
        count, at = int(self._info[_core.LI_OSCILLATIONS]), self._at.oscillations
        return self._out[at + count:at + 2 * count]

    @property
    def stable(self) -> bool | None:
        """False when an eigenvalue has a positive real part (beyond its error bound,
        `eigenvalue_errors`): a small motion grows; True otherwise (neutral modes — a free
        motion, a cyclic coordinate — do not count); None when the state is not steady."""
        if not self.steady:
            return None
        return self._info[_core.LI_GROWING] == 0

    @cached_property
    def K_geometric(self) -> np.ndarray:
        """The constraint forces' geometric stiffness: K less the loads' own stiffness
        −Tᵀ (∂(Q − b)/∂x) T (the bodies' velocities held), the part a linearisation in the
        bodies' coordinates leaves out when it forgets λ ∂Gᵀ/∂q."""
        return self.K - loads_stiffness(self)

    def __repr__(self) -> str:
        verdict = {True: "stable", False: "unstable", None: "not steady"}[self.stable]
        f = ", ".join(f"{x:.4g}" for x in self.frequencies[:4]) + (
            ", …" if len(self.frequencies) > 4 else "")
        return (f"<Linearization of {self.model.name!r}: {len(self.coordinates)} coordinates, "
                f"{len(self.frequencies)} oscillation(s)" + (f" ({f} rad/s)" if f else "")
                + f", {verdict}; .M, .D, .K, .eigenvalues, .modes>")

    def _repr_pretty_(self, p, cycle: bool) -> None:  # IPython shows the text table
        from mbody.present.modes import modes_text  # a display hook

        p.text(modes_text(self))


def free_coordinates(model: Model, coordinates: Sequence[str] | None = None) -> CoordinateSet:
    """The coordinate set with the drivers held: the default set without the drivers'
    coordinates, or `coordinates` (which must not name a driven one)."""
    if coordinates is None:
        base = coordinate_set(model)
        driven = {k for _, k in base.efforts}
        if not driven:
            return base
        coordinates = [c for k, c in enumerate(base.labels) if k not in driven]
    return coordinate_set(model, list(coordinates))


_SKIP: weakref.WeakKeyDictionary[CoordinateSet, np.ndarray] = weakref.WeakKeyDictionary()


def _skip(model: Model, cs: CoordinateSet) -> np.ndarray:
    """(k,) int64: 1 for a coordinate the generalized forces cannot depend on, so that its
    column of K is 0 without evaluations: a body's own position coordinate when the body
    has no joint and no spring (uniform gravity and loads fixed in world or body axes do
    not depend on where it is); its rotation too when every load on it is a world force
    at its mass centre or a couple in body axes."""
    out = _SKIP.get(cs)
    if out is not None:
        return out
    jt, sp, ft = model.joint_table, model.springs, model.forces
    jointed = set(jt.parent.tolist()) | set(jt.child.tolist())
    sprung = set(sp.a.tolist()) | set(sp.b.tolist())
    turning = set()
    for i, body in enumerate(ft.body.tolist()):
        at_centre_world = not ft.in_body[i] and not ft.couple[i] and not np.any(ft.B_r[i])
        body_couple = bool(ft.in_body[i]) and bool(ft.couple[i])
        if not (at_centre_world or body_couple):
            turning.add(body)
    out = np.zeros(len(cs), dtype=np.int64)
    for k, c in enumerate(cs.items):
        if c.kind != _core.GQ_BODY or c.index in jointed or c.index in sprung:
            continue
        out[k] = 1 if c.axis < 3 or c.index not in turning else 0
    _SKIP[cs] = out
    return out


def linearize(model: Model, state: State | None = None, *,
              coordinates: Sequence[str] | None = None) -> Linearization:
    """Linearise `model` about `state` (default: its initial state), an equilibrium or a
    steady motion (module doc).

    Parameters
    ----------
    model : Model
        The model (its drivers are held: their coordinates are not free).
    state : State, optional
        An equilibrium (from `mbody.equilibrium`, or the file's) or a
        steady motion.
    coordinates : sequence of str, optional
        The free coordinates (default: `Assembly.generalized`'s, less the drivers').

    Returns
    -------
    Linearization
        M, D, K, the eigenvalues, natural frequencies, damping ratios, modes, `stable`.

    Raises
    ------
    MbodyError
        Unknown or dependent coordinates, or coordinates singular at the state; a
        `model` or `state` that is not one of this model (`mbody.model.arguments`).
    """
    if not isinstance(model, Model):
        model = checked_model(model)
    state = model.initial if state is None else checked_state(model, state, "state")
    cs = free_coordinates(model, coordinates)
    at = _offsets(len(cs.cols), len(cs))
    out = np.empty(at.end)
    ws = workspace(model)
    ws.solver(cs.held).linearize(float(state.t), ws.pack_state(state), cs.held.lam, cs.Iq,
                                 cs.cols, cs.scales, cs.quasi_int, _skip(model, cs),
                                 _PARAMS, out)
    _, _, warnings = checked(model, state, cs, out[:at.ngen])
    info = out[at.info:at.spectrum].tolist()
    if info[_core.LI_SINGULAR]:
        raise MbodyError(f"the generalized mass of '{model.name}' is not positive definite "
                         "at this state: a motion of the coordinates carries no mass")
    if info[_core.LI_UNCONVERGED]:
        raise MbodyError(f"the eigenvalues of '{model.name}'s linearisation did not converge "
                         "(the QR iteration's limit)")
    if not info[_core.LI_RESTING]:
        residual = out[at.resid:at.resid + at.k]
        worst = int(np.argmax(np.abs(residual)))
        warnings += (f"not an equilibrium or a steady motion: the generalized "
                     f"accelerations here are not 0 ({cs.items[worst].acceleration_label} = "
                     f"{residual[worst]:.4g} {cs.items[worst].unit}/s^2); the eigenvalues "
                     "are those of the tangent system at this instant",)
    j = int(info[_core.LI_UNSTEADY]) - 1
    if j >= 0:
        warnings += (f"not a steady motion: {cs.labels[j]} moves ({out[at.qdot + j]:.4g} "
                     f"{cs.items[j].rate_unit}) and the forces depend on it",)
    return Linearization(model, state, cs, warnings, out, at, info)


def loads_stiffness(lin: Linearization) -> np.ndarray:
    """−Tᵀ ∂(Q − b)/∂x T: the loads' own stiffness, the bodies' velocities held (central
    differences with Richardson's extrapolation, steps as `linearize`'s)."""
    model, g = lin.model, lin.generalized
    state = g.consistent_state
    ws = workspace(model)
    cols = columns(model)
    k = len(g.f)
    h = STEP * g.coordinate_set.scales
    out = np.zeros((k, k))
    wrench = np.empty((model.n, 6))

    def Qb(s: State) -> np.ndarray:
        ws.core.net_wrench(float(s.t), ws.pack_state(s), wrench)
        return wrench.reshape(-1)[cols].copy()

    for j in range(k):
        d = []
        for s in (1.0, 0.5, 0.25):
            step = g.T[:, j] * s * h[j]
            d.append((Qb(move(model, state, step)) - Qb(move(model, state, -step)))
                     / (2 * s * h[j]))
        r2 = (4 * d[2] - d[1]) / 3
        out[:, j] = -g.T.T @ r2
    return out
