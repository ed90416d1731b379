"""Which rows an answers file is asked to give, and which it gave.

A file can be right in every equation and still be incomplete: one row written three
times is three correct equations and one row. Coverage counts the rows asked for that
a correct equation gave, and the correct equations that repeat a row already given.

What is asked for (``--require``, ``require=``), one or more of:

- ``all``: the whole model: every Newton-Euler row of every body; for a file written in
  generalized coordinates only (no entry with a body), every Lagrange equation instead.
  Either set describes the model's dynamics completely, so either is a complete answer.
  A class's summary asks for this unless told otherwise: an instructor grading a model
  expects its equations, and a student who leaves a body out must not pass.
- ``answered``: the rows of the bodies the file has equations for (and every Lagrange
  equation when it has one). What ``mbody verify`` of one file lists by default, for a
  student who works a body at a time.
- ``lagrange``: every Lagrange equation (one per generalized coordinate).
- a body's name (``lower``): its rows; a row's label (``upper.theta``): that row.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from mbody.answers.load import Answers
from mbody.answers.text import equation_text
from mbody.equations.assemble import Assembly
from mbody.errors import MbodyError, comma_words, did_you_mean, option_name
from mbody.model.model import Model

ALL, ANSWERED, LAGRANGE = "all", "answered", "lagrange"
KEYWORDS = (ALL, ANSWERED, LAGRANGE)
"""The words of a requirement that name no body or row (module doc)."""


@dataclass(frozen=True)
class Asked:
    """A row asked for.

    Parameters
    ----------
    body : str
        Its body (a Lagrange equation: its coordinate's name in the answers).
    label : str
        The row's label: ``rod.theta``; a Lagrange equation's coordinate (``O.angle``).
    text : str
        The row as text.
    lagrange : bool
        A Lagrange equation rather than a Newton-Euler row.
    """

    body: str
    label: str
    text: str
    lagrange: bool = False


@dataclass(frozen=True)
class Requirement:
    """The rows a file is asked to give (module doc), as words checked against a model.

    Parameters
    ----------
    words : tuple of str
        ``("all",)``, ``("answered",)``, ``("lower", "upper.theta")``...
    """

    words: tuple[str, ...] = (ANSWERED,)

    @property
    def answered(self) -> bool:
        """Only the rows of the bodies answered: what one file's check lists by default."""
        return self.words == (ANSWERED,)

    def describe(self) -> str:
        """The requirement in words, for the reports: ``every row of the model``."""
        if self.words == (ALL,):
            return "every row of the model"
        if self.answered:
            return "the rows of the bodies answered"
        return "the rows asked for: " + ", ".join(self.words)

    def rows(self, asm: Assembly, sheet: Answers,
             lagrange: Callable[[], list[Asked]]) -> list[Asked]:
        """The rows asked of `sheet` (no row twice).

        Parameters
        ----------
        asm : Assembly
            The model's (the student's variant's) equations.
        sheet : Answers
            The answers: which bodies they answer, whether in generalized coordinates.
        lagrange : callable
            Every Lagrange equation of the model, as `Asked` (made only when asked for).

        Returns
        -------
        list of Asked
            In the order of the words, each body's rows in stacking order.
        """
        model = asm.model
        readable = [a for a in sheet.equations if a.lagrange or a.body in model.index]
        bodies = [a.body for a in readable if not a.lagrange]
        in_lagrange = any(a.lagrange for a in readable)
        out: dict[tuple[bool, str], Asked] = {}

        def body(name: str, only: str = "") -> None:
            for eq in asm.bodies[name].equations:
                if not only or eq.row == only:
                    out.setdefault((False, eq.row), Asked(name, eq.row, equation_text(eq)))

        def generalized() -> None:
            for a in lagrange():
                out.setdefault((True, a.label), a)

        rows = _row_labels(model)
        for w in self.words:
            if w == ALL and (bodies or not in_lagrange):
                for name in model.body_names:
                    body(name)
            elif w in (ALL, LAGRANGE):
                generalized()
            elif w == ANSWERED:
                for name in dict.fromkeys(bodies):
                    body(name)
                if in_lagrange:
                    generalized()
            elif w in model.index:
                body(w)
            elif w in rows:
                body(rows[w], only=w)
        return list(out.values())


def _row_labels(model: Model) -> dict[str, str]:
    """Each Newton-Euler row's label (``upper.theta``) -> its body."""
    return {model.coordinates[r]: name for i, name in enumerate(model.body_names)
            for r in model.body_rows(i)}


def requirement(model: Model, require: str | Sequence[str] | None) -> Requirement:
    """`require` read and checked against `model`.

    Parameters
    ----------
    model : Model
        The model the answers are for.
    require : str, sequence of str or None
        Words (module doc), comma-separated in a text or as a sequence; None:
        ``answered``.

    Returns
    -------
    Requirement

    Raises
    ------
    MbodyError
        A word that is no keyword, body or row of the model (with a did-you-mean), or no
        word at all.
    """
    if require is None:
        return Requirement()
    if isinstance(require, Requirement):
        return require
    flag = option_name("require")
    words = [w for w in comma_words(require, "require",
                                    "words such as 'all' or 'lower,upper.theta'") if w]
    if not words:
        raise MbodyError(f"{flag}: no rows named; give all, answered, lagrange, a body's "
                         "name or a row's label (upper.theta)")
    rows = _row_labels(model)
    for w in words:
        if w in KEYWORDS or w in model.index or w in rows:
            continue
        choices = [*KEYWORDS, *model.body_names, *rows]
        hint = did_you_mean(w, choices)
        raise MbodyError(f"{flag}: {w!r} is no body or row of model '{model.name}' (give "
                         f"{', '.join(KEYWORDS)}, a body such as {model.body_names[0]!r} "
                         f"or a row such as {next(iter(rows))!r})"
                         + (f"; {hint}" if hint else ""))
    return Requirement(tuple(dict.fromkeys(words)))
