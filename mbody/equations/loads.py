"""Applied loads -> per-body net force (world axes) and moment about the mass centre
(body axes), and each load's own share for diagrams: both from the compiled core
(`mbody.kernel`, loads.c: one function per load and per spring end).

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

from mbody.equations.workspace import workspace
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
    is computed on first access; the sums are one (6, n) array `Q6` (rows [W_F; B_M]).
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


def wrench_parts(model: Model, state: State) -> tuple[np.ndarray, np.ndarray]:
    """(Q6, b6), each (n, 6): the applied loads per body [W_F (world, N); B_M (about G,
    body axes, N m)] with gravity and springs, and the gyroscopic term [0; ω × J ω]."""
    ws = workspace(model)
    Q6, b6 = np.empty((model.n, 6)), np.empty((model.n, 6))
    ws.core.wrench_parts(float(state.t), ws.pack_state(state), Q6, b6)
    return Q6, b6


def spring_states(model: Model, state: State
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each spring-damper's (L, L̇, T, u): length (m), its rate (m/s), tension
    T = k (L − L0) + c L̇ (N) and unit direction from end a to end b (s, 3) (world), from
    the compiled core (the numbers its wrench is made of)."""
    ws = workspace(model)
    rows = np.empty((len(model.springs.names), 6))
    ws.core.springs(float(state.t), ws.pack_state(state), rows)
    return rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3:6]


def applied_loads(model: Model, state: State, R: np.ndarray | None = None) -> AppliedLoads:
    """Net applied force and moment on every body at `state` (gravity and springs included).

    W_F = Σ W_f + m g (world axes), B_M = Σ B_r × (W_R_Bᵀ W_f) + couples (body axes).
    `R` is accepted for compatibility and not needed.
    """
    return AppliedLoads(model, state, wrench_parts(model, state)[0].T)


def contributions(model: Model, state: State, R: np.ndarray | None = None) -> Contributions:
    """Each point force, couple and spring end on its body at `state` (for diagrams)."""
    ws = workspace(model)
    ft, sp = model.forces, model.springs
    k, s = len(ft.names), len(sp.names)
    rows = np.empty((k + 2 * s, 7))  # [body, W_F (3), B_M (3)] per load, spring end a, b
    ws.core.load_wrenches(float(state.t), ws.pack_state(state), rows)
    body = rows[:, 0].astype(np.intp)
    B_r = np.concatenate((ft.B_r, np.where((sp.a >= 0)[:, None], sp.r_a, 0.0),
                          np.where((sp.b >= 0)[:, None], sp.r_b, 0.0)))
    order = np.concatenate((np.arange(k), k + 2 * np.arange(s), k + 2 * np.arange(s) + 1))
    return Contributions(body[order], (*ft.names, *sp.names, *sp.names), rows[order, 1:4],
                         B_r, rows[order, 4:7],
                         np.concatenate((ft.couple, np.zeros(2 * s, dtype=bool))))
