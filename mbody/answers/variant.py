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
"""

from __future__ import annotations

from dataclasses import replace

from mbody.answers.load import Answers, AnswersError, Setting
from mbody.errors import Issue, MbodyError, ModelError
from mbody.model.model import Model
from mbody.model.values import apply, edits, entry_names, resolve


def variant(model: Model, sheet: Answers) -> Model:
    """`model` with the values of `sheet`'s ``set:`` (module doc); `model` itself when
    the answers set none.

    Parameters
    ----------
    model : Model
        The class's model (with the command line's ``--set`` values, if any: the
        answers' values are set on top of them, so the answers' own win).
    sheet : Answers
        A student's answers.

    Returns
    -------
    Model
        A new model, as `mbody.load` would give for the model file with those values.

    Raises
    ------
    AnswersError
        A ``set:`` that could not be read, a path that names nothing in the model file,
        or a value it could not hold, located in the answers file; or a model built in
        Python, which has no file to set values in.
    """
    unread = [i for i in sheet.problems if i.key == "set" or i.key.startswith("set.")]
    if unread:  # a value that could not be read: the numbers would not be the student's
        raise AnswersError(unread)
    if not sheet.settings:
        return model
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
