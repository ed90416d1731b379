"""Cache-blocked numpy kernels for the per-body right-hand sides of

    m a_G = W_F                                   (Newton, world axes)
    J ω̇ + ω × (J ω) = B_M (+ reactions)          (Euler, body axes)

Layout: structure of arrays. Every per-body quantity is a ``(3, n)`` or ``(6, n)`` array
whose rows are components, so each numpy call works on one long contiguous row. The
bodies are processed in chunks of `CHUNK` so that a chunk's working set (a few dozen
rows of `CHUNK` doubles) stays in the L2 cache; every intermediate goes into a
preallocated scratch buffer (``out=``), so the hot loop allocates nothing.

Rotations use the quaternion directly (no ``(n, 3, 3)`` matrices): with q = (w, u),

    W_R_B v  = v + w c + u × c,   c = 2 u × v
    W_R_Bᵀ v = v + w c + c × u,   c = 2 v × u

What depends only on the model and on the load values at time t is computed once and
cached (`Plan` per model, `LoadFrame` per load-value array):

- world-frame forces and gravity sum to a constant ``W_F`` (and ``a_G = W_F / m``);
- body-frame forces and couples sum to a constant body-axis moment; the body-frame
  forces' sum still has to be turned into world axes each step;
- world-frame couples sum per body and are turned into body axes each step;
- each world-frame force applied away from the mass centre needs its own moment
  ``B_r × (W_R_Bᵀ W_f)`` each step; such forces are laid out in dense "slots" (slot j
  holds every body's j-th offset force) so there is no gather and no scatter.

A group of loads that touches fewer than one body in `DENSE_FRACTION` goes instead
through a sparse path (per load, gathered, summed per body with `np.bincount`), as do
springs and reaction wrenches; the sparse sums are added chunk by chunk.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple, overload

import numpy as np

if TYPE_CHECKING:
    from mbody.model.model import Model, State


CHUNK = 16384
"""Bodies per block (measured best on a 2 MB-L2 machine: fewer, longer numpy calls)."""
DENSE_FRACTION = 8
"""A load group goes through the dense layout when it touches ≥ n / DENSE_FRACTION bodies."""

_mul, _add, _sub = np.multiply, np.add, np.subtract


# -- small vector kernels on "rolled" component rows --------------------------------------
# A vector field is stored as (5, L) rows [x, y, z, x, y], so that V[1:4] = (y, z, x) and
# V[2:5] = (z, x, y) are views: a cross product is then 3 numpy calls on (3, L) blocks
# instead of 9 on single rows (fewer calls = less interpreter overhead per body).
def roll(V: np.ndarray) -> np.ndarray:
    """Make (5, L) rows [x, y, z, ., .] rolled: rows 3, 4 = rows 0, 1."""
    np.copyto(V[3:5], V[0:2])
    return V


def cross(a: np.ndarray, b: np.ndarray, out: np.ndarray, tmp: np.ndarray) -> np.ndarray:
    """out (3, L) = a × b for rolled a, b (5, L); `tmp` is (3, L) scratch."""
    _mul(a[1:4], b[2:5], out)
    _mul(a[2:5], b[1:4], tmp)
    return _sub(out, tmp, out)


def cross_add(a: np.ndarray, b: np.ndarray, out: np.ndarray, tmp: np.ndarray,
              sign: float = 1.0) -> np.ndarray:
    """out (3, L) += sign (a × b) for rolled a, b (sign ±1)."""
    inc, dec = (_add, _sub) if sign > 0 else (_sub, _add)
    _mul(a[1:4], b[2:5], tmp)
    inc(out, tmp, out)
    _mul(a[2:5], b[1:4], tmp)
    return dec(out, tmp, out)


def rotate(w: np.ndarray, u: np.ndarray, v: np.ndarray, out: np.ndarray, c: np.ndarray,
           tmp: np.ndarray, transpose: bool = False) -> np.ndarray:
    """out[0:3] = W_R_B v (or W_R_Bᵀ v with `transpose`) for q = (w, u).

    w: (L,); u, v, out, c: rolled (5, L) (c: scratch); tmp: (3, L). W_R_B v = v + w c +
    u × c with c = 2 u × v; the transpose uses −u, i.e. c = 2 v × u and v + w c + c × u.
    """
    c3, o3 = c[0:3], out[0:3]
    if transpose:
        cross(v, u, c3, tmp)
    else:
        cross(u, v, c3, tmp)
    _mul(c3, 2.0, c3)
    roll(c)
    _mul(c3, w, o3)
    _add(o3, v[0:3], o3)
    if transpose:
        cross_add(c, u, o3, tmp)
    else:
        cross_add(u, c, o3, tmp)
    return out


def matvec(A: np.ndarray, v: np.ndarray, out: np.ndarray, p: np.ndarray, tmp: np.ndarray,
           mode: str) -> np.ndarray:
    """out (3, L) = A v per body; v and p (scratch) rolled (5, L).

    mode "diag": A (3, L) diagonals. "sym": A (6, L) = [A00, A11, A22, A01, A12, A02], and
    A v = D∘v + E∘(v_y, v_z, v_x) + P(E∘v) with D the diagonal, E = (A01, A12, A02) and
    P(p) = (p_z, p_x, p_y). "full": A (9, L) row-major entries, one row at a time.
    """
    if mode == "diag":
        return _mul(A, v[0:3], out)
    if mode == "sym":
        E = A[3:6]
        _mul(A[0:3], v[0:3], out)
        _mul(E, v[1:4], tmp)
        _add(out, tmp, out)
        _mul(E, v[0:3], p[0:3])
        roll(p)
        return _add(out, p[2:5], out)
    for i in range(3):
        o, term = out[i], tmp[0]
        _mul(A[3 * i], v[0], o)
        _mul(A[3 * i + 1], v[1], term)
        _add(o, term, o)
        _mul(A[3 * i + 2], v[2], term)
        _add(o, term, o)
    return out


def quat_rotate(q: np.ndarray, v: np.ndarray, transpose: bool = False) -> np.ndarray:
    """W_R_B v (or W_R_Bᵀ v) for (..., 4) unit quaternions and (..., 3) vectors: the one
    quaternion rotation of the numpy path (AoS, for the sparse paths and springs)."""
    w, u = q[..., :1], q[..., 1:]
    if transpose:
        u = -u
    c = 2.0 * np.cross(u, v)
    return v + w * c + np.cross(u, c)


# -- per-model and per-load-value data ---------------------------------------------------
@dataclass(frozen=True)
class Plan:
    """What a model's hot path needs, laid out once (constant in body axes).

    inv_mass: (n,) 1/m. J, J_inv: entries as `matvec` reads them for `mode` ("diag" when
    every tensor is diagonal, "sym" when every tensor is exactly symmetric, else "full").
    chunks: [(start, stop)] body blocks. Vector fields are rolled (5, n) rows.
    """

    n: int
    mass: np.ndarray
    inv_mass: np.ndarray
    gravity: np.ndarray
    mode: str
    J: np.ndarray
    J_inv: np.ndarray
    chunks: tuple[tuple[int, int], ...]
    block: int  # the longest chunk (scratch size)
    kind: np.ndarray  # per load: 0 world force, 1 body force, 2 world couple, 3 body couple
    slot_bodies: tuple[np.ndarray, ...]  # dense offset-force slots: bodies of slot j
    slot_loads: tuple[np.ndarray, ...]  # ... and the force-table rows they hold
    slot_r: tuple[np.ndarray, ...]  # (5, n) application points of slot j (0 elsewhere)
    sparse_loads: np.ndarray  # force-table rows that take the sparse path each step
    dense_body_forces: bool
    dense_world_couples: bool
    dense_body_couples: bool


def _entries(J: np.ndarray, mode: str) -> np.ndarray:
    if mode == "diag":
        return np.ascontiguousarray(np.diagonal(J, axis1=1, axis2=2).T)
    if mode == "sym":
        i, j = [0, 1, 2, 0, 1, 0], [0, 1, 2, 1, 2, 2]
        return np.ascontiguousarray(0.5 * (J[:, i, j] + J[:, j, i]).T)
    return np.ascontiguousarray(J.reshape(-1, 9).T)


def rolled(a: np.ndarray) -> np.ndarray:
    """(k, 3) rows -> rolled (5, k) component rows [x, y, z, x, y]."""
    return np.ascontiguousarray(np.asarray(a, float).T[[0, 1, 2, 0, 1]])


def _distinct(index: np.ndarray) -> int:
    return len(np.unique(index)) if len(index) else 0


def build_plan(model: Model) -> Plan:
    n = model.n
    J = np.asarray(model.J)
    off = J.copy()
    off[:, [0, 1, 2], [0, 1, 2]] = 0.0
    # J⁻¹ of an exactly symmetric J is symmetric up to rounding: "sym" averages it out.
    mode = ("diag" if not off.any() else
            "sym" if np.array_equal(J, J.transpose(0, 2, 1)) else "full")
    ft = model.forces
    kind = np.where(ft.couple, 2, 0) + ft.in_body.astype(np.intp)
    dense = lambda sel: _distinct(ft.body[sel]) * DENSE_FRACTION >= max(n, 1)  # noqa: E731

    # World-frame forces away from the mass centre: slot j holds every body's j-th one.
    rows = np.flatnonzero((kind == 0) & np.any(ft.B_r != 0.0, axis=1))
    rows = rows[np.argsort(ft.body[rows], kind="stable")]
    body = ft.body[rows]
    first = np.searchsorted(body, body, side="left")
    rank = np.arange(len(rows)) - first
    slot_bodies, slot_loads, slot_r, sparse = [], [], [], []
    for j in range(int(rank.max()) + 1 if len(rows) else 0):
        sel = rank == j
        if len(np.unique(body[sel])) * DENSE_FRACTION >= n:
            r = np.zeros((5, n))
            r[:, body[sel]] = rolled(ft.B_r[rows[sel]])
            slot_bodies.append(body[sel])
            slot_loads.append(rows[sel])
            slot_r.append(r)
        else:
            sparse.append(rows[rank >= j])
            break
    dbf, dwc, dbc = dense(kind == 1), dense(kind == 2), dense(kind == 3) or dense(kind == 1)
    for k, d in ((1, dbf), (2, dwc), (3, dbc)):
        if not d:
            sparse.append(np.flatnonzero(kind == k))
    sparse_loads = np.sort(np.concatenate(sparse)) if sparse else np.zeros(0, np.intp)
    return Plan(n, np.asarray(model.mass), 1.0 / np.asarray(model.mass),
                np.asarray(model.gravity, float), mode, _entries(J, mode),
                _entries(np.asarray(model.J_inv), mode),
                tuple((s, min(s + CHUNK, n)) for s in range(0, n, CHUNK)), max(1, min(CHUNK, n)),
                kind, tuple(slot_bodies), tuple(slot_loads), tuple(slot_r),
                sparse_loads.astype(np.intp), dbf, dwc, dbc)


@dataclass(frozen=True)
class LoadFrame:
    """Sums that depend only on the load values (cached while they stay the same array).

    W_F: (3, n) world forces + m g; a_G: W_F / m; B_F: rolled (5, n) body-frame forces to
    turn into world axes each step (or None); B_M: (3, n) body-frame moments: couples and
    B_r × f of body-frame forces (or None); W_C: rolled (5, n) world couples (or None);
    slot_f: rolled (5, n) per offset-force slot.
    """

    vector: np.ndarray
    W_F: np.ndarray
    a_G: np.ndarray
    B_F: np.ndarray | None
    B_M: np.ndarray | None
    W_C: np.ndarray | None
    slot_f: tuple[np.ndarray, ...]


def _sum_rows(n: int, body: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(k, 3) rows summed per body -> (3, n)."""
    out = np.zeros((3, n))
    for c in range(3):
        out[c] = np.bincount(body, values[:, c], minlength=n)
    return out


def build_frame(model: Model, plan: Plan, vector: np.ndarray) -> LoadFrame:
    n, ft, kind = plan.n, model.forces, plan.kind
    vec = np.asarray(vector, float)
    w = kind == 0
    W_F = _sum_rows(n, ft.body[w], vec[w]) + plan.mass * plan.gravity[:, None]
    B_F = B_M = W_C = None
    if plan.dense_body_forces and (kind == 1).any():
        s = kind == 1
        B_F = roll(np.vstack((_sum_rows(n, ft.body[s], vec[s]), np.empty((2, n)))))
        B_M = _sum_rows(n, ft.body[s], np.cross(ft.B_r[s], vec[s]))
    if plan.dense_body_couples and (kind == 3).any():
        s = kind == 3
        C = _sum_rows(n, ft.body[s], vec[s])
        B_M = C if B_M is None else B_M + C
    if plan.dense_world_couples and (kind == 2).any():
        s = kind == 2
        W_C = roll(np.vstack((_sum_rows(n, ft.body[s], vec[s]), np.empty((2, n)))))
    slot_f = []
    for bodies, loads in zip(plan.slot_bodies, plan.slot_loads, strict=True):
        f = np.zeros((5, n))
        f[:, bodies] = rolled(vec[loads])
        slot_f.append(f)
    return LoadFrame(vector, W_F, W_F * plan.inv_mass, B_F, B_M, W_C, tuple(slot_f))


def plan_for(model: Model) -> Plan:
    """The model's `Plan` (owned by its evaluation plan, `model.plan`)."""
    return model.plan.kernels


def frame_at(model: Model, t: float) -> LoadFrame:
    """The `LoadFrame` for ``model.forces.vector_at(t)`` (rebuilt only if that array changed)."""
    return model.plan.load_frame(t)


# -- the sparse path ----------------------------------------------------------------------
@dataclass(frozen=True)
class Sparse:
    """Per-body sums from the sparse path: bodies (u,) sorted, W (6, u) rows
    [force (world); moment (body axes)]; bounds (len(chunks) + 1,) into `bodies`."""

    bodies: np.ndarray
    W: np.ndarray
    bounds: np.ndarray


def sparse_wrench(plan: Plan, parts: list[tuple[np.ndarray, np.ndarray]]) -> Sparse | None:
    """Sum (body (k,), wrench (k, 6)) parts per body; body −1 (ground) is dropped."""
    parts = [(b, w) for b, w in parts if len(b)]
    if not parts:
        return None
    body = np.concatenate([b for b, _ in parts])
    W = np.concatenate([w for _, w in parts])
    keep = body >= 0
    body, W = body[keep], W[keep]
    if not len(body):
        return None
    bodies, inv = np.unique(body, return_inverse=True)
    S = np.empty((6, len(bodies)))
    for c in range(6):
        S[c] = np.bincount(inv, W[:, c], minlength=len(bodies))
    starts = np.array([s for s, _ in plan.chunks] + [plan.n])
    return Sparse(bodies, S, np.searchsorted(bodies, starts))


def load_wrenches(model: Model, plan: Plan, frame: LoadFrame, state: State
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Per-load wrenches (k, 6) of the loads on the sparse path at `state`."""
    rows = plan.sparse_loads
    if not len(rows):
        return rows, np.zeros((0, 6))
    ft = model.forces
    body = ft.body[rows]
    vec = np.asarray(frame.vector, float)[rows]
    kind = plan.kind[rows]
    q = state.quaternion[body]
    W = np.zeros((len(rows), 6))
    r = ft.B_r[rows]
    # World-frame forces: their force is already in W_F (frame); only the moment here.
    f = kind == 0
    W[f, 3:] = np.cross(r[f], quat_rotate(q[f], vec[f], transpose=True))
    f = kind == 1
    W[f, :3] = quat_rotate(q[f], vec[f])
    W[f, 3:] = np.cross(r[f], vec[f])
    f = kind == 2
    W[f, 3:] = quat_rotate(q[f], vec[f], transpose=True)
    f = kind == 3
    W[f, 3:] = vec[f]
    return body, W


@overload
def spring_ends(model: Model, position: np.ndarray, quaternion: np.ndarray,
                velocity: np.ndarray, omega: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...
@overload
def spring_ends(model: Model, position: np.ndarray, quaternion: np.ndarray,
                velocity: None = None, omega: None = None
                ) -> tuple[np.ndarray, np.ndarray, None, None]: ...
def spring_ends(model: Model, position: np.ndarray, quaternion: np.ndarray,
                velocity: np.ndarray | None = None, omega: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """World positions P_a, P_b (..., s, 3) of every spring's two ends, and their
    velocities V_a, V_b when `velocity` and `omega` are given (else None). Arrays may have
    a leading time axis (..., n, k). An end on ground (index −1) is its fixed world point.

    P = x + W_R_B r,  V = v + W_R_B (ω × r)  (ω in body axes).
    """
    sp = model.springs
    out = []
    for end, r in ((sp.a, sp.r_a), (sp.b, sp.r_b)):
        on = (end >= 0)[:, None]
        b = np.where(end >= 0, end, 0)
        q = quaternion[..., b, :]
        out.append(np.where(on, position[..., b, :] + quat_rotate(q, r), r))
    if velocity is None or omega is None:
        return out[0], out[1], None, None
    for end, r in ((sp.a, sp.r_a), (sp.b, sp.r_b)):
        on = (end >= 0)[:, None]
        b = np.where(end >= 0, end, 0)
        V = velocity[..., b, :] + quat_rotate(quaternion[..., b, :],
                                               np.cross(omega[..., b, :], r))
        out.append(np.where(on, V, 0.0))
    return out[0], out[1], out[2], out[3]


def spring_tension(model: Model, Pa: np.ndarray, Pb: np.ndarray, Va: np.ndarray,
                   Vb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(L, u, T): length (s,), unit vector from end a to end b (s, 3) and tension (s,)
    T = k (L − L0) + c L̇ (N; positive pulls the ends together)."""
    sp = model.springs
    d = Pb - Pa
    L = np.linalg.norm(d, axis=-1)
    u = np.divide(d, L[..., None], out=np.zeros_like(d), where=L[..., None] > 1e-12)
    T = sp.stiffness * (L - sp.rest_length) + sp.damping * np.einsum("...i,...i->...", u,
                                                                     Vb - Va)
    return L, u, T


def spring_wrenches(model: Model, state: State) -> tuple[np.ndarray, np.ndarray]:
    """Spring-damper wrenches on both ends: +T u on end a, −T u on end b; the moment is
    B_r × (W_R_Bᵀ f)."""
    sp = model.springs
    k = len(sp.names)
    if not k:
        return np.zeros(0, np.intp), np.zeros((0, 6))
    Pa, Pb, Va, Vb = spring_ends(model, state.position, state.quaternion, state.velocity,
                                 state.omega)
    _, u, T = spring_tension(model, Pa, Pb, Va, Vb)
    f = T[:, None] * u
    qa = state.quaternion[np.where(sp.a >= 0, sp.a, 0)]
    qb = state.quaternion[np.where(sp.b >= 0, sp.b, 0)]
    W = np.zeros((2 * k, 6))
    W[:k, :3], W[k:, :3] = f, -f
    W[:k, 3:] = np.cross(sp.r_a, quat_rotate(qa, f, transpose=True))
    W[k:, 3:] = np.cross(sp.r_b, quat_rotate(qb, -f, transpose=True))
    return np.concatenate((sp.a, sp.b)), W


# -- the chunked passes -------------------------------------------------------------------
class ChunkRows(NamedTuple):
    """One chunk's scratch rows (views of length L into a thread's `Scratch`). Rolled
    fields are (5, L) [x, y, z, x, y]."""

    quaternion: np.ndarray  # (6, L) [w, x, y, z, x, y]: u = rows 1:6 is rolled
    omega: np.ndarray  # rolled ω (body axes)
    rotate_c: np.ndarray  # rolled: `rotate`'s c = 2 u × v
    rotated: np.ndarray  # rolled: W_R_Bᵀ of one world load (`moments`)
    moment: np.ndarray  # rolled: B_M, then B_M − ω × J ω (rolled for the J⁻¹ product)
    J_omega: np.ndarray  # rolled: h = J ω
    matvec_p: np.ndarray  # rolled: `matvec`'s scratch p
    force: np.ndarray  # rolled: W_R_B B_F, or the summed world force (`solve`)
    tmp: np.ndarray  # (3, L): the cross products' scratch


_ROLLED_ROWS = 6  # ChunkRows fields from rotate_c to force, stored as one (6, 5, n) block


class Scratch:
    """Preallocated rows for one thread, with the views of each chunk length cached."""

    def __init__(self, size: int):
        self.size = size
        self.q = np.empty((6, size))
        self.omega = np.empty((5, size))
        self.rolled = np.empty((_ROLLED_ROWS, 5, size))
        self.tmp = np.empty((3, size))
        self._views: dict[int, ChunkRows] = {}

    def views(self, L: int) -> ChunkRows:
        """The scratch rows cut to length L."""
        rows = self._views.get(L)
        if rows is None:
            r = self.rolled[:, :, :L]
            rows = self._views[L] = ChunkRows(
                quaternion=self.q[:, :L], omega=self.omega[:, :L], rotate_c=r[0],
                rotated=r[1], moment=r[2], J_omega=r[3], matvec_p=r[4], force=r[5],
                tmp=self.tmp[:, :L])
        return rows


_local = threading.local()


def scratch(size: int) -> Scratch:
    s = getattr(_local, "scratch", None)
    if s is None or s.size < size:
        s = _local.scratch = Scratch(size)
    return s


def _load(a: np.ndarray, s: int, e: int, buf: np.ndarray, rows: int) -> np.ndarray:
    """Bodies s:e of an (n, k) array as (k, L) component rows in `buf`, then rolled."""
    np.copyto(buf[:rows], a[s:e].T)
    np.copyto(buf[rows:], buf[rows - 3:rows - 1])
    return buf


def moments(plan: Plan, frame: LoadFrame, w: np.ndarray, u: np.ndarray, s: int, e: int,
            M: np.ndarray, rows: ChunkRows) -> None:
    """Body-axis applied moments of bodies s:e into M (3, L) (`rows`: the chunk's scratch):

    B_M = Σ_slots B_r × (W_R_Bᵀ W_f) + W_R_Bᵀ W_C + (body-frame moments).
    """
    c, v, tmp = rows.rotate_c, rows.rotated, rows.tmp
    first = True
    if frame.B_M is not None:
        np.copyto(M, frame.B_M[:, s:e])
        first = False
    for r, f in zip(plan.slot_r, frame.slot_f, strict=True):
        rotate(w, u, f[:, s:e], v, c, tmp, transpose=True)
        roll(v)
        if first:
            cross(r[:, s:e], v, M, tmp)
            first = False
        else:
            cross_add(r[:, s:e], v, M, tmp)
    if frame.W_C is not None:
        rotate(w, u, frame.W_C[:, s:e], v, c, tmp, transpose=True)
        if first:
            np.copyto(M, v[0:3])
            first = False
        else:
            _add(M, v[0:3], M)
    if first:
        M.fill(0.0)


def accelerations(plan: Plan, frame: LoadFrame, state: State, sparse: Sparse | None,
                  out: np.ndarray) -> np.ndarray:
    """out (6, n) = [a_G; ω̇] = [W_F / m; J⁻¹ (B_M − ω × J ω)], chunk by chunk.

    `sparse` (forces, moments of the sparse path and reactions) is added per chunk.
    """
    sc = scratch(plan.block)
    mode = plan.mode
    for c, (s, e) in enumerate(plan.chunks):
        rows = sc.views(e - s)
        M, F, om, h, p, tmp = (rows.moment, rows.force, rows.omega, rows.J_omega,
                               rows.matvec_p, rows.tmp)
        qb = _load(state.quaternion, s, e, rows.quaternion, 4)
        w, u = qb[0], qb[1:6]
        a, wd = out[0:3, s:e], out[3:6, s:e]
        M3 = M[0:3]
        moments(plan, frame, w, u, s, e, M3, rows)
        if frame.B_F is not None:  # body-frame forces: a = a_G + (W_R_B B_F) / m
            rotate(w, u, frame.B_F[:, s:e], F, rows.rotate_c, tmp)
            _mul(F[0:3], plan.inv_mass[s:e], F[0:3])
            _add(frame.a_G[:, s:e], F[0:3], a)
        else:
            np.copyto(a, frame.a_G[:, s:e])
        if sparse is not None:
            lo, hi = sparse.bounds[c], sparse.bounds[c + 1]
            if hi > lo:
                b = sparse.bodies[lo:hi]
                a[:, b - s] += sparse.W[:3, lo:hi] * plan.inv_mass[b]
                M3[:, b - s] += sparse.W[3:, lo:hi]
        # Euler: J ω̇ = B_M − ω × (J ω)
        _load(state.omega, s, e, om, 3)
        matvec(plan.J[:, s:e], om, h[0:3], p, tmp, mode)
        roll(h)
        cross_add(om, h, M3, tmp, sign=-1.0)
        roll(M)
        matvec(plan.J_inv[:, s:e], M, wd, p, tmp, mode)
    return out


def loads_and_gyroscopic(plan: Plan, frame: LoadFrame, state: State, sparse: Sparse | None,
                         Q: np.ndarray, b: np.ndarray | None) -> None:
    """Q (6, n) = [W_F; B_M] applied loads and b (3, n) = ω × (J ω) (skipped when b is
    None), chunk by chunk."""
    sc = scratch(plan.block)
    mode = plan.mode
    for c, (s, e) in enumerate(plan.chunks):
        rows = sc.views(e - s)
        F, om, h, p, tmp = rows.force, rows.omega, rows.J_omega, rows.matvec_p, rows.tmp
        qb = _load(state.quaternion, s, e, rows.quaternion, 4)
        w, u = qb[0], qb[1:6]
        moments(plan, frame, w, u, s, e, Q[3:6, s:e], rows)
        if frame.B_F is not None:  # W_F = (world forces + m g) + W_R_B B_F
            rotate(w, u, frame.B_F[:, s:e], F, rows.rotate_c, tmp)
            _add(frame.W_F[:, s:e], F[0:3], Q[0:3, s:e])
        else:
            np.copyto(Q[0:3, s:e], frame.W_F[:, s:e])
        if sparse is not None:
            lo, hi = sparse.bounds[c], sparse.bounds[c + 1]
            if hi > lo:
                Q[:, sparse.bodies[lo:hi]] += sparse.W[:, lo:hi]
        if b is not None:
            _load(state.omega, s, e, om, 3)
            matvec(plan.J[:, s:e], om, h[0:3], p, tmp, mode)
            roll(h)
            cross(om, h, b[:, s:e], tmp)


def solve(plan: Plan, Q: np.ndarray, b: np.ndarray, extra: Sparse | None,
          out: np.ndarray) -> np.ndarray:
    """out (6, n) = [Q_F / m; J⁻¹ (Q_M − b)] plus the `extra` (reaction) wrenches."""
    sc = scratch(plan.block)
    mode = plan.mode
    for c, (s, e) in enumerate(plan.chunks):
        rows = sc.views(e - s)
        M, F, p, tmp = rows.moment, rows.force, rows.matvec_p, rows.tmp
        M3 = M[0:3]
        _sub(Q[3:6, s:e], b[:, s:e], M3)
        a = out[0:3, s:e]
        if extra is not None:
            F3 = F[0:3]
            np.copyto(F3, Q[0:3, s:e])
            lo, hi = extra.bounds[c], extra.bounds[c + 1]
            if hi > lo:
                i = extra.bodies[lo:hi] - s
                F3[:, i] += extra.W[:3, lo:hi]
                M3[:, i] += extra.W[3:, lo:hi]
            _mul(F3, plan.inv_mass[s:e], a)
        else:
            _mul(Q[0:3, s:e], plan.inv_mass[s:e], a)
        roll(M)
        matvec(plan.J_inv[:, s:e], M, out[3:6, s:e], p, tmp, mode)
    return out
