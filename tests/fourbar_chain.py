"""A chain of parallelogram four-bars (cranks pinned to the ground line at spacing d,
couplers joining neighbouring crank tips): one degree of freedom, and at θ = 0 or π every
link lies on the ground line, where the constraint Jacobian loses rank (a second branch,
the anti-parallelogram, meets the parallel one there).

On the parallel branch every crank has the same angle θ and the couplers translate, so
the motion is one ODE (`theta_ddot`): the exact reference for the solver at and near the
flat positions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FourbarChain:
    loops: int = 3
    crank: float = 0.2  # m, crank length L
    spacing: float = 0.5  # m, ground pivot spacing d (= coupler length)
    crank_mass: float = 1.0  # kg
    coupler_mass: float = 2.0  # kg
    width: float = 0.02  # m, bar section (for the inertias)
    g: float = 9.81

    @property
    def crank_inertia_pivot(self) -> float:
        m, L, w = self.crank_mass, self.crank, self.width
        return m * (L * L + w * w) / 12.0 + m * (L / 2) ** 2

    def theta_ddot(self, theta: float) -> float:
        """θ̈ of the parallel motion: cranks rotate about their pivots, couplers translate
        on circles of radius L."""
        n, L = self.loops, self.crank
        inertia = (n + 1) * self.crank_inertia_pivot + n * self.coupler_mass * L * L
        torque = -((n + 1) * self.crank_mass * L / 2 + n * self.coupler_mass * L) * self.g \
            * math.cos(theta)
        return torque / inertia

    def energy(self, theta: float, omega: float) -> float:
        n, L = self.loops, self.crank
        inertia = (n + 1) * self.crank_inertia_pivot + n * self.coupler_mass * L * L
        height = ((n + 1) * self.crank_mass * L / 2 + n * self.coupler_mass * L) \
            * math.sin(theta)
        return 0.5 * inertia * omega * omega + self.g * height

    def accelerations(self, theta: float, omega: float) -> np.ndarray:
        """The exact planar accelerations [a_x, a_y, α] of every body (cranks, then
        couplers), in the model's body order."""
        L, al = self.crank, self.theta_ddot(theta)
        c, s = math.cos(theta), math.sin(theta)
        out = []
        for _ in range(self.loops + 1):
            out += [L / 2 * (-al * s - omega ** 2 * c), L / 2 * (al * c - omega ** 2 * s), al]
        for _ in range(self.loops):
            out += [L * (-al * s - omega ** 2 * c), L * (al * c - omega ** 2 * s), 0.0]
        return np.array(out)

    def yaml(self, theta: float, omega: float = 0.0) -> str:
        """The model at crank angle θ (rad) and crank speed ω (rad/s), on the parallel
        branch."""
        L, d, w = self.crank, self.spacing, self.width
        c, s = math.cos(theta), math.sin(theta)
        r = lambda x: repr(float(x))  # noqa: E731 - full precision
        lines = ["model: fourbar-chain", "dimension: 2", f"gravity: [0, {-self.g!r}]",
                 "bodies:"]
        for i in range(self.loops + 1):
            lines += [f"  - name: crank{i}", f"    mass: {self.crank_mass!r}",
                      f"    shape: {{box: [{L!r}, {w!r}]}}",
                      f"    position: [{r(i * d + L / 2 * c)}, {r(L / 2 * s)}]",
                      f"    angle: {theta!r}", f"    angular_velocity: {omega!r}",
                      f"    velocity: [{r(-L / 2 * omega * s)}, {r(L / 2 * omega * c)}]"]
        for i in range(self.loops):
            lines += [f"  - name: coupler{i}", f"    mass: {self.coupler_mass!r}",
                      f"    shape: {{box: [{d!r}, {w!r}]}}",
                      f"    position: [{r(i * d + L * c + d / 2)}, {r(L * s)}]",
                      "    angle: 0.0", "    angular_velocity: 0.0",
                      f"    velocity: [{r(-L * omega * s)}, {r(L * omega * c)}]"]
        lines.append("joints:")
        for i in range(self.loops + 1):
            lines.append(f"  - {{name: O{i}, type: revolute, parent: ground, "
                         f"child: crank{i}, at: [{r(i * d)}, 0.0]}}")
        for i in range(self.loops):
            for k, side in ((i, "A"), (i + 1, "B")):
                lines.append(f"  - {{name: {side}{i}, type: revolute, parent: crank{k}, "
                             f"child: coupler{i}, at: [{r(k * d + L * c)}, {r(L * s)}]}}")
        return "\n".join(lines) + "\n"
