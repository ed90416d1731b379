"""An answers file: a student's equations, one entry per equation, with line marks.

```yaml
student: A. Student            # optional, free text
note: sheet 3, question 2      # optional, free text (also `comment`), never read
set: {bodies.rod.mass: 2.5}    # optional: this student's values (`--set PATH=VALUE`'s paths)
equations:
  - {body: rod, eq: "2*a_y = O.Fy - 19.62"}
  - body: rod
    eq: I_G*alpha = -0.433013*O.Fx - 0.25*O.Fy
    note: about G              # optional, free text (also `comment`), never read
```

An entry without a body is an equation in generalized coordinates (Lagrange's), written
with the model's coordinate labels (``O.angle_ddot``) or with the answers' own names
(``coordinates: {theta1: O.angle}``, then ``theta1_ddot``); ``coordinate: theta1`` may
say which coordinate's equation it is (`mbody.answers.lagrange`).

The file is read by mbody's own safe YAML loader (`mbody.model.loader`), so every value
keeps its line and column: a problem with an entry is reported at the entry, and a
problem inside an equation at its character. An entry that cannot be read does not stop
the others: `read_answers(path, partial=True)` keeps the readable entries and lists the
problems (`Answers.problems`), so that they are reported together with the problems of
the equations themselves, or, in a class's summary, as the errors of those entries.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from mbody.errors import Issue, ModelError, did_you_mean
from mbody.model.loader import Document, dotted, load_text, read_file

NOTE_KEYS = ("note", "comment")
"""Free text a person may add to the file or to an entry: read as text, never checked."""
TOP_KEYS = ("equations", "student", "coordinates", "set", *NOTE_KEYS)
ENTRY_KEYS = ("body", "eq", "coordinate", *NOTE_KEYS)
MAX_EQUATIONS = 20_000
"""Most equations in one answers file (a student's answers hold tens; each one costs about a
millisecond or two to diagnose, so this bounds the work at about half a minute)."""


class AnswersError(ModelError):
    """An answers file (or answers given in Python) is invalid.

    Parameters
    ----------
    issues : sequence of Issue
        Every problem found, each with its file, line and column; the first `SHOWN` (those
        the message writes out) with a did-you-mean where there is one (`hinted`).
    """

    def _text(self) -> str:
        n = len(self.issues)
        body = "\n".join(str(i) for i in self.issues[:self.SHOWN])
        if n > self.SHOWN:
            body += f"\n... and {n - self.SHOWN} more"
        return f"{n} problems in the answers:\n{body}" if n > 1 else body


def hinted(issues: Sequence[Issue]) -> bool:
    """Whether the next problem found in an answers file gets a did-you-mean: only the
    first `AnswersError.SHOWN`, those its message writes out, do. A did-you-mean is a pass
    over the model's names (thousands for a large model's Lagrange equations), so that a
    file of thousands of bad entries is refused in time linear in it, the problems past
    those shown still counted ("... and N more"), as a model file's are (`ModelError`)."""
    return len(issues) < AnswersError.SHOWN


@dataclass(frozen=True)
class Answer:
    """One equation of the answers, with where it was written.

    Parameters
    ----------
    index : int
        1-based place in the file.
    body : str
        The body it is an equation of.
    eq : str
        The equation as written.
    line, column : int
        1-based position of the equation's first character in the file (0 when not from
        a file).
    key : str
        Its place in the file: ``equations[2].eq``.
    body_line, body_column : int
        1-based position of its body's name (0 when not from a file).
    coordinate : str
        A Lagrange equation (no body): the coordinate it is the equation of, as the
        answers name it ('' when not said).
    """

    index: int
    body: str
    eq: str
    line: int = 0
    column: int = 0
    key: str = ""
    body_line: int = 0
    body_column: int = 0
    coordinate: str = ""

    @property
    def lagrange(self) -> bool:
        """An equation in generalized coordinates (an entry without a body)."""
        return not self.body


@dataclass(frozen=True)
class Setting:
    """One value of the answers' ``set:`` mapping: a model file's value that this student's
    numbers were computed with (``bodies.rod.mass: 2.5``), as ``--set PATH=VALUE`` gives
    one (`mbody.model.values`).

    Parameters
    ----------
    path : str
        The path, as ``--set`` writes it (``bodies.rod.mass``).
    value : object
        What the model file would hold there (a number, text such as ``"30 deg"``, a list).
    line, column : int
        1-based position of the value in the answers file (0 when not from a file).
    key_line, key_column : int
        1-based position of the path (the mapping's key).
    """

    path: str
    value: Any
    line: int = 0
    column: int = 0
    key_line: int = 0
    key_column: int = 0


@dataclass(frozen=True)
class Answers:
    """A student's equations in file order.

    Parameters
    ----------
    file : str
        The answers file's path ('<answers>' when given as data).
    equations : tuple of Answer
        The equations that could be read, in file order.
    student : str
        The optional ``student`` line of the file.
    """

    file: str
    equations: tuple[Answer, ...]
    student: str = ""
    coordinates: tuple[tuple[str, str], ...] = ()
    """The answers' own names of the generalized coordinates and the model's coordinate
    each stands for (``coordinates: {theta1: O.angle}``), in the file's order."""
    settings: tuple[Setting, ...] = ()
    """The values the answers were computed with (``set:``), in the file's order."""
    problems: tuple[Issue, ...] = ()
    """What could not be read, each located (only when read with ``partial=True``: the
    other readings raise them): an entry left out of `equations`, a top-level key."""
    entries: int = 0
    """How many entries the ``equations:`` list has, read or not (0: as `equations`)."""

    @property
    def given(self) -> int:
        """How many equations the answers give: their entries, read or not."""
        return max(self.entries, len(self.equations))

    @property
    def values(self) -> dict[str, Any]:
        """The ``set:`` values as `mbody.Model.with_values` takes them (path -> value)."""
        return {s.path: s.value for s in self.settings}

    def issue(self, a: Answer, message: str, *, position: int | None = None,
              body: bool = False, hint: str = "") -> Issue:
        """An `Issue` located at answer `a` (its body, or a character of its equation).

        Parameters
        ----------
        a : Answer
            The answer the problem is in.
        message : str
            What is wrong.
        position : int, optional
            0-based character of the equation where it is.
        body : bool
            Point at the answer's body name instead of its equation.
        hint : str
            A did-you-mean or a way to fix it.

        Returns
        -------
        Issue
            With this file, line and column.
        """
        line, col = a.line, a.column
        key = a.key
        if body:
            line, col = a.body_line, a.body_column
            key = key.rpartition(".")[0] + ".body"
        elif position is not None and line:
            col += position
        return Issue(self.file, line, col, key, message, hint)


def read_answers(path: str | os.PathLike[str], *, partial: bool = False) -> Answers:
    """Read an answers file.

    Parameters
    ----------
    path : str or path-like
        The YAML file.
    partial : bool
        Keep the entries that can be read and list the problems of the others in
        `Answers.problems`, instead of raising them (an unknown key, an entry without an
        equation...). The file itself must be an answers file: one that cannot be read,
        is not YAML, or has no list of equations is still an error.

    Returns
    -------
    Answers
        Its equations with their line marks.

    Raises
    ------
    AnswersError
        The file is missing, not YAML, or not an answers file; every problem located.
    """
    try:
        text = read_file(path)
    except ModelError as exc:
        raise AnswersError([_reword(i) for i in exc.issues]) from None
    name = str(path)
    if not text.strip():
        raise AnswersError([Issue(name, 1, 1, "", "the file is empty; expected a mapping "
                                  "with 'equations:', a list of {body: NAME, eq: \"...\"}")])
    try:
        doc = load_text(text, name)
    except ModelError as exc:
        raise AnswersError(exc.issues) from None
    return _build(doc.data, name, doc, text, partial)


def answers_from_data(data: Any, file: str = "<answers>", *,
                      partial: bool = False) -> Answers:
    """Answers given as Python data.

    Parameters
    ----------
    data : mapping or sequence
        ``{"equations": [...]}`` (with ``student``, ``set``... as a file has them), or
        the list itself; each entry ``{"body": ..., "eq": ...}`` or a pair ``(body, eq)``.
    file : str
        The name shown in messages.
    partial : bool
        As `read_answers`'s.

    Returns
    -------
    Answers
        The equations (without line marks).

    Raises
    ------
    AnswersError
        An entry without a body or an equation, or of the wrong kind.
    """
    if isinstance(data, Sequence) and not isinstance(data, str | bytes):
        data = {"equations": [{"body": e[0], "eq": e[1]} if isinstance(e, tuple | list)
                              and len(e) == 2 else e for e in data]}
    return _build(data, file, None, "", partial)


def _reword(issue: Issue) -> Issue:
    """The loader speaks of model files; an answers file is not one."""
    msg = _MODEL_PIPE.sub("", issue.message)
    msg = msg.replace("a model file", "an answers file").replace("model file", "answers file")
    return Issue(issue.file, issue.line, issue.column, issue.key, msg, issue.hint)


_MODEL_PIPE = re.compile(r" \(to read a model from a pipe: [^)]*\)")
"""The loader's advice on a model read from a pipe (``mbody check /dev/stdin``)."""


_Where = Callable[..., tuple[int, int]]
"""Where a path of the document is: (line, column); ``key=True``: its key's."""
_Err = Callable[..., None]
"""Report a problem at a path of the document: (path, message, hint='', key=False)."""


def _build(data: Any, file: str, doc: Document | None, text: str, partial: bool) -> Answers:
    """The answers in `data`; with `partial`, the entries that can be read and the
    problems of the others (module doc). A file that is no answers file (not a mapping,
    no list of equations) raises either way."""
    issues: list[Issue] = []
    lines = text.split("\n") if text else []  # once: split per entry was quadratic

    def where(path: tuple, key: bool = False) -> tuple[int, int]:
        return doc.where(path, key=key) if doc is not None else (0, 0)

    def err(path: tuple, message: str, hint: str = "", key: bool = False) -> None:
        line, col = where(path, key)
        issues.append(Issue(file, line, col, dotted(path), message, hint))

    if not isinstance(data, Mapping):
        err((), f"expected a mapping with 'equations:', got {_kind(data)}",
            "write equations: followed by a list of {body: NAME, eq: \"...\"}")
        raise AnswersError(issues)
    entries = data.get("equations")
    if entries is None:
        err((), "no 'equations:' list", "add equations: with one {body: NAME, eq: \"...\"} "
            "per equation")
    elif not isinstance(entries, list):
        err(("equations",), f"expected a list of {{body, eq}} entries, got {_kind(entries)}")
    elif not entries:
        err(("equations",), "the list of equations is empty")
    elif len(entries) > MAX_EQUATIONS:
        err(("equations",), f"{len(entries)} equations; at most {MAX_EQUATIONS} are checked at "
            "once", "split the answers into several files")
    fatal = bool(issues)
    for k in data:
        if k not in TOP_KEYS:
            hint = did_you_mean(str(k), TOP_KEYS)
            err((k,), f"unknown key {k!r}; an answers file has {', '.join(TOP_KEYS)}",
                hint, key=True)
    student = data.get("student", "")
    if student is None:
        student = ""
    if not isinstance(student, str | int | float):
        err(("student",), f"expected free text, got {_kind(student)}")
        student = ""
    for k in NOTE_KEYS:
        if not _free_text(data.get(k)):
            err((k,), f"expected free text, got {_kind(data.get(k))}", "quote it: "
                f"{k}: \"...\"")
    coords = _coordinates(data.get("coordinates"), err)
    settings = _settings(data, where, err)
    if fatal or not isinstance(entries, list):  # nothing to read: every problem at once
        raise AnswersError(issues)
    out: list[Answer] = []
    for n, e in enumerate(entries):
        answer = _entry(n, e, where, err, lines)
        if answer is not None:
            out.append(answer)
    if issues and not partial:
        raise AnswersError(issues)
    return Answers(file, tuple(out), str(student), tuple(coords), tuple(settings),
                   tuple(issues), len(entries))


def _free_text(value: Any) -> bool:
    """A ``note``, ``comment`` or ``student`` value: text or a number (or nothing)."""
    return value is None or (isinstance(value, str | int | float) and not isinstance(value,
                                                                                  bool))


def _coordinates(given: Any, err: _Err) -> list[tuple[str, str]]:
    """``coordinates: {theta1: O.angle}`` -> [(theta1, O.angle)]; each bad pair reported."""
    coords: list[tuple[str, str]] = []
    if given is None:
        return coords
    if not isinstance(given, Mapping) or not given:
        err(("coordinates",), f"expected a mapping of your names to the model's "
            f"coordinates, got {_kind(given)}", "coordinates: {theta1: O.angle, "
            "theta2: A.angle}")
        return coords
    for name, label in given.items():
        if not isinstance(name, str) or not name.isidentifier():
            err(("coordinates", name), f"expected a name such as theta1, got "
                f"{_kind(name)}", key=True)
        elif not isinstance(label, str):
            err(("coordinates", name), f"expected a coordinate label such as "
                f"O.angle, got {_kind(label)}")
        else:
            coords.append((name, label))
    return coords


def _settings(data: Mapping, where: _Where, err: _Err) -> list[Setting]:
    """``set: {bodies.rod.mass: 2.5}`` -> its `Setting`s, each with its marks; the paths
    and values themselves are the model's to check (`mbody.answers.variant`)."""
    given = data.get("set")
    out: list[Setting] = []
    if "set" not in data:
        return out
    example = "set: {bodies.rod.mass: 2.5, drivers.motor.speed: 100 rpm}"
    if not isinstance(given, Mapping) or not given:
        err(("set",), f"expected a mapping of model paths to values, got {_kind(given)}",
            example)
        return out
    for path, value in given.items():
        if not isinstance(path, str) or not path.strip():
            err(("set", path), f"expected a path such as bodies.rod.mass, got {_kind(path)}",
                example, key=True)
        elif value is None:
            err(("set", path), "no value", f"{path}: followed by the value the model file "
                "would hold there", key=True)
        else:
            out.append(Setting(path.strip(), value, *where(("set", path)),
                               *where(("set", path), key=True)))
    return out


def _entry(n: int, e: Any, where: _Where, err: _Err, lines: list[str]) -> Answer | None:
    """Entry `n` of ``equations:`` as an `Answer`, or None when it has no body and
    equation to check; its problems reported either way (an entry with a key too many
    is still an equation: checked, and the key reported)."""
    path: tuple = ("equations", n)
    if not isinstance(e, Mapping):
        err(path, f"expected {{body: NAME, eq: \"...\"}}, got {_kind(e)}")
        return None
    bad = [k for k in e if k not in ENTRY_KEYS]
    for k in bad:
        err((*path, k), f"unknown key {k!r}; an entry has body and eq (and coordinate, "
            "note or comment)", did_you_mean(str(k), ENTRY_KEYS), key=True)
    notes = [k for k in NOTE_KEYS if not _free_text(e.get(k))]
    for k in notes:
        err((*path, k), f"expected free text, got {_kind(e.get(k))}", f'quote it: {k}: "..."')
    body, eq = e.get("body"), e.get("eq")
    coordinate = e.get("coordinate")
    if body is None and eq is not None:  # an equation in generalized coordinates
        if coordinate is not None and not isinstance(coordinate, str):
            err((*path, "coordinate"), f"expected a coordinate's name, got "
                f"{_kind(coordinate)}")
            return None
        body = ""
    elif coordinate is not None:
        err((*path, "coordinate"), "an entry with a body is a Newton-Euler equation: "
            "it has no coordinate", "leave out body: for an equation in generalized "
            "coordinates", key=True)
        return None
    if body is None or eq is None:
        missing = " and ".join(k for k, v in (("body", body), ("eq", eq)) if v is None)
        err(path, f"missing {missing}", "each entry is {body: NAME, eq: \"...\"}")
        return None
    if not isinstance(body, str):
        err((*path, "body"), f"expected a body name, got {_kind(body)}")
        return None
    if not isinstance(eq, str):
        err((*path, "eq"), f"expected the equation as text, got {_kind(eq)}",
            'quote it: eq: "2*a_y = O.Fy - 19.62"')
        return None
    line, col = where((*path, "eq"))
    col += _quote_offset(lines, line, col, eq)
    return Answer(n + 1, body, eq, line, col, dotted((*path, "eq")),
                  *where((*path, "body")), coordinate=str(coordinate or ""))


def _quote_offset(lines: list[str], line: int, col: int, eq: str) -> int:
    """Characters between a value's mark and its first character: 1 for a quote."""
    if not lines or not line:
        return 0
    if line > len(lines):
        return 0
    row = lines[line - 1][col - 1:]
    if row[:1] in ("'", '"') and row[1:].startswith(eq[:8]):
        return 1
    return 0


def _kind(value: Any) -> str:
    if value is None:
        return "nothing"
    return {dict: "a mapping", list: "a list", str: f"the text {value!r}", bool: "a boolean",
            int: "a number", float: "a number"}.get(type(value), type(value).__name__)
