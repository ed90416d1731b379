"""Generalized coordinates of a model: one per degree of freedom, each a rate row of
the compiled core (``MB_GQ_*`` in kernel.h).

The candidates, labelled as the coordinates of the stacked equations are:

- every joint's allowed motions (`mbody.joint_types`): ``<joint>.angle`` (the turn about
  its axis, fixed in the parent), ``<joint>.displacement`` (the slide along it),
  ``<joint>.angle1`` / ``.angle2`` (a universal joint), and for a ball joint the three
  quasi-velocities ``<joint>.w1, .w2, .w3`` (the child's angular velocity relative to the
  parent, along the child's body axes: rates without an angle to integrate);
- every body's own coordinates, as the stacked equations label their rows: ``<body>.x``,
  ``.y`` (``.z``) for the mass centre (world axes), ``<body>.theta`` (planar angle) or the
  quasi-velocities ``<body>.w1, .w2, .w3`` (angular velocity along body axes).

By default (`choose`), in this order of preference: each driver's coordinate, the
motions of a spanning tree of the joints (taken in file order, so that a chain's joints
come first and a loop's last joint closes it), then the own coordinates of each body the
tree leaves unattached to the ground (a free body, a particle). A candidate is taken when
it adds a motion the joints and the coordinates taken so far leave free (a rank test at
the state, on the rows scaled to one length unit), until there is one per degree of
freedom. A driver whose coordinate is chosen is not held: its effort becomes that
coordinate's generalized force (``M_q q'' = f_q + effort``); a driver whose coordinate is
not chosen stays a constraint, and moves the mechanism through v = T q' + v_e.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from mbody import conventions as cv
from mbody import joint_types
from mbody.equations.workspace import Unknowns, workspace
from mbody.errors import MbodyError, did_you_mean, option_name
from mbody.kernel import _core
from mbody.model.model import Model, State

RANK_RTOL = 1e-9
"""The joints' rows (scaled to length units: rotation columns over the model's size, each
row to unit length) are independent down to singular values of this fraction of 1."""
INDEPENDENT_RTOL = 1e-6
"""A candidate row adds a motion when its part outside the rows taken so far exceeds this
fraction of its length: a coordinate within a micro-radian of depending on the others
would make T's columns a million times its rate."""

WRAP = 2.0 * np.pi


@dataclass(frozen=True)
class Coordinate:
    """One generalized coordinate: a rate row of the compiled core.

    Parameters
    ----------
    label : str
        ``O.angle``, ``P.displacement``, ``S.w1``, ``plate.x``...
    kind, index, axis, rule : int
        Its row in the core (kernel.h's ``MB_GQ_*``): the kind, the joint or body index,
        the axis, the value rule.
    unit : str
        Of its value: ``rad`` or ``m`` (a quasi-velocity has none: ``rad`` of its rate).
    quasi : bool
        A quasi-velocity: a rate with no coordinate whose derivative it is (a ball's or a
        spatial body's angular velocity components).
    offset : float
        Added to the core's value: a planar revolute's angle counts from the bodies'
        ``angle`` keys (the child's minus the parent's), as a driver's does.
    source : str
        The joint or body it belongs to.
    meaning : str
        A phrase for listings.
    """

    label: str
    kind: int
    index: int
    axis: int
    rule: int
    unit: str
    quasi: bool
    offset: float
    source: str
    meaning: str

    @property
    def row(self) -> tuple[int, int, int, int]:
        return (self.kind, self.index, self.axis, self.rule)

    @property
    def rate_unit(self) -> str:
        return f"{self.unit}/s"

    @property
    def acceleration_label(self) -> str:
        """``O.angle''`` (a coordinate's second derivative), ``S.w1'`` (a quasi-velocity's
        rate: it is itself a velocity)."""
        return f"{self.label}'" if self.quasi else f"{self.label}''"


@dataclass(frozen=True, eq=False)
class CoordinateSet:
    """The chosen coordinates of a model, and what is held while they move.

    Parameters
    ----------
    items : tuple of Coordinate
        The coordinates, in order.
    held : Unknowns
        The reaction components held as constraints (the joints, and the drivers whose
        coordinate is not chosen); the others (known reactions) act as loads.
    efforts : tuple of (str, int)
        A chosen driver's effort label and the index of its coordinate.
    dof : int
        Degrees of freedom at the state they were chosen at.
    cols : (N,) int array
        The model's velocity columns (`columns`).
    length : float
        The model's length scale (m, `size`).
    tree : tuple of str
        The joints of the spanning tree (default choice), or ().
    """

    items: tuple[Coordinate, ...]
    held: Unknowns
    efforts: tuple[tuple[str, int], ...]
    dof: int
    cols: np.ndarray
    length: float
    tree: tuple[str, ...] = ()

    @property
    def labels(self) -> list[str]:
        return [c.label for c in self.items]

    def __len__(self) -> int:
        return len(self.items)

    @cached_property
    def Iq(self) -> np.ndarray:
        """(nq, 4) int64: the rows as the core takes them."""
        return np.array([c.row for c in self.items], dtype=np.int64).reshape(-1, _core.GQ_W)

    @cached_property
    def offsets(self) -> np.ndarray:
        return np.array([c.offset for c in self.items], dtype=float)

    @cached_property
    def scales(self) -> np.ndarray:
        """(k,) each coordinate's scale: 1 rad, or the model's length (m)."""
        return np.where(self.angles, 1.0, self.length)

    @cached_property
    def angles(self) -> np.ndarray:
        """(k,) True for a coordinate in rad (its value wraps)."""
        return np.array([c.unit == "rad" for c in self.items], dtype=bool)

    @cached_property
    def quasi(self) -> np.ndarray:
        return np.array([c.quasi for c in self.items], dtype=bool)

    @cached_property
    def quasi_int(self) -> np.ndarray:
        return self.quasi.astype(np.int64)

    def values(self, raw: np.ndarray) -> np.ndarray:
        """The coordinates' values from the core's (offsets added, angles in (−π, π])."""
        q = raw + self.offsets
        return np.where(self.angles, q - WRAP * np.ceil((q - np.pi) / WRAP), q)

    def __repr__(self) -> str:
        return f"<CoordinateSet: {', '.join(self.labels)} ({self.dof} dof)>"


def columns(model: Model) -> np.ndarray:
    """The velocity columns of the model's stacked rows (indices into 6 n: planar x, y, w3
    per body; a particle's rotations left out), in the order of `Model.coordinates`."""
    rpb = model.rows_per_body
    rows = np.asarray(model.rows)
    body, r = np.divmod(rows, rpb)
    sel = cv.PLANAR_SELECT[r] if model.dimension == cv.PLANAR else r
    return (6 * body + sel).astype(np.int64)


def candidates(model: Model) -> list[Coordinate]:
    """Every joint's motions, then every body's own coordinates (module doc)."""
    out: list[Coordinate] = []
    planar = model.dimension == cv.PLANAR
    jt = model.joint_table
    ref = model.file_state if model.file_state is not None else model.initial
    angle = _planar_angles(ref) if planar else None
    for j, joint in enumerate(model.joints):
        if joint.particle_joint or (jt.child[j] >= 0 and model.particle[jt.child[j]]):
            continue  # a particle's rotation is nothing: it moves by its own coordinates
        typ = joint_types.joint_type(model.dimension, joint.type)
        universal = len([m for m in typ.motions if m.what == joint_types.ROTATION]) == 2 \
            and any(m.on == "child" for m in typ.motions)
        for m in typ.motions:
            if m.what == joint_types.BALL:
                for k in range(3):
                    out.append(Coordinate(f"{joint.name}.w{k + 1}", _core.GQ_CHILD_TURN, j, k, 0,
                                          "rad", True, 0.0, joint.name,
                                          f"{joint.child}'s angular velocity relative to "
                                          f"{joint.parent}, along its body axis {k + 1}"))
                continue
            rotation = m.what == joint_types.ROTATION
            if rotation and m.on == "child":
                kind, axis, rule = _core.GQ_CHILD_TURN, 3, 2
            elif rotation:
                kind, axis, rule = _core.GQ_TURN, m.axis, 1 if universal else 0
            else:
                kind, axis, rule = _core.GQ_SLIDE, m.axis, 0
            offset = 0.0
            if planar and rotation and angle is not None:
                p, c = int(jt.parent[j]), int(jt.child[j])
                offset = float(angle[c] - (angle[p] if p >= 0 else 0.0))
            meaning = (f"turn of {joint.child} relative to {joint.parent} about joint "
                       f"{joint.name}'s {'second ' if m.on == 'child' else ''}axis"
                       if rotation else
                       f"slide of {joint.child} relative to {joint.parent} along joint "
                       f"{joint.name}'s axis")
            out.append(Coordinate(f"{joint.name}.{m.name}", kind, j, axis, rule,
                                  "rad" if rotation else "m", False, offset, joint.name,
                                  meaning))
    labels = model.coordinates
    cols = columns(model)
    for label, col in zip(labels, cols, strict=True):
        body, axis = divmod(int(col), 6)
        name = model.body_names[body]
        rotation = axis >= 3
        quasi = rotation and not planar
        what = ("angle" if planar else f"angular velocity along body axis {axis - 2}"
                ) if rotation else f"mass centre's {'xyz'[axis]} (world)"
        out.append(Coordinate(label, _core.GQ_BODY, body, axis, 0, "rad" if rotation else "m",
                              quasi, 0.0, name, f"{name}'s {what}"))
    seen: dict[str, Coordinate] = {}
    for cand in out:
        if cand.label in seen:
            raise MbodyError(f"the coordinate label {cand.label!r} names both a motion of "
                             f"joint '{seen[cand.label].source}' and one of body "
                             f"'{cand.source}'; rename the joint or the body")
        seen[cand.label] = cand
    return out


def _planar_angles(state: State) -> np.ndarray:
    q = state.quaternion
    return 2.0 * np.arctan2(q[:, 3], q[:, 0])


def size(model: Model) -> float:
    """The model's length scale (m): the spread of its mass centres, joint points and
    springs' ends at the initial state, or its joints' arms if larger (at least 1 mm)."""
    st = model.initial
    R = st.W_R_B
    jt, sp = model.joint_table, model.springs
    pts = [st.position]
    if len(jt.child):
        pts.append(st.position[jt.child] + np.einsum("jab,jb->ja", R[jt.child], jt.B_r_child))
        p = np.asarray(jt.parent)
        pts.append(np.where((p < 0)[:, None], jt.B_r_parent, st.position[p]
                            + np.einsum("jab,jb->ja", R[p], jt.B_r_parent)))
    for end, r in ((sp.a, sp.r_a), (sp.b, sp.r_b)):
        if len(end):
            body = np.asarray(end)
            world = np.where((body < 0)[:, None], r, st.position[body]
                             + np.einsum("jab,jb->ja", R[body], r))
            pts.append(world)
    allp = np.concatenate(pts)
    spread = float(np.ptp(allp, axis=0).max()) if len(allp) > 1 else 0.0
    arms = float(np.abs(jt.B_r_child).max()) if len(jt.child) else 0.0
    return max(spread, arms, 1e-3)


def spanning_tree(model: Model) -> tuple[list[int], list[int]]:
    """(tree joints, roots): joints joining two parts not yet joined, in file order (ground
    is one part; a joint with a particle at its child end never joins); the first body of
    each part the tree leaves apart from ground (its root: it gets its own coordinates)."""
    n = model.n
    parent = list(range(n + 1))  # union-find; node n is ground

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    jt = model.joint_table
    tree = []
    for j, joint in enumerate(model.joints):
        c = int(jt.child[j])
        if joint.particle_joint or model.particle[c]:
            continue
        p = int(jt.parent[j])
        a, b = find(n if p < 0 else p), find(c)
        if a != b:
            parent[b] = a
            tree.append(j)
    roots, seen = [], set()
    ground = find(n)
    for i in range(n):
        r = find(i)
        if r != ground and r not in seen:
            seen.add(r)
            roots.append(i)
    return tree, roots


def held_rows(model: Model, state: State, U: np.ndarray) -> np.ndarray:
    """G_Uᵀ dense (len(U) x N) over the model's velocity columns (`columns`), from the
    compiled core's columns at `state`."""
    ws = workspace(model)
    m, n = len(model.reactions), model.n
    child6, parent6 = np.empty((m, 6)), np.empty((m, 6))
    W_e, W_P = np.empty((m, 3)), np.empty((m, 3))
    gamma, phi, gtv = np.empty(m), np.empty(m), np.empty(m)
    ws.core.columns(float(state.t), ws.pack_state(state), child6, parent6, W_e, W_P, gamma,
                    phi, gtv)
    jt = model.joint_table
    U = np.asarray(U, dtype=np.intp)
    joint = np.asarray(model.reaction_table.joint)[U]
    cols = columns(model)
    where = np.full(6 * n, -1, dtype=np.intp)  # a body's 6 components -> their column
    where[cols] = np.arange(len(cols))
    out = np.zeros((len(U), len(cols)))
    rows = np.arange(len(U))[:, None]
    # a child and its parent are two bodies: each entry gets one value at most
    for body, six in ((np.asarray(jt.child)[joint], child6[U]),
                      (np.asarray(jt.parent)[joint], parent6[U])):
        at = where[6 * np.maximum(body, 0)[:, None] + np.arange(6)]
        keep = (at >= 0) & (body >= 0)[:, None]
        out[np.broadcast_to(rows, at.shape)[keep], at[keep]] = six[keep]
    return out


class _Rows:
    """The rate rows of candidates and of the held components at one state, scaled to
    length units, with a growing orthonormal basis of the rows taken."""

    def __init__(self, model: Model, state: State, cands: list[Coordinate], held: np.ndarray):
        self.model = model
        ws = workspace(model)
        cols = columns(model)
        Iq = np.array([c.row for c in cands], dtype=np.int64).reshape(-1, _core.GQ_W)
        rows = np.empty((len(cands), len(cols)))
        values = np.empty(len(cands))
        y = ws.pack_state(state)
        ws.core.coordinate_rows(float(state.t), y, Iq, cols, rows, values)
        L = size(model)
        scale = np.where(cols % 6 >= 3, 1.0 / L, 1.0)
        self.rows = rows * scale
        G = held_rows(model, state, held) * scale
        self.N = len(cols)
        self._basis = np.zeros((self.N, self.N))  # filled row by row: no copies
        self.rank = 0
        if len(G):
            norms = np.linalg.norm(G, axis=1)
            G = G[norms > 0] / norms[norms > 0, None]
            _, s, Vt = np.linalg.svd(G, full_matrices=False)
            self.rank = int(np.count_nonzero(s > RANK_RTOL * max(s[0], 1.0))) if len(s) else 0
            self._basis[:self.rank] = Vt[:self.rank]
        self._size = self.rank

    @property
    def basis(self) -> np.ndarray:
        """The orthonormal rows spanning the held rows and the candidates taken."""
        return self._basis[:self._size]

    def adds(self, k: int) -> bool:
        """Take candidate k if it adds a motion (then it joins the basis)."""
        a = self.rows[k]
        norm = float(np.linalg.norm(a))
        if norm == 0.0:
            return False
        basis = self.basis
        r = a - basis.T @ (basis @ a)
        r = r - basis.T @ (basis @ r)  # twice is enough (Kahan, Parlett)
        nr = float(np.linalg.norm(r))
        if nr <= INDEPENDENT_RTOL * norm:
            return False
        self._basis[self._size] = r / nr
        self._size += 1
        return True


def _first_distinct(order: list[int], count: int) -> list[int]:
    """The first `count` distinct entries of `order` (fewer when it has fewer)."""
    out: list[int] = []
    seen: set[int] = set()
    for k in order:
        if len(out) >= count:
            break
        if k not in seen:
            seen.add(k)
            out.append(k)
    return out


def _independent(model: Model, state: State, held: Unknowns, items: list[Coordinate]) -> bool:
    """Whether `choose`'s tests would take every one of `items`, in order, after the held
    rows, and find the held rows independent: proved without those tests, whose dense
    orthogonal bases cost the cube of the model's size (a chain of a thousand bodies: minutes).

    With B the held rows and the items' rows stacked (each scaled as `_Rows` scales it, to
    unit length), square, the compiled core gives each row's distance from the span of all
    the others, d_i = 1/|B⁻¹ e_i|, at the band's cost (`mb_independence`). An item's
    distance from the rows before it is at least its d_i: above `INDEPENDENT_RTOL` (twice,
    for the rounding of both) it is taken. The held rows' smallest singular value is at
    least B's, at least 1/√(Σ 1/d_i²): above `RANK_RTOL` √m (twice) the SVD finds all m
    independent. When either bound falls short, `choose` runs its own tests."""
    cols = columns(model)
    m, k = len(held.U), len(items)
    if m + k != len(cols) or k == 0:
        return False
    scale = np.where(cols % 6 >= 3, 1.0 / size(model), 1.0)
    Iq = np.array([c.row for c in items], dtype=np.int64).reshape(-1, _core.GQ_W)
    out = np.empty(m + k + 1)
    ws = workspace(model)
    ws.solver(held).independence(float(state.t), ws.pack_state(state), Iq, cols, scale, out)
    d = out[:-1]
    if not out[-1] > 0.0 or not np.all(d > 0.0):
        return False
    sigma = 1.0 / float(np.sqrt(np.sum(1.0 / d**2)))
    return bool(np.all(d[m:] > 2.0 * INDEPENDENT_RTOL)
                and sigma > 2.0 * RANK_RTOL * max(np.sqrt(m), 1.0))


def _held(model: Model, known: dict[str, float], free_drivers: Sequence[int]) -> Unknowns:
    """Every component but the known ones and the efforts of the drivers in `free_drivers`
    (their coordinates are chosen)."""
    ws = workspace(model)
    given = dict(known)
    first = len(model.reactions) - (len(model.drivers) if model.drivers is not None else 0)
    for d in free_drivers:
        given[model.reactions[first + d]] = 0.0
    return ws.unknowns(given)


def _driver_labels(model: Model) -> list[str]:
    """Each driver's coordinate label (``<joint>.<motion>``)."""
    drivers = model.drivers
    if drivers is None:
        return []
    out = []
    jt = joint_types
    for j, axis, kind in zip(drivers.joint, drivers.axis, drivers.kind, strict=True):
        joint = model.joints[int(j)]
        typ = jt.joint_type(model.dimension, joint.type)
        what = jt.ROTATION if int(kind) == jt.base.TURN else jt.TRANSLATION
        m = next(m for m in typ.motions if m.what == what and m.axis == int(axis)
                 and m.on == "parent")
        out.append(f"{joint.name}.{m.name}")
    return out


def choose(model: Model, state: State | None = None, labels: Sequence[str] | None = None,
           known: dict[str, float] | None = None) -> CoordinateSet:
    """The generalized coordinates of `model` (module doc): the default choice, or the
    coordinates named by `labels`, checked to be one per degree of freedom and independent
    at `state` (default: the model's initial state).

    Raises
    ------
    MbodyError
        An unknown label (with a did-you-mean), too many or too few, or coordinates that
        do not determine the motion (which one adds nothing).
    """
    state = model.initial if state is None else state
    known = dict(model.known_reactions_at(state.t) if known is None else known)
    cands = candidates(model)
    by_label = {c.label: k for k, c in enumerate(cands)}
    driver_labels = _driver_labels(model)
    n_drivers = len(driver_labels)
    m = len(model.reactions)
    first_driver = m - n_drivers
    if labels is not None:
        chosen_idx = []
        for lab in labels:
            if lab not in by_label:
                hint = did_you_mean(lab, list(by_label))
                raise MbodyError(f"no coordinate {lab!r} in model '{model.name}'"
                                 + (f"; {hint}" if hint else "")
                                 + f" (joint coordinates: "
                                 f"{', '.join(c.label for c in cands if c.kind != _core.GQ_BODY)}"
                                 "; or a body's own: " + ", ".join(model.coordinates[:6])
                                 + (" ..." if len(model.coordinates) > 6 else "") + ")")
            if by_label[lab] in chosen_idx:
                raise MbodyError(f"coordinate {lab!r} is given twice")
            chosen_idx.append(by_label[lab])
        free = [d for d, lab in enumerate(driver_labels) if lab in labels]
        held = _held(model, known, free)
        items = tuple(cands[k] for k in chosen_idx)
        if _independent(model, state, held, list(items)):
            dof = len(items)
        else:
            rows = _Rows(model, state, cands, held.U)
            dof = rows.N - rows.rank
            if len(chosen_idx) != dof:
                raise MbodyError(f"{len(chosen_idx)} coordinate(s) given for {dof} degree(s) "
                                 f"of freedom of model '{model.name}'"
                                 + (" (with its drivers held)" if n_drivers > len(free) else "")
                                 + f": give {dof}")
            for k in chosen_idx:
                if not rows.adds(k):
                    raise MbodyError(f"coordinate {cands[k].label!r} does not add a motion "
                                     "the joints and the coordinates before it leave free at "
                                     "this state: choose another")
        efforts = tuple((model.reactions[first_driver + d],
                         labels.index(driver_labels[d])) for d in free)
        return CoordinateSet(items, held, efforts, dof, columns(model), size(model))
    # the default: drivers' coordinates, the tree's motions, the floating parts' roots
    tree, roots = spanning_tree(model)
    held = _held(model, known, range(n_drivers))
    order: list[int] = [by_label[lab] for lab in driver_labels]
    tree_names = {model.joints[j].name for j in tree}
    order += [k for k, c in enumerate(cands) if c.kind != _core.GQ_BODY and c.source in tree_names]
    root_names = {model.body_names[i] for i in roots}
    particles = {model.body_names[i] for i in np.flatnonzero(model.particle)}
    order += [k for k, c in enumerate(cands) if c.kind == _core.GQ_BODY
              and (c.source in root_names or c.source in particles)]
    listed = set(order)
    order += [k for k in range(len(cands)) if k not in listed]  # anything else, last
    first = _first_distinct(order, len(columns(model)) - len(held.U))
    if _independent(model, state, held, [cands[k] for k in first]):
        taken, dof = first, len(first)
    else:
        rows = _Rows(model, state, cands, held.U)
        dof = rows.N - rows.rank
        taken = []
        chosen: set[int] = set()
        for k in order:
            if len(taken) == dof:
                break
            if k not in chosen and rows.adds(k):
                taken.append(k)
                chosen.add(k)
    if len(taken) < dof:  # cannot happen: the bodies' own coordinates span everything
        raise MbodyError(f"could not choose {dof} independent coordinates for model "
                         f"'{model.name}' at this state; name them with "
                         f"{option_name('coordinates', '[...]')}")
    items = tuple(cands[k] for k in taken)
    efforts = tuple((model.reactions[first_driver + d], taken.index(by_label[lab]))
                    for d, lab in enumerate(driver_labels))
    return CoordinateSet(items, held, efforts, dof, columns(model), size(model),
                         tuple(model.joints[j].name for j in tree))


_CACHE: weakref.WeakKeyDictionary[Model, dict[tuple, CoordinateSet]] = \
    weakref.WeakKeyDictionary()


def coordinate_set(model: Model, labels: Sequence[str] | None = None,
                   known: dict[str, float] | None = None) -> CoordinateSet:
    """`choose` at the model's initial state, kept with the model (per labels and known
    values): a model's coordinates do not change from one state to the next."""
    key = (tuple(labels) if labels is not None else None,
           tuple(sorted((known or {}).items())) if known is not None else None)
    per = _CACHE.get(model)
    if per is None:
        per = {}
        _CACHE[model] = per
    out = per.get(key)
    if out is None:
        out = choose(model, None, labels, known)
        per[key] = out
    return out
