"""Type stubs of the C extension mbody.kernel._core (sources in src/; layout in kernel.h).

Every array argument is a C-contiguous float64 (int64 for F/I/Iu: I and Iu) buffer of
exactly the size the model implies; a wrong one raises ValueError naming it.
"""

from collections.abc import Callable
from typing import Any, overload

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
KR_STEP: int
KR_NEWTON: int
KR_WORST: int
KR_SINGULAR: int
KR_INFO: int

# DOP853 (src/dop853.h, dop853_module.c): state slots, statuses, work rows, test systems;
# a mechanism's params (src/mechanism.h)
DOP_STATE_SIZE: int
DOP_PROJECT_INFO: int
DOP_RTOL: int
DOP_ATOL: int
DOP_MAX_STEP: int
DOP_T_BOUND: int
DOP_SAFETY: int
DOP_FAC_MIN: int
DOP_FAC_MAX: int
DOP_REFRESH: int
DOP_T: int
DOP_H: int
DOP_DIRECTION: int
DOP_T_OLD: int
DOP_H_OLD: int
DOP_STATUS: int
DOP_CODE: int
DOP_STEPS: int
DOP_REJECTED: int
DOP_NFEV: int
DOP_REFRESHED: int
DOP_FILTER: int
DOP_FILTER_NEXT: int
DOP_DENSE: int
DOP_DENSE_NFEV: int
DOP_WALL: int
DOP_MARK_WIDTH: int
DOP_MARK_NEXT: int
DOP_RETURN_AFTER: int
DOP_INFO: int
DOP_RUNNING: int
DOP_FINISHED: int
DOP_TOO_SMALL: int
DOP_STOPPED: int
DOP_W_Y: int
DOP_W_F: int
DOP_W_Y_OLD: int
DOP_W_K: int
DOP_W_DENSE: int
DOP_W_ROWS: int
DOP_PY_ERROR: int
DOP_SYSTEM_OSCILLATOR: int
DOP_SYSTEM_VAN_DER_POL: int
DOP_SYSTEM_ARENSTORF: int
DOP_SYSTEM_PENDULUM: int
MECH_RATE: int
MECH_ROBUST: int
MECH_ITERS: int
MECH_STAGE_ITERS: int
MECH_PARAMS: int

_Problem = tuple[Any, Any, Any, Any, Any, Any]

def dop853_start(problem: _Problem, t0: float, y0: _F, first_step: float, state: _F,
                 work: _F) -> int: ...
def dop853_run(problem: _Problem, t_stop: float, max_steps: int, state: _F,
               work: _F) -> int: ...
def dop853_dense(problem: _Problem, t: _F, out: _F, state: _F, work: _F) -> int: ...
@overload
def dop853_sampled(problem: _Problem, t_stop: float, max_steps: int, t_eval: _F, k: int,
                   out: _F, project_samples: bool, state: _F, work: _F) -> tuple[int, int]: ...
@overload
def dop853_sampled(problem: _Problem, t_stop: float, max_steps: int, t_eval: _F, k: int,
                   out: _F, project_samples: bool, state: _F, work: _F, marks: _F
                   ) -> tuple[int, int, int]: ...
def unit_samples(Y: _F, n: int, planar: bool) -> float: ...
def conservation(mass: _F, J: _F, gravity: _F, stiffness: _F, rest: _F, lengths: _F | None,
                 Y: _F, planar: bool, kind: int, T: _F, V: _F, H: _F, figures: _F,
                 spin: _F) -> None: ...
def samples(unknowns: Unknowns, lam: _F, t: _F, Y: _F, reactions: _F | None,
            lengths: _F | None, drift: _F) -> None: ...
def spectrum(A: _F, dA: float, tol: float, out: _F) -> int: ...
def modes(spectrum: _F, k: int, kept: _I, out: _F) -> int: ...
def dop853_system(number: int, params: _F, t: float, y: _F, ydot: _F) -> None: ...
def dop853_tableau() -> dict[str, list[float]]: ...
def dop853_work_size(n: int) -> int: ...
GQ_TURN: int
GQ_CHILD_TURN: int
GQ_SLIDE: int
GQ_BODY: int
GQ_W: int
GI_RANK: int
GI_RESIDUAL: int
GENERALIZED_INFO: int
LP_STEP: int
LP_ROUNDING: int
LP_STEADY: int
LP_MOVING: int
LP_STOP: int
STOP_NONE: int
STOP_STIFFNESS: int
STOP_SYSTEM: int
LINEARIZE_PARAMS: int
LI_STEADY: int
LI_UNSTEADY: int
LI_TOL: int
LI_KEPT: int
LI_SINGULAR: int
LI_DA: int
MODE_INDEX: int
MODE_KIND: int
MODE_RE: int
MODE_IM: int
MODE_FREQUENCY: int
MODE_DAMPING: int
MODE_W: int
MODE_NEUTRAL: int
MODE_OSCILLATION: int
MODE_GROWTH: int
MODE_DECAY: int
LI_GROWING: int
LI_MODES: int
LI_OSCILLATIONS: int
LI_UNCONVERGED: int
LI_RESTING: int
LI_NORM: int
LINEARIZE_INFO: int
STAGE_GENERALIZED: int
STAGE_DAMPING: int
STAGE_STIFFNESS: int
STAGE_SYSTEM: int
STAGE_HESSENBERG: int
STAGE_SCHUR: int
STAGE_VECTORS: int
STAGES: int

def solve_layout(n: int, m: int, planar: bool) -> tuple[int, int, int]: ...
def pack_unknowns(child: np.ndarray, parent: np.ndarray, n: int, U: np.ndarray,
                  out: np.ndarray) -> int: ...

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
    def coordinate_rows(self, t: float, y: _F, Iq: _I, cols: _I, rows: _F,
                        values: _F) -> None: ...

class Unknowns:
    mu: int
    bw: int
    model: Model
    def __init__(self, model: Model, Iu: _I) -> None: ...
    def solve(self, t: float, y: _F, lam: _F, out: _F
              ) -> tuple[int, float, int, int, int, int]: ...
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
    def kinematic_run(self, t: _F, y: _F, lam: _F, max_newton: int, tol: float, Y: _F,
                      OUT: _F, ENERGY: _F, info: _F) -> int: ...
    def energy_samples(self, t: _F, Y: _F, lam: _F, ACC: _F, ENERGY: _F) -> int: ...
    def generalized(self, t: float, y: _F, lam: _F, Iq: _I, cols: _I, qdot: _F | None,
                    out: _F) -> None: ...
    def independence(self, t: float, y: _F, Iq: _I, cols: _I, colscale: _F, out: _F) -> None: ...
    def generalized_perturbed(self, t: float, y: _F, lam: _F, Iq: _I, cols: _I, qdot: _F,
                              P: _F, out: _F) -> None: ...
    def linearize(self, t: float, y: _F, lam: _F, Iq: _I, cols: _I, scales: _F, quasi: _I,
                  skip: _I, params: _F, out: _F,
                  progress: Callable[[int, int, int], object] | None = None) -> None: ...
    def differences(self, t: float, y: _F, lam: _F, Iq: _I, cols: _I, qdot: _F, h: _F,
                    hu: _F, fscale: _F, rounding: float, skip: _I, out: _F) -> None: ...
