"""What the joints say about one body's accelerations, as relations a student may use.

The joints hold at acceleration level, ``Gᵀ v̇ = γ`` (`mbody.equations.constraints`):
for every motion they allow. A combination of these rows in which no other body's
acceleration is left is a relation among this body's accelerations alone (a pendulum's
``a_x = 0.433013 alpha`` at rest, ``- 2.25`` more at ω = 3 rad/s: a_G = α × r − ω² r).
Such relations hold whatever the loads, and they carry no reaction, so a body's row plus
a combination of them is still a true equation: Newton's law with a_G written from a
pivot's kinematics, or the moment equation about a fixed pivot with I_P = I_G + m d².

The relations are kept solved for some of the body's accelerations ("dependent", the
translations first) in terms of the others ("free"): ``a_dep = Σ E z + a0``. Putting
them into a row (`BodyKinematics.substitute`) leaves a row in the free accelerations,
the reactions and the constant; two rows are equal for every allowed motion exactly
when their substituted rows are equal. The checker puts them into the true row only,
for the accelerations a student did not write (those the student writes are compared
as they are), and `mbody.answers.compare` judges the student's row against that with
its tolerance on rounded numbers.

Only the model's enforced joints count (a reaction whose value the model gives is a
load, its joint not held), and the work is bounded: beyond `MAX_COORDINATES` of
connected bodies only the joints of the nearest bodies are used, which gives fewer
relations, never a wrong one.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from mbody.answers.compare import CONST, Row
from mbody.answers.text import num, terms
from mbody.equations.assemble import Assembly

MAX_COORDINATES = 300
"""At most this many coordinates (of the body and the bodies joined to it) enter the
elimination: a dense SVD of the joints' rows over them."""
_RANK = 1e-9
"""A singular value below this fraction of the largest entry of Gᵀ is zero."""
_PIVOT = 1e-3
"""An acceleration is solved for only when that keeps the solved block this far from
singular (the relations' rows are orthonormal): else the next one in order is tried."""


@dataclass(frozen=True)
class Relation:
    """One of the body's accelerations in terms of its free ones: ``acc = Σ coef z +
    const``.

    Parameters
    ----------
    acc : str
        The dependent acceleration (``a_x``).
    coef : dict of str to float
        Free acceleration -> coefficient (m per rad/s² from an angular one).
    const : float
        The velocity terms (m/s² or rad/s²).
    """

    acc: str
    coef: dict[str, float]
    const: float

    @property
    def text(self) -> str:
        """``a_x = 0.433013 alpha - 2.25``."""
        right, c = terms(self.coef), num(self.const)
        if right == "0":
            return f"{self.acc} = {c}"
        if c != "0":
            right += f" - {c[1:]}" if c.startswith("-") else f" + {c}"
        return f"{self.acc} = {right}"


@dataclass(frozen=True)
class BodyKinematics:
    """The relations the enforced joints impose on one body's accelerations.

    Parameters
    ----------
    relations : tuple of Relation
        One per dependent acceleration.
    sources : tuple of str
        The joints and drivers whose rows make them, in the model's order (``joint O``,
        ``driver motor``).
    """

    relations: tuple[Relation, ...]
    sources: tuple[str, ...]

    @property
    def dependent(self) -> set[str]:
        """The accelerations the relations replace."""
        return {rel.acc for rel in self.relations}

    def substitute(self, row: Row, keep: Iterable[str] = ()) -> Row:
        """A true row with each dependent acceleration but those in `keep` replaced by
        its relation: a row in the free accelerations (and those kept), the reactions
        and the constant, noise cleaned. A coefficient the relations change has its
        own magnitude as its error scale, with the scale it had: the true row's numbers
        are exact, and terms that cancel on the way (the centripetal parts of a_G in the
        moment about a fixed pivot) are not numbers a student writes.

        Parameters
        ----------
        row : Row
            A true row, or a variant of one.
        keep : iterable of str
            Dependent accelerations left as they are (the student writes them).

        Returns
        -------
        Row
        """
        keep = set(keep)
        coef = dict(row.coef)
        mag = {k: abs(v) for k, v in row.coef.items()}
        touched: set[str] = set()
        for rel in self.relations:
            if rel.acc in keep:
                continue
            c = coef.pop(rel.acc, 0.0)
            mag.pop(rel.acc, None)
            if c == 0.0:
                continue
            for key, e in (*rel.coef.items(), (CONST, rel.const)):
                if e != 0.0:
                    coef[key] = coef.get(key, 0.0) + c * e
                    mag[key] = mag.get(key, 0.0) + abs(c * e)
                    touched.add(key)
        scale = {k: max(row.err(k) if k in row.coef else 0.0, abs(v)) if k in touched
                 else row.err(k) for k, v in coef.items()}
        return Row(coef, scale).cleaned(mag)

    def replaced(self, row: Row, keep: Iterable[str] = ()) -> list[Relation]:
        """The relations `substitute` puts into `row` (keeping `keep`)."""
        keep = set(keep)
        return [rel for rel in self.relations
                if rel.acc not in keep and row.get(rel.acc) != 0.0]


def body_kinematics(asm: Assembly, body: str, labels: tuple[str, ...],
                    accelerations: tuple[str, ...]) -> BodyKinematics | None:
    """The relations the joints impose on `body`'s accelerations (module doc).

    Parameters
    ----------
    asm : Assembly
        The model's equations at its state.
    body : str
        The body.
    labels : tuple of str
        Its coordinates' labels (``rod.x``...), in row order.
    accelerations : tuple of str
        The acceleration each stands for (``a_x``...).

    Returns
    -------
    BodyKinematics or None
        None when the joints leave the body's accelerations free.
    """
    model = asm.model
    known = model.known_reactions_at(asm.state.t)
    jac = asm.jacobian()
    GT = jac.matrix.tocsr()
    enforced = np.array([lab not in known for lab in jac.rows], dtype=bool)
    if not enforced.any():
        return None
    column_body = np.empty(len(jac.columns), dtype=np.int64)
    for i in range(model.n):
        column_body[model.body_rows(i)] = i
    own = model.index[body]
    bodies = _neighbourhood(GT, enforced, column_body, own)
    cols = np.flatnonzero(np.isin(column_body, list(bodies)))
    inside = np.zeros(len(jac.columns), dtype=bool)
    inside[cols] = True
    rows = [r for r in range(GT.shape[0]) if enforced[r] and _within(GT, r, inside)]
    if not rows:
        return None
    A = GT[rows][:, cols].toarray()
    gamma = np.asarray(jac.gamma, dtype=float)[rows]
    position = {c: j for j, c in enumerate(cols.tolist())}
    mine = [position[jac.columns.index(lab)] for lab in labels]
    others = [j for j in range(len(cols)) if j not in set(mine)]
    big = float(np.abs(A).max())
    if big == 0.0:
        return None
    if others:
        U, sv, _ = np.linalg.svd(A[:, others], full_matrices=True)
        rank = int(np.count_nonzero(sv > _RANK * big))
        null = U[:, rank:]
    else:
        null = np.eye(len(rows))
    if null.shape[1] == 0:
        return None
    K_raw = null.T @ A[:, mine]
    d_raw = null.T @ gamma
    P, sv, Vt = np.linalg.svd(K_raw, full_matrices=False)
    r = int(np.count_nonzero(sv > _RANK * big))
    if r == 0:
        return None
    K = Vt[:r]
    d = (P[:, :r].T @ d_raw) / sv[:r]
    weights = null @ (P[:, :r] / sv[:r])  # each joint row's share of the relations
    dependent = _dependent(K, r)
    free = [j for j in range(len(mine)) if j not in dependent]
    KD = K[:, dependent]
    E = -np.linalg.solve(KD, K[:, free]) if free else np.zeros((r, 0))
    a0 = np.linalg.solve(KD, d)
    E[np.abs(E) <= 1e-12 * max(1.0, float(np.abs(E).max(initial=0.0)))] = 0.0
    a0[np.abs(a0) <= 1e-12 * (1.0 + float(np.abs(E).max(initial=0.0)))
       * float(np.abs(d).max(initial=0.0))] = 0.0
    relations = tuple(
        Relation(accelerations[dependent[i]],
                 {accelerations[free[j]]: float(E[i, j]) for j in range(len(free))
                  if E[i, j] != 0.0}, float(a0[i]))
        for i in range(r))
    share = np.abs(weights).max(axis=1)
    used = {jac.rows[rows[i]] for i in range(len(rows)) if share[i] > 1e-9 * share.max()}
    return BodyKinematics(relations, _sources(model, [lab for lab in jac.rows if lab in used]))


def _within(GT, r: int, inside: np.ndarray) -> bool:
    idx = GT.indices[GT.indptr[r]:GT.indptr[r + 1]]
    return len(idx) > 0 and bool(inside[idx].all())


def _neighbourhood(GT, enforced: np.ndarray, column_body: np.ndarray, own: int) -> set[int]:
    """The bodies joined to `own` by enforced joints, nearest first, while their
    coordinates number at most `MAX_COORDINATES`."""
    count = np.bincount(column_body, minlength=int(column_body.max()) + 1)
    by_body: dict[int, set[int]] = {}
    for r in np.flatnonzero(enforced).tolist():
        touched = set(column_body[GT.indices[GT.indptr[r]:GT.indptr[r + 1]]].tolist())
        for b in touched:
            by_body.setdefault(b, set()).update(touched)
    bodies, frontier, size = {own}, [own], int(count[own])
    while frontier:
        nxt = []
        for b in frontier:
            for c in sorted(by_body.get(b, ())):
                if c in bodies or size + int(count[c]) > MAX_COORDINATES:
                    continue
                bodies.add(c)
                size += int(count[c])
                nxt.append(c)
        frontier = nxt
    return bodies


def _dependent(K: np.ndarray, r: int) -> list[int]:
    """r columns of K (orthonormal rows) to solve for: in order (the translations come
    first), each kept when the block stays well conditioned; then the best of the rest."""
    chosen: list[int] = []
    for j in range(K.shape[1]):
        if len(chosen) == r:
            return chosen
        if np.linalg.svd(K[:, [*chosen, j]], compute_uv=False).min() >= _PIVOT:
            chosen.append(j)
    while len(chosen) < r:
        rest = [j for j in range(K.shape[1]) if j not in chosen]
        chosen.append(max(rest, key=lambda j: np.linalg.svd(
            K[:, [*chosen, j]], compute_uv=False).min()))
    return sorted(chosen)


def _sources(model, labels: list[str]) -> tuple[str, ...]:
    """``joint O``, ``driver motor``: the joints and drivers of constraint rows, once
    each, in the model's order."""
    drivers = set(model.drivers.names) if model.drivers is not None else set()
    out: list[str] = []
    for lab in labels:
        name = lab.rpartition(".")[0]
        words = f"driver {name}" if name in drivers else f"joint {name}"
        if words not in out:
            out.append(words)
    return tuple(out)
