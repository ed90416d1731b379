"""Static equilibrium: a configuration at rest where every acceleration vanishes.

With the bodies at rest (v = 0, so no gyroscopic terms) and the drivers held where
their laws put them at the time asked for, a state is an equilibrium when the solve
gives v̇ = 0: the applied loads and gravity are carried by the joints alone. mbody
finds one by Newton's method in the motions the joints allow (a basis of the null space
of Gᵀ, orthonormal in the kinetic metric): from the file's pose, the residual is the
accelerations at rest, a(q); a step δ solves J δ = −a with J = ∂a/∂δ by central
differences along the basis; after each step the positions are moved back onto the
joints (the compiled core's projection). At the equilibrium, J is −M⁻¹K in that basis:
its eigenvalues say whether the configuration is stable (all negative: K positive
definite), unstable (one positive) or neutral (one zero, to the differences' accuracy).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from mbody.equations.assemble import assemble
from mbody.equations.workspace import workspace
from mbody.errors import MbodyError
from mbody.kernel import _core
from mbody.model.calculus import derivative
from mbody.model.drivers import DriverTable
from mbody.model.expressions import compile_expression
from mbody.model.model import Model, State
from mbody.solve.kinematics import kinematics

NEWTON_STEPS = 50
ACCEL_RTOL = 1e-10
"""Equilibrium when every acceleration is below this times g (or 1 m/s²) per length."""
STEP_RTOL = 1e-6
"""Central differences step: this fraction of the model's length (and radians)."""


@dataclass(frozen=True)
class Equilibrium:
    """What `find_equilibrium` found.

    state: the configuration at rest; found: whether the accelerations vanished (to
    ACCEL_RTOL); moved: the largest distance a mass centre moved from the start (m) and
    the largest angle a body turned (rad); stiffness: the eigenvalues of K = −M J in the
    allowed motions (1/s² per unit mass: positive is stiff), sorted; stable: every one
    positive (None: not decided, one within the differences' error of 0); iterations.
    """

    state: State
    found: bool
    moved: tuple[float, float]
    stiffness: np.ndarray
    stable: bool | None
    iterations: int

    def __str__(self) -> str:
        if not self.found:
            return (f"no equilibrium found in {self.iterations} Newton steps (the "
                    "accelerations did not vanish)")
        verdict = {True: "stable (the stiffness is positive definite)",
                   False: "unstable (the stiffness has a negative direction)",
                   None: "neutral to the accuracy of the differences (a zero stiffness)"}
        return (f"equilibrium found in {self.iterations} Newton steps: bodies moved up to "
                f"{self.moved[0]:.4g} m and turned up to {np.degrees(self.moved[1]):.4g} deg "
                f"from the start; {verdict[self.stable]}")


def held(model: Model, t: float) -> Model:
    """The model with each driver held at its law's value at t (a constant law)."""
    d = model.drivers
    if d is None or not len(d):
        return model
    laws = []
    for law in d.laws:
        f = compile_expression(repr(float(law[0](t))))
        f1 = derivative(f)
        laws.append((f, f1, f1))
    table = DriverTable(d.names, d.joint, d.kind, d.axis, d.component, d.offset,
                        tuple(laws), d.where)
    return dataclasses.replace(model, drivers=table)


def find_equilibrium(model: Model, *, start: State | None = None, t: float = 0.0
                     ) -> Equilibrium:
    """An equilibrium near `start` (default: the file's pose), the drivers held at t."""
    m = held(model, t)
    begin = (start if start is not None else model.initial).replace(t=t)
    zero = np.zeros_like(begin.velocity)
    state = kinematics(m, t, start=begin.replace(velocity=zero, omega=zero))
    state = state.replace(velocity=zero, omega=zero.copy())
    n = m.n
    size = max(float(np.ptp(m.initial.position, axis=0).max()) if n > 1 else 0.0,
               float(np.abs(m.joint_table.B_r_child).max()) if len(m.joints) else 0.0, 1e-3)
    g = max(float(np.linalg.norm(m.gravity)), 1.0)
    tol = ACCEL_RTOL * g
    J = np.zeros((0, 0))
    it = 0
    found = False
    while it < NEWTON_STEPS:
        it += 1
        acc = _accel(m, state)
        if np.abs(acc).max(initial=0.0) <= tol:
            found = True
            break
        basis, to_s = _allowed(m, state)
        a = to_s @ acc  # s̈: the accelerations in the allowed coordinates
        J = _jacobian(m, state, basis, to_s, STEP_RTOL * size, t)
        try:
            step = np.linalg.solve(J, -a)
        except np.linalg.LinAlgError:
            step = np.linalg.lstsq(J, -a, rcond=None)[0]
        limit = 0.2 * size  # a trust region: no jump across the configuration space
        norm = float(np.linalg.norm(step))
        if norm > limit:
            step *= limit / norm
        state = _moved(m, state, basis @ step, t)
    basis, to_s = _allowed(m, state)
    stiffness = np.zeros(0)
    stable: bool | None = None
    if basis.shape[1]:
        J = _jacobian(m, state, basis, to_s, STEP_RTOL * size, t)
        stiffness = np.sort(np.linalg.eigvals(-J).real)
        err = 1e-6 * max(1.0, float(np.abs(stiffness).max()))
        stable = (True if stiffness[0] > err else False if stiffness[0] < -err else None)
    moved = (float(np.linalg.norm(state.position - begin.position, axis=1).max()),
             float((2 * np.arccos(np.abs(np.einsum("ij,ij->i", state.quaternion,
                                                    begin.quaternion)).clip(0, 1))).max()))
    out = state.replace(t=t)
    return Equilibrium(out, found, moved, stiffness, stable, it)


def equilibrium(model: Model, *, start: State | None = None, t: float = 0.0) -> State:
    """A configuration at rest where every acceleration vanishes, near `start` (the file's
    pose by default), the drivers held at time t (`find_equilibrium` says more: how far
    it moved, whether it is stable).

    Raises
    ------
    MbodyError
        When Newton's method does not find one.
    """
    found = find_equilibrium(model, start=start, t=t)
    if not found.found:
        raise MbodyError(str(found))
    return found.state


def _accel(model: Model, state: State) -> np.ndarray:
    """The accelerations at rest (N,): v̇ in the model's coordinates."""
    return assemble(model, state).solve().accelerations


def _jacobian(model: Model, state: State, basis: np.ndarray, to_s: np.ndarray, h: float,
              t: float) -> np.ndarray:
    """J = ∂s̈/∂s at rest by central differences along each allowed coordinate."""
    J = np.empty((basis.shape[1], basis.shape[1]))
    for k in range(basis.shape[1]):
        ap = to_s @ _accel(model, _moved(model, state, basis[:, k] * h, t))
        am = to_s @ _accel(model, _moved(model, state, -basis[:, k] * h, t))
        J[:, k] = (ap - am) / (2 * h)
    return J


def _allowed(model: Model, state: State) -> tuple[np.ndarray, np.ndarray]:
    """(B (N, k), Bᵀ M): a basis of the velocities the joints allow at `state` (the model's
    coordinates), orthonormal in the kinetic metric (Bᵀ M B = I), and the map from
    accelerations to the basis's coordinates (s̈ = Bᵀ M v̇)."""
    asm = assemble(model, state)
    G = asm.G.toarray()
    M = asm.M.toarray()
    N = len(model.coordinates)
    if G.shape[1] == 0:
        B = np.eye(N)
    else:
        u, s, vt = np.linalg.svd(G.T)
        rank = int(np.sum(s > 1e-10 * (s[0] if len(s) else 1.0)))
        B = vt[rank:].T
    if B.shape[1] == 0:
        return B, B.T
    L = np.linalg.cholesky(B.T @ M @ B)
    B = B @ np.linalg.inv(L).T  # Bᵀ M B = I: unit kinetic energy per coordinate
    return B, B.T @ M


def _moved(model: Model, state: State, dv: np.ndarray, t: float) -> State:
    """`state` moved by the small motion `dv` (the model's coordinates: displacements and
    rotations about body axes), then projected back onto the joints, at rest."""
    n = model.n
    rpb = model.rows_per_body
    full = np.zeros(n * rpb)
    full[model.rows if model.has_particles else slice(None)] = dv
    d6 = np.zeros((n, 6))
    d6[:, [0, 1, 5] if model.dimension == 2 else slice(None)] = full.reshape(n, rpb)
    x = state.position + d6[:, :3]
    q = state.quaternion.copy()
    half = 0.5 * d6[:, 3:]
    w, u = q[:, :1], q[:, 1:]
    q = q + np.concatenate((-np.einsum("ij,ij->i", u, half)[:, None],
                            w * half + np.cross(u, half)), axis=1)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    moved = state.replace(position=x, quaternion=q)
    ws = workspace(model)
    y = ws.state_vector(moved)
    info = np.empty(_core.PROJECT_INFO)
    ws.solver(ws.unknowns({})).project(t, y, 10, 1e-2, 1, info)
    zero = np.zeros((n, 3))
    return State(y[:3 * n].reshape(n, 3), y[3 * n:7 * n].reshape(n, 4) /
                 np.linalg.norm(y[3 * n:7 * n].reshape(n, 4), axis=1)[:, None], zero,
                 zero.copy(), t)
