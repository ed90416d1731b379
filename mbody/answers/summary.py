"""A class's answers checked together: one row per answers file, and the class's most
frequent mistakes.

    summary = grade(model, ["answers/ana.yaml", "answers/ben.yaml", ...])
    summary.csv()                  # what ``mbody verify MODEL answers/*.yaml --summary
                                   # class.csv`` writes

Every file is checked as `mbody.answers.verify.verify` checks one, against one assembly
of the model (its rows made once for the class; once per variant, for answers that set
their own values with ``set:``). An entry that cannot be read is that entry's problem:
the file's other entries are checked, and the problem shown in the file's ``error``
cell. A file that cannot be read at all is a row with its problem, never the end of the
class. A file is all correct when every equation is right, every entry could be read,
and the rows asked for (`mbody.answers.coverage`; by default every row of the model)
are all given.
"""

from __future__ import annotations

import csv
import io
import os
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from mbody.answers.coverage import ALL, requirement
from mbody.answers.load import AnswersError, read_answers
from mbody.answers.variant import allow_list, variant
from mbody.answers.verify import MEANINGS, TOLERANCE, Check, Verification, check, tolerance
from mbody.equations.assemble import Assembly, assemble
from mbody.model.model import Model
from mbody.model.reprs import count
from mbody.model.values import plain
from mbody.util.formatting import spreadsheet_text

HEADER = ("file", "student", "equations", "correct")
"""The first columns of a row; then one ``mistake <k>`` column per wrong equation (as many
as the file with the most), then `COVERAGE_HEADER`, then ``error`` (why a file, or some of
its entries, could not be checked). The columns of the model-format contract come first,
in its order; the later ones were added after it."""
COVERAGE_HEADER = ("rows covered", "rows asked", "duplicates", "set")
"""The rows asked for that a correct equation gave, the rows asked for, the correct
equations that repeat a row, the values the file set."""
VARIANTS_KEPT = 64
"""Most variants of the model (answers' ``set:`` values) kept assembled at once."""
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
        """How many equations the file gives (its entries, checked or not)."""
        return self.verification.equations if self.verification else 0

    @property
    def correct(self) -> int:
        return self.verification.correct if self.verification else 0

    @property
    def covered(self) -> int:
        """How many of the rows asked for a correct equation gave."""
        return self.verification.covered if self.verification else 0

    @property
    def asked(self) -> int:
        """How many rows were asked for (0 when the file could not be checked)."""
        return self.verification.rows if self.verification else 0

    @property
    def duplicates(self) -> int:
        """Correct equations that repeat a row an earlier one gave."""
        return self.verification.duplicates if self.verification else 0

    @property
    def values(self) -> str:
        """The values the file set (``set:``), as ``--set`` writes them."""
        v = self.verification
        return "; ".join(f"{p}={plain(x)}" for p, x in v.values) if v else ""

    @property
    def problems(self) -> str:
        """Why the file, or some of its entries, could not be checked ('' when all was)."""
        if self.error or self.verification is None:
            return self.error
        return "; ".join(str(i) for i in self.verification.errors)

    @property
    def all_correct(self) -> bool:
        """Every equation right, every entry read, every row asked for given."""
        return self.verification is not None and self.verification.all_correct

    @property
    def incomplete(self) -> bool:
        """Every equation right and every entry read, but rows asked for missing."""
        v = self.verification
        return v is not None and v.ok and not v.complete

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
    required : str
        What each file was asked for, in words (`mbody.answers.coverage`).
    allowed : tuple of str or None
        The paths a file's ``set:`` could name (`mbody.answers.variant.allow_list`); None:
        any.
    """

    model: str
    graded: tuple[Graded, ...]
    required: str = "every row of the model"
    allowed: tuple[str, ...] | None = None

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
            `HEADER`, ``mistake 1`` ... (`width` of them), `COVERAGE_HEADER`, ``error``.
        """
        return [*HEADER, *(f"mistake {k + 1}" for k in range(self.width)), *COVERAGE_HEADER,
                "error"]

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
            out.append([g.file, g.student, g.equations, g.correct, *cells,
                        *([""] * (self.width - len(cells))), g.covered, g.asked,
                        g.duplicates, g.values, g.problems])
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
            The class's counts (files all correct, incomplete, partly or not read;
            equations; rows asked for and given, in the files checked; the files that set
            their own values, and which paths they could) and its five most frequent
            mistakes.
        """
        n = len(self.graded)
        ok = sum(1 for g in self.graded if g.all_correct)
        short = sum(1 for g in self.graded if g.incomplete)
        partly = sum(1 for g in self.graded if g.verification and g.verification.errors)
        bad = sum(1 for g in self.graded if g.verification is None)
        eqs = sum(g.equations for g in self.graded)
        right = sum(g.correct for g in self.graded)
        lines = [f"{count(n, 'answers file')} for model '{self.model}': {ok} all correct"
                 + (f", {short} incomplete (every equation right, rows missing)"
                    if short else "")
                 + (f", {partly} with entries that could not be read" if partly else "")
                 + (f", {bad} could not be checked" if bad else "")
                 + f"; {right} of {eqs} equations correct",
                 f"rows asked for: {self.required.removeprefix('the rows asked for: ')}; "
                 f"{sum(g.covered for g in self.graded)} of "
                 f"{sum(g.asked for g in self.graded)} given"
                 + (f" in the {count(n - bad, 'file')} checked" if bad else "")]
        setting = sum(1 for g in self.graded if g.values)
        if setting or self.allowed is not None:
            lines.append(f"{count(setting, 'file')} "
                         + ("sets its own values" if setting == 1 else "set their own values")
                         + " (the set column); "
                         + (f"a file may set {', '.join(self.allowed) or 'none'}"
                            if self.allowed is not None else
                            "any path was allowed: --allow-set PATHS says which a "
                            "student may set"))
        top = self.mistakes[:5]
        if top:
            lines.append("most frequent mistakes:")
            lines += [f"  {m.equations:4d} x {m.diagnosis} ({m.row}) in "
                      f"{count(m.students, 'file')}"
                      for m in top]
        return "\n".join(lines)


def _as_text(row: list[str | int]) -> list[str | int]:
    """A CSV row with its text cells safe to open in a spreadsheet (numbers as they are)."""
    return [spreadsheet_text(c) if isinstance(c, str) else c for c in row]


def grade(model: Model, files: Sequence[str | os.PathLike[str]], *,
          tol: float = TOLERANCE, require: str | Sequence[str] | None = ALL,
          allow_set: str | Sequence[str] | None = None) -> ClassSummary:
    """Check every answers file against `model` (module doc).

    Parameters
    ----------
    model : Model
        The model the class wrote its equations for.
    files : sequence of str or path-like
        The answers files.
    tol : float
        Relative tolerance on each coefficient (as `verify`'s).
    require : str or sequence of str, optional
        The rows each file is asked to give (`mbody.answers.coverage`): default
        ``"all"``, every row of the model (or every Lagrange equation, for a file in
        generalized coordinates); None: the rows of the bodies each file answers.
    allow_set : str or sequence of str, optional
        The paths a file's ``set:`` may name (`mbody.answers.variant.allow_list`); None:
        any (the summary's first line then counts the files that set values).

    Returns
    -------
    ClassSummary

    Raises
    ------
    MbodyError
        `tol` outside (0, 1), or `require` or `allow_set` naming nothing in the model (a
        file's own problem never raises: it is that file's row).
    """
    tol = tolerance(tol)
    wanted = requirement(model, require)
    allow = allow_list(model, allow_set)
    variants: dict[tuple, tuple[Model, Assembly]] = {}
    graded = []
    for f in files:
        stem = Path(f).stem
        sheet = None
        try:
            sheet = read_answers(f, partial=True)
            key = tuple((s.path, repr(plain(s.value))) for s in sheet.settings)
            if key not in variants:
                if len(variants) >= VARIANTS_KEPT:
                    variants.pop(next(iter(variants)))
                changed = variant(model, sheet, allow)
                variants[key] = (changed, assemble(changed))
            changed, asm = variants[key]
            v = check(changed, sheet, tol=tol, asm=asm, require=wanted, partial=True)
        except AnswersError as exc:  # the student's name when the file said it
            who = sheet.student if sheet is not None and sheet.student else stem
            graded.append(Graded(str(f), who, None, " ".join(str(exc).split())))
            continue
        graded.append(Graded(str(f), v.student or stem, v))
    return ClassSummary(model.name, tuple(graded), wanted.describe(), allow)
