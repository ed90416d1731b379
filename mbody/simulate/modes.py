"""Mode shapes as motions: the configurations q0 + a Re(φ e^{λt}) of a linearisation's
mode, for pictures and animations.

A configuration at coordinates δq from the reference is reached by moving the bodies
along v = T(x) δq in small steps (the midpoint rule, each step back onto the joints by the
core's projection): along the way every true coordinate changes at its rate, since the
coordinates' rows satisfy Aᵀ T = I, and a few Newton steps at the end put the coordinates
on q0 + δq exactly (a ball joint's or a free body's quasi-velocities, which have no
values, turn the body about its axes instead). The reference
motion's own motion — a steady spin, a precession — is not shown: the modes are drawn
about the reference configuration.
"""

from __future__ import annotations

import numpy as np

from mbody.equations.generalized import evaluate, state_with_velocities
from mbody.errors import MbodyError
from mbody.model.model import State
from mbody.simulate.trajectory import Trajectory, appearance
from mbody.solve.configure import move, project
from mbody.solve.linearize import Linearization, Mode

STEPS_PER_RAD = 20
"""Midpoint steps per radian (or per model size) of the path to a configuration."""
CORRECTIONS = 4
"""Newton steps at most onto the true coordinates' values at the path's end (the midpoint
rule leaves them off by its O(h²))."""
AMPLITUDE = 0.15
"""Default amplitude: the largest mass-centre displacement (or a body's turn times the
model's size) this fraction of the model's size."""


def mode_number(lin: Linearization, k: int) -> Mode:
    """Mode k (1-based, in `Linearization.modes`' order: neutral ones first)."""
    modes = lin.modes
    if not 1 <= k <= len(modes):
        raise MbodyError(f"no mode {k}: the linearisation of '{lin.model.name}' has "
                         f"{len(modes)} mode(s), 1 to {len(modes)} (mbody modes MODEL lists "
                         "them)")
    return modes[k - 1]


def unit_amplitude(lin: Linearization, shape: np.ndarray) -> float:
    """The amplitude a of `shape` whose largest displacement is `AMPLITUDE` of the
    model's size (`shape` real, the coordinates' amplitudes)."""
    g = lin.generalized
    cs = g.coordinate_set
    v = g.T @ shape
    cols = cs.cols
    trans = np.abs(v[cols % 6 < 3]).max(initial=0.0)
    rot = np.abs(v[cols % 6 >= 3]).max(initial=0.0) * cs.length
    big = max(trans, rot)
    return AMPLITUDE * cs.length / big if big > 0 else 1.0


def displaced(lin: Linearization, start: State, dq: np.ndarray) -> State:
    """`start` moved by the coordinates' change `dq` (module doc), at rest."""
    g0 = lin.generalized
    cs = g0.coordinate_set
    model = lin.model
    size = float(np.max(np.abs(dq) / cs.scales)) if len(dq) else 0.0
    steps = max(1, int(np.ceil(size * STEPS_PER_RAD)))
    h = np.asarray(dq, dtype=float) / steps
    zero = np.zeros(len(cs))
    state = start
    g = evaluate(model, state, cs, zero)
    target = g.q + np.asarray(dq, dtype=float)
    for _ in range(steps):
        mid = move(model, state, 0.5 * (g.T @ h))
        T1 = evaluate(model, mid, cs, zero).T
        state = project(model, cs, move(model, state, T1 @ h))
        g = evaluate(model, state, cs, zero)
    for _ in range(CORRECTIONS):  # Newton onto the true coordinates' values
        miss = np.where(cs.quasi, 0.0, target - g.q)
        if not np.any(np.abs(miss) > 1e-13 * cs.scales):
            break
        state = project(model, cs, move(model, state, g.T @ miss))
        g = evaluate(model, state, cs, zero)
    return state


def mode_configurations(lin: Linearization, mode: Mode, amplitude: float | None = None
                        ) -> tuple[State, State, State]:
    """(reference, +a φ, −a φ): the reference configuration and the mode's extremes
    (φ's real part; a from `unit_amplitude` unless given)."""
    shape = mode.shape.real
    a = unit_amplitude(lin, shape) if amplitude is None else float(amplitude)
    ref = lin.generalized.consistent_state
    return ref, displaced(lin, ref, a * shape), displaced(lin, ref, -a * shape)


def mode_trajectory(lin: Linearization, k: int, *, periods: float = 3.0, fps: float = 60.0,
                    amplitude: float | None = None) -> Trajectory:
    """Mode k played as a motion: q(t) = q0 + a Re(φ e^{λt}) for `periods` periods of an
    oscillation (with its damping); a mode that does not oscillate (λ real or 0) is
    played back and forth, q0 + a φ sin(2π t), for 3 s."""
    mode = mode_number(lin, k)
    model = lin.model
    shape = mode.shape
    a = unit_amplitude(lin, shape.real) if amplitude is None else float(amplitude)
    lam = mode.eigenvalue
    if mode.kind == "oscillation":
        t = np.arange(0.0, periods * mode.period + 0.5 / fps, 1.0 / fps)
        z = a * shape[None, :] * np.exp(lam * t)[:, None]
        q, qdot = z.real, (lam * z).real
    else:
        t = np.arange(0.0, 3.0 + 0.5 / fps, 1.0 / fps)
        q = a * np.sin(2 * np.pi * t)[:, None] * shape.real[None, :]
        qdot = a * 2 * np.pi * np.cos(2 * np.pi * t)[:, None] * shape.real[None, :]
    cs = lin.generalized.coordinate_set
    state = lin.generalized.consistent_state
    pos, quat, vel, om = [], [], [], []
    previous = np.zeros(len(cs))
    for i in range(len(t)):
        state = displaced(lin, state, q[i] - previous)
        previous = q[i]
        g = evaluate(model, state, cs, qdot[i])
        s = state_with_velocities(model, state, g.velocities(qdot[i]))
        pos.append(s.position)
        quat.append(s.quaternion)
        vel.append(s.velocity)
        om.append(s.omega)
    info = {"mode": k, "eigenvalue": [lam.real, lam.imag], "kind": mode.kind,
            "amplitude": a, "frequency_hz": mode.frequency_hz,
            # the linearisation's own (a state not at rest: the tangent system's modes)
            "warnings": list(lin.warnings) + ([] if mode.kind == "oscillation" else
            [f"mode {k} does not oscillate ({mode.kind}): its shape is played back and forth "
             "at 1 Hz"])}
    shapes, colors = appearance(model)
    return Trajectory.from_states(
        t, np.array(pos), np.array(quat), np.array(vel), np.array(om),
        body_names=model.body_names, dimension=model.dimension, model_name=model.name,
        model_file=model.file, info=info, mass=np.array(model.mass),
        inertia=np.array(model.J), shapes=shapes, colors=colors,
        gravity=np.array(model.gravity))
