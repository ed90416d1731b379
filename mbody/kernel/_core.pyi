"""Type stubs of the C extension mbody.kernel._core (sources in src/; layout in kernel.h).

Every array argument is a C-contiguous float64 (int64 for F/I/Iu: I and Iu) buffer of
exactly the size the model implies; a wrong one raises ValueError naming it.
"""

from typing import Any

import numpy as np
import numpy.typing as npt

_F = npt.NDArray[np.float64]
_I = npt.NDArray[np.int64]

KIND_FORCE: int
KIND_TILT: int
KIND_LOCK: int
KIND_RIGHT_ANGLE: int
KIND_LINK: int
KIND_TURN: int
KIND_SCREW: int
KINDS: int
I_HEADER: int
BODY_W: int
LOAD_W: int
SPRING_W: int
JOINT_W: int
COMP_W: int
J_LINK: int
J_PARTICLE_PARENT: int
OP_NUM: int
OP_T: int
OP_NEG: int
OP_ADD: int
OP_SUB: int
OP_MUL: int
OP_DIV: int
OP_POW: int
OP_SIN: int
OP_COS: int
OP_TAN: int
OP_EXP: int
OP_LOG: int
OP_SQRT: int
OP_ABS: int
ST_RANK: int
ST_BERR: int
ST_BROKEN: int
ST_MU: int
ST_PATH: int
ST_SINGULAR: int
INFO: int
PR_STEP: int
PR_VELOCITY: int
PR_RATIO: int
PR_SINGULAR: int
PROJECT_INFO: int
KN_ITERS: int
KN_ERROR: int
KN_SINGULAR: int
KN_STEP: int
KN_INFO: int

def solve_layout(n: int, m: int, planar: bool) -> tuple[int, int, int]: ...

class Model:
    n: int
    m: int
    k: int
    s: int
    planar: bool
    state_size: int
    n_expr: int
    def __init__(self, F: _F, I: _I, planar: bool) -> None: ...
    def springs(self, t: float, y: _F, out: _F) -> None: ...
    def wrench_parts(self, t: float, y: _F, Q: _F, b: _F) -> None: ...
    def net_wrench(self, t: float, y: _F, out: _F) -> None: ...
    def load_wrenches(self, t: float, y: _F, out: _F) -> None: ...
    def loads_at(self, t: float, out: _F) -> None: ...
    def columns(self, t: float, y: _F, child6: _F, parent6: _F, W_e: _F, W_P: _F,
                gamma: _F, phi: _F, gtv: _F) -> None: ...
    def expression(self, e: int, t: float) -> float: ...

class Unknowns:
    mu: int
    bw: int
    model: Model
    def __init__(self, model: Model, Iu: _I) -> None: ...
    def solve(self, t: float, y: _F, lam: _F, out: _F) -> None: ...
    generic_rank: int
    def set_generic_rank(self, rank: int) -> None: ...
    def solve_given(self, r6: _F, child6: _F, parent6: _F, gamma_U: _F, out: _F) -> None: ...
    def derivative(self, t: float, y: _F, lam: _F, rate: float, out: _F) -> int: ...
    def project(self, t: float, y: _F, iters: int, robust_below: float, homogeneous: Any,
                info: _F) -> None: ...
    def schur(self, t: float, y: _F, S_out: _F) -> None: ...
    def solve_many(self, t: _F, Y: _F, lam: _F, out: _F, F: _F | None,
                   rows: _I | None, states: _I | None) -> None: ...
    def peaks_many(self, t: _F, Y: _F, lam: _F, peaks: _F, F: _F | None, rows: _I | None,
                   states: _I, segment: int) -> None: ...
    def kinematics_many(self, t: _F, Y: _F, F: _F | None, rows: _I | None,
                        chain: _I | None, phi_scale: _F, settings: _F, info: _F) -> None: ...
