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
    skip = set(free)
    keys = sorted((s.keys | t.keys) - skip)
    tk = [t.get(key) for key in keys]
    sk = [s.get(key) for key in keys]
    tt = sum(v * v for v in tk)
    if tt == 0.0:
        return None
    k = sum(a * b for a, b in zip(sk, tk, strict=True)) / tt
    if k == 0.0:
        return None
    for _ in range(3):  # weighted least squares: each key counts by its own tolerance
        num = den = 0.0
        for key, a, b in zip(keys, sk, tk, strict=True):
            w = max(s.err(key), abs(k) * t.err(key))
            if w > 0.0 and b != 0.0:
                num += a * b / (w * w)
                den += b * b / (w * w)
        if den == 0.0 or num == 0.0:
            break
        k = num / den
    errors = {}
    for key, a, b in zip(keys, sk, tk, strict=True):
        ref = max(s.err(key), abs(k) * t.err(key))
        diff = abs(a - k * b)
        errors[key] = 0.0 if diff == 0.0 else (diff / ref if ref > 0.0 else math.inf)
    return Fit(k, max(errors.values(), default=0.0), errors)


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
