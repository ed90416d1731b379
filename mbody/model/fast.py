"""A fast path for large, regular model files: read in bulk, checked with numpy.

Reading a file through PyYAML's events costs about a microsecond per event from Python,
and a 10 000-body model has some 500 000 of them. Files that large are nearly always
written by a program (``yaml.dump``), so their ``bodies:`` and ``loads:`` lists repeat
one layout per item with different numbers. This module reads such a list in bulk:

1. Each list is cut out of the text; every value written at the end of a line (after
   ``key: `` or ``- [``) is a *slot*, replaced by a marker. What is left (the item's
   *skeleton*) is usually the same for every item.
2. Each distinct skeleton is parsed once by the located loader (`load_text`), with its
   slots numbered, which gives the item's structure: which key path each slot fills.
3. The slots of all items with that skeleton are typed a column at a time: a flow list
   of numbers, a number, or a name. One regular expression checks a whole column against
   the decimal forms both paths read identically; numpy parses its numbers.
4. The columns are checked with numpy against the same rules as `validate` (the rest of
   the file, small, goes through `validate`'s own functions), and `BodyTable` is filled.

Anything else (a comment or an anchor on a value line, a tab, a quoted or non-ASCII
value, a flow mapping, a number written ``1_000`` or ``.5``, a shape, an Euler angle, a
string angle, a spring, more than `MAX_TEMPLATES` layouts) and any value that `validate`
would refuse or warn about gives None: the caller then runs the located path on the
whole text, which reports every problem with its line and column. So this path never
accepts a file the located path refuses, and it builds the same `Model` (tested:
tests/test_fast.py compares both on generated and perturbed files).
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody.errors import ModelError
from mbody.model.checks import (
    _TOL,
    MAX_ANGLE,
    MAX_MAGNITUDE,
    MIN_MAGNITUDE,
    Checker,
    quat_norm,
    vec_norm,
)
from mbody.model.loader import load_text, value_limit
from mbody.model.validate import (
    FRAMES,
    BodyTable,
    JointSpec,
    LoadTable,
    Spec,
    header,
    rest,
)

MIN_BYTES = 64 * 1024
"""Smaller texts go straight to the located path: there is nothing to gain."""
MAX_TEMPLATES = 16
"""Most distinct item layouts in one list; more means a hand-written file."""
CHUNK = 1 << 18
"""Characters of a list read at a time, so that its temporary strings stay small."""

_PLACEHOLDER = "__mbody_fast_"
_NUMBER_BYTES = b"0123456789.eE+-"
"""What a column of numbers may hold besides its separators: json.loads then checks each
number against JSON's grammar, whose numbers YAML's core schema reads the same way (an
integer as int, anything with '.' or an exponent as float, through the same correctly
rounded conversion). Forms JSON refuses ('+1', '.5', '1.', '010', '1_000') go to the
located path, as do exponents of three digits (which may underflow to 0, or overflow;
YAML keeps those as unrepresentable) and magnitudes beyond MAX_MAGNITUDE."""
_EXPONENT_DIGITS = bytes.maketrans(b"123456789E+", b"000000000e-")
_ZEROS = b"0" * 200
"""A run of zeros this long goes to the located path: with an exponent of two digits at
most, a nonzero number underflows to 0 only after some 224 zeros ("0.000...1e-99"), which
YAML keeps as unrepresentable; repr never writes more than 4."""
_NAMES = re.compile(r"[A-Za-z][A-Za-z0-9_-]*(?:\n[A-Za-z][A-Za-z0-9_-]*)*")
_SPECIAL = frozenset(("null", "Null", "NULL", "true", "True", "TRUE", "false", "False",
                      "FALSE"))
"""Names the pattern above lets through that YAML reads as null or a boolean."""
_SECTION_END = re.compile(r"\n[^- ]")
_PRINTABLE = bytes(range(0x20, 0x7f)) + b"\n"
"""Printable ASCII and newlines; anything else (tabs, CR, a BOM...): the located path."""
_ODD = re.compile(r"[^\n\x20-\x7e]")
_SLOT_NAME = re.compile(r"__mbody_slot_([0-9]+)__")


class _Bail(Exception):
    """The fast path does not handle this text: use the located path."""


def fast_spec(text: str, file: str) -> Spec | None:
    """The `Spec` of a large, regular, valid model text, or None.

    Parameters
    ----------
    text : str
        The model file's text.
    file : str
        Its name, for the spec (the fast path reports nothing itself).

    Returns
    -------
    Spec or None
        None when the text is small, not in the subset this path reads, or not valid:
        then `validate(load_text(text, file))` gives the answer, with located problems.
    """
    if len(text) < MIN_BYTES or not text.isascii() or _PLACEHOLDER in text:
        return None
    try:
        return _spec(text, file)
    except (_Bail, ModelError):
        return None


def _spec(text: str, file: str) -> Spec:
    found = []
    for key in ("bodies", "loads", "joints"):
        head = f"\n{key}:\n- "
        at = 0 if text.startswith(head[1:]) else text.find(head) + 1
        if at == 0 and not text.startswith(head[1:]) or text.find(head, at) >= 0:
            continue  # absent, or twice (then the located loader names both lines)
        start = at + len(key) + 2  # the list's first '- '
        m = _SECTION_END.search(text, start)
        found.append((at, start, m.start() + 1 if m else len(text), key))
    found.sort()
    sections: dict[str, tuple[int, int]] = {}
    pieces = []
    at = 0
    for head_at, start, end, key in found:
        sections[key] = (start, end)
        pieces += [text[at:head_at], f"{key}: {_PLACEHOLDER}{key}__\n"]
        at = end
    if "bodies" not in sections:
        raise _Bail
    pieces.append(text[at:])
    rest_text = "".join(pieces)
    if _ODD.search(rest_text):
        raise _Bail
    doc = load_text(rest_text, file)
    c = Checker(doc)
    name, description, gravity = header(c)
    if c.issues or c.warnings:
        raise _Bail
    data = doc.data
    # every key and value counts towards the located reader's limit: the same limit here
    values = len(doc.marks) + len(doc.key_marks)
    lists = {}
    for key in sections:
        if data.get(key) != f"{_PLACEHOLDER}{key}__":
            raise _Bail  # the cut was not where the located reader sees the list
        lists[key], count = _read_list(text, *sections[key], file)
        values += count
    if values > value_limit(len(text)):
        raise _Bail
    table = _bodies(c, lists["bodies"])
    point = _loads(c, lists["loads"]) if "loads" in lists else None
    joints = _joints(c, lists["joints"]) if "joints" in lists else None
    loads, joints, reactions, expressions = rest(c, [], [] if point else None, joints)
    if c.issues or c.warnings:
        raise _Bail  # warnings need their lines: the located path gives them
    return Spec(name, file, c.dim, gravity, [], loads, joints, reactions, description,
                [], expressions, table, point)


# -- reading a list in bulk ---------------------------------------------------------------
@dataclass
class _Group:
    """The items of a list that share one layout: their indices and each slot's column.

    Column values: (k, L) floats for a flow list of L numbers, (k,) floats for a number,
    a list of str for a name.
    """

    index: np.ndarray
    columns: dict[tuple[Any, ...], Any]


def _read_list(text: str, start: int, end: int, file: str) -> tuple[list[_Group], int]:
    """The items of the block list text[start:end] (each starts with '- ' at column 0),
    grouped by layout, with every slot typed a column at a time; and how many keys and
    values they hold beyond the list itself (as the located reader counts them).

    The list is read a chunk of about `CHUNK` characters at a time, and each chunk's
    columns are parsed before the next is cut; no string is made per value (a column's
    bytes are gathered with numpy and parsed by json in one call).
    """
    layouts: dict[str, int] = {}
    structure: list[dict[tuple[Any, ...], int]] = []
    nodes: list[int] = []  # per layout: keys and values of one item, a flow list as one
    pieces: list[dict[tuple[Any, ...], list[Any]]] = []  # per layout, per path: chunks
    rows: list[list[int]] = []  # per layout: item indices
    item = 0
    pos = start
    while pos < end:
        stop = end if end - pos <= CHUNK else text.find("\n- ", pos + CHUNK, end) + 1 or end
        data = text[pos:stop].encode("ascii")
        if data.translate(None, _PRINTABLE):
            raise _Bail  # a tab, a carriage return, a control character
        b = np.frombuffer(data, dtype=np.uint8)
        s, e = _slots(b)
        skeleton = b.copy()
        skeleton[s] = 0  # each value becomes one NUL, its marker
        inside = np.zeros(len(b) + 1, dtype=np.int8)
        inside[s + 1] += 1
        inside[e] -= 1  # no two slots share a start or an end, nor touch (see _slots)
        body = skeleton[np.cumsum(inside[:-1], dtype=np.int8) == 0].tobytes().decode("ascii")
        # items without the leading '- ' and the newline that ends each one
        skeletons = body[2:-1 if body.endswith("\n") else None].split("\n- ")
        for sk in set(skeletons).difference(layouts):
            if len(layouts) >= MAX_TEMPLATES:
                raise _Bail
            layouts[sk] = len(layouts)
            paths, count = _structure(sk, file)
            structure.append(paths)
            nodes.append(count)
            pieces.append({path: [] for path in structure[-1]})
            rows.append([])
        ids = np.fromiter(map(layouts.__getitem__, skeletons), dtype=np.intp,
                          count=len(skeletons))
        widths = np.array([len(st) for st in structure], dtype=np.intp)[ids]
        first = np.cumsum(widths) - widths  # each item's first slot
        if first[-1] + widths[-1] != len(s):
            raise _Bail
        for k in np.unique(ids).tolist():
            mine = np.flatnonzero(ids == k)
            for path, slot in structure[k].items():
                at = first[mine] + slot
                pieces[k][path].append(_column(b, s[at], e[at]))
            rows[k].extend((mine + item).tolist())
        item += len(skeletons)
        pos = stop
    groups = [_Group(np.array(r, dtype=np.intp),
                     {path: _joined(chunks) for path, chunks in pieces[k].items()})
              for k, r in enumerate(rows)]
    count = sum(len(g.index) * (nodes[k] + sum(c.shape[1] for c in g.columns.values()
                                               if isinstance(c, np.ndarray) and c.ndim == 2))
                for k, g in enumerate(groups))
    return groups, count


def _slots(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and end (exclusive) of every value in the text `b` (bytes), in order.

    A value follows ': ' (in a block mapping, or in a one-line flow mapping as yaml.dump
    writes a mapping of scalars), or '- ' before '[' on a line indented with spaces
    only. It is a flow list ('[' to the next ']'), or it runs to the end of the line, the
    next ', ' or the next '}'. Anything odd (a value that would swallow the next, an
    empty one, a list that does not close) is `_Bail`; and a slot that is not where YAML
    sees a whole value leaves a skeleton whose marker is not a whole value: `_structure`
    refuses it.
    """
    n = len(b)
    space = b == 32
    after_colon = np.flatnonzero((b[:-1] == 58) & space[1:]) + 2
    dash = np.flatnonzero((b[:-2] == 45) & space[1:-1] & (b[2:] == 91))
    newline = np.append(np.flatnonzero(b == 10), n)
    if len(dash):  # '- [' with only spaces before it on its line
        line = np.searchsorted(newline, dash)
        line_start = np.where(line > 0, newline[line - 1] + 1, 0)
        blanks = np.concatenate(([0], np.cumsum(~space, dtype=np.int32)))
        dash = dash[blanks[dash] == blanks[line_start]] + 2
    s = np.sort(np.concatenate((after_colon, dash)))
    if len(s) == 0 or s[-1] >= n:
        raise _Bail
    close = np.append(np.flatnonzero(b == 93) + 1, n + 1)
    comma = np.append(np.flatnonzero((b[:-1] == 44) & space[1:]), n)
    brace = np.append(np.flatnonzero(b == 125), n)
    plain_end = np.minimum(newline[np.searchsorted(newline, s)],
                           np.minimum(comma[np.searchsorted(comma, s)],
                                      brace[np.searchsorted(brace, s)]))
    e = np.where(b[s] == 91, close[np.searchsorted(close, s)], plain_end)
    if np.any(e <= s) or np.any(e > n) or np.any(e[:-1] > s[1:] - 2):
        raise _Bail
    return s, e


def _gather(b: np.ndarray, s: np.ndarray, e: np.ndarray, sep: int) -> bytes:
    """The values b[s[i]:e[i]] (none empty), joined by the byte `sep`."""
    lengths = e - s
    out_start = np.cumsum(lengths + 1) - (lengths + 1)  # where value i goes
    total = int(out_start[-1] + lengths[-1])
    out = np.full(total, sep, dtype=np.uint8)
    filled = np.ones(total, dtype=bool)
    filled[out_start[1:] - 1] = False  # the separators
    to = np.flatnonzero(filled)
    out[to] = b[to + np.repeat(s - out_start, lengths)]
    return out.tobytes()


def _joined(chunks: list[Any]) -> Any:
    """One column from its chunks: all arrays of one width, or all lists of names."""
    if all(isinstance(c, list) for c in chunks):
        return [name for c in chunks for name in c]
    try:
        return np.concatenate(chunks) if len(chunks) > 1 else chunks[0]
    except (ValueError, TypeError):  # names in one chunk, numbers in another; widths
        raise _Bail from None


def _structure(skeleton: str, file: str) -> tuple[dict[tuple[Any, ...], int], int]:
    """key path -> slot number of one item layout, parsed by the located loader; and the
    item's count of keys and values (a slot as one)."""
    count = iter(range(1 << 30))
    src = "- " + re.sub("\x00", lambda _: f"__mbody_slot_{next(count)}__", skeleton)
    doc = load_text(src, file)  # a ModelError: the located path reports it
    data = doc.data
    if not (isinstance(data, list) and len(data) == 1 and isinstance(data[0], dict)):
        raise _Bail
    out: dict[tuple[Any, ...], int] = {}

    def walk(path: tuple[Any, ...], value: Any) -> None:
        if isinstance(value, dict) and value:
            for k, v in value.items():
                walk((*path, k), v)
        elif isinstance(value, list) and value:
            for i, v in enumerate(value):
                walk((*path, i), v)
        else:
            m = _SLOT_NAME.fullmatch(value) if isinstance(value, str) else None
            if m is None:  # a value without a slot of its own (a multi-line value...)
                raise _Bail
            out[path] = int(m.group(1))

    walk((), data[0])
    if sorted(out.values()) != list(range(next(count))):
        raise _Bail  # a slot swallowed by a multi-line value
    return out, len(doc.marks) + len(doc.key_marks) - 1  # not the list around it


def _column(b: np.ndarray, s: np.ndarray, e: np.ndarray) -> Any:
    """The values b[s[i]:e[i]] of one slot over many items, typed as the located loader
    types them: (k, L) floats for flow lists of L numbers, (k,) floats for numbers, else
    a list of names."""
    n = len(s)
    first = int(b[s[0]])
    if first == ord("["):
        data = _gather(b, s, e, 1)
        # each value is one flat list: '[...]' joined by '\x01', no bracket inside
        if not (data.count(b"[") == n == data.count(b"]") and data[-1:] == b"]"
                and data.count(b"]\x01[") == n - 1
                and data.count(b" ") == data.count(b", ")):  # separators as dumped
            raise _Bail
        width = 0 if e[0] - s[0] == 2 else int(np.count_nonzero(b[s[0]:e[0]] == 44)) + 1
        # each list's length, from its commas: one flat list of numbers for json (nested
        # lists would make a container per item for the garbage collector to trace)
        c = np.frombuffer(data, dtype=np.uint8)
        commas = np.add.reduceat((c == ord(",")).view(np.uint8), np.flatnonzero(c == ord("[")),
                                 dtype=np.intp)
        if np.any(commas != max(width - 1, 0)):
            raise _Bail
        flat = _parse(data, b", []\x01", b"[" + data[1:-1].replace(b"]\x01[", b",") + b"]",
                      n * width)
        return flat.reshape(n, width)
    if chr(first) in "0123456789-":
        data = _gather(b, s, e, ord(","))
        if data.count(b",") != n - 1:
            raise _Bail
        return _parse(data, b",", b"[" + data + b"]", n)
    joined = _gather(b, s, e, ord("\n")).decode("ascii")
    names = joined.split("\n")
    if len(names) == n and _NAMES.fullmatch(joined) and _SPECIAL.isdisjoint(names):
        return names
    raise _Bail


def _parse(data: bytes, separators: bytes, as_json: bytes, n: int) -> np.ndarray:
    """The `n` numbers of a column, checked (see `_NUMBER_BYTES`) and parsed by json."""
    if data.translate(None, _NUMBER_BYTES + separators):
        raise _Bail  # text, quotes, true/null...: not numbers only
    digits = data.translate(_EXPONENT_DIGITS)
    if b"e000" in digits or b"e-000" in digits or _ZEROS in data:
        raise _Bail
    try:
        values = np.array(json.loads(as_json), dtype=float)
    except (ValueError, OverflowError):  # not JSON numbers, ragged lists, huge integers
        raise _Bail from None
    if len(values) != n or not np.all(np.abs(values) <= MAX_MAGNITUDE):
        raise _Bail
    return values


# -- checking ------------------------------------------------------------------------------
def _numbers(group: _Group, path: tuple[Any, ...], width: int | None) -> np.ndarray:
    """A column of `width` numbers per item (None: one number per item)."""
    col = group.columns.get(path)
    if not isinstance(col, np.ndarray) or (col.ndim == 1) != (width is None) \
            or (width is not None and col.shape[1] != width):
        raise _Bail
    return col


def _names(group: _Group, path: tuple[Any, ...]) -> list[str]:
    col = group.columns.get(path)
    if not isinstance(col, list):
        raise _Bail
    return col


def _pad3(v: np.ndarray) -> np.ndarray:
    out = np.zeros((len(v), 3))
    out[:, :v.shape[1]] = v
    return out


def _bodies(c: Checker, groups: list[_Group]) -> BodyTable:
    """The body table; `_Bail` unless every body passes every check of `validate`."""
    n = sum(len(g.index) for g in groups)
    dim = c.dim
    planar = dim == cv.PLANAR
    names: list[str] = [""] * n
    mass = np.empty(n)
    J = np.zeros((n, 3, 3))
    pos = np.zeros((n, 3))
    vel = np.zeros((n, 3))
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    omega = np.zeros((n, 3))
    allowed = ({("name",), ("mass",), ("inertia",), ("position",), ("velocity",), ("angle",),
                ("angular_velocity",)} if planar else
               {("name",), ("mass",), ("inertia",), ("inertia", 0), ("inertia", 1),
                ("inertia", 2), ("position",), ("velocity",), ("orientation", "quaternion"),
                ("angular_velocity",)})
    for g in groups:
        cols = g.columns
        if not set(cols) <= allowed:
            raise _Bail
        i = g.index
        for k, nm in zip(i.tolist(), _names(g, ("name",)), strict=True):
            names[k] = nm
        m = _numbers(g, ("mass",), None)
        if not np.all(m >= MIN_MAGNITUDE):  # positive, and 1/m a normal double
            raise _Bail
        mass[i] = m
        J[i] = _inertia(g, planar)
        if ("position",) in cols:
            pos[i] = _pad3(_numbers(g, ("position",), dim))
        if ("velocity",) in cols:
            vel[i] = _pad3(_numbers(g, ("velocity",), dim))
        if planar:
            if ("angle",) in cols:
                th = _numbers(g, ("angle",), None)
                if not np.all(np.abs(th) <= MAX_ANGLE):
                    raise _Bail
                # math.cos, as the located path: numpy's may differ in the last bit
                q[i, 0] = [math.cos(t / 2) for t in th.tolist()]
                q[i, 3] = [math.sin(t / 2) for t in th.tolist()]
            if ("angular_velocity",) in cols:
                omega[i, 2] = _numbers(g, ("angular_velocity",), None)
        else:
            if ("orientation", "quaternion") in cols:
                qq = _numbers(g, ("orientation", "quaternion"), 4)
                norm = quat_norm(qq)
                if not np.all(np.abs(norm - 1) <= 1e-6):  # else a warning, or zero
                    raise _Bail
                q[i] = qq / norm[:, None]
            if ("angular_velocity",) in cols:
                omega[i] = _numbers(g, ("angular_velocity",), 3)
    index = dict(zip(names, range(n), strict=True))
    if len(index) != n or cv.GROUND in index:
        raise _Bail  # a duplicate name, or 'ground'
    c.body_names.update(index)
    return BodyTable(tuple(names), mass, J, pos, q, vel, omega, np.zeros(n, dtype=bool),
                     [None] * n, [None] * n)


def _inertia(g: _Group, planar: bool) -> np.ndarray:
    """(k, 3, 3) inertia tensors of a group, checked as `validate._inertia` and
    `_reciprocable` check them (with a margin: near a limit, the located path decides)."""
    cols = g.columns
    k = len(g.index)
    J = np.zeros((k, 3, 3))
    if planar:
        I = _numbers(g, ("inertia",), None)
        if not np.all(I >= 1e10 * MIN_MAGNITUDE):
            raise _Bail
        J[:, 0, 0] = I / 2
        J[:, 1, 1] = I / 2
        J[:, 2, 2] = I
        return J
    if ("inertia",) in cols:
        v = _numbers(g, ("inertia",), 3)
        J[:, [0, 1, 2], [0, 1, 2]] = v
        principal = v
    else:
        for r in range(3):
            J[:, r] = _numbers(g, ("inertia", r), 3)
        scale = np.abs(J).max(axis=(1, 2))
        scale[scale == 0] = 1.0
        if not np.all(np.abs(J - J.transpose(0, 2, 1)).max(axis=(1, 2)) <= 0.5 * _TOL * scale):
            raise _Bail
        principal = np.linalg.eigvalsh(J)
        # eigvalsh over a stack may differ from one at a time in the last bits (relative
        # to the largest moment): near-singular tensors are left to the located path
        if not np.all(principal[:, 0] >= 1e-9 * principal[:, 2]):
            raise _Bail
    if not np.all(principal >= 1e10 * MIN_MAGNITUDE):  # positive definite, reciprocable
        raise _Bail
    a, b, d = np.sort(principal, axis=1).T
    if not np.all(a + b >= d * (1 - 0.5 * _TOL)):  # triangle inequality, with a margin
        raise _Bail
    return J


LOAD_PATHS = {
    "force": {("name",), ("type",), ("body",), ("force",), ("at",), ("frame",)},
    "torque": {("name",), ("type",), ("body",), ("torque",), ("frame",)},
}


def _loads(c: Checker, groups: list[_Group]) -> LoadTable:
    """Force and torque loads with constant components; `_Bail` for anything else."""
    n = sum(len(g.index) for g in groups)
    names_all: list[str] = [""] * n
    types: list[str] = [""] * n
    bodies: list[str] = [""] * n
    frames_all: list[str] = [""] * n
    vector = np.zeros((n, 3))
    at_all = np.zeros((n, 3))
    dim = c.dim
    known = c.body_names
    seen: set[str] = set()
    for g in groups:
        cols = g.columns
        kind = "force" if ("force",) in cols else "torque"
        if not set(cols) <= LOAD_PATHS[kind] or ("name",) not in cols:
            raise _Bail  # a generated name depends on the others: the located path
        if any(t != kind for t in _names(g, ("type",))):
            raise _Bail
        names = _names(g, ("name",))
        on = _names(g, ("body",))
        if not all(b in known for b in on):
            raise _Bail
        seen.update(names)
        frames = _names(g, ("frame",)) if ("frame",) in cols else ["world"] * len(names)
        if not set(frames) <= set(FRAMES):
            raise _Bail
        if kind == "force":
            vec = _pad3(_numbers(g, ("force",), dim))
            at = _pad3(_numbers(g, ("at",), dim)) if ("at",) in cols else np.zeros_like(vec)
        else:
            vec = np.zeros((len(names), 3))
            if dim == cv.PLANAR:
                vec[:, 2] = _numbers(g, ("torque",), None)
            else:
                vec[:] = _numbers(g, ("torque",), 3)
            at = np.zeros_like(vec)
        for k, nm, b, fr in zip(g.index.tolist(), names, on, frames, strict=True):
            names_all[k], types[k], bodies[k], frames_all[k] = nm, kind, b, fr
        vector[g.index] = vec
        at_all[g.index] = at
    if len(seen) != n:
        raise _Bail  # a duplicate load name
    return LoadTable(names_all, types, bodies, frames_all, vector, at_all)



def _joints(c: Checker, groups: list[_Group]) -> list[JointSpec]:
    """Joints between bodies (no particles in a fast-path model), checked as
    `validate._joints` checks them; `_Bail` for anything it would refuse."""
    n = sum(len(g.index) for g in groups)
    out: list[JointSpec | None] = [None] * n
    dim = c.dim
    types = cv.JOINT_COMPONENTS[dim]
    known = c.body_names
    seen: set[str] = set()
    for g in groups:
        cols = g.columns
        if not set(cols) <= {("name",), ("type",), ("parent",), ("child",), ("at",),
                             ("axis",), ("axis2",)}:
            raise _Bail
        names, kinds = _names(g, ("name",)), _names(g, ("type",))
        parents, children = _names(g, ("parent",)), _names(g, ("child",))
        if not (set(kinds) <= set(types) and all(b in known for b in children)
                and all(b in known or b == cv.GROUND for b in parents)
                and all(a != b for a, b in zip(parents, children, strict=True))):
            raise _Bail
        seen.update(names)
        at = _pad3(_numbers(g, ("at",), dim))
        axes: list[np.ndarray | None] = [None] * len(names)
        if ("axis",) in cols:
            axis = _unit(_pad3(_numbers(g, ("axis",), dim)))
            axes = list(axis)
        elif not set(kinds).isdisjoint(cv.AXIS_REQUIRED[dim]):
            raise _Bail
        axes2: list[np.ndarray | None] = [None] * len(names)
        if ("axis2",) in cols or "universal" in kinds:
            if not (("axis2",) in cols and ("axis",) in cols and set(kinds) == {"universal"}):
                raise _Bail
            axis2 = _unit(_pad3(_numbers(g, ("axis2",), dim)))
            if not np.all(np.abs(np.einsum("ij,ij->i", axis, axis2)) <= 0.5e-6):
                raise _Bail  # perpendicular (with a margin: near the limit, the located path)
            axes2 = list(axis2)
        for k, nm, typ, pa, ch, a, ax, ax2 in zip(g.index.tolist(), names, kinds, parents,
                                                 children, at, axes, axes2, strict=True):
            out[k] = JointSpec(nm, typ, pa, ch, a, ax, ax2)
            c.joint_types.setdefault(nm, typ)
    if len(seen) != n:
        raise _Bail  # a duplicate joint name
    return [j for j in out if j is not None]


def _unit(v: np.ndarray) -> np.ndarray:
    """Rows of `v` normalised as `validate._axis` normalises one; `_Bail` for a zero one."""
    norm = vec_norm(v)
    if not np.all(norm >= 1e-12):
        raise _Bail
    return v / norm[:, None]
