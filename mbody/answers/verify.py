"""``verify(model, answers) -> Verification``: a student's equations checked against
each body's Newton-Euler pair, every wrong one explained in the course's terms.

    v = mbody.verify("models/pendulum.yaml", "models/answers/pendulum.yaml")
    print(v)                      # one paragraph per equation, then the rows not covered
    v.checks[0].diagnosis         # 'correct', 'wrong_moment_point', ...
    v.to_dict()                   # what `mbody verify --json` prints
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mbody.answers.compare import Row
from mbody.answers.coverage import Asked, Requirement, requirement
from mbody.answers.diagnose import CORRECT, DIAGNOSES, NOT_AN_EQUATION, Diagnosis, diagnose
from mbody.answers.lagrange import LAGRANGE_DIAGNOSES, check_lagrange, coordinate_names
from mbody.answers.linear import NotLinear, linear_row
from mbody.answers.load import (
    Answer,
    Answers,
    AnswersError,
    answers_from_data,
    hinted,
    read_answers,
)
from mbody.answers.parse import EquationError, parse_equation
from mbody.answers.rows import BodyRows, body_rows
from mbody.answers.variant import allow_list, variant
from mbody.answers.vocabulary import Vocabulary, vocabulary
from mbody.equations.assemble import Assembly, assemble
from mbody.errors import Issue, MbodyError, did_you_mean, real_number, wrong_type
from mbody.loading import load
from mbody.model.model import Model, State
from mbody.model.reprs import name_list

TOLERANCE = 1e-3
"""Default relative tolerance on each coefficient: numbers written to about four
significant figures match."""
MEANINGS = {**DIAGNOSES, **LAGRANGE_DIAGNOSES}
"""Every diagnosis a `Check` can have, Newton-Euler's and Lagrange's, with its meaning."""


@dataclass(frozen=True)
class Check:
    """The verdict on one equation.

    Parameters
    ----------
    index : int
        1-based place in the answers.
    body : str
        The body the equation is for.
    eq : str
        The equation as written.
    line : int
        Its line in the answers file (0 when not from a file).
    diagnosis : str
        A key of `MEANINGS`: one of `mbody.answers.diagnose.DIAGNOSES`, or of
        `mbody.answers.lagrange.LAGRANGE_DIAGNOSES` for an equation of no body.
    expected : str
        The row it was compared with, as text ('' when none is close).
    row : str
        That row's coordinate label (``rod.theta``), or ''.
    explanation : str
        One or two sentences in the course's terms.
    details : dict
        What the diagnosis found (the term, the point, the load, a value used...).
    """

    index: int
    body: str
    eq: str
    line: int
    diagnosis: str
    expected: str
    row: str
    explanation: str
    details: dict = field(default_factory=dict)

    @property
    def correct(self) -> bool:
        """Whether the equation is one of the body's rows."""
        return self.diagnosis == CORRECT

    @property
    def meaning(self) -> str:
        """What the diagnosis means here: its `MEANINGS` entry, or, for an equation that
        is not linear in the unknowns (``not_an_equation_of_this_body``, or
        ``not_an_equation_of_this_model`` for one of no body, with
        ``details["not_linear"]``), that and the term: "not linear in the unknowns (a_x
        squared)"."""
        why = self.details.get("not_linear")
        return f"not linear in the unknowns ({why})" if why else MEANINGS[self.diagnosis]

    def __repr__(self) -> str:  # the dataclass's would print the explanation and details
        return f"<Check [{self.index}] {self.body}: {self.eq!r}: {self.diagnosis}>"

    def to_dict(self) -> dict[str, Any]:
        """The check as JSON-ready data.

        Returns
        -------
        dict
            index, body, eq, line, diagnosis, expected, row, explanation, details.
        """
        return {"index": self.index, "body": self.body, "eq": self.eq, "line": self.line,
                "diagnosis": self.diagnosis, "expected": self.expected, "row": self.row,
                "explanation": self.explanation, "details": _plain(self.details)}


@dataclass(frozen=True)
class Uncovered:
    """A row of an answered body that no correct equation gave.

    Parameters
    ----------
    body : str
        The body.
    row : str
        The row's coordinate label.
    expected : str
        The row as text.
    """

    body: str
    row: str
    expected: str


@dataclass(frozen=True)
class Verification:
    """Every equation's verdict, in file order, and the rows no answer covered.

    Parameters
    ----------
    model : str
        The model's name.
    model_file : str
        Its file ('' when built in Python).
    answers_file : str
        The answers' file ('<answers>' when given as data).
    student : str
        The answers' ``student`` line.
    tol : float
        The relative tolerance used.
    checks : tuple of Check
        One per equation, in file order.
    uncovered : tuple of Uncovered
        Rows asked for (by default those of the bodies that have answers) that no correct
        equation gave.
    rows : int
        How many rows are asked for.
    required : str
        What was asked for, in words ('' for the rows of the bodies answered:
        `mbody.answers.coverage`).
    errors : tuple of Issue
        The problems of the entries that could not be checked (and of the file's other
        keys), each located; only when checked with ``partial=True`` (otherwise they are
        raised).
    entries : int
        How many equations the answers give, checked or not (0: as `checks`).
    values : tuple of (str, object)
        The values the answers set on the model (``set:``), path and value.
    """

    model: str
    model_file: str
    answers_file: str
    student: str
    tol: float
    checks: tuple[Check, ...]
    uncovered: tuple[Uncovered, ...]
    rows: int
    required: str = ""
    errors: tuple[Issue, ...] = ()
    entries: int = 0
    values: tuple[tuple[str, Any], ...] = ()

    @property
    def ok(self) -> bool:
        """Whether every equation is correct (and every entry could be checked)."""
        return all(c.correct for c in self.checks) and not self.errors

    @property
    def correct(self) -> int:
        """How many equations are correct."""
        return sum(c.correct for c in self.checks)

    @property
    def equations(self) -> int:
        """How many equations the answers give: the checked ones and those that could
        not be read."""
        return max(self.entries, len(self.checks))

    @property
    def duplicates(self) -> int:
        """How many correct equations give a row that an earlier correct one gave."""
        return len(_repeats(self.checks))

    @property
    def covered(self) -> int:
        """How many of the rows asked for a correct equation gave."""
        return self.rows - len(self.uncovered)

    @property
    def complete(self) -> bool:
        """Whether every row asked for was given by a correct equation."""
        return not self.uncovered

    @property
    def all_correct(self) -> bool:
        """Every equation correct, every entry checked and every row asked for given."""
        return self.ok and self.complete

    def to_dict(self) -> dict[str, Any]:
        """What ``mbody verify --json`` prints.

        Returns
        -------
        dict
            model, model_file, answers, student, tol, equations (one entry per equation,
            in file order), uncovered (rows), summary (counts).
        """
        return {"model": self.model, "model_file": self.model_file,
                "answers": self.answers_file, "student": self.student, "tol": self.tol,
                "set": {path: _plain(value) for path, value in self.values},
                "equations": [c.to_dict() for c in self.checks],
                "errors": [{"line": i.line, "column": i.column, "key": i.key,
                            "message": i.message, "hint": i.hint, "text": str(i)}
                           for i in self.errors],
                "uncovered": [{"body": u.body, "row": u.row, "expected": u.expected}
                              for u in self.uncovered],
                "summary": {"equations": self.equations, "correct": self.correct,
                            "rows": self.rows, "uncovered": len(self.uncovered),
                            "duplicates": self.duplicates,
                            "required": self.required or "answered"}}

    def text(self, width: int = 88) -> str:
        """The report `mbody verify` prints: a paragraph per equation, then the rows
        not covered, then a one-line summary.

        Parameters
        ----------
        width : int
            Column at which explanations are wrapped.

        Returns
        -------
        str
            The report (no final newline).
        """
        where = f" ({self.model_file})" if self.model_file else ""
        values = ", ".join(f"{p}={v}" for p, v in self.values)
        out = [f"model '{self.model}'{where}" + (f" with {values}" if values else "")
               + f"; answers {self.answers_file}"
               + (f" by {self.student}" if self.student else "")
               + f"; tolerance {self.tol:g} on each coefficient", ""]
        wrap = textwrap.TextWrapper(width=width, initial_indent="    ",
                                    subsequent_indent="    ")
        for c in self.checks:
            at = f"  (line {c.line})" if c.line else ""
            out.append(f"[{c.index}] {c.body}: {c.eq}{at}")
            out.append(f"    {c.diagnosis}" + ("" if c.correct else f": {c.meaning}"))
            if not c.correct and c.expected:
                out.append(f"    expected ({c.row}): {c.expected}")
            out.extend(wrap.wrap(c.explanation))
            out.append("")
        if self.errors:
            unread = self.equations - len(self.checks)
            out.append("problems in the answers" + (f" ({unread} equation"
                       f"{'s' if unread != 1 else ''} not checked)" if unread else "") + ":")
            out += [f"    {i}" for i in self.errors]
            out.append("")
        again = _repeats(self.checks)
        if again:
            out.append("equations that repeat a row an earlier correct equation gave:")
            out += [f"    [{c.index}] {c.row} (as [{first}])" for c, first in again]
            out.append("")
        if self.uncovered:
            out.append("rows no correct equation gave"
                       + (f" ({self.required})" if self.required else "") + ":")
            out += [f"    {u.row}: {u.expected}" for u in self.uncovered]
            out.append("")
        n = self.equations
        out.append(f"{self.correct} of {n} equation{'s' if n != 1 else ''} correct; "
                   f"{self.covered} of {self.rows} rows covered.")
        return "\n".join(out)

    def __str__(self) -> str:
        return self.text()

    def __repr__(self) -> str:  # the dataclass's would print every check in full
        wrong = sorted({c.diagnosis for c in self.checks if not c.correct})
        n = len(self.checks)
        by = f" by {self.student}" if self.student else ""
        return (f"<Verification of {self.model!r}{by}: {self.correct} of {n} "
                f"equation{'s' if n != 1 else ''} correct"
                + (f" ({', '.join(wrong)})" if wrong else "")
                + f", {self.rows - len(self.uncovered)} of {self.rows} rows covered; "
                "print() it, .checks, .to_dict()>")

    def _repr_pretty_(self, p, cycle: bool) -> None:  # IPython shows the report
        p.text(self.text())


def check_assembly_of(model: Model, asm: object) -> None:
    """Refuse an `asm` that is not an assembly of `model`: another model's (other name,
    bodies or reaction components), or this one's with other masses, inertias or gravity
    (`Model.with_values`), whose equations are not the model's."""
    if not isinstance(asm, Assembly):
        raise wrong_type("asm", "an Assembly of the model (mbody.assemble(model, state))", asm)
    other = asm.model
    if other is model:
        return
    fix = "give mbody.assemble(model, state) of this model, or leave asm out"
    if (other.name, other.dimension, tuple(other.body_names), list(other.reactions)) != (
            model.name, model.dimension, tuple(model.body_names), list(model.reactions)):
        raise MbodyError(f"asm: an assembly of model {other.name!r} (bodies "
                         f"{name_list(other.body_names)}), not of {model.name!r} (bodies "
                         f"{name_list(model.body_names)}); {fix}")
    differ = [what for what, a, b in (("masses", other.mass, model.mass),
                                      ("inertias", other.J, model.J),
                                      ("gravity", other.gravity, model.gravity))
              if not np.array_equal(a, b)]
    if differ:
        raise MbodyError(f"asm: an assembly of model {model.name!r} with other values "
                         f"({', '.join(differ)} differ from the model's); {fix}")


def tolerance(tol: Any) -> float:
    """`tol` checked: a relative tolerance, a number strictly between 0 and 1.

    Raises
    ------
    MbodyError
        Outside (0, 1) (`mbody.errors.MbodyTypeError` for what is not a number).
    """
    tol = real_number(tol, "tol", "a relative tolerance, a number between 0 and 1")
    if not (tol > 0.0 and tol < 1.0):
        raise MbodyError(f"the tolerance must be between 0 and 1 (relative), got {tol!r}")
    return tol


def verify(model: Model | str | os.PathLike[str], answers: Any, *, tol: float = TOLERANCE,
           state: State | None = None, asm: Assembly | None = None,
           require: str | Sequence[str] | None = None,
           partial: bool = False, allow_set: str | Sequence[str] | None = None
           ) -> Verification:
    """Check a student's equations against each body's Newton-Euler pair.

    Parameters
    ----------
    model : Model, str or path-like
        The model, or its file.
    answers : Answers, str, path-like, mapping or sequence
        An answers file's path, `Answers`, or the same as data: ``{"equations": [{"body":
        "rod", "eq": "2*a_y = O.Fy - 19.62"}, ...]}`` or the list itself. Values the
        answers set (``set: {bodies.rod.mass: 2.5}``) are set on the model first
        (`mbody.answers.variant`).
    tol : float
        Relative tolerance on each coefficient (numbers written by a student are
        rounded); default 1e-3.
    state : State, optional
        The state the equations are written at (default: the model's initial state,
        with the answers' values).
    asm : Assembly, optional
        The model's assembly at that state, when already made (an assembly of another
        model, or of this one with other masses, inertias or gravity, is refused).
    require : str or sequence of str, optional
        The rows the answers are asked to give (`mbody.answers.coverage`): ``"all"``,
        a body's name, a row's label...; default: the rows of the bodies answered.
    partial : bool
        Check the entries that can be read and list the problems of the others in
        `Verification.errors`, instead of raising them (what a class's summary does).
    allow_set : str or sequence of str, optional
        The paths the answers' ``set:`` may name (`mbody.answers.variant.allow_list`:
        ``"bodies.*.mass"``...); default None: any path.

    Returns
    -------
    Verification
        One `Check` per equation in file order, and the rows no answer covered.

    Raises
    ------
    AnswersError
        The answers are invalid: an unknown body or name (with a did-you-mean), an
        equation that cannot be read (with its column), a key that is not an answers
        file's, a value ``set:`` that the model file could not hold; every problem at
        once. With `partial`, only a file that is no answers file, or whose ``set:``
        cannot be applied.
    MbodyError
        `tol` outside (0, 1), `require` or `allow_set` naming nothing in the model, or
        `asm` of another
        model (`mbody.errors.MbodyTypeError`, a `TypeError` too, for a `tol` that is not
        a number or an `asm` that is not an `Assembly`).
    """
    tol = tolerance(tol)
    if isinstance(model, str | os.PathLike):
        model = load(model)
    sheet = _answers(answers)
    wanted = requirement(model, require)
    allow = allow_list(model, allow_set)
    problems: list[Issue] = []
    try:
        model = variant(model, sheet, allow)
    except AnswersError as exc:
        if partial:  # every number depends on them: the file cannot be checked
            raise
        problems = list(exc.issues)  # reported with the equations' problems
        asm = None
    if asm is None:
        asm = assemble(model, state)
    else:
        check_assembly_of(model, asm)
    return check(model, sheet, tol=tol, asm=asm, require=wanted, partial=partial,
                 problems=problems)


def check(model: Model, sheet: Answers, *, tol: float, asm: Assembly,
          require: Requirement, partial: bool = False,
          problems: Sequence[Issue] = ()) -> Verification:
    """`verify`'s work once the answers are read, their values set on `model` and the
    model assembled: what a class's summary calls for each file, with each variant's
    assembly made once.

    Parameters
    ----------
    model : Model
        The model with the answers' values (`mbody.answers.variant.variant`).
    sheet : Answers
        The answers (read with ``partial=True``: their problems are reported with the
        equations').
    tol : float
        Relative tolerance on each coefficient, in (0, 1).
    asm : Assembly
        `model`'s assembly at the state the answers are for.
    require : Requirement
        The rows asked for (`mbody.answers.coverage.requirement`).
    partial : bool
        As `verify`'s.
    problems : sequence of Issue
        Further problems found before (the answers' ``set:``).

    Returns
    -------
    Verification

    Raises
    ------
    AnswersError
        Without `partial`: every problem of the answers, structure and equations, in
        the file's order.
    """
    state = asm.state
    vocab: dict[str, Vocabulary] = {}
    rows: dict[str, BodyRows] = {}
    issues: list[Issue] = [*sheet.problems, *(p for p in problems if p not in sheet.problems)]
    parsed: list[tuple[Answer, Row | None, NotLinear | None]] = []
    lagrange = [a for a in sheet.equations if a.lagrange]
    for a in sheet.equations:
        if a.lagrange:  # an equation in generalized coordinates: checked below
            continue
        if a.body not in model.index:
            hint = did_you_mean(a.body, model.body_names) if hinted(issues) else ""
            issues.append(sheet.issue(a, f"no body named {a.body!r} in model "
                                      f"'{model.name}' (its bodies: "
                                      f"{name_list(model.body_names, 10)})",
                                      body=True, hint=hint))
            continue
        if a.body not in vocab:
            vocab[a.body] = vocabulary(model, state, a.body)
        try:
            eq = parse_equation(a.eq, model.reactions)
            row = linear_row(eq, vocab[a.body] if hinted(issues) else vocab[a.body].quiet)
            parsed.append((a, row, None))
        except EquationError as exc:
            issues.append(sheet.issue(a, exc.reason, position=exc.position, hint=exc.hint))
        except NotLinear as exc:
            parsed.append((a, None, exc))
    lagrange_result = None
    if lagrange:
        lagrange_result, lost = _lagrange(model, state, sheet, lagrange, tol, partial)
        issues += lost
    if issues and not partial:
        raise AnswersError(_in_file_order(issues))

    solved: list[Mapping[str, float] | None] = []

    def reactions() -> Mapping[str, float] | None:
        """The reactions by label and the accelerations by coordinate, solved."""
        if not solved:
            try:
                sol = asm.solve()
                solved.append({**sol.as_dict(), **dict(sol.reactions)})
            except MbodyError:
                solved.append(None)
        return solved[0]

    checks = []
    seen: dict[tuple, Diagnosis] = {}  # the same row of the same body: the same verdict
    for a, student, problem in parsed:
        if a.body not in rows:
            rows[a.body] = body_rows(asm, a.body)
        if student is None:
            d = _not_linear(a, problem)
        else:
            key = (a.body, tuple(student.coef.items()), tuple(student.scale.items()))
            d = seen.get(key) or seen.setdefault(key, diagnose(student, rows[a.body], tol,
                                                                 reactions))
        checks.append(Check(a.index, a.body, a.eq, a.line, d.diagnosis, d.expected, d.row,
                            d.explanation, d.details))
    covered = {(False, c.row) for c in checks if c.correct}
    missing: list[tuple[str, str]] = []
    if lagrange_result is not None:
        verdicts, missing, _ = lagrange_result
        more = [Check(a.index, name, a.eq, a.line, d.diagnosis, d.expected, d.row,
                      d.explanation, d.details) for a, d, name in verdicts]
        covered |= {(True, c.row) for c in more if c.correct}
        checks = sorted([*checks, *more], key=lambda c: c.index)

    def generalized() -> list[Asked]:
        """Every Lagrange equation: from the check when the answers have some."""
        names, labels = coordinate_names(model, sheet)
        if lagrange_result is None:
            try:
                _, left, _ = check_lagrange(model, state, sheet, [], tol)
            except AnswersError:
                if partial:  # the answers' coordinates, reported with their entries
                    return []
                raise
        else:
            left = missing
        text = dict(left)
        text.update((c.body, c.expected) for c in checks
                    if c.correct and (True, c.row) in covered and c.body in names)
        return [Asked(n, lab, text.get(n, ""), True) for n, lab in zip(names, labels,
                                                                          strict=True)]

    asked = require.rows(asm, sheet, generalized)
    uncovered = [Uncovered(r.body, r.body if r.lagrange else r.label, r.text) for r in asked
                 if (r.lagrange, r.label) not in covered]
    return Verification(model.name, model.file or "", sheet.file, sheet.student, tol,
                        tuple(checks), tuple(uncovered), len(asked),
                        "" if require.answered else require.describe(),
                        tuple(_in_file_order(issues)), sheet.given,
                        tuple((s.path, s.value) for s in sheet.settings))


def _lagrange(model: Model, state: State, sheet: Answers, entries: list[Answer], tol: float,
              partial: bool) -> tuple[Any, list[Issue]]:
    """`check_lagrange` of `entries`, and the problems found; with `partial`, the entries
    that cannot be read are left out and the others checked (None when none can be)."""
    try:
        return check_lagrange(model, state, sheet, entries, tol), []
    except AnswersError as exc:
        if not partial:
            return None, list(exc.issues)
        lost = list(exc.issues)
    bad = {i.key for i in lost}
    rest = [a for a in entries if a.key not in bad]
    if not rest or len(rest) == len(entries):  # the coordinates themselves: no entry read
        return None, lost
    try:
        return check_lagrange(model, state, sheet, rest, tol), lost
    except AnswersError as exc:
        return None, [*lost, *exc.issues]


def _in_file_order(issues: Sequence[Issue]) -> list[Issue]:
    """Issues by line and column (those without a line, such as answers given as data,
    in the order found, after the others)."""
    return sorted(issues, key=lambda i: (i.line == 0, i.line, i.column))


def _repeats(checks: Sequence[Check]) -> list[tuple[Check, int]]:
    """Each correct equation that gives a row an earlier correct one gave, with the
    earlier one's index."""
    first: dict[tuple[str, str], int] = {}
    out = []
    for c in checks:
        if not c.correct:
            continue
        key = (c.body, c.row)
        if key in first:
            out.append((c, first[key]))
        else:
            first[key] = c.index
    return out


def _answers(answers: Any) -> Answers:
    """The answers, read partially: their problems are reported with the equations'."""
    if isinstance(answers, Answers):
        return answers
    if isinstance(answers, str | os.PathLike):
        return read_answers(answers, partial=True)
    if isinstance(answers, Mapping | list | tuple):
        return answers_from_data(answers, partial=True)
    raise AnswersError([Issue("<answers>", 0, 0, "", f"expected an answers file or a list "
                              f"of {{body, eq}} entries, got {type(answers).__name__}")])


def _not_linear(a: Answer, problem: NotLinear | None) -> Diagnosis:
    why = problem.why if problem is not None else "not linear"
    return Diagnosis(NOT_AN_EQUATION, "", "",
                     f"This is not linear in the unknowns: it has {why}. The Newton-Euler "
                     "equations are linear in the accelerations and the reactions; each "
                     "term is a number (mass, inertia, lever arm) times one of them.",
                     {"not_linear": why, "position": problem.position + 1 if problem else 0})


def _plain(value: Any) -> Any:
    """numpy scalars and tuples -> JSON types."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if hasattr(value, "item"):
        return value.item()
    return value
