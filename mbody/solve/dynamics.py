"""The per-step path of a simulation: accelerations of every body at one state,

    v̇ = M⁻¹ (Q + G λ − b),   i.e.   a_G = W_F / m,   ω̇ = J⁻¹ (B_M + reactions − ω × J ω)

evaluated by the compiled core (`mbody.kernel`, through the model's
`mbody.equations.workspace`): with every reaction value given it is the core's
right-hand side with no unknown to solve for. Rows of the result are per body
``[a_G (world axes, m/s²), ω̇ (body axes, rad/s²)]`` for planar and spatial models
alike (a planar body's rows 2-4 are 0).

For integrators, `derivative` returns the time derivative of the packed state
``[position (3), quaternion (4), velocity (3), omega (3)]`` per body (see `pack`), and
`StateDerivative` is ẏ = f(t, y) in the core's block layout, with the unknown reactions
solved at every call.
"""

from __future__ import annotations

import dataclasses
import weakref
from collections.abc import Callable

import numpy as np

from mbody.equations.solution import singular_mass_error
from mbody.equations.workspace import Unknowns, Workspace, workspace
from mbody.errors import MbodyError
from mbody.kernel import _core
from mbody.model.model import Model, State
from mbody.util.spatial import quaternion_rate


def status_error(model: Model, code: int) -> MbodyError:
    """The core's status code of a motion without mass (1 + 6 body + row) as the error."""
    return singular_mass_error(model, (code - 1) // 6, (code - 1) % 6)


_GIVEN: weakref.WeakKeyDictionary[Model, tuple[Workspace, _core.Unknowns]] = \
    weakref.WeakKeyDictionary()


def _every_reaction_given(model: Model) -> tuple[Workspace, _core.Unknowns]:
    """The workspace and the core's solver of `model` with no unknown reaction, on a copy
    without the file's known reactions that vary in t (the core would set those at t:
    here the caller's values are the ones applied). Made once per model."""
    got = _GIVEN.get(model)
    if got is None:
        plain = (dataclasses.replace(model, known_expressions={}) if model.known_expressions
                 else model)
        ws = workspace(plain)
        m = len(model.reaction_table.labels)
        mask = np.zeros(m, dtype=bool)
        none = Unknowns(mask, np.zeros(0, np.int64), np.zeros(m), mask.tobytes())
        got = (ws, ws.solver(none))
        _GIVEN[model] = got
    return got


def accelerations(model: Model, state: State, reactions: np.ndarray | None = None, *,
                  out: np.ndarray | None = None) -> np.ndarray:
    """v̇ = M⁻¹ (Q + G λ − b) per body -> (n, 6) rows [a_G world, ω̇ body axes].

    Every reaction value is given: nothing is solved for (`Assembly.solve` solves for
    the unknown ones). Load values are taken at ``state.t``.

    Parameters
    ----------
    model : Model
        The model, from `load` or `loads`.
    state : State
        Positions (world, m), orientations, velocities (world, m/s), angular velocities
        (body axes, rad/s) and time (s).
    reactions : (m,) array, optional
        Values λ of the reaction components (N; N m), in the order of
        ``model.reactions`` (None: no reaction forces).
    out : (n, 6) array, optional
        An array to fill (any memory layout); by default a new one is returned.

    Returns
    -------
    (n, 6) array
        Per body, in file order: a_G, mass-centre acceleration in world axes (m/s²), then
        ω̇, angular acceleration in body axes (rad/s²); a planar body's rows 2-4 are 0.
        `out` when given.

    Raises
    ------
    MbodyError
        `reactions` does not have one value per reaction component, or a motion the
        loads act on has no mass or inertia.
    """
    ws, solver = _every_reaction_given(model)
    m = len(model.reaction_table.labels)
    if reactions is None:
        lam = np.zeros(m)
    else:
        lam = np.ascontiguousarray(reactions, dtype=float).reshape(-1)
        if len(lam) != m:
            raise MbodyError(f"expected {m} reaction values (one per label of "
                             f"model.reactions), got {len(lam)}")
    n = model.n
    y = np.zeros(ws.state_size)  # a planar model's angles are not read
    y[:13 * n] = ws.pack_state(state)
    ydot = np.empty(ws.state_size)
    code = solver.derivative(float(state.t), y, lam, 0.0, ydot)
    if code:
        raise status_error(model, code)
    acc = ydot[7 * n:13 * n].reshape(2, n, 3)
    if out is None:
        out = np.empty((n, 6))
    out[:, :3] = acc[0]
    out[:, 3:] = acc[1]
    return out


Dynamics = Callable[[Model, State], np.ndarray]
"""f(model, state) -> (n, 6) accelerations [a_G (world, m/s²), ω̇ (body axes, rad/s²)]."""


_NO_VALUES = np.zeros(0)
_NO_VALUES.flags.writeable = False
"""The given reaction values of a right-hand side without unknowns (`dynamics`): none,
one shared read-only array rather than one made per run."""


class StateDerivative:
    """ẏ = f(t, y) for the packed state a simulation integrates (the core's layout),

        y = [x (n, 3) | q (n, 4) | v (n, 3) | ω (n, 3) | θ (n,), planar only]   (flat),
        ẏ = [v | ½ q ⊗ (0, ω) | a_G | ω̇ | ω_z],

    with the accelerations from the compiled core (`unknowns`: a
    `mbody.equations.workspace.Unknowns` of the model; those components solved at every
    call, Baumgarte's terms with α = β = `rate`, the others at their given values, those
    varying in t evaluated by the core) or from `dynamics` (a `Dynamics` callable,
    evaluated in Python). The rotation is built from q/‖q‖; q itself is integrated as it
    is. Planar models' out-of-plane rows are exactly 0.
    """

    def __init__(self, model: Model, dynamics: Dynamics | None = None, *,
                 unknowns: Unknowns | None = None, rate: float = 0.0):
        if (dynamics is None) == (unknowns is None):
            raise ValueError("StateDerivative needs either dynamics or unknowns")
        self.model, self.dynamics, self.rate = model, dynamics, float(rate)
        self.unknowns = unknowns
        self.planar = model.dimension == 2
        n = model.n
        self.size = 13 * n + (n if self.planar else 0)
        self.solver: _core.Unknowns | None = None
        """The core's solver of `unknowns` (None: `dynamics` serves)."""
        self.lam = _NO_VALUES
        """The given reaction values (0 on the unknown components; read only)."""
        if unknowns is not None:
            self.solver = workspace(model).solver(unknowns)
            self.lam = np.ascontiguousarray(unknowns.lam, dtype=float)

    @property
    def compiled(self) -> bool:
        """Whether evaluations go through the compiled core (else `dynamics`, Python)."""
        return self.solver is not None

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty(self.size)
        if self.solver is not None:
            code = self.solver.derivative(float(t), np.ascontiguousarray(y, dtype=float),
                                          self.lam, self.rate, out)
            if code:
                raise status_error(self.model, code)
            return out
        return self._python(float(t), np.asarray(y, dtype=float), out)

    def _python(self, t: float, y: np.ndarray, d: np.ndarray) -> np.ndarray:
        n = self.model.n
        x = y[:3 * n].reshape(n, 3)
        q = y[3 * n:7 * n].reshape(n, 4)
        v = y[7 * n:10 * n].reshape(n, 3)
        w = y[10 * n:13 * n].reshape(n, 3)
        qn = q / np.sqrt(np.einsum("ij,ij->i", q, q))[:, None]
        assert self.dynamics is not None
        acc = self.dynamics(self.model, State(x, qn, v, w, t))
        d[:3 * n] = y[7 * n:10 * n]
        d[3 * n:7 * n] = quaternion_rate(q, w).ravel()
        d[7 * n:10 * n].reshape(n, 3)[:] = acc[:, :3]
        d[10 * n:13 * n].reshape(n, 3)[:] = acc[:, 3:]
        if self.planar:
            d[7 * n + 2:10 * n:3] = 0.0
            d[10 * n:13 * n].reshape(n, 3)[:, :2] = 0.0
            d[13 * n:] = w[:, 2]
        return d


def pack(state: State) -> np.ndarray:
    """State -> flat (13 n,) vector, per body [position, quaternion, velocity, omega]."""
    return np.concatenate((state.position, state.quaternion, state.velocity, state.omega),
                          axis=1).reshape(-1)


def unpack(y: np.ndarray, t: float = 0.0) -> State:
    """Inverse of `pack` (the quaternion is used as given; renormalise in the integrator)."""
    Y = np.asarray(y, dtype=float).reshape(-1, 13)
    return State(Y[:, 0:3], Y[:, 3:7], Y[:, 7:10], Y[:, 10:13], t)


def derivative(model: Model, state: State, reactions: np.ndarray | None = None) -> np.ndarray:
    """ẏ for y = `pack(state)`: per body [v, q̇ = ½ q ⊗ (0, ω), a_G, ω̇], flat (13 n,)."""
    acc = accelerations(model, state, reactions)
    return np.concatenate((state.velocity, quaternion_rate(state.quaternion, state.omega),
                           acc), axis=1).reshape(-1)
