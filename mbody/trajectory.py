"""`Trajectory`: the motion of every body over time (what `simulate` returns).

Arrays have a leading time axis K and a body axis n, as in the contract (section 6):

    t: (K,) s
    position: (K, n, d) mass centres, world frame, m (d = 2 planar, 3 spatial)
    velocity: (K, n, d) mass-centre velocities, world frame, m/s
    orientation: spatial (K, n, 4) unit quaternions W_R_B, w first; planar (K, n) angles, rad
    angular_velocity: spatial (K, n, 3) body axes, rad/s; planar (K, n), rad/s
    reactions: (K, m) reaction values by `reaction_labels` (empty when none are tracked)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import conventions as cv
from .model import State


@dataclass(frozen=True, eq=False)
class Trajectory:
    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    orientation: np.ndarray
    angular_velocity: np.ndarray
    body_names: tuple[str, ...]
    dimension: int
    model_name: str = ""
    model_file: str = ""
    reaction_labels: tuple[str, ...] = ()
    reactions: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    info: dict = field(default_factory=dict)
    """Run facts: integrator, tolerances, energy/momentum/constraint drift."""

    @property
    def n(self) -> int:
        return len(self.body_names)

    def __len__(self) -> int:
        return len(self.t)

    def state(self, k: int) -> State:
        """The `State` (internal spatial form) at sample k."""
        if self.dimension == cv.PLANAR:
            return State.planar(self.position[k], self.orientation[k], self.velocity[k],
                                self.angular_velocity[k], float(self.t[k]))
        return State(self.position[k], self.orientation[k], self.velocity[k],
                     self.angular_velocity[k], float(self.t[k]))

    @classmethod
    def from_states(cls, t: np.ndarray, pos3: np.ndarray, quat: np.ndarray, vel3: np.ndarray,
                    omega3: np.ndarray, *, body_names: tuple[str, ...], dimension: int,
                    **kw) -> Trajectory:
        """Build from internal spatial arrays (K, n, 3|4); planar ones are reduced."""
        if dimension == cv.PLANAR:
            ang = 2.0 * np.arctan2(quat[..., 3], quat[..., 0])
            return cls(t, pos3[..., :2], vel3[..., :2], np.unwrap(ang, axis=0),
                       omega3[..., 2], body_names, dimension, **kw)
        return cls(t, pos3, vel3, quat, omega3, body_names, dimension, **kw)
