"""A model packed for the compiled core (`mbody.kernel`, layout in ``kernel.h``).

`pack_model(model)` gives the float array F and the int array I that
``mbody.kernel._core.Model(F, I, planar)`` reads; `pack_unknowns(model, U)` the int
array of one set of unknown reaction components (``_core.Unknowns(model, Iu)``), ordered
for a narrow band of S = G_Uᵀ M⁻¹ G_U. Every reaction component is one constraint
primitive of the core (its `mbody.joint_types` entry); expressions of t (time-varying
loads and known reactions, the laws of driven components) are packed as postfix
programs, each distinct expression once.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from mbody.kernel import _core

if TYPE_CHECKING:
    from mbody.model.expressions import Expression
    from mbody.model.model import Model

BAND_ORDER_ABOVE = 64
"""Unknowns beyond this many are put in breadth-first order from the ground (a narrow band
of S, see `band_order`); fewer keep their label order (any order is fast)."""


class Component(NamedTuple):
    """A reaction component beyond the model's own (a driven joint's, for tests until
    drivers land): one primitive `kind` (``_core.KIND_*``) of joint `joint` about or
    along the joint frame's `axis`, its offset and screw parameter (kernel.h's param0,
    param1), and optionally its law (f, f', f'') as expressions of t."""

    joint: int
    kind: int
    axis: int
    off: float = 0.0
    h: float = 0.0
    law: tuple[Expression, Expression, Expression] | None = None


class _Programs:
    """Distinct expressions of t in packing order, each with its index."""

    def __init__(self) -> None:
        self.exprs: list[Expression] = []
        self._index: dict[object, int] = {}

    def add(self, e: Expression) -> int:
        key = e.tree
        if key not in self._index:
            self._index[key] = len(self.exprs)
            self.exprs.append(e)
        return self._index[key]

    def packed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(starts (u + 1), codes, numbers)."""
        if not self.exprs:  # most models: no cumulative sum of nothing (0.05 ms, first)
            return np.zeros(1, dtype=np.int64), np.zeros(0, np.int64), np.zeros(0)
        progs = [e.program for e in self.exprs]
        starts = np.zeros(len(progs) + 1, dtype=np.int64)
        starts[1:] = np.cumsum([len(c) for c, _ in progs])
        codes = np.concatenate([c for c, _ in progs]) if progs else np.zeros(0, np.int64)
        numbers = np.concatenate([v for _, v in progs]) if progs else np.zeros(0)
        return starts, codes.astype(np.int64), numbers.astype(float)


def _components(model: Model, extra: Sequence[Component]) -> np.ndarray:
    """(m, 3) [joint, kind, axis] of the model's components (each one's constraint
    primitive and joint-frame axis, from its type in `mbody.joint_types`), then the extra
    ones."""
    rt = model.reaction_table
    out = np.empty((len(rt.joint) + len(extra), 3), dtype=np.int64)
    m = len(rt.joint)
    out[:m, 0], out[:m, 1], out[:m, 2] = rt.joint, rt.kind, rt.frame_axis
    for i, c in enumerate(extra):
        out[m + i] = (c.joint, c.kind, c.axis)
    return out


def _rows(*columns: np.ndarray) -> np.ndarray:
    """The integer columns side by side, row after row, flat: ``np.stack(columns,
    axis=1).ravel()`` as int64, without np.stack's checks (a model's first packing pays
    them, cold, 0.03 ms)."""
    out = np.empty((len(columns[0]), len(columns)), dtype=np.int64)
    for i, c in enumerate(columns):
        out[:, i] = c
    return out.ravel()


def pack_model(model: Model, extra: Sequence[Component] = ()) -> tuple[np.ndarray, np.ndarray]:
    """(F, I): the model's constants as one float64 and one int64 array (kernel.h's
    layout); `extra` components follow the model's own (indices m, m + 1, ...)."""
    n = model.n
    ft, sp, jt = model.forces, model.springs, model.joint_table
    k, s, nj = len(ft.names), len(sp.names), len(jt.parent)
    comps = _components(model, extra)
    m = len(comps)
    programs = _Programs()
    varying = np.zeros((0, 3), dtype=np.int64)
    if ft.varying is not None:
        vt = ft.varying
        index = [programs.add(e) for e in vt.exprs]
        varying = np.stack((vt.rows, vt.cols, np.asarray(index, np.int64)[vt.which]),
                           axis=1).astype(np.int64)
    laws: list[list[int]] = []
    law_of = np.empty(m, dtype=np.int64)
    law_of.fill(-1)
    m0 = m - len(extra)
    drivers = getattr(model, "drivers", None)
    first_driver = m0 - (len(drivers) if drivers is not None else 0)
    for i, law in enumerate(drivers.laws if drivers is not None else ()):
        law_of[first_driver + i] = len(laws)
        laws.append([programs.add(e) for e in law])
    for i, c in enumerate(extra):
        if c.law is not None:
            law_of[m0 + i] = len(laws)
            laws.append([programs.add(e) for e in c.law])
    known = [(model.reaction_index[label], programs.add(e))
             for label, e in getattr(model, "known_expressions", {}).items()]
    starts, codes, numbers = programs.packed()
    bodies = np.concatenate((np.asarray(model.mass, float)[:, None],
                             np.asarray(model.J).reshape(n, 9),
                             np.asarray(model.J_inv).reshape(n, 9)), axis=1)
    loads = np.concatenate((np.asarray(ft.B_r, float).reshape(k, 3),
                            np.asarray(ft.vector, float).reshape(k, 3)), axis=1)
    springs = np.concatenate((sp.r_a, sp.r_b, sp.stiffness[:, None],
                              sp.rest_length[:, None], sp.damping[:, None]), axis=1)
    joints = np.concatenate((jt.B_r_child, jt.B_r_parent, jt.C_axis2,
                             jt.P_E3.reshape(nj, 9), jt.C_E3.reshape(nj, 9),
                             jt.length[:, None]), axis=1)
    comps_f = np.zeros((m, 2))
    screw = (comps[:m0, 1] == _core.KIND_SCREW).nonzero()[0]  # h = pitch / 2 pi
    if len(screw):
        comps_f[screw, 1] = jt.pitch[comps[screw, 0]] / (2.0 * np.pi)
    if drivers is not None:  # a driven coordinate's value at the file's pose (param0)
        comps_f[first_driver:m0, 0] = drivers.offset
    for i, c in enumerate(extra):
        comps_f[m0 + i] = (c.off, c.h)
    flags = _core.J_LINK * jt.link.astype(np.int64) + _core.J_PARTICLE_PARENT * jt.particle_parent
    F = np.concatenate((np.asarray(model.gravity, float), bodies.ravel(), loads.ravel(),
                        springs.ravel(), joints.ravel(), comps_f.ravel(), numbers))
    Ii = np.concatenate((
        [n, k, s, nj, m, len(starts) - 1, len(codes), len(varying), len(laws), len(known)],
        _rows(ft.body, ft.in_body, ft.couple), _rows(sp.a, sp.b),
        _rows(jt.parent, jt.child, flags),
        np.concatenate((comps, law_of[:, None]), axis=1).ravel(),
        varying.ravel(), np.asarray(laws, np.int64).ravel(),
        np.asarray(known, np.int64).ravel(), starts, codes,
    )).astype(np.int64)
    return np.ascontiguousarray(F, dtype=float), np.ascontiguousarray(Ii)


def _bodies(model: Model, extra: Sequence[Component]) -> tuple[np.ndarray, np.ndarray]:
    """(child, parent) body of every component (parent −1: ground)."""
    jt = model.joint_table
    joint = _components(model, extra)[:, 0] if extra else model.reaction_table.joint
    return jt.child[joint], jt.parent[joint]


def band_order(child: np.ndarray, parent: np.ndarray, n: int) -> np.ndarray:
    """A breadth-first (Cuthill-McKee) order of components that starts at a joint to the
    ground, so that S = G_Uᵀ M⁻¹ G_U has a narrow band and its pivots measure the joints,
    not the mechanism's size. child/parent: each component's bodies (parent −1: ground).

    Components are coupled through the bodies they act on. From a ground joint, every
    further joint of a tree comes after one that reaches its parent body, so its column
    brings a body no earlier column touches, and its Cholesky pivot keeps a share of its
    diagonal set by its own geometry; only a loop's closing joint has none, and its pivot
    then measures that loop. Reverse Cuthill-McKee, the order before, starts at a far tip:
    a chain's ground joint came last and bound the whole chain at once, its pivot ratio
    falling like the ratio of one link's mass (inertia) to the chain's, 1/n to 1/n³, and
    below 1e-2 the projection, below 1e-6 the solve, took the dense null-space route
    (cubic in n). Each connected part starts at its ground joint nearest to a far body
    (one pass of the usual pseudo-peripheral search), or there if it is not held."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import breadth_first_order

    mu = len(child)
    held = parent < 0
    comp = np.concatenate((np.arange(mu), np.arange(mu)))
    body = np.concatenate((child, parent))
    keep = body >= 0  # nodes: components 0..mu-1, then bodies mu..mu+n-1
    size = mu + n
    A = sp.csr_matrix((np.ones(int(keep.sum())), (comp[keep], mu + body[keep])),
                      shape=(size, size))
    A = (A + A.T).tocsr()

    def reach(start: int) -> np.ndarray:  # the part's components, nearest first
        out = breadth_first_order(A, start, directed=False, return_predecessors=False)
        return out[out < mu]

    seen = np.zeros(mu, bool)
    order = []
    for first in range(mu):
        if seen[first]:
            continue
        far = reach(first)[-1]
        around = reach(int(far))
        grounded = around[held[around]]
        part = reach(int(grounded[0])) if len(grounded) else around
        seen[part] = True
        order.append(part)
    return np.concatenate(order) if order else np.zeros(0, np.int64)


def pack_unknowns(model: Model, U: np.ndarray, extra: Sequence[Component] = ()) -> np.ndarray:
    """The int64 array describing the unknown components U (indices into the packed
    components: the model's, then `extra`), in their solve order (breadth-first from the
    ground beyond BAND_ORDER_ABOVE of them, else as given): see `pack_unknowns_of`."""
    child_all, parent_all = _bodies(model, extra)
    return pack_unknowns_of(child_all, parent_all, model.n, U)


def pack_unknowns_of(child_all: np.ndarray, parent_all: np.ndarray, n: int, U: np.ndarray
                     ) -> np.ndarray:
    """The unknowns array of components U, given every component's child and parent body
    (parent −1: ground) and the number of bodies n.

    Layout: [mu, bw, nnz], U (mu), inc_ptr (n + 1), inc (nnz × [position in U, side]):
    per body, the unknown components acting on it (side 0 child, 1 parent), so that
    S is summed body by body; bw is S's half bandwidth in U's order. Made by the core
    (`mb_pack_unknowns`, one pass per side in U's order: numpy's sort, called cold in
    a model's first run, cost it 0.04 ms).
    """
    U = np.ascontiguousarray(U, dtype=np.int64)
    if len(U) > BAND_ORDER_ABOVE:
        U = U[band_order(child_all[U], parent_all[U], n)]
    out = np.empty(3 + 5 * len(U) + n + 1, dtype=np.int64)
    used = _core.pack_unknowns(np.ascontiguousarray(child_all, dtype=np.int64),
                               np.ascontiguousarray(parent_all, dtype=np.int64), n, U, out)
    return out[:used]


def pack_columns_model(mass: np.ndarray, J: np.ndarray, J_inv: np.ndarray,
                       parent: np.ndarray, child: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F, I) of a system known only by its matrices (an export): n bodies with these
    masses and inertia tensors, and one component per column of G acting on its child and
    parent body, with no geometry (the columns are given to ``Unknowns.solve_given``)."""
    n, m = len(mass), len(child)
    bodies = np.concatenate((np.asarray(mass, float)[:, None], np.asarray(J).reshape(n, 9),
                             np.asarray(J_inv).reshape(n, 9)), axis=1)
    F = np.concatenate((np.zeros(3), bodies.ravel(), np.zeros(m * (_core.JOINT_W + 2))))
    joints = np.stack((parent, child, np.zeros(m, np.int64)), axis=1)
    comps = np.stack((np.arange(m), np.full(m, _core.KIND_FORCE), np.zeros(m, np.int64),
                      np.full(m, -1)), axis=1)
    Ii = np.concatenate(([n, 0, 0, m, m, 0, 0, 0, 0, 0], joints.ravel(), comps.ravel(),
                         [0])).astype(np.int64)
    return np.ascontiguousarray(F, dtype=float), Ii
