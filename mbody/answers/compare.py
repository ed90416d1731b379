"""Rows ``Σ c_k u_k + c_0 = 0`` and their comparison up to scale, within a tolerance.

A `Row` holds, per unknown (and for the constant, key `CONST`), its coefficient and an
error scale: the sum of the magnitudes of the rounded numbers that went into it. A
student who writes every number to about four significant figures makes errors of about
``tol × scale`` in each coefficient, also where terms cancel (``50 - 49.9``), so two
rows match when, for some factor k,

    |s_i − k t_i| ≤ tol · max(scale_s_i, |k| scale_t_i)        for every key i.

An exact zero on one side must be an exact zero (or rounding noise of the terms that
made it) on the other: a term that is left out is never within tolerance, however
small it is.

The comparison does not depend on the scale a row is written at: ``1e-170*a_x =
5e-170`` is ``a_x = 5``. `fit` brings both rows to magnitudes about 1 by powers of two
(exact in floating point) before it squares anything.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

CONST = "1"
"""The key of the constant term in a `Row`."""
NOISE = 1e-12
"""A coefficient below this fraction of the magnitudes that made it is rounding noise."""


@dataclass(frozen=True)
class Row:
    """``Σ coef[k]·k + coef[CONST] = 0``, with an error scale per key.

    Parameters
    ----------
    coef : dict of str to float
        Unknown name -> coefficient; `CONST` -> the constant term.
    scale : dict of str to float
        Key -> the sum of the magnitudes of the rounded numbers that made the
        coefficient: its error scale (0 for a coefficient that is exact, such as one
        written with the vocabulary's names; a key absent from `scale` uses the
        coefficient's magnitude).
    """

    coef: dict[str, float]
    scale: dict[str, float]

    @classmethod
    def of(cls, coef: Mapping[str, float], scale: Mapping[str, float] | None = None) -> Row:
        """A row from coefficients, the scale defaulting to their magnitudes.

        Parameters
        ----------
        coef : mapping of str to float
            Key -> coefficient.
        scale : mapping of str to float, optional
            Key -> error scale, raised to at least the coefficient's magnitude.

        Returns
        -------
        Row
        """
        scale = dict(scale or {})
        return cls(dict(coef), {k: max(abs(v), scale.get(k, 0.0)) for k, v in coef.items()})

    def get(self, key: str) -> float:
        """The coefficient of `key` (0 when absent)."""
        return self.coef.get(key, 0.0)

    def err(self, key: str) -> float:
        """The error scale of `key` (its magnitude when not given)."""
        return self.scale.get(key, abs(self.coef.get(key, 0.0)))

    @property
    def keys(self) -> set[str]:
        """Keys with a nonzero coefficient."""
        return {k for k, v in self.coef.items() if v != 0.0}

    @property
    def unknowns(self) -> set[str]:
        """Unknowns with a nonzero coefficient."""
        return self.keys - {CONST}

    def cleaned(self, magnitude: Mapping[str, float] | None = None,
                absolute: Iterable[str] = ()) -> Row:
        """Coefficients that are rounding noise set to exactly 0: below `NOISE` times
        their scale (or times `magnitude`), or below `NOISE` itself for the keys named in
        `absolute` (direction cosines and lever arms of the reaction columns).

        Parameters
        ----------
        magnitude : mapping of str to float, optional
            Key -> the magnitude of the terms that made it, when larger than its scale.
        absolute : iterable of str
            Keys whose noise is judged in absolute terms.

        Returns
        -------
        Row
            The same row, noise set to 0.
        """
        mag = magnitude or {}
        absolute = set(absolute)
        coef = {}
        for k, v in self.coef.items():
            ref = max(self.err(k), mag.get(k, 0.0))
            if abs(v) <= NOISE * ref or (k in absolute and abs(v) < NOISE):
                v = 0.0
            coef[k] = v
        return Row(coef, dict(self.scale))

    def scaled(self, k: float) -> Row:
        """k times the row (scales times |k|)."""
        return Row({n: k * v for n, v in self.coef.items()},
                   {n: abs(k) * s for n, s in self.scale.items()})

    def without(self, keys: Iterable[str]) -> Row:
        """The row with the terms of `keys` dropped.

        Parameters
        ----------
        keys : iterable of str
            The terms to drop.

        Returns
        -------
        Row
        """
        drop = set(keys)
        return Row({n: v for n, v in self.coef.items() if n not in drop},
                   {n: s for n, s in self.scale.items() if n not in drop})

    def plus(self, other: Row, factor: float = 1.0) -> Row:
        """self + factor·other (scales add as magnitudes).

        Parameters
        ----------
        other : Row
            The row added.
        factor : float
            Its factor.

        Returns
        -------
        Row
        """
        coef, scale = dict(self.coef), dict(self.scale)
        for n, v in other.coef.items():
            coef[n] = coef.get(n, 0.0) + factor * v
            scale[n] = scale.get(n, abs(self.get(n))) + abs(factor) * other.err(n)
        return Row(coef, scale)

    def with_term(self, key: str, value: float, scale: float | None = None) -> Row:
        """The row with the coefficient of `key` set to `value` (and its scale)."""
        coef, sc = dict(self.coef), dict(self.scale)
        coef[key] = value
        sc[key] = abs(value) if scale is None else max(abs(value), scale)
        return Row(coef, sc)


@dataclass(frozen=True)
class Fit:
    """How well a student's row s matches k·t.

    Parameters
    ----------
    k : float
        The factor: s ≈ k t.
    error : float
        The largest relative error over the keys compared, in units of the tolerance's
        reference (``|s_i − k t_i| / max(scale_s_i, |k| scale_t_i)``).
    errors : dict of str to float
        That error per key (inf where one side has a term the other lacks).
    """

    k: float
    error: float
    errors: dict[str, float]
    ratio: float = 0.0
    """k as the ratio of the two rows brought to magnitude 1: k = ratio·2^(es − et)."""
    exponents: tuple[int, int] = (0, 0)
    """(es, et): the powers of two that brought the student's row and the true row there."""

    def times(self, x: float) -> float:
        """k·x for a coefficient x of the true row, without overflow where k alone would
        (a row written at 1e300 against one at 1e-10): a number at the student's scale."""
        if self.ratio == 0.0:
            return self.k * x
        es, et = self.exponents
        return _ldexp(self.ratio * math.ldexp(x, -et), es)

    def ok(self, tol: float) -> bool:
        """Whether every key matches within `tol`."""
        return self.error <= tol

    def wrong(self, tol: float) -> list[str]:
        """Keys whose coefficients do not match, worst first.

        Parameters
        ----------
        tol : float
            The relative tolerance.

        Returns
        -------
        list of str
        """
        bad = [(e, key) for key, e in self.errors.items() if e > tol]
        return [key for _, key in sorted(bad, key=lambda p: (-p[0], p[1]))]


def fit(s: Row, t: Row, free: Iterable[str] = ()) -> Fit | None:
    """The best k with s ≈ k·t, comparing every key but those in `free`.

    Parameters
    ----------
    s : Row
        The student's row.
    t : Row
        A true row (or a variant of one).
    free : iterable of str
        Keys left out of the comparison (a coefficient the variant leaves open).

    Returns
    -------
    Fit or None
        None when t has no term to compare on, or s has none in common with it.
    """
    keys = sorted((s.keys | t.keys) - set(free))
    (sk, se, es), (tk, te, et) = _unit(s, keys), _unit(t, keys)
    tt = sum(v * v for v in tk)
    if tt == 0.0:
        return None
    k = sum(a * b for a, b in zip(sk, tk, strict=True)) / tt
    if k == 0.0:
        return None
    for _ in range(3):  # weighted least squares: each key counts by its own tolerance
        num = den = 0.0
        for a, b, ea, eb in zip(sk, tk, se, te, strict=True):
            w = max(ea, abs(k) * eb)
            if w > 0.0 and b != 0.0:
                w = max(w, _FLOOR)  # a coefficient known to 1e-150 counts as exact
                num += a * b / (w * w)
                den += b * b / (w * w)
        if den == 0.0 or num == 0.0:
            break
        k = num / den
    return _errors(keys, (sk, se, es), (tk, te, et), k, 0.0)


def fit_on(s: Row, t: Row, key: str) -> Fit:
    """The fit with the factor that makes the coefficients of `key` agree exactly
    (k = s_key / t_key), every key compared; a difference below 1e-15 of its tolerance's
    reference counts as none.

    Parameters
    ----------
    s, t : Row
        The student's row and a true row (or a variant), both with a nonzero `key`.
    key : str
        The key whose coefficients fix the factor.

    Returns
    -------
    Fit
    """
    keys = sorted(s.keys | t.keys)
    (sk, se, es), (tk, te, et) = _unit(s, keys), _unit(t, keys)
    i = keys.index(key)
    k = sk[i] / tk[i] if tk[i] != 0.0 else 0.0  # 0: t spans over 2000 binades
    return _errors(keys, (sk, se, es), (tk, te, et), k, 1e-15)


Unit = tuple[list[float], list[float], int]
"""A row over some keys brought to magnitude about 1: (coefficients, error scales, e),
both lists divided by 2^e."""


def _unit(row: Row, keys: list[str]) -> Unit:
    """The row's coefficients and error scales over `keys`, divided by the power of two
    nearest above the largest of them when that is beyond 2^±200: exact in floating
    point, and the squares `fit` takes neither overflow (a row written at 1e200) nor
    vanish (at 1e-170); a row within 2^±200 is taken as it is (e = 0)."""
    coef, scale = row.coef, row.scale
    c = [coef.get(k, 0.0) for k in keys]
    err = [scale[k] if k in scale else abs(v) for k, v in zip(keys, c, strict=True)]
    big = max(max(map(abs, c), default=0.0), max(err, default=0.0))
    e = math.frexp(big)[1] if 0.0 < big < math.inf else 0
    if -_SAFE <= e <= _SAFE:
        return c, err, 0
    return [math.ldexp(v, -e) for v in c], [math.ldexp(v, -e) for v in err], e


_SAFE = 200
"""Rows whose magnitudes are within 2^±200 are compared as they are: their squares and
the weights 1/w² (w down to `_FLOOR` times them) stay normal doubles."""


def _errors(keys: list[str], s: Unit, t: Unit, k: float, noise: float) -> Fit:
    """The `Fit` of factor k between two rows at unit scale: per key |s − k t| over
    max(scale_s, |k| scale_t), 0 where that difference is within `noise` of it."""
    (sk, se, es), (tk, te, et) = s, t
    errors = {}
    for key, a, b, ea, eb in zip(keys, sk, tk, se, te, strict=True):
        ref = max(ea, abs(k) * eb)
        diff = abs(a - k * b)
        errors[key] = 0.0 if diff <= noise * ref else (diff / ref if ref > 0.0 else math.inf)
    return Fit(_ldexp(k, es - et), max(errors.values(), default=0.0), errors, k, (es, et))


def _ldexp(x: float, e: int) -> float:
    """x·2^e, ±inf where that overflows (math.ldexp raises)."""
    try:
        return math.ldexp(x, e)
    except OverflowError:
        return math.copysign(math.inf, x)


_FLOOR = 1e-150
"""Smallest weight scale in `fit`, relative to a row's largest magnitude (its square is
still a normal double)."""


def consensus(s: Row, t: Row, tol: float, prefer: str = "") -> Fit | None:
    """The fit of `s` to `t` whose factor most of their common terms agree with (each
    term's coefficients made equal in turn, `fit_on`), the key `prefer` breaking ties
    (a row's own acceleration), so that the minority of wrong terms stands out; the
    least-squares `fit` when they share no term.

    Parameters
    ----------
    s, t : Row
        The student's row and a true row (or a variant).
    tol : float
        Relative tolerance on each coefficient.
    prefer : str
        The key whose factor wins a tie.

    Returns
    -------
    Fit or None
    """
    best: tuple | None = None
    for key in sorted(s.keys & t.keys):
        fk = fit_on(s, t, key)
        score = (len(fk.wrong(tol)), key != prefer, fk.error)
        if best is None or score < best[0]:
            best = (score, fk)
    return best[1] if best is not None else fit(s, t)


ROUNDING = 0.03
"""A coefficient within this fraction of the row's (and beyond the tolerance) in an
equation with every term in place is a number rounded too coarsely."""


def rounded_off(s: Row, t: Row, f: Fit, tol: float) -> dict[str, float] | None:
    """How far each differing coefficient of `s` is from ``k·t`` (the fit `f`), relative,
    when `s` has exactly the terms of `t` and each is within `ROUNDING`: a number
    written with too few figures; else None.

    Parameters
    ----------
    s, t : Row
        The student's row and the row it is compared with.
    f : Fit
        Their fit (`consensus`).
    tol : float
        The relative tolerance.

    Returns
    -------
    dict of str to float or None
        Key -> |s − k t| / |k t|, for the keys beyond the tolerance.
    """
    if s.keys != t.keys:
        return None
    off = {}
    for key in f.wrong(tol):
        want = f.times(t.get(key))
        off[key] = abs(s.get(key) - want) / abs(want) if want != 0.0 else math.inf
    if not off or max(off.values()) > ROUNDING:
        return None
    return off


def matches(s: Row, t: Row, tol: float, free: Iterable[str] = ()) -> Fit | None:
    """`fit` when it is within `tol`, else None.

    Parameters
    ----------
    s, t : Row
        The student's row and a true row (or a variant).
    tol : float
        Relative tolerance on each coefficient.
    free : iterable of str
        Keys left out of the comparison.

    Returns
    -------
    Fit or None
    """
    f = fit(s, t, free)
    return f if f is not None and f.ok(tol) else None


def same(a: Row, b: Row, tol: float) -> bool:
    """Whether two true rows are proportional (a variant that changes nothing).

    Parameters
    ----------
    a, b : Row
        The rows.
    tol : float
        Relative tolerance on each coefficient.

    Returns
    -------
    bool
    """
    f = fit(a, b)
    if f is None:
        return not a.keys and not b.keys
    return f.ok(tol) and set(a.keys) == set(b.keys)
