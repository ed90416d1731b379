"""Values set by path: ``bodies.rod.mass``, ``drivers.motor.speed``,
``bodies.rod.position.1`` (`Model.with_values`, ``--set PATH=VALUE``).

A path names an entry of the model file by its section and name, then a key of that
entry, then, inside a list or a mapping, a component by index or key:

    bodies.<name>.<key>[.<index or key>...]      loads.<name>.<key>...
    joints.<name>.<key>...                       drivers.<name>.<key>...
    gravity[.<index>]

A value is what the file would hold there (a number, text such as ``"100 rpm"`` or
``"30 deg"``, a list): it is written into a copy of the model's document, and the whole
document is validated again (`mbody.model.validate`), so every rule of the file applies
to it, and a problem is reported at the file's line of the entry, naming the path. An
MJCF or URDF model's document is the YAML form its import gives (what ``mbody convert
... -o model.yaml`` writes): its bodies are the links, by their names there.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from mbody.errors import Issue, MbodyError, ModelError, did_you_mean
from mbody.model.checks import (
    RATE_UNITS,
    _show,
    key_unit,
    number_hint,
    prefixed,
    si_quantity,
    written_quantity,
)
from mbody.model.drivers import DRIVER_KEYS, SPEED_UNITS
from mbody.model.loader import Document, Path_, dotted, load_text
from mbody.model.validate import BODY_KEYS, JOINT_KEYS, LOAD_KEYS, Spec, validate

SECTIONS = ("bodies", "loads", "joints", "drivers")
"""The file's lists whose entries a path names."""
TOP = ("gravity",)
"""Top-level keys a path may name directly."""
_WHAT = {"bodies": "body", "loads": "load", "joints": "joint", "drivers": "driver"}
_ALL_LOAD_KEYS = tuple(dict.fromkeys(k for keys in LOAD_KEYS.values() for k in keys))


@dataclass(frozen=True)
class Edit:
    """One value set: the path as given, where it is in the document, the value."""

    given: str
    path: Path_
    value: Any


def entry_names(model: Any) -> dict[str, Sequence[str]]:
    """Each section's entry names in file order (a load without a name has the one the
    model generated for it: ``force1``; a driver ``driver1``)."""
    drivers = model.drivers
    return {"bodies": model.body_names, "loads": [ld.name for ld in model.loads],
            "joints": model.joint_table.names,
            "drivers": drivers.names if drivers is not None else ()}


def plain(value: Any) -> Any:
    """A value as the file would hold it: numpy numbers and arrays as Python numbers and
    lists, tuples as lists, mappings as dicts."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    return value


def parse_value(text: str, path: str = "") -> Any:
    """A value written on the command line, read as YAML reads it in a model file: ``2``
    and ``1e-3`` are numbers, ``100 rpm`` and ``30 deg`` text, ``[0, 1.5]`` a list."""
    label = f"{path}: " if path else ""
    if not text.strip():
        raise MbodyError(f"{label}no value after '='")
    try:
        return load_text(text, "<value>").data
    except ModelError as exc:
        first = exc.issues[0]
        hint = f" ({first.hint})" if first.hint else ""
        raise MbodyError(f"{label}cannot read the value {text!r}: {first.message}{hint}"
                         ) from None


def parse_assignment(text: str, flag: str = "--set") -> tuple[str, str]:
    """``"bodies.rod.mass=2"`` -> ``("bodies.rod.mass", "2")``."""
    path, sep, value = text.partition("=")
    if not sep or not path.strip():
        raise MbodyError(f"{flag} expects PATH=VALUE (for example bodies.rod.mass=2), got "
                         f"{text!r}")
    return path.strip(), value.strip()


UNIT_KEYS: dict[str, tuple[str, ...]] = {
    "angle": ("deg", "rad"), "euler": ("deg", "rad"), "angular_velocity": tuple(RATE_UNITS),
    "speed": SPEED_UNITS}
"""A model file's keys that read a number written with a unit, and its units (text such
as ``"30 deg"``); every other key's number is written without one."""


def unit_refused(path: str, text: str) -> tuple[str, str | None] | None:
    """Why `text`, a number with a unit (``'2 kg'``), is refused at `path`
    (``bodies.rod.mass``), by the path's last key: what the key takes and
    `mbody.model.checks.number_hint`'s advice (``"takes no unit (numbers are in SI
    units, ...)"``), and the number to write instead (``'2'``, ``'0.5'`` for ``'500
    g'``) when the unit converts to the key's. None when the key reads that unit
    (``'600 rpm'`` as a driver's speed) or `text` is not a number with a unit (an
    expression, a range)."""
    written = written_quantity(text)
    keys = [k for k in path.replace("[", ".").replace("]", "").split(".")
            if k and not k.lstrip("-").isdigit()]
    units = UNIT_KEYS.get(keys[-1], ()) if keys else ()
    if written is None or not keys or written[1] in units:
        return None
    if units:
        converted = prefixed(text, units)
        return (f"takes a number in SI units or with a unit ({', '.join(units)}; "
                + (f"units take no prefix: {converted})" if converted else
                   f"got {written[1]!r})"), None)
    expected = key_unit((keys[-1],))
    si = si_quantity(text)
    meant = (f"{si[0]:.6g}" if si is not None and expected is not None and si[1] == expected
             else None)
    return f"takes no unit ({number_hint(text, expected)})", meant


def resolve(doc: Document, given: str, names: Mapping[str, Sequence[str]]) -> Path_:
    """Where in `doc` the path `given` points (its parts as document keys and indices).

    Raises
    ------
    ModelError
        The path names no section, entry, key or component of the file, with a
        did-you-mean and the line of the deepest part that exists.
    """
    parts = given.split(".")

    def fail(at: Path_, message: str, hint: str = "") -> ModelError:
        # a section by its key's line (its list starts on the next); anything else by its value
        line, col = doc.where(at, key=len(at) == 1) if at else (0, 0)
        return ModelError([_located(doc, Issue(doc.file, line, col, given, message, hint))])

    head = parts[0]
    if head in TOP:
        return _inside(doc, (head,), parts[1:], given, fail)
    if head not in SECTIONS:
        choices = (*SECTIONS, *TOP)
        raise fail((), f"a path starts with one of {', '.join(choices)}; got {head!r}",
                   did_you_mean(head, choices) or "for example bodies.rod.mass")
    what = _WHAT[head]
    if len(parts) < 3:
        raise fail((head,) if head in doc.data else (), f"a path names a {what} and one of "
                   f"its keys: {head}.<name>.<key>", f"for example {head}."
                   f"{(list(names.get(head, ())) or ['name'])[0]}.{_example_key(head)}")
    section = list(names.get(head, ()))
    name = parts[1]
    if name not in section:
        shown = ", ".join(section[:12]) + (" ..." if len(section) > 12 else "")
        raise fail((head,) if head in doc.data else (), f"no {what} named {name!r}",
                   did_you_mean(name, section)
                   or (f"the {head} are: {shown}" if section else f"the model has no {head}"))
    i = section.index(name)
    entry = doc.data[head][i]
    at: Path_ = (head, i)
    key = parts[2]
    keys = _keys(head, entry)
    if key not in keys:
        raise fail(at, f"{what} {name!r} has no key {key!r}",
                   did_you_mean(key, keys) or f"a {what}'s keys: {', '.join(keys)}")
    if key == "name":
        raise fail((*at, key), "a name cannot be set: paths name entries by it",
                   "rename the entry in the file")
    return _inside(doc, (*at, key), parts[3:], given, fail)


def settable_paths(doc: Document, names: Mapping[str, Sequence[str]]) -> list[str]:
    """Every path `resolve` accepts in `doc`: each entry's keys (those the file leaves out
    too, which a value may add; not ``name``), the components of the values it gives, and
    ``gravity`` with its components; for matching a pattern (``bodies.*.mass``) against
    the model. As many as the document's values, plus each entry's unused keys."""
    out: list[str] = []

    def inside(prefix: str, value: Any) -> None:
        out.append(prefix)
        if isinstance(value, list):
            for i, v in enumerate(value):
                inside(f"{prefix}.{i}", v)
        elif isinstance(value, dict):
            for k, v in value.items():
                inside(f"{prefix}.{k}", v)

    data = doc.data if isinstance(doc.data, dict) else {}
    for head in TOP:
        inside(head, data.get(head, _ABSENT))
    for head in SECTIONS:
        entries = data.get(head)
        for i, name in enumerate(names.get(head, ())):
            entry = entries[i] if isinstance(entries, list) and i < len(entries) else {}
            for key in _keys(head, entry):
                if key != "name":
                    inside(f"{head}.{name}.{key}",
                           entry.get(key, _ABSENT) if isinstance(entry, dict) else _ABSENT)
    return out


def _example_key(section: str) -> str:
    return {"bodies": "mass", "loads": "force", "joints": "at", "drivers": "speed"}[section]


def _keys(section: str, entry: Any) -> tuple[str, ...]:
    if section == "bodies":
        return BODY_KEYS
    if section == "joints":
        return JOINT_KEYS
    if section == "drivers":
        return DRIVER_KEYS
    typ = entry.get("type") if isinstance(entry, dict) else None
    return LOAD_KEYS.get(typ, _ALL_LOAD_KEYS) if isinstance(typ, str) else _ALL_LOAD_KEYS


def _inside(doc: Document, at: Path_, rest: list[str], given: str, fail) -> Path_:
    """The path `at` (a key of an entry, or of the top level) followed into its list
    components and mapping keys by `rest`."""
    data: Any = doc.data
    for p in at[:-1]:
        data = data[p]
    value = data.get(at[-1], _ABSENT) if isinstance(data, dict) else _ABSENT
    path = at
    shown = given.rsplit(".", len(rest))[0] if rest else given
    for part in rest:
        if value is _ABSENT:
            raise fail(path[:-1], f"the file gives no {path[-1]!r} here, so it has no "
                       f"component {part!r}", f"set the whole value: {shown}=[...]")
        if isinstance(value, list):
            if not (part.isdigit() and int(part) < len(value)):
                raise fail(path, f"{shown} has {len(value)} components; a component is "
                           f"its index, 0 to {len(value) - 1}, got {part!r}")
            path, value = (*path, int(part)), value[int(part)]
        elif isinstance(value, dict):
            if part not in value:
                raise fail(path, f"{shown} has no {part!r}",
                           did_you_mean(part, list(value)) or
                           f"it has: {', '.join(map(str, value))}")
            path, value = (*path, part), value[part]
        else:
            raise fail(path, f"{shown} is a single value ({_show(value)}); it has no "
                       f"component {part!r}", f"set it whole: {shown}=VALUE")
        shown = f"{shown}.{part}"
    return path


class _Absent:
    pass


_ABSENT = _Absent()


def edits(doc: Document, values: Sequence[tuple[str, Any]],
          names: Mapping[str, Sequence[str]]) -> list[Edit]:
    """Each value's place in `doc`, checked (every bad path at once)."""
    out, issues = [], []
    for given, value in values:
        try:
            out.append(Edit(given, resolve(doc, given, names), plain(value)))
        except ModelError as exc:
            issues += exc.issues
    if issues:
        raise ModelError(issues)
    return out


def apply(doc: Document, changes: Sequence[Edit]) -> None:
    """Write each value into `doc`'s values (a copy: `Source.read`), in order."""
    for e in changes:
        data = doc.data
        for p in e.path[:-1]:
            data = data[p]
        data[e.path[-1]] = e.value


def validate_edited(doc: Document, changes: Sequence[Edit]) -> Spec:
    """`validate` the edited document (an MJCF or URDF import's issues at their own
    files); a problem with a value set names its path, and every other problem says which
    values were set."""
    try:
        spec = validate(doc)
    except ModelError as exc:
        raise ModelError([_located(doc, _blame(doc, i, changes)) for i in exc.issues]
                         ) from None
    spec.warnings[:] = [_located(doc, _blame(doc, w, changes)) for w in spec.warnings]
    return spec


def _blame(doc: Document, issue: Issue, changes: Sequence[Edit]) -> Issue:
    for e in reversed(changes):
        d = dotted(e.path)
        if issue.key == d or issue.key.startswith((d + ".", d + "[")):
            rest = issue.key[len(d):].replace("[", ".").replace("]", "")
            in_file = e.path in doc.marks
            where = (f"; the file's own value is on line {doc.where(e.path)[0]}" if in_file
                     else "; the file gives none")
            note = f"set by {e.given}={_show(e.value)}{where}"
            return replace(issue, key=e.given + rest,
                           hint=f"{issue.hint}; {note}" if issue.hint else note)
    if not changes:
        return issue
    shown = ", ".join(f"{e.given}={_show(e.value)}" for e in changes[:4])
    note = f"with {shown}{' ...' if len(changes) > 4 else ''} set"
    return replace(issue, hint=f"{issue.hint}; {note}" if issue.hint else note)


def _located(doc: Document, issue: Issue) -> Issue:
    """An MJCF or URDF import's issue naming the (included) file its line is in."""
    locate = getattr(doc, "locate", None)
    return locate(issue) if locate is not None else issue
