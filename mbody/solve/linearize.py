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
from mbody.solve.modal_bounds import modal_bounds
from mbody.util.progress import Progress, progress_of

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

CORE_SPECTRUM_LIMIT = 150
"""Largest first-order system (rows of A) whose eigenvalues the compiled core finds itself:
its QR iteration is written for the small systems of a course's models, where the call
around the arithmetic is what costs. A larger one's are LAPACK's (``scipy.linalg.eig``
with the left vectors: blocked, about ten times faster at a thousand rows), with the same
error bounds, order and modes (`_lapack_spectrum`)."""

_PARAMS = np.zeros(_core.LINEARIZE_PARAMS)
_PARAMS[[_core.LP_STEP, _core.LP_ROUNDING, _core.LP_STEADY, _core.LP_MOVING,
         _core.LP_STOP]] = (STEP, ROUNDING, STEADY_RTOL, MOVING_RTOL, _core.STOP_NONE)
_SYSTEM_PARAMS = _PARAMS.copy()  # up to A: its spectrum found here (a large system)
_SYSTEM_PARAMS[_core.LP_STOP] = _core.STOP_SYSTEM
_STIFFNESS_PARAMS = _PARAMS.copy()  # up to K: no first-order system, no spectrum
_STIFFNESS_PARAMS[_core.LP_STOP] = _core.STOP_STIFFNESS

STAGES = {
    _core.STAGE_GENERALIZED: "the equations M q'' = f",
    _core.STAGE_DAMPING: "damping D = -df/dq'",
    _core.STAGE_STIFFNESS: "stiffness K = -df/dq",
    _core.STAGE_SYSTEM: "first-order system",
    _core.STAGE_HESSENBERG: "eigenvalues (Hessenberg form)",
    _core.STAGE_SCHUR: "eigenvalues (QR iteration)",
    _core.STAGE_VECTORS: "mode shapes",
}
"""What each of the compiled core's stages of a linearisation is, for its progress bars
(`mbody.util.progress`)."""


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
        (the bound of a double one); where that exceeds `LOOSE` of an eigenvalue and every
        coordinate is kept, the smaller of it and the bound from the modes of K's
        symmetric part (`mbody.solve.modal_bounds`: free of ‖M⁻¹‖); at least 1e3 ε ‖A‖."""
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
              coordinates: Sequence[str] | None = None, progress: bool | Progress = False
              ) -> Linearization:
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
    progress : bool or Progress
        Say on standard error what is being computed, once it has taken a second (tqdm
        bars, `mbody.util.progress`; or the steps on a `Progress` of the caller's): a
        model of hundreds of coordinates takes seconds, of thousands minutes, most of it
        the eigenvalues (their cost grows as the cube of the number of coordinates).

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
    if progress is False:  # the usual call: no bars to set up (a small model's takes µs)
        return linearized(model, state, free_coordinates(model, coordinates))
    with progress_of(progress, f"linearize {model.name}", STAGES) as bar:
        bar.step("choosing the coordinates")
        cs = free_coordinates(model, coordinates)
        return linearized(model, state, cs, bar)


def linearized(model: Model, state: State, cs: CoordinateSet, bar: Progress | None = None
               ) -> Linearization:
    """`linearize` for a checked `state` and the coordinate set `cs` (the drivers held),
    its progress on `bar`."""
    at = _offsets(len(cs.cols), len(cs))
    out = np.empty(at.end)
    ws = workspace(model)
    large = 2 * at.k > CORE_SPECTRUM_LIMIT
    ws.solver(cs.held).linearize(float(state.t), ws.pack_state(state), cs.held.lam, cs.Iq,
                                 cs.cols, cs.scales, cs.quasi_int, _skip(model, cs),
                                 _SYSTEM_PARAMS if large else _PARAMS, out,
                                 bar.callback if bar is not None else None)
    pivot, _, warnings = checked(model, state, cs, out[:at.ngen])
    info = out[at.info:at.spectrum].tolist()
    if info[_core.LI_SINGULAR]:
        raise MbodyError(f"the generalized mass of '{model.name}' is not positive definite "
                         "at this state: a motion of the coordinates carries no mass")
    if large:
        _spectrum_here(out, at, info, bar)
    if info[_core.LI_UNCONVERGED]:
        raise MbodyError(f"the eigenvalues of '{model.name}'s linearisation did not converge "
                         "(the QR iteration's limit)")
    if _tightened(out, at, info, ROUNDING / max(pivot, np.finfo(float).tiny), bar):
        _modes_here(out, at, info)
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


def _spectrum_here(out: np.ndarray, at: _Offsets, info: list[float],
                   bar: Progress | None) -> None:
    """What `mb_linearize` does after A when it stopped there (``STOP_SYSTEM``): A's
    spectrum (the core's for a small A, else `_lapack_spectrum`), the growing count, the
    modes (``mb_modes``) and the oscillations' frequencies and damping ratios, into `out`
    and `info` as the core lays them out."""
    k = at.k
    nz = int(info[_core.LI_KEPT]) + k
    if nz == 0:
        return
    A = out[at.resid + 2 * k:at.resid + 2 * k + nz * nz].reshape(nz, nz)
    spec = out[at.spectrum:at.spectrum + 3 * nz + 2 * nz * nz]
    dA, tol = info[_core.LI_DA], info[_core.LI_TOL]
    if nz <= CORE_SPECTRUM_LIMIT:
        if _core.spectrum(A, dA, tol, spec):
            info[_core.LI_UNCONVERGED] = 1.0
            return
    elif not _lapack_spectrum(A, dA, tol, spec, bar):
        info[_core.LI_UNCONVERGED] = 1.0
        return
    if bar is not None:
        bar.step(f"mode shapes ({nz} eigenvalues)")
    _modes_here(out, at, info)


def _modes_here(out: np.ndarray, at: _Offsets, info: list[float]) -> None:
    """`mb_linearize`'s last steps from A's spectrum in `out`: the growing count, the
    modes (``mb_modes``), the oscillations' frequencies and damping ratios."""
    k = at.k
    nz = int(info[_core.LI_KEPT]) + k
    spec = out[at.spectrum:at.spectrum + 3 * nz + 2 * nz * nz]
    w, err = spec[:2 * nz].view(complex), spec[2 * nz + 2 * nz * nz:]
    info[_core.LI_GROWING] = float(np.count_nonzero(~(w.real <= err)))
    kept = np.flatnonzero(out[at.resid + k:at.resid + 2 * k] == 0).astype(np.int64)
    modes = out[at.modes:at.modes + _core.MODE_W * nz + 2 * nz * k]
    m = _core.modes(spec, k, kept, modes)
    info[_core.LI_MODES] = float(m)
    rows = modes[:_core.MODE_W * m].reshape(m, _core.MODE_W)
    osc = rows[rows[:, _core.MODE_KIND] == _core.MODE_OSCILLATION]
    count = len(osc)
    out[at.oscillations:at.oscillations + count] = osc[:, _core.MODE_FREQUENCY]
    out[at.oscillations + count:at.oscillations + 2 * count] = osc[:, _core.MODE_DAMPING]
    info[_core.LI_OSCILLATIONS] = float(count)


LOOSE = 1e-6
"""A first-order system's bound above this fraction of its eigenvalue is loose enough to
be worth `_tightened`'s (an O(k³) computation a small model's call does without)."""


def _tightened(out: np.ndarray, at: _Offsets, info: list[float], m_rel: float,
               bar: Progress | None) -> bool:
    """Whether the eigenvalues' bounds in `out` were lowered to the modal bounds of K's
    symmetric part (`mbody.solve.modal_bounds`; both are bounds: the smaller is kept):
    tried when every coordinate is kept and a bound is `LOOSE`."""
    k = at.k
    nz = int(info[_core.LI_KEPT]) + k
    if k == 0 or nz != 2 * k:
        return False
    spec = out[at.spectrum:at.spectrum + 3 * nz + 2 * nz * nz]
    w, err = spec[:2 * nz].view(complex), spec[2 * nz + 2 * nz * nz:]
    d = out[at.ngen:at.ngen + 4 * k * k].reshape(4, k, k)
    if not np.any(err > LOOSE * np.abs(w)) or not np.all(np.diagonal(d[0]) > 0.0):
        return False  # tight already, or K not positive definite (a free or cyclic motion)
    if bar is not None:
        bar.step(f"error bounds from the modes of K's symmetric part ({k} x {k})")
    M = out[at.M:at.M + k * k].reshape(k, k)
    modal = modal_bounds(M, d[0], d[1], d[2], d[3], m_rel, w)
    if modal is None:
        return False
    A = out[at.resid + 2 * k:at.resid + 2 * k + nz * nz].reshape(nz, nz)
    floor = 1e3 * np.finfo(float).eps * float(np.abs(A).sum(axis=1).max())  # as the core's
    tighter = np.maximum(np.minimum(err, modal), floor)
    if not np.any(tighter < err):
        return False
    err[:] = tighter
    return True


def _lapack_spectrum(A: np.ndarray, dA: float, tol: float, spec: np.ndarray,
                     bar: Progress | None) -> bool:
    """`mb_spectrum` by LAPACK (``geev`` with both vectors): into `spec` as the core lays
    it out, the same quantities: each eigenvalue's bound κ_i ‖δA‖ (κ_i = ‖x_i‖ ‖y_i‖ /
    |y_iᴴ x_i| from its right and left vectors), at most `tol`, at least 1e3 ε ‖A‖∞;
    unit right vectors with their largest entry real and positive; the order by real part
    then imaginary part, ties kept in LAPACK's order. False when LAPACK did not
    converge."""
    import scipy.linalg  # large systems only: ~0.2 s to import

    nz = len(A)
    if bar is not None:
        bar.step(f"eigenvalues and their vectors ({nz} x {nz}, LAPACK)")
    try:
        w, yl, xr = scipy.linalg.eig(A, left=True, right=True)
    except (np.linalg.LinAlgError, ValueError):
        return False
    floor = 1e3 * np.finfo(float).eps * float(np.abs(A).sum(axis=1).max())
    nx, ny = np.linalg.norm(xr, axis=0), np.linalg.norm(yl, axis=0)
    yx = np.abs(np.einsum("ij,ij->j", yl.conj(), xr))
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = np.where(yx > 0.0, nx * ny / yx, np.inf)
    top = np.argmax(np.abs(xr), axis=0)  # the first of the largest, as the core's
    big = np.abs(xr[top, np.arange(nz)])
    phase = np.where(big > 0.0, xr[top, np.arange(nz)].conj() / np.where(big > 0, big, 1.0),
                     1.0)
    V = xr * (phase / np.where(nx > 0.0, nx, 1.0))
    order = np.lexsort((w.imag, w.real))
    w, V, kappa = w[order], V[:, order], kappa[order]
    first = kappa * dA
    err = np.maximum(np.where(np.isfinite(first), np.minimum(first, tol), tol), floor)
    spec[:2 * nz] = w.astype(complex).view(float)
    spec[2 * nz:2 * nz + 2 * nz * nz] = np.ascontiguousarray(V, dtype=complex).view(
        float).reshape(-1)
    spec[2 * nz + 2 * nz * nz:] = err
    return True


def stiffness(model: Model, state: State, cs: CoordinateSet, bar: Progress | None = None
              ) -> np.ndarray:
    """K = −∂f/∂q at `state` as `linearize` computes it (its coordinates left out zeroed),
    without the first-order system and its eigenvalues: what a Newton step needs.

    Raises
    ------
    MbodyError
        The coordinates singular at the state; a generalized mass that is not positive
        definite.
    """
    at = _offsets(len(cs.cols), len(cs))
    out = np.empty(at.end)
    ws = workspace(model)
    ws.solver(cs.held).linearize(float(state.t), ws.pack_state(state), cs.held.lam, cs.Iq,
                                 cs.cols, cs.scales, cs.quasi_int, _skip(model, cs),
                                 _STIFFNESS_PARAMS, out,
                                 bar.callback if bar is not None else None)
    checked(model, state, cs, out[:at.ngen])
    if out[at.info + _core.LI_SINGULAR]:
        raise MbodyError(f"the generalized mass of '{model.name}' is not positive definite "
                         "at this state: a motion of the coordinates carries no mass")
    k = at.k
    return out[at.ngen:at.ngen + k * k].reshape(k, k).copy()


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
