"""A student's variant of the model: the answers' ``set:`` values applied to it.

An instructor who gives each student their own numbers (another mass, another angle)
has each answers file say which:

```yaml
student: Ana
set: {bodies.rod.mass: 2.5, bodies.rod.angle: 40 deg}
equations: [...]
```

The paths and values are those of ``--set PATH=VALUE`` (`mbody.model.values`), applied
the same way, by `mbody.Model.with_values`: the model file read again with the values in
place and every rule of the file checked. A problem is reported in the answers file, at
the path (a path that names nothing in the model, with a did-you-mean) or at the value
(a value the model file could not hold), with the model's reason.

A ``set:`` can change anything the model file holds, gravity included, so a grader says
which paths a student may set (``--allow-set``, `allow_list`): a path no pattern allows
is an error of that file, and its equations are not checked against numbers the
instructor never gave.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from fnmatch import fnmatchcase

from mbody.answers.load import Answers, AnswersError, Setting
from mbody.errors import (
    Issue,
    MbodyError,
    ModelError,
    comma_words,
    did_you_mean,
    option_name,
    option_setting,
)
from mbody.model.model import Model
from mbody.model.values import apply, edits, entry_names, resolve, settable_paths

WILDCARDS = "*?["
"""The characters that make a pattern of `allow_list` match several paths (fnmatch's)."""


def allow_list(model: Model, patterns: str | Sequence[str] | None
               ) -> tuple[str, ...] | None:
    """The paths a student's ``set:`` may name, checked against `model`: None (any path)
    when `patterns` is None, else the patterns, each a ``--set`` path
    (``bodies.lower.mass``; a whole entry's key allows its components,
    ``gravity`` allows ``gravity.1``, ``bodies.lower`` every key of that body) or one
    with fnmatch's wildcards (``bodies.*.mass``). A comma separates patterns in one text.

    Raises
    ------
    MbodyError
        A pattern without wildcards that names nothing in the model file (with the
        model's did-you-mean), one with wildcards that matches none of its paths, or an
        empty pattern; `mbody.errors.MbodyTypeError` for
        what is not text.
    """
    if patterns is None:
        return None
    out = comma_words(patterns, "allow_set", "paths such as bodies.rod.mass")
    if any(not p for p in out):
        raise MbodyError(f"{option_name('allow_set')}: an empty path; expected paths such "
                         "as bodies.rod.mass, separated by commas")
    src = model.source
    if src is not None:
        doc = src.read()
        names = entry_names(model)
        paths: list[str] | None = None
        for p in out:
            if any(c in p for c in WILDCARDS):
                # a pattern that matches no path of the model allows nothing: a typo
                # that would refuse every file setting a value
                paths = settable_paths(doc, names) if paths is None else paths
                if not any(allowed(path, (p,)) for path in paths):
                    hint = did_you_mean(p, paths)
                    raise MbodyError(
                        f"{option_setting('allow_set', p)}: the pattern matches no path of "
                        "the model; paths are section.name.key[.component], such as "
                        f"bodies.*.mass or gravity.1" + (f" ({hint})" if hint else ""))
                continue
            head, _, name = p.partition(".")
            if name in names.get(head, ()):
                continue  # a whole entry (bodies.lower): every key of it
            try:
                resolve(doc, p, names)
            except ModelError as exc:
                i = exc.issues[0]
                raise MbodyError(f"{option_setting('allow_set', p)}: {i.message}"
                                 + (f" ({i.hint})" if i.hint else "")) from None
    return tuple(dict.fromkeys(out))


def allowed(path: str, patterns: Sequence[str]) -> bool:
    """Whether the ``set:`` path `path` is one `patterns` (`allow_list`) allow."""
    return any(fnmatchcase(path, p) or path.startswith(p + ".") for p in patterns)


def variant(model: Model, sheet: Answers, allow: Sequence[str] | None = None) -> Model:
    """`model` with the values of `sheet`'s ``set:`` (module doc); `model` itself when
    the answers set none.

    Parameters
    ----------
    model : Model
        The class's model (with the command line's ``--set`` values, if any: the
        answers' values are set on top of them, so the answers' own win).
    sheet : Answers
        A student's answers.
    allow : sequence of str, optional
        The paths the answers may set (`allow_list`); None: any.

    Returns
    -------
    Model
        A new model, as `mbody.load` would give for the model file with those values.

    Raises
    ------
    AnswersError
        A ``set:`` that could not be read, a path that names nothing in the model file,
        a path `allow` does not allow, or a value the model file could not hold, located
        in the answers file; or a model built in Python, which has no file to set values
        in.
    """
    unread = [i for i in sheet.problems if i.key == "set" or i.key.startswith("set.")]
    if unread:  # a value that could not be read: the numbers would not be the student's
        raise AnswersError(unread)
    if not sheet.settings:
        return model
    if allow is not None:
        refused = [s for s in sheet.settings if not allowed(s.path, allow)]
        if refused:  # every number would depend on values the instructor never gave
            may = (f"only {', '.join(allow)}" if allow else "no value")
            raise AnswersError([Issue(
                sheet.file, s.key_line, s.key_column, f"set.{s.path}",
                f"a student may set {may} here ({option_name('allow_set')}); this path is "
                "not among them", "use the values the assignment gives you") for s in refused])
    src = model.source
    if src is None:
        s = sheet.settings[0]
        raise AnswersError([Issue(sheet.file, s.key_line, s.key_column, "set",
                                  f"model {model.name!r} was built from a Spec, not read "
                                  "from a file: there is no document to set values in",
                                  "load the model with mbody.load")])
    doc = src.read()
    names = entry_names(model)
    apply(doc, edits(doc, src.values, names))  # as `with_values` sees the document
    issues = []
    good = []
    for s in sheet.settings:  # a path that names nothing: at the path
        try:
            resolve(doc, s.path, names)
            good.append(s)
        except ModelError as exc:
            issues += [_at(sheet, s, i, key=True) for i in exc.issues]
    changed = model
    try:
        if good:
            changed = model.with_values({s.path: s.value for s in good})
    except ModelError as exc:  # a value the file could not hold: at the value
        issues += [_relocated(sheet, model, i) for i in exc.issues]
    except MbodyError as exc:  # the model file changed since it was read
        s = sheet.settings[0]
        issues.append(Issue(sheet.file, s.key_line, s.key_column, "set", str(exc)))
    if issues:  # every problem of the values at once
        raise AnswersError(sorted(issues, key=lambda i: (i.line, i.column)))
    return changed


def _relocated(sheet: Answers, model: Model, issue: Issue) -> Issue:
    """A problem of the model with the values set: at the value it names in the answers
    file; another (a rule between entries, such as a joint that no longer closes) where
    the model file has it, saying which values were set."""
    for s in reversed(sheet.settings):
        if issue.key == s.path or issue.key.startswith((s.path + ".", s.path + "[")):
            return _at(sheet, s, issue, key=False, model_file=model.file or "")
    return issue


def _at(sheet: Answers, s: Setting, issue: Issue, *, key: bool,
        model_file: str = "") -> Issue:
    """`issue` (the model's words) located at setting `s` of the answers file."""
    line, col = (s.key_line, s.key_column) if key else (s.line, s.column)
    rest = issue.key[len(s.path):] if issue.key.startswith(s.path) else ""
    return replace(issue, file=sheet.file, line=line, column=col,
                   key=f"set.{s.path}{rest}", hint=_hint(issue.hint, model_file))


def _hint(hint: str, model_file: str) -> str:
    """The model's hint without its note of which value was set (the answers' line says
    it), the model file's own value named as the model file's."""
    parts = []
    for part in hint.split("; "):
        if part.startswith("set by ") or part == "the file gives none":
            continue
        if part.startswith("the file's own value is on line") and model_file:
            part = part.replace("the file's own value", "the model's own value") + \
                f" of {model_file}"
        parts.append(part)
    return "; ".join(parts)
