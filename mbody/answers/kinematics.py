"""What the joints say about one body's accelerations, as relations a student may use.

The joints hold at acceleration level, ``Gᵀ v̇ = γ`` (`mbody.equations.constraints`):
for every motion they allow. A combination of these rows in which no other body's
acceleration is left is a relation among this body's accelerations alone (a pendulum's
``a_x = 0.433013 alpha`` at rest, ``- 2.25`` more at ω = 3 rad/s: a_G = α × r − ω² r).
Such relations hold whatever the loads, and they carry no reaction, so a body's row plus
a combination of them is still a true equation: Newton's law with a_G written from a
pivot's kinematics, or the moment equation about a fixed pivot with I_P = I_G + m d².

The relations are kept as r orthonormal rows over the body's n accelerations z,
``K z = d`` (`BodyKinematics.K`, ``d``), not solved once for some of them: a student
may use them in any direction (a screw's ``a_z = h alpha_3`` put in for a_z, or as
``alpha_3 = a_z / h`` for alpha_3). `BodyKinematics.put_in` writes a true row ``t`` in
the accelerations a student wrote:

Write R = [K | −d], the relations as rows over (z, 1), zero on every reaction. The
student's row s (lhs − rhs, over accelerations, reactions and the constant) is a true
equation got from t by the joints' kinematics exactly when

    s = k (t + νᵀR)        for some factor k ≠ 0 and some ν in ℝ^r,

because a relation holds for every motion the joints allow and any linear equation in
the body's accelerations alone that does is a combination of them. R is zero on the
reactions, so those must be k times t's: a reaction left out, reversed or replaced by a
number is never made right. Split the accelerations into W, those the student wrote
(nonzero in s), and U, the others. On U the target is zero:

    K_Uᵀ ν = −t_U        (|U| equations, r unknowns).

Its least-squares solution ν₀ (by the SVD of K_Uᵀ) must leave no residual: else t
cannot be written without an acceleration the student left out, and there is no
target. Every solution is ν = ν₀ + N β, N the null space of K_Uᵀ: the combinations of
relations in which no unwritten acceleration is left, that is, the relations among the
written accelerations alone (a block on a rail has a_y = 0; a pendulum whose student
writes a_x and alpha has a_x = 0.433013 alpha). When there is none (N empty: as many
independent relations as unwritten accelerations, the usual case) the target t + ν₀ᵀR
is t with each unwritten acceleration replaced by the written ones, and it is unique.
When there are some, every β gives a true target, and no one of them is "the"
substitution (a_y = 0.25 alpha and a_y = 0.57735 a_x are both the pendulum's, for a
student who writes a_x and alpha in the moment about the pin). ν₀, the least-squares
solution, is orthogonal to N: it uses no relation among the written accelerations
beyond what eliminating the others takes. β is left free only where that is a choice
of how the eliminated terms are written, `BodyKinematics._choices`: when the row has an
acceleration the student did not write (else nothing was put in, and the row is
compared as written), and only along relations among the row's own written
accelerations that hold none of them at a value (with a_y = 0 held by the joints, any
multiple of a_y would do, and 2.33 alpha_1 written into Newton's row along y of a body
whose joints hold alpha_1 at 0 is not that row). Along those, β is the one that brings
the target closest to s: with t₀ = t + ν₀ᵀR and n_i = (N e_i)ᵀR, the least-squares
(k, γ) of s ≈ k t₀ + Σ γ_i n_i over the keys, each weighted by its tolerance's
reference, and β = γ / k. `mbody.answers.compare` then judges s against the target
with its tolerance on rounded numbers, as against any row: the fit only chooses among
true targets, it never loosens a coefficient.

So an acceleration the student wrote is compared as written: its coefficient in the
target is the row's plus what eliminating the unwritten ones adds to it (in whichever
direction the student solved the relations); only the unwritten ones are eliminated.
Every equation accepted this way is k times the row plus relations, true for every
motion the joints allow.

Only the model's enforced joints count (a reaction whose value the model gives is a
load, its joint not held), and the work is bounded: beyond `MAX_COORDINATES` of
connected bodies only the joints of the nearest bodies are used, which gives fewer
relations, never a wrong one.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from mbody.answers.compare import CONST, Row
from mbody.answers.text import num, terms
from mbody.equations.assemble import Assembly

MAX_COORDINATES = 300
"""At most this many coordinates (of the body and the bodies joined to it) enter the
elimination: a dense SVD of the joints' rows over them."""
_RANK = 1e-9
"""A singular value below this fraction of the largest entry of Gᵀ is zero."""
_SOLVED = 1e-9
"""The unwritten accelerations are eliminated when what is left of them is below this
fraction of their coefficients in the row (rounding noise of the solve)."""
_PIVOT = 1e-3
"""An acceleration is solved for only when that keeps the solved block this far from
singular (the relations' rows are orthonormal): else the next one in order is tried."""


@dataclass(frozen=True)
class Relation:
    """One of the body's accelerations in terms of others: ``acc = Σ coef z + const``.

    Parameters
    ----------
    acc : str
        The acceleration written in terms of the others (``a_x``; or a sum, as a row
        has it, ``0.866025 a_x + 0.5 a_y``, when the joints fix only the sum from the
        others).
    coef : dict of str to float
        Other acceleration -> coefficient (m per rad/s² from an angular one).
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
class PutIn:
    """A true row written in the accelerations a student wrote (`BodyKinematics.put_in`).

    Parameters
    ----------
    row : Row
        The row plus the relations used (module doc): zero on every acceleration the
        student did not write, noise cleaned.
    kinematics : BodyKinematics
        Whose relations.
    t : Row
        The row as it was.
    nu : (r,) array
        The combination of the relations added (module doc).
    written : frozenset of str
        The accelerations the student wrote.
    """

    row: Row
    kinematics: BodyKinematics
    t: Row
    nu: np.ndarray
    written: frozenset[str]

    @property
    def changed(self) -> bool:
        """Whether any relation was put in."""
        return bool(np.any(self.nu != 0.0))

    @cached_property
    def relations(self) -> tuple[Relation, ...]:
        """What was put in, in words: each of the row's accelerations the student did
        not write, in terms of those written (one relation for their sum as the row has
        it, when the joints do not fix them one by one); or, when only relations among
        the written accelerations were used, that relation. Empty when nothing was put
        in. (Worked out when asked: only a verdict's words need it.)"""
        return self.kinematics.used(self.t, self.nu, self.written)


@dataclass(frozen=True, eq=False)
class BodyKinematics:
    """The relations the enforced joints impose on one body's accelerations.

    Parameters
    ----------
    relations : tuple of Relation
        The relations solved for some accelerations ("dependent", the translations
        first) in terms of the others: one way of writing them, the one shown when no
        student's equation says which accelerations it writes.
    sources : tuple of str
        The joints and drivers whose rows make them, in the model's order (``joint O``,
        ``driver motor``).
    accelerations : tuple of str
        The body's accelerations, in row order (``a_x``, ``a_y``, ``alpha``): the
        columns of `K`.
    K : (r, n) array
        The relations' rows over the accelerations, orthonormal: ``K z = d``.
    d : (r,) array
        Their right sides: the velocity terms (m/s², rad/s²).
    """

    relations: tuple[Relation, ...]
    sources: tuple[str, ...]
    accelerations: tuple[str, ...]
    K: np.ndarray
    d: np.ndarray
    _svd: dict = field(default_factory=dict, repr=False, compare=False)
    """K_Uᵀ's SVD by the unwritten accelerations U: a student's equations write the same
    few sets, each compared with many rows."""

    @property
    def dependent(self) -> set[str]:
        """The accelerations `relations` are solved for."""
        return {rel.acc for rel in self.relations}

    @property
    def involved(self) -> set[str]:
        """The accelerations the relations involve: those a student may write from the
        joints' kinematics (the others are free of the joints)."""
        size = np.abs(self.K).max(axis=0, initial=0.0)
        return {a for a, x in zip(self.accelerations, size.tolist(), strict=True)
                if x > _RANK}

    def substitute(self, row: Row) -> Row:
        """A true row with each dependent acceleration (`relations`) replaced by its
        relation: a row in the free accelerations, the reactions and the constant, noise
        cleaned (`put_in` with the free accelerations written).

        Parameters
        ----------
        row : Row
            A true row, or a variant of one.

        Returns
        -------
        Row
        """
        put = self._put_in(row, set(self.accelerations) - self.dependent)
        assert put is not None  # the dependent accelerations are solvable: _dependent
        return put.row

    def put_in(self, row: Row, student: Row, free: Iterable[str] = ()) -> PutIn | None:
        """`row` (a true row, or a variant of one) plus the relations that write it in
        the accelerations `student` writes: zero on every other; where the relations
        among the written accelerations leave a choice, the one closest to `student`
        (module doc).

        A coefficient the relations change has its own magnitude as its error scale,
        with the scale it had: the true row's numbers are exact, and terms that cancel on
        the way (the centripetal parts of a_G in the moment about a fixed pivot) are not
        numbers a student writes.

        Parameters
        ----------
        row : Row
            The row to write.
        student : Row
            The student's row: which accelerations it writes, and what the choice is
            fitted to.
        free : iterable of str
            Keys the comparison leaves open (a variant's constant), left out of the fit.

        Returns
        -------
        PutIn or None
            None when the row cannot be written without an acceleration the student
            left out.
        """
        written = {a for a in self.accelerations if student.get(a) != 0.0}
        return self._put_in(row, written, student, set(free))

    def _put_in(self, t: Row, written: set[str], student: Row | None = None,
                free: set[str] | None = None) -> PutIn | None:
        K, accs = self.K, self.accelerations
        U = [j for j, a in enumerate(accs) if a not in written]
        tU = np.array([t.get(accs[j]) for j in U])
        if not tU.any():  # nothing to eliminate: the row as it is
            return PutIn(t, self, t, np.zeros(K.shape[0]), frozenset(written))
        key = tuple(U)
        if key not in self._svd:
            self._svd[key] = _factor(K[:, U])
        solved = _unwritten(self._svd[key], K[:, U], tU)
        if solved is None:
            return None
        nu, N = solved
        if student is not None and N.shape[1]:
            N = self._choices(N, t, written)
            if N.shape[1]:
                beta = self._closest(t, nu, N, student, written, free or set())
                if beta is not None:
                    nu = nu + N @ beta
        unwritten = {accs[j] for j in U}
        return PutIn(self._plus(t, nu, unwritten), self, t, nu, frozenset(written))

    @cached_property
    def _column_size(self) -> np.ndarray:
        """The largest entry of each column of K (each acceleration's)."""
        return np.abs(self.K).max(axis=0, initial=0.0)

    @cached_property
    def _d_size(self) -> float:
        """The largest entry of d."""
        return float(np.abs(self.d).max(initial=0.0))

    def _choices(self, N: np.ndarray, t: Row, written: set[str]) -> np.ndarray:
        """The part of N (relations among the written accelerations) that only moves the
        eliminated terms among the row's own written accelerations: zero on a written
        acceleration the row does not have, and none that holds one of them at a value
        (a_y = 0 would make its coefficient anything: 2.33 alpha_1 written into Newton's
        row of a body whose joints hold alpha_1 at 0 is not that row). Columns, like N."""
        accs = self.accelerations
        inside = [j for j, a in enumerate(accs) if a in written and t.get(a) != 0.0]
        outside = [j for j, a in enumerate(accs) if a in written and t.get(a) == 0.0]
        N = N @ _null((N.T @ self.K[:, outside]).T)
        S = (N.T @ self.K)[:, inside]  # their rows over the row's written accelerations
        if not S.size:
            return N
        P = np.linalg.pinv(S, rcond=_RANK) @ S
        held = [i for i in range(len(inside)) if abs(P[i, i] - 1.0) <= 1e-9]
        return N @ _null(S[:, held].T) if held else N

    def _plus(self, t: Row, nu: np.ndarray, unwritten: set[str]) -> Row:
        """t + νᵀR without the unwritten accelerations (zero there by construction).
        Each added term's magnitude, for the noise, is |ν|₁ times the largest entry it
        is made of: ν carries the solve's rounding (about 1e-16 of |ν|₁, over the
        smallest singular value it divides by), which a term may not show."""
        add = (nu @ self.K).tolist()
        l1 = float(np.abs(nu).sum())
        size = (l1 * self._column_size).tolist()
        coef = dict(t.coef)
        mag = {k: abs(v) for k, v in t.coef.items()}
        touched: set[str] = set()
        extra = list(zip(self.accelerations, add, size, strict=True))
        extra.append((CONST, -float(nu @ self.d), l1 * self._d_size))
        for key, v, m in extra:
            if key in unwritten:
                coef.pop(key, None)
                mag.pop(key, None)
                continue
            if v != 0.0:
                coef[key] = coef.get(key, 0.0) + v
                mag[key] = mag.get(key, 0.0) + m
                touched.add(key)
        scale = {k: max(t.err(k) if k in t.coef else 0.0, abs(v)) if k in touched
                 else t.err(k) for k, v in coef.items()}
        return Row(coef, scale).cleaned(mag)

    def _closest(self, t: Row, nu: np.ndarray, N: np.ndarray, s: Row, written: set[str],
                 free: set[str]) -> np.ndarray | None:
        """β of the module doc: the relations among the written accelerations (N's
        columns) that bring k (t₀ + Σ β_i n_i) closest to s, each key weighted by its
        tolerance's reference; both rows at unit scale by powers of two (exact), so that
        the choice does not depend on the scale either is written at."""
        unwritten = set(self.accelerations) - written
        t0 = self._plus(t, nu, unwritten)
        R = np.hstack([self.K, -self.d[:, None]])
        n = (N.T @ R)  # (q, n + 1): the relations among the written accelerations
        cols = {a: j for j, a in enumerate(self.accelerations)}
        cols[CONST] = len(self.accelerations)
        keys = sorted((s.keys | t0.keys | (written & set(cols)) | {CONST})
                      - free - unwritten)
        es, et = _exponent(s, keys), _exponent(t0, keys)
        sv = np.array([math.ldexp(s.get(k), -es) for k in keys])
        se = np.array([math.ldexp(s.err(k), -es) for k in keys])
        tv = np.array([math.ldexp(t0.get(k), -et) for k in keys])
        te = np.array([math.ldexp(t0.err(k), -et) for k in keys])
        A = np.column_stack([tv, *(np.array([n[i, cols[k]] if k in cols else 0.0
                                             for k in keys]) for i in range(n.shape[0]))])
        weight = np.ones(len(keys))
        x = None
        for _ in range(3):  # weighted least squares, as compare.fit
            x, *_ = np.linalg.lstsq(A * weight[:, None], sv * weight, rcond=None)
            k = float(x[0])
            ref = np.maximum(se, abs(k) * te)
            floor = 1e-12 * max(float(ref.max(initial=0.0)), 1e-300)
            weight = 1.0 / np.maximum(ref, floor)
        if x is None or not np.all(np.isfinite(x)) or x[0] == 0.0:
            return None
        return x[1:] / x[0] * math.ldexp(1.0, et)

    def used(self, t: Row, nu: np.ndarray, written: frozenset[str]) -> tuple[
            Relation, ...]:
        """What νᵀR puts into t, in words (`PutIn.relations`)."""
        accs, K, d = self.accelerations, self.K, self.d
        U = [j for j, a in enumerate(accs) if a not in written]
        delta, delta_c = nu @ K, -float(nu @ d)
        W = [j for j, a in enumerate(accs) if a in written]
        D = [j for j in U if t.get(accs[j]) != 0.0]
        ref = float(np.abs(nu).sum()) * float(np.abs(K).max(initial=0.0))
        ref_c = float(np.abs(nu).sum()) * float(np.abs(d).max(initial=0.0))
        if not D:
            # only relations among the written accelerations: the largest of them
            # written in terms of the others
            if not W or not np.abs(delta[W]).max() > 1e-12 * max(ref, 1e-300):
                return ()
            j = max(W, key=lambda w: abs(delta[w]))
            c = -float(delta[j])
            return (_relation(accs[j], {accs[w]: delta[w] / c for w in W if w != j},
                              delta_c / c, ref / abs(c), ref_c / abs(c)),)
        if len(D) == 1:
            # z_D = (Σ_W Δ_w z_w + Δ_c) / t_D: Δ = νᵀR is −t_D on z_D and 0 on the rest of U
            c = t.get(accs[D[0]])
            return (_relation(accs[D[0]], {accs[w]: delta[w] / c for w in W}, delta_c / c,
                              ref / abs(c), ref_c / abs(c)),)
        # several: each from K_U z_U = d − K_W z_W, where the joints fix it alone
        KU = K[:, U]
        pinv = np.linalg.pinv(KU, rcond=_RANK)
        proj = pinv @ KU
        out = []
        for j in D:
            i = U.index(j)
            if abs(proj[i, i] - 1.0) > 1e-9:
                break  # not fixed by the written ones alone: their sum, as the row has it
            out.append(_relation(accs[j], {accs[w]: -float(pinv[i] @ K[:, w]) for w in W},
                                 float(pinv[i] @ d), float(np.abs(pinv[i]).sum()),
                                 float(np.abs(pinv[i]) @ np.abs(d))))
        else:
            return tuple(out)
        return (_relation(terms({accs[j]: t.get(accs[j]) for j in D}),
                          {accs[w]: delta[w] for w in W}, delta_c, ref, ref_c),)


def _factor(KU: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """K_Uᵀ's SVD (left, singular values, right) and its rank."""
    if KU.shape[1] == 0:
        r = KU.shape[0]
        return np.zeros((0, 0)), np.zeros(0), np.eye(r), 0
    left, sv, right = np.linalg.svd(KU.T, full_matrices=True)
    return left, sv, right, int(np.count_nonzero(sv > _RANK))  # K's rows: sv <= 1


def _unwritten(factor: tuple[np.ndarray, np.ndarray, np.ndarray, int], KU: np.ndarray,
               tU: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """ν₀ and N of the module doc: the least-squares solution of K_Uᵀ ν = −t_U (None when
    it leaves a residual: t cannot be written without the unwritten accelerations), and
    the null space of K_Uᵀ, as columns; `factor` is K_Uᵀ's `_factor`."""
    left, sv, right, rank = factor
    if KU.shape[1] == 0:
        return np.zeros(KU.shape[0]), right
    nu = right[:rank].T @ ((left[:, :rank].T @ -tU) / sv[:rank])
    residual = KU.T @ nu + tU
    if np.abs(residual).max(initial=0.0) > _SOLVED * float(np.abs(tU).max(initial=0.0)):
        return None
    return nu, right[rank:].T


def _null(M: np.ndarray) -> np.ndarray:
    """An orthonormal basis of {x : M x = 0}, as columns (every x when M has no row)."""
    q = M.shape[1]
    if M.shape[0] == 0:
        return np.eye(q)
    _, sv, right = np.linalg.svd(M, full_matrices=True)
    big = max(float(sv.max(initial=0.0)), 1.0)
    rank = int(np.count_nonzero(sv > _RANK * big))
    return right[rank:].T


def _exponent(row: Row, keys: list[str]) -> int:
    """The power of two that brings `row`'s largest coefficient or scale over `keys` to
    about 1."""
    big = max([abs(row.get(k)) for k in keys] + [row.err(k) for k in keys] + [0.0])
    return math.frexp(big)[1] if 0.0 < big < math.inf else 0


def _relation(acc: str, coef: dict[str, float], const: float, ref: float,
              ref_c: float) -> Relation:
    """A `Relation`, its coefficients below 1e-12 of `ref` and its constant below 1e-12
    of `ref_c` (the magnitudes that made them) set to 0: rounding noise of the solve."""
    kept = {k: float(v) for k, v in coef.items() if abs(v) > 1e-12 * max(ref, 1.0)}
    return Relation(acc, kept, float(const) if abs(const) > 1e-12 * ref_c else 0.0)


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
    return BodyKinematics(relations, _sources(model, [lab for lab in jac.rows if lab in used]),
                          accelerations, K, d)


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
