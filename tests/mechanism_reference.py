"""A simulation's mechanism callbacks written in Python over single calls of the compiled
core (`Unknowns.derivative`, `Unknowns.project`), as mbody.simulate.mechanism's Python
path computed them before the C glue (mbody/kernel/src/mechanism.c) took over: the
reference that glue is held to step for step (tests/test_stepping.py, test_singular.py).
"""

from __future__ import annotations

import numpy as np

from mbody.equations.workspace import Unknowns, workspace
from mbody.kernel import _core
from mbody.kernel.dop853 import DOP853
from mbody.model.model import Model
from mbody.simulate.mechanism import ITERATIONS, STAGE_ITERATIONS, STAGE_PIVOT_RTOL
from mbody.simulate.stepping import REFRESH_ATOL
from mbody.util.spatial import quaternion_rate


class Callbacks:
    """rhs(t, y), project(t, y) -> info, stage(t, y), tangent(t, y, e) of DOP853 (see
    mbody.kernel.dop853) for `model` with the reactions `unknowns` solved."""

    def __init__(self, model: Model, unknowns: Unknowns, rate: float = 0.0):
        self.model, self.rate = model, rate
        self.solver = workspace(model).solver(unknowns)
        self.lam = np.ascontiguousarray(unknowns.lam)
        self.info = np.empty(_core.PROJECT_INFO)

    def _project(self, y: np.ndarray, t: float, iterations: int,
                 homogeneous: bool = False) -> np.ndarray:
        self.solver.project(t, y, iterations, STAGE_PIVOT_RTOL, homogeneous, self.info)
        assert not self.info[_core.PR_SINGULAR]
        return self.info

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty(len(y))
        assert self.solver.derivative(t, np.ascontiguousarray(y), self.lam, self.rate,
                                      out) == 0
        return out

    def project(self, t: float, y: np.ndarray) -> list[float]:
        info = self._project(y, t, ITERATIONS)
        ratio = float(info[_core.PR_RATIO])
        return [max(info[_core.PR_STEP], info[_core.PR_VELOCITY]),
                float(ratio < STAGE_PIVOT_RTOL), ratio]

    def stage(self, t: float, y: np.ndarray) -> None:
        self._project(y, t, STAGE_ITERATIONS)

    def tangent(self, t: float, y: np.ndarray, e: np.ndarray) -> None:
        """e <- its part along the joints at y: the velocity block and the position block
        (Δx, and the body rotation 2 vec(q̄ ⊗ Δq) of the quaternion block) each projected
        mass-orthogonally onto the tangent space; the quaternion's radial part kept."""
        n = self.model.n
        out = e.copy()
        z = y.copy()
        z[7 * n:13 * n] = e[7 * n:13 * n]
        self._project(z, 0.0, 0, homogeneous=True)
        out[7 * n:13 * n] = z[7 * n:13 * n]
        q = y[3 * n:7 * n].reshape(n, 4)
        dq = e[3 * n:7 * n].reshape(n, 4)
        norm2 = np.einsum("ij,ij->i", q, q)
        radial = np.einsum("ij,ij->i", q, dq) / norm2
        rest = dq - radial[:, None] * q
        w, u = q[:, :1], q[:, 1:]
        dphi = 2.0 * (w * rest[:, 1:] - rest[:, :1] * u - np.cross(u, rest[:, 1:])) \
            / norm2[:, None]
        z = y.copy()
        z[7 * n:10 * n] = e[:3 * n]
        z[10 * n:13 * n] = dphi.ravel()
        self._project(z, 0.0, 0, homogeneous=True)
        out[:3 * n] = z[7 * n:10 * n]
        dphi = z[10 * n:13 * n].reshape(n, 3)
        out[3 * n:7 * n] = (quaternion_rate(q, dphi) + radial[:, None] * q).ravel()
        if self.model.dimension == 2:
            out[13 * n:] = dphi[:, 2]
        e[:] = out

    def dop853(self, y0: np.ndarray, t_bound: float, rtol: float, atol: float, *,
               filter_first: bool = False) -> DOP853:
        """The core's DOP853 with these Python callbacks (projection after each step)."""
        return DOP853(self.rhs, 0.0, y0, t_bound, rtol=rtol, atol=atol, project=self.project,
                      stage=self.stage, tangent=self.tangent, refresh=REFRESH_ATOL,
                      filter_first=filter_first)
