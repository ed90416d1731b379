"""A class's answers checked together: one row per answers file, and the class's most
frequent mistakes.

    summary = grade(model, ["answers/ana.yaml", "answers/ben.yaml", ...])
    summary.csv()                  # what ``mbody verify MODEL answers/*.yaml --summary
                                   # class.csv`` writes

Every file is checked as `mbody.answers.verify.verify` checks one, against one assembly
of the model (its rows made once for the class). A file that cannot be read is a row
with its problem, never the end of the class.
"""

from __future__ import annotations

import csv
import io
import os
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from mbody.answers.load import AnswersError
from mbody.answers.verify import MEANINGS, TOLERANCE, Check, Verification, verify
from mbody.equations.assemble import assemble
from mbody.model.model import Model
from mbody.util.formatting import spreadsheet_text

HEADER = ("file", "student", "equations", "correct")
"""The first columns of a row; then one ``mistake <k>`` column per wrong equation (as many
as the file with the most), then ``error`` (why a file could not be checked)."""
MISTAKES_HEADER = ("mistake", "row", "equations", "students", "meaning")
"""The columns of the table of the class's mistakes."""


@dataclass(frozen=True)
class Graded:
    """One answers file's result.

    Parameters
    ----------
    file : str
        The answers file as given.
    student : str
        The file's ``student`` line, or its name without the extension.
    verification : Verification or None
        Every equation's verdict (None when the file could not be checked).
    error : str
        Why it could not be checked ('' when it was).
    """

    file: str
    student: str
    verification: Verification | None
    error: str = ""

    @property
    def equations(self) -> int:
        return len(self.verification.checks) if self.verification else 0

    @property
    def correct(self) -> int:
        return self.verification.correct if self.verification else 0

    @property
    def wrong(self) -> list[Check]:
        """The equations that are not correct, in file order."""
        return [c for c in self.verification.checks if not c.correct] if self.verification \
            else []


def mistake_text(c: Check) -> str:
    """A wrong equation as its cell shows it: ``reaction_sign (equation 3, upper.y)``."""
    where = f"equation {c.index}" + (f", {c.row}" if c.row else f", {c.body}")
    return f"{c.diagnosis} ({where})"


@dataclass(frozen=True)
class Mistake:
    """One of the class's mistakes: a diagnosis on one row (``upper.y``), how many
    equations made it and in how many files."""

    diagnosis: str
    row: str
    equations: int
    students: int


@dataclass(frozen=True)
class ClassSummary:
    """Every file's result, in the order given, and the class's mistakes.

    Parameters
    ----------
    model : str
        The model's name.
    graded : tuple of Graded
        One per answers file.
    """

    model: str
    graded: tuple[Graded, ...]

    @property
    def mistakes(self) -> list[Mistake]:
        """The class's mistakes, the most frequent first (by equations, then files)."""
        eqs: Counter[tuple[str, str]] = Counter()
        files: Counter[tuple[str, str]] = Counter()
        for g in self.graded:
            keys = [(c.diagnosis, c.row or c.body) for c in g.wrong]
            eqs.update(keys)
            files.update(set(keys))
        order = sorted(eqs, key=lambda k: (-eqs[k], -files[k], k))
        return [Mistake(d, r, eqs[(d, r)], files[(d, r)]) for d, r in order]

    @property
    def width(self) -> int:
        """The most wrong equations of any file (the ``mistake <k>`` columns)."""
        return max((len(g.wrong) for g in self.graded), default=0)

    def header(self) -> list[str]:
        """The files' table's columns.

        Returns
        -------
        list of str
            `HEADER`, ``mistake 1`` ... (`width` of them), ``error``.
        """
        return [*HEADER, *(f"mistake {k + 1}" for k in range(self.width)), "error"]

    def rows(self) -> list[list[str | int]]:
        """The files' table.

        Returns
        -------
        list of lists
            One row per file, in the order given (columns: `header`).
        """
        out: list[list[str | int]] = []
        for g in self.graded:
            cells = [mistake_text(c) for c in g.wrong]
            out.append([g.file, g.student, g.equations, g.correct,
                        *cells, *([""] * (self.width - len(cells))), g.error])
        return out

    def csv(self) -> str:
        """The summary as CSV.

        Returns
        -------
        str
            The files' table; a blank line; the class's mistakes (`MISTAKES_HEADER`), the
            most frequent first. A text cell that a spreadsheet would run as a formula (a
            ``student:`` line or a file name starting with ``=``...) has a ``'`` in front
            (`mbody.util.formatting.spreadsheet_text`); the counts are numbers as they are.
        """
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.header())
        w.writerows(_as_text(r) for r in self.rows())
        w.writerow([])
        w.writerow(MISTAKES_HEADER)
        for m in self.mistakes:
            w.writerow(_as_text([m.diagnosis, m.row, m.equations, m.students,
                                 MEANINGS[m.diagnosis]]))
        return buf.getvalue()

    def text(self) -> str:
        """What ``mbody verify --summary`` prints.

        Returns
        -------
        str
            The class's counts and its five most frequent mistakes.
        """
        n = len(self.graded)
        ok = sum(1 for g in self.graded if g.verification and g.verification.ok)
        bad = sum(1 for g in self.graded if g.error)
        eqs = sum(g.equations for g in self.graded)
        right = sum(g.correct for g in self.graded)
        lines = [f"{n} answers file(s) for model '{self.model}': {ok} all correct"
                 + (f", {bad} could not be checked" if bad else "")
                 + f"; {right} of {eqs} equations correct"]
        top = self.mistakes[:5]
        if top:
            lines.append("most frequent mistakes:")
            lines += [f"  {m.equations:4d} x {m.diagnosis} ({m.row}) in {m.students} file(s)"
                      for m in top]
        return "\n".join(lines)


def _as_text(row: list[str | int]) -> list[str | int]:
    """A CSV row with its text cells safe to open in a spreadsheet (numbers as they are)."""
    return [spreadsheet_text(c) if isinstance(c, str) else c for c in row]


def grade(model: Model, files: Sequence[str | os.PathLike[str]], *,
          tol: float = TOLERANCE) -> ClassSummary:
    """Check every answers file against `model` (module doc).

    Parameters
    ----------
    model : Model
        The model the class wrote its equations for.
    files : sequence of str or path-like
        The answers files.
    tol : float
        Relative tolerance on each coefficient (as `verify`'s).

    Returns
    -------
    ClassSummary
    """
    asm = assemble(model)
    graded = []
    for f in files:
        stem = Path(f).stem
        try:
            v = verify(model, f, tol=tol, asm=asm)
        except AnswersError as exc:
            graded.append(Graded(str(f), stem, None, " ".join(str(exc).split())))
            continue
        graded.append(Graded(str(f), v.student or stem, v))
    return ClassSummary(model.name, tuple(graded))
