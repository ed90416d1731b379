"""Applied loads -> per-body net force (world axes) and moment about the mass centre
(body axes), vectorised over loads and bodies (the sums: `mbody.equations.kernels`).

For a force ``W_f`` at the body point ``B_r`` (from the mass centre, body axes):

    W_F += W_f                      (Newton, world axes)
    B_M += B_r × (W_R_Bᵀ W_f)        (Euler, body axes)

Gravity adds ``m g`` at every mass centre. A spring-damper between points P_a and P_b
pulls them together with tension ``T = k (L − L0) + c L̇`` along ``u = (P_b − P_a)/L``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from mbody.equations import kernels
from mbody.equations.spatial import cross, matvec, rmatvec
from mbody.model.model import Model, State


@dataclass(frozen=True)
class Contributions:
    """Each applied force or couple acting on a body, one row each (for diagrams).

    body: (k,) body index; W_f: (k, 3) force, world axes (0 for a couple);
    B_r: (k, 3) point of application from the mass centre, body axes;
    B_m: (k, 3) its moment about the mass centre, body axes; names: (k,) load names;
    couple: (k,) True for a pure couple.
    """

    body: np.ndarray
    names: tuple[str, ...]
    W_f: np.ndarray
    B_r: np.ndarray
    B_m: np.ndarray
    couple: np.ndarray


class AppliedLoads:
    """Net applied loads per body: W_F (n, 3) world axes, B_M (n, 3) body axes about G.

    `contributions` lists point forces, couples and spring ends; gravity is m g at each
    mass centre and is not repeated there. Only diagrams need the per-load list, so it
    is computed on first access; the sums come from the cache-blocked kernels
    (`mbody.equations.kernels`) as one (6, n) array `Q6` (rows [W_F; B_M]).
    """

    def __init__(self, model: Model, state: State, Q6: np.ndarray):
        self.model, self.state, self.Q6 = model, state, Q6

    @property
    def W_F(self) -> np.ndarray:
        return self.Q6[0:3].T

    @property
    def B_M(self) -> np.ndarray:
        return self.Q6[3:6].T

    @cached_property
    def contributions(self) -> Contributions:
        return contributions(self.model, self.state)

    def __repr__(self) -> str:  # the default names only the class and an address
        return (f"<AppliedLoads on {self.model.n} bodies at t = {self.state.t:g} s: "
                f".W_F (n, 3) N world, .B_M (n, 3) N m body axes, .contributions>")


def scatter(index: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """Sum rows of `values` (k, 3) into (n, 3) by body `index`; index −1 (ground) is dropped."""
    out = np.zeros((n, 3))
    keep = index >= 0
    if not keep.all():
        index, values = index[keep], values[keep]
    if not len(index):
        return out
    if len(index) == len(np.unique(index)):  # one row per body: a direct write
        out[index] = values
        return out
    for c in range(3):  # loop over 3 components, not over bodies
        out[:, c] = np.bincount(index, values[:, c], minlength=n)
    return out


def applied_loads(model: Model, state: State, R: np.ndarray | None = None) -> AppliedLoads:
    """Net applied force and moment on every body at `state` (gravity and springs included).

    W_F = Σ W_f + m g (world axes), B_M = Σ B_r × (W_R_Bᵀ W_f) + couples (body axes).
    `R` is accepted for compatibility and not needed (rotations use the quaternions).
    """
    plan = kernels.plan_for(model)
    frame = kernels.frame_at(model, state.t)
    sparse = kernels.sparse_wrench(plan, [kernels.load_wrenches(model, plan, frame, state),
                                          kernels.spring_wrenches(model, state)])
    Q6 = np.empty((6, model.n))
    kernels.loads_and_gyroscopic(plan, frame, state, sparse, Q6, None)
    return AppliedLoads(model, state, Q6)


def contributions(model: Model, state: State, R: np.ndarray | None = None) -> Contributions:
    """Each point force, couple and spring end on its body at `state` (for diagrams)."""
    R = state.W_R_B if R is None else R
    ft, sp = model.forces, model.springs

    # Point forces and couples.
    Rf = R[ft.body]
    vec = ft.vector_at(state.t)
    W_vec = np.where(ft.in_body[:, None], matvec(Rf, vec), vec)
    B_vec = np.where(ft.in_body[:, None], vec, rmatvec(Rf, vec))
    couple = ft.couple[:, None]
    W_f = np.where(couple, 0.0, W_vec)
    B_m = np.where(couple, B_vec, cross(ft.B_r, B_vec))
    bodies, names = [ft.body], list(ft.names)
    Wfs, Brs, Bms, couples = [W_f], [ft.B_r], [B_m], [ft.couple]

    # Spring-dampers: two contributions each, +T u on end a, −T u on end b.
    if len(sp.names):
        ends = kernels.spring_ends(model, state.position, state.quaternion, state.velocity,
                                   state.omega)
        _, u, T = kernels.spring_tension(model, *ends)
        f = T[:, None] * u
        for end, r, sign in ((sp.a, sp.r_a, 1.0), (sp.b, sp.r_b, -1.0)):
            on = end >= 0
            Re = R[np.where(on, end, 0)]
            Br = np.where(on[:, None], r, 0.0)
            bodies.append(end)
            names.extend(sp.names)
            Wfs.append(sign * f)
            Brs.append(Br)
            Bms.append(cross(Br, rmatvec(Re, sign * f)))
            couples.append(np.zeros(len(end), dtype=bool))

    return Contributions(np.concatenate(bodies), tuple(names), np.concatenate(Wfs),
                         np.concatenate(Brs), np.concatenate(Bms), np.concatenate(couples))


def gyroscopic(J: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """ω × (J ω) for (n, 3, 3) inertia tensors and (n, 3) angular velocities, body axes."""
    return cross(omega, matvec(J, omega))
