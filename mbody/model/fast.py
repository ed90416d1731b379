"""A fast path for large, regular model files: read in bulk, checked with numpy.

Reading a file through PyYAML's events costs about a microsecond per event from Python,
and a 10 000-body model has some 500 000 of them. Files that large are nearly always
written by a program (``yaml.dump``), so their ``bodies:``, ``loads:`` and ``joints:``
lists repeat one layout per item with different numbers. This module reads such a list
in bulk, a chunk of whole items (`CHUNK`) at a time:

1. Each list is cut out of the text; every value written at the end of a line (after
   ``key: `` or ``- [``, or in a one-line flow mapping) is a *slot*, replaced by a
   marker. What is left (the item's *skeleton*) is usually the same for every item.
2. Each distinct skeleton is parsed once by the located loader (`load_text`), with its
   slots numbered, which gives the item's structure: which key path each slot fills.
3. Each slot is a flow list of numbers, a number or a name; its kind, and a list's
   length, must be the same in every item of a layout. All the numbers of a chunk are
   gathered with numpy masks into one text (each followed by a comma), checked byte by
   byte against the decimal forms both paths read identically and parsed by one
   ``json.loads``; all its names are gathered likewise and split once. Columns (every
   body's ``position``...) are cut from those; names of bodies become body indices.
4. The columns are checked with numpy against the same rules as `validate` (the rest of
   the file, small, goes through `validate`'s own functions), and the tables of the
   `Spec` are filled: `BodyTable`, `LoadTable`, `JointSpecTable`.

Anything else (a comment or an anchor on a value line, a tab, a quoted or non-ASCII
value, a flow mapping, a number written ``1_000`` or ``.5``, a shape, an Euler angle, a
string angle, a spring, more than `MAX_TEMPLATES` layouts) and any value that `validate`
would refuse or warn about gives None: the caller then runs the located path on the
whole text, which reports every problem with its line and column. So this path never
accepts a file the located path refuses, and it builds the same `Model` (tested:
tests/test_fast.py compares both on generated and perturbed files).
"""

from __future__ import annotations

import bisect
import json
import math
import re
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody import joint_types
from mbody.errors import ModelError
from mbody.model.checks import (
    _TOL,
    BARE_ANGLE_LIMIT,
    MAX_MAGNITUDE,
    MIN_MAGNITUDE,
    MIN_NORM,
    PERPENDICULAR_TOL,
    UNIT_TOL,
    Checker,
    asymmetry,
    quat_norm,
    realisable,
    vec_norm,
)
from mbody.model.loader import load_text, value_limit
from mbody.model.validate import (
    BODY_KEYS,
    FRAMES,
    JOINT_KEYS,
    LOAD_KEYS,
    PARAM_KEYS,
    BodyTable,
    JointSpecTable,
    LoadTable,
    Spec,
    far_joint_points,
    header,
    reach_of_bodies,
    rest,
)

MIN_BYTES = 64 * 1024
"""Smaller texts go straight to the located path: there is nothing to gain."""
MAX_TEMPLATES = 16
"""Most distinct item layouts in one list; more means a hand-written file."""
CHUNK = 1 << 17
"""Characters of a list read at a time (then on to the end of an item): a chunk's
temporary arrays, some 6 bytes per character, stay small against the file."""

_PLACEHOLDER = "__mbody_fast_"
_NUMBER_BYTES = b"0123456789.eE+-"
"""What the numbers may hold besides their separators: json.loads then checks each
number against JSON's grammar, whose numbers YAML's core schema reads the same way (an
integer as int, anything with '.' or an exponent as float, through the same correctly
rounded conversion). Forms JSON refuses ('+1', '.5', '1.', '010', '1_000') go to the
located path, as do exponents of three digits (which may underflow to 0, or overflow;
YAML keeps those as unrepresentable) and magnitudes beyond MAX_MAGNITUDE."""
_ZEROS = b"0" * 200
"""A run of zeros this long goes to the located path: with an exponent of two digits at
most, a nonzero number underflows to 0 only after some 224 zeros ("0.000...1e-99"), which
YAML keeps as unrepresentable; repr never writes more than 4."""
_NAMES = re.compile(r"[A-Za-z][A-Za-z0-9_-]*(?:\n[A-Za-z][A-Za-z0-9_-]*)*")
_SPECIAL = frozenset(("null", "Null", "NULL", "true", "True", "TRUE", "false", "False",
                      "FALSE"))
"""Names the pattern above lets through that YAML reads as null or a boolean."""
_SECTION_END = re.compile(r"\n(?=[^- ])")
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
    # the lines at column 0 that neither start nor continue a list item: one pass
    tops = [0, *(m.start() + 1 for m in _SECTION_END.finditer(text)), len(text)]
    heads: dict[str, list[int]] = {}
    for at in tops[:-1]:
        for key in ("bodies", "loads", "joints"):
            if text.startswith(f"{key}:\n- ", at):
                heads.setdefault(key, []).append(at)
    found = []
    for key, where in heads.items():
        if len(where) > 1:
            continue  # twice: then the located loader names both lines
        at = where[0]
        start = at + len(key) + 2  # the list's first '- '
        found.append((at, start, tops[bisect.bisect_right(tops, start)], key))
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
    if any(data.get(key) != f"{_PLACEHOLDER}{key}__" for key in sections):
        raise _Bail  # the cut was not where the located reader sees the list
    limit = value_limit(len(text))
    table, point, joints = None, None, None
    # one list at a time, into its table, before the next is read (its columns of names
    # and numbers are the largest thing made); bodies first: the others name them
    for key in ("bodies", "loads", "joints"):
        if key not in sections:
            continue
        groups, count = _read_list(text, *sections[key], file, _conversions(key, c))
        values += count
        if values > limit:
            raise _Bail
        if key == "bodies":
            table = _bodies(c, groups)
        elif key == "loads":
            point = _loads(c, groups)
        else:
            joints = _joints(c, groups)
        del groups
    assert table is not None
    # a list not cut out above (absent, or written another way) goes through validate
    loads, joint_list, reactions, expressions, drivers = rest(
        c, [], [] if point else None, [] if joints is not None else None)
    if c.issues or c.warnings:
        raise _Bail  # warnings need their lines: the located path gives them
    if joints is not None and np.any(far_joint_points(
            joints.at, joints.parent, joints.child, table.position,
            reach_of_bodies(table.mass, table.inertia, c.dim == cv.PLANAR))):
        raise _Bail  # the located path warns (validate._far_joint_points)
    return Spec(name, file, c.dim, gravity, [], loads, joint_list, reactions, description,
                [], expressions, table, point, joints, drivers)


# -- reading a list in bulk ---------------------------------------------------------------
@dataclass
class _Group:
    """The items of a list that share one layout: their indices and each slot's column.

    Column values: (k, L) floats for a flow list of L numbers, (k,) floats for a number,
    a list of str for a name.
    """

    index: np.ndarray
    columns: dict[tuple[Any, ...], Any]


Convert = Callable[[list[str]], Any]
"""What a column of names becomes, chunk by chunk (see `_read_list`)."""


def _conversions(key: str, c: Checker) -> dict[tuple[Any, ...], Convert]:
    """The conversions of the name columns of the list `key`: references to bodies become
    body indices (ground -1), and types and frames one string per distinct name; a name
    neither would accept is `_Bail`."""
    known = c.body_names
    if key == "loads":
        return {("body",): _references(known, False),
                ("type",): _canonical(LOAD_KEYS), ("frame",): _canonical(FRAMES)}
    if key == "joints":
        return {("parent",): _references(known, True), ("child",): _references(known, False),
                ("type",): _canonical(FAST_TYPES[c.dim])}
    return {}


def _canonical(allowed: Iterable[str]) -> Convert:
    table = {x: x for x in allowed}

    def convert(names: list[str]) -> list[str]:
        try:
            return [table[x] for x in names]
        except KeyError:
            raise _Bail from None

    return convert


def _references(known: dict[str, int], ground: bool) -> Convert:
    def convert(names: list[str]) -> np.ndarray:
        index = np.fromiter((known.get(x, -1) for x in names), dtype=np.intp,
                            count=len(names))
        if not all(ground and names[i] == cv.GROUND for i in np.flatnonzero(index < 0)):
            raise _Bail  # neither a body nor (where allowed) ground
        return index

    return convert


def _read_list(text: str, start: int, end: int, file: str,
               convert: dict[tuple[Any, ...], Convert] | None = None
               ) -> tuple[list[_Group], int]:
    """The items of the block list text[start:end] (each starts with '- ' at column 0),
    grouped by layout, with every slot typed a column at a time; and how many keys and
    values they hold beyond the list itself (as the located reader counts them).

    The list is read a chunk of at most about `CHUNK` characters at a time (a 64th of
    the text, and at least a quarter of `CHUNK`). In each chunk, one
    pass of numpy masks gives the skeletons, every number of every slot in order (parsed
    by one json call) and every name (split once); no string is made per number. A
    column of names with a path in `convert` is converted chunk by chunk (to body
    indices, or to one string per distinct name), so that its strings do not pile up.
    """
    layouts: dict[str, int] = {}
    found: list[_Layout] = []
    pieces: list[dict[tuple[Any, ...], list[Any]]] = []  # per layout, per path: chunks
    rows: list[list[np.ndarray]] = []  # per layout: item indices, per chunk
    item = 0
    pos = start
    # a smaller chunk for a smaller file: its temporary arrays stay small beside the file
    chunk_size = min(CHUNK, max(CHUNK // 4, len(text) // 64))
    while pos < end:
        stop = (end if end - pos <= chunk_size
                else text.find("\n- ", pos + chunk_size, end) + 1 or end)
        data = text[pos:stop].encode("ascii")
        if data.translate(None, _PRINTABLE):
            raise _Bail  # a tab, a carriage return, a control character
        if not data.endswith(b"\n"):
            data += b"\n"  # every value ends before a byte of its own
        chunk = _Chunk(np.frombuffer(data, dtype=np.uint8))
        skeletons = chunk.skeletons()
        for sk in set(skeletons).difference(layouts):
            if len(layouts) >= MAX_TEMPLATES:
                raise _Bail
            layouts[sk] = len(layouts)
            paths, count = _structure(sk, file)
            found.append(_Layout(paths, count))
            pieces.append({path: [] for path in paths})
            rows.append([])
        ids = np.fromiter(map(layouts.__getitem__, skeletons), dtype=np.intp,
                          count=len(skeletons))
        for k, mine, columns in chunk.columns(ids, found):
            for path, column in columns.items():
                if convert and path in convert and isinstance(column, list):
                    column = convert[path](column)
                pieces[k][path].append(column)
            rows[k].append(mine + item)
        item += len(skeletons)
        pos = stop
        del chunk, data, skeletons, ids  # before the next chunk is cut
    groups = []
    for k, r in enumerate(rows):
        columns = {}
        for path in list(pieces[k]):  # each column's chunks dropped once joined
            columns[path] = _joined(pieces[k].pop(path))
        groups.append(_Group(np.concatenate(r) if r else np.zeros(0, dtype=np.intp),
                             columns))
    count = sum(len(g.index) * found[k].values for k, g in enumerate(groups))
    return groups, count


class _Layout:
    """One item layout: which key path each slot fills; its slots' kinds and widths (from
    the first item read with it: every other item must match them)."""

    def __init__(self, paths: dict[tuple[Any, ...], int], nodes: int):
        self.paths = paths
        self.nodes = nodes
        self.slots = len(paths)
        self.kind: np.ndarray | None = None  # per slot: NUMBER, LIST or NAME
        self.width: np.ndarray | None = None  # per slot: numbers it holds (a name: 0)

    @property
    def values(self) -> int:
        """Keys and values of one item as the located reader counts them (a flow list
        is one value and each of its items one more)."""
        assert self.kind is not None and self.width is not None
        return self.nodes + int(self.width[self.kind == _LIST].sum())


_NUMBER, _LIST, _NAME = 0, 1, 2
_STARTS_NUMBER = np.zeros(256, dtype=bool)
_STARTS_NUMBER[list(b"0123456789-")] = True


class _Chunk:
    """One chunk of a list (whole items) as bytes, and its slots (see `_slots`)."""

    def __init__(self, b: np.ndarray):
        self.b = b
        s, e, commas = _slots(b)
        self.s, self.e = s, e
        first = b[s]
        kind = np.where(first == ord("["), _LIST, np.where(_STARTS_NUMBER[first], _NUMBER,
                                                            _NAME))
        self.kind = kind
        listed = kind == _LIST
        # Each value's bytes, as a level: 1 for the numbers, 2 for the names, 0 for the
        # rest (the skeleton). A list keeps what is between its brackets and its ']'; a
        # number or a name keeps the byte that ends it: those become the separators.
        lo = np.where(listed, s + 1, s)
        hi = np.where(listed, e, e + 1)
        step = np.where(kind == _NAME, 2, 1).astype(np.int8)
        marks = np.zeros(len(b) + 1, dtype=np.int8)
        marks[lo] = step  # all distinct: slots do not touch (see _slots)
        marks[hi] = -step
        self.level: np.ndarray | None = np.cumsum(marks[:-1], dtype=np.int8)
        inside = np.searchsorted(commas, e) - np.searchsorted(commas, s)
        if np.any(inside[kind == _NUMBER]) or np.any(e[listed] - s[listed] < 3):
            raise _Bail  # '1,5' (text in YAML), or an empty list
        self.width = np.where(listed, inside + 1, np.where(kind == _NUMBER, 1, 0))
        self.separated: np.ndarray | None = None

    def skeletons(self) -> list[str]:
        """Each item's text with every value replaced by one NUL, without its leading
        '- ' and the newline that ends it."""
        assert self.level is not None
        keep = self.level == 0
        keep[self.s] = True
        ends = self.e[self.kind != _LIST]
        keep[ends] = True
        skeleton = self.b.copy()
        skeleton[self.s] = 0
        body = skeleton[keep].tobytes().decode("ascii")
        return body[2:-1].split("\n- ")

    def columns(self, ids: np.ndarray, layouts: list[_Layout]
                ) -> Iterator[tuple[int, np.ndarray, dict[tuple[Any, ...], Any]]]:
        """Per layout in the chunk: its items (indices in the chunk) and each slot's
        column: (k, L) floats for flow lists of L numbers, (k,) floats for numbers, a
        list of names; `_Bail` when an item's slots differ in kind or width from its
        layout's."""
        kind, width = self.kind, self.width
        slots = np.array([lay.slots for lay in layouts], dtype=np.intp)[ids]
        first = np.cumsum(slots) - slots  # each item's first slot
        if first[-1] + slots[-1] != len(kind):
            raise _Bail
        used = np.flatnonzero(np.bincount(ids, minlength=len(layouts))).tolist()
        for k in used:
            lay = layouts[k]
            mine = np.flatnonzero(ids == k)
            at = first[mine][:, None] + np.arange(lay.slots)
            if lay.kind is None or lay.width is None:
                lay.kind, lay.width = kind[at[0]], width[at[0]]
            if not (np.array_equal(kind[at], np.broadcast_to(lay.kind, at.shape))
                    and np.array_equal(width[at], np.broadcast_to(lay.width, at.shape))):
                raise _Bail  # a number where another item has a name, lists of two lengths
        per_item = np.array([int(lay.width.sum()) if lay.width is not None else 0
                             for lay in layouts], dtype=np.intp)[ids]
        numbers = self.numbers(int(per_item.sum()))
        number_at = np.cumsum(per_item) - per_item  # each item's first number
        named = np.array([int(np.count_nonzero(lay.kind == _NAME)) if lay.kind is not None
                          else 0 for lay in layouts], dtype=np.intp)[ids]
        names = self.names(int(named.sum()))
        name_at = np.cumsum(named) - named
        self.level = self.separated = None  # the bytes are read: let them go
        single = len(used) == 1
        for k in used:
            lay = layouts[k]
            assert lay.kind is not None and lay.width is not None
            mine = np.flatnonzero(ids == k)
            offset = np.cumsum(lay.width) - lay.width  # each slot's first number
            name_index = np.cumsum(lay.kind == _NAME) - 1
            columns: dict[tuple[Any, ...], Any] = {}
            for path, slot in lay.paths.items():
                if lay.kind[slot] == _NAME:
                    if single:
                        columns[path] = names[int(name_index[slot])::int(named[0])]
                    else:
                        columns[path] = [names[i] for i in
                                         (name_at[mine] + name_index[slot]).tolist()]
                    continue
                w = int(lay.width[slot])
                where = number_at[mine] + offset[slot]
                if lay.kind[slot] == _LIST:
                    columns[path] = numbers[where[:, None] + np.arange(w)]
                else:
                    columns[path] = numbers[where]
            yield k, mine, columns

    def _stream(self, level: int, n: int) -> np.ndarray:
        """The bytes of level `level` (see `__init__`) in order, each value followed by
        its separator, with one byte to spare in front."""
        if self.separated is None:
            separated = self.b.copy()
            kind, e = self.kind, self.e
            separated[np.where(kind == _LIST, e - 1, e)[kind != _NAME]] = ord(",")
            separated[e[kind == _NAME]] = ord("\n")
            self.separated = separated
        assert self.level is not None
        mask = self.level == level
        out = np.empty(int(np.count_nonzero(mask)) + 1, dtype=np.uint8)
        np.compress(mask, self.separated, out=out[1:])
        return out

    def numbers(self, n: int) -> np.ndarray:
        """Every number of the chunk, slot after slot, checked (see `_NUMBER_BYTES`) and
        parsed by json at once."""
        if n == 0:
            return np.zeros(0)
        out = self._stream(1, n)
        out[0], out[-1] = ord("["), ord("]")  # the last value's separator
        if np.count_nonzero((out == ord("[")) | (out == ord("]"))) != 2:
            raise _Bail  # a list in a list ('[1, [2]]'): one flat list of numbers only
        exponent = np.flatnonzero((out == ord("e")) | (out == ord("E")))
        if len(exponent):  # three digits (after a sign) may underflow to 0 or overflow
            digits = exponent + 1 + ((out[exponent + 1] == ord("-"))
                                     | (out[exponent + 1] == ord("+")))
            long = np.ones(len(digits), dtype=bool)
            for k in range(3):
                at = np.minimum(digits + k, len(out) - 1)
                long &= (out[at] >= ord("0")) & (out[at] <= ord("9"))
            if long.any():
                raise _Bail
        data = out.tobytes()
        if data.translate(None, _NUMBER_BYTES + b", []") or _ZEROS in data:
            raise _Bail  # text, quotes, true/null...: not numbers only; a long run of 0
        try:
            values = np.array(json.loads(data), dtype=float)
        except (ValueError, OverflowError, TypeError):  # not JSON numbers, huge integers
            raise _Bail from None
        if values.shape != (n,) or not np.all(np.abs(values) <= MAX_MAGNITUDE):
            raise _Bail
        return values

    def names(self, n: int) -> list[str]:
        """Every name of the chunk, slot after slot (names as `_NAMES`, not read by YAML
        as anything else)."""
        if n == 0:
            return []
        joined = self._stream(2, n)[1:-1].tobytes().decode("ascii")
        names = joined.split("\n")
        if len(names) != n or not _NAMES.fullmatch(joined) or not _SPECIAL.isdisjoint(names):
            raise _Bail
        return names


def _slots(b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start and end (exclusive) of every value in the text `b` (bytes, ending with a
    newline), in order; and where its commas are.

    A value follows ': ' (in a block mapping, or in a one-line flow mapping as yaml.dump
    writes a mapping of scalars), or '- ' before '[' on a line indented with spaces
    only. It is a flow list ('[' to the next ']'), or it runs to the end of the line, the
    next ', ' or the next '}'. Anything odd (a value that would swallow the next, an
    empty one, a list that does not close) is `_Bail`; and a slot that is not where YAML
    sees a whole value leaves a skeleton whose marker is not a whole value: `_structure`
    refuses it.
    """
    n = len(b)
    # one pass over the bytes finds every byte that matters; each kind is picked from those
    pos = np.flatnonzero((b == 58) | (b == 45) | (b == 10) | (b == 93) | (b == 44)
                         | (b == 125))
    at = b[pos]
    colon = pos[at == 58]
    after_colon = colon[b[colon + 1] == 32] + 2  # b ends with a newline: colon + 1 < n
    dash = pos[at == 45]
    dash = dash[dash < n - 2]
    dash = dash[(b[dash + 1] == 32) & (b[dash + 2] == 91)]
    newline = np.append(pos[at == 10], n)
    if len(dash):  # '- [' with only spaces before it on its line
        line = np.searchsorted(newline, dash)
        line_start = np.where(line > 0, newline[line - 1] + 1, 0)
        indent = dash - line_start
        before = np.arange(int(indent.sum())) + np.repeat(line_start - (np.cumsum(indent)
                                                                        - indent), indent)
        odd = np.repeat(np.arange(len(dash)), indent)[b[before] != 32]
        keep = np.ones(len(dash), dtype=bool)
        keep[odd] = False
        dash = dash[keep] + 2
    s = np.sort(np.concatenate((after_colon, dash)))
    if len(s) == 0 or s[-1] >= n:
        raise _Bail
    close = np.append(pos[at == 93] + 1, n + 1)
    commas = pos[at == 44]
    comma = np.append(commas[b[commas + 1] == 32], n)
    brace = np.append(pos[at == 125], n)
    plain_end = np.minimum(newline[np.searchsorted(newline, s)],
                           np.minimum(comma[np.searchsorted(comma, s)],
                                      brace[np.searchsorted(brace, s)]))
    e = np.where(b[s] == 91, close[np.searchsorted(close, s)], plain_end)
    if np.any(e <= s) or np.any(e > n) or np.any(e[:-1] > s[1:] - 2):
        raise _Bail
    return s, e, commas


def _joined(chunks: list[Any]) -> Any:
    """One column from its chunks (emptying `chunks`, each dropped once copied): all
    arrays of one type and width, or all lists of names."""
    if all(isinstance(c, list) for c in chunks):
        return [name for c in chunks for name in c]
    if len(chunks) == 1:
        return chunks.pop()
    if not all(isinstance(c, np.ndarray) for c in chunks) or \
            len({(c.dtype, c.shape[1:]) for c in chunks}) != 1:
        raise _Bail  # names in one chunk, numbers in another; lists of two lengths
    out = np.empty((sum(len(c) for c in chunks), *chunks[0].shape[1:]), dtype=chunks[0].dtype)
    at = 0
    chunks.reverse()
    while chunks:
        c = chunks.pop()
        out[at:at + len(c)] = c
        at += len(c)
    return out


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


# -- checking ------------------------------------------------------------------------------
def _numbers(group: _Group, path: tuple[Any, ...], width: int | None) -> np.ndarray:
    """A column of `width` numbers per item (None: one number per item), taken from the
    group (each column is read once: its memory goes as soon as it is used)."""
    col = group.columns.pop(path, None)
    if not isinstance(col, np.ndarray) or (col.ndim == 1) != (width is None) \
            or (width is not None and col.shape[1] != width):
        raise _Bail
    return col


def _bodies_of(group: _Group, path: tuple[Any, ...]) -> np.ndarray:
    """A column of references to bodies, as body indices (ground -1), taken."""
    col = group.columns.pop(path, None)
    if not (isinstance(col, np.ndarray) and col.dtype == np.intp and col.ndim == 1):
        raise _Bail
    return col


def _names(group: _Group, path: tuple[Any, ...]) -> list[str]:
    """A column of names, taken from the group."""
    col = group.columns.pop(path, None)
    if not isinstance(col, list):
        raise _Bail
    return col


def _pad3(v: np.ndarray) -> np.ndarray:
    """Rows of 2 or 3 numbers as rows of 3 (`v` itself when they are 3 already)."""
    if v.shape[1] == 3:
        return v
    out = np.zeros((len(v), 3))
    out[:, :v.shape[1]] = v
    return out


BODY_PATHS: dict[int, set[tuple[Any, ...]]] = {
    cv.PLANAR: {(k,) for k in BODY_KEYS if k not in ("orientation", "shape", "color")},
    cv.SPATIAL: {(k,) for k in BODY_KEYS if k not in ("angle", "orientation", "shape", "color")}
    | {("inertia", 0), ("inertia", 1), ("inertia", 2), ("orientation", "quaternion")},
}
"""What a body may give here: no shape or colour, a spatial attitude as a quaternion."""


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
    allowed = BODY_PATHS[dim]
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
                if not np.all(np.abs(th) <= BARE_ANGLE_LIMIT):
                    raise _Bail  # refused beyond MAX_ANGLE, else warned about (degrees?)
                # math.cos, as the located path: numpy's may differ in the last bit
                q[i, 0] = [math.cos(t / 2) for t in th.tolist()]
                q[i, 3] = [math.sin(t / 2) for t in th.tolist()]
            if ("angular_velocity",) in cols:
                omega[i, 2] = _numbers(g, ("angular_velocity",), None)
        else:
            if ("orientation", "quaternion") in cols:
                qq = _numbers(g, ("orientation", "quaternion"), 4)
                norm = quat_norm(qq)
                if not np.all(np.abs(norm - 1) <= UNIT_TOL):  # else a warning, or zero
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
    """(k, 3, 3) inertia tensors of a group, checked by the rules `validate._inertia` and
    `_reciprocable` use (`checks.asymmetry`, `checks.realisable`), with a margin: near a
    limit, the located path decides."""
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
        off, scale = asymmetry(J)
        if not np.all(off <= 0.5 * _TOL * scale):  # with a margin, as below
            raise _Bail
        principal = np.linalg.eigvalsh(J)
        # eigvalsh over a stack may differ from one at a time in the last bits (relative
        # to the largest moment): near-singular tensors are left to the located path
        if not np.all(principal[:, 0] >= 1e-9 * principal[:, 2]):
            raise _Bail
    if not np.all(principal >= 1e10 * MIN_MAGNITUDE):  # positive definite, reciprocable
        raise _Bail
    if not np.all(realisable(principal, 0.5 * _TOL)):  # with a margin
        raise _Bail
    return J


LOAD_PATHS = {kind: {(k,) for k in LOAD_KEYS[kind]} for kind in ("force", "torque")}
"""What a force or torque load may give (no expressions: a number per component)."""
FAST_PARAMS = {"axis", "axis2"}
"""The joint parameters this reader takes; a type with others (a helical joint's pitch)
goes to the located path."""
JOINT_PATHS = {(k,) for k in JOINT_KEYS if k not in PARAM_KEYS or k in FAST_PARAMS}
FAST_TYPES = {d: tuple(name for name, t in types.items()
                       if {p.name for p in t.params} <= FAST_PARAMS)
              for d, types in joint_types.TYPES.items()}
"""The joint types this reader takes (by dimension)."""
AXIS2_TYPES = {d: {name for name, t in types.items() if t.param("axis2")}
               for d, types in joint_types.TYPES.items()}
"""The types that have (and need) a second axis."""


def _placed(n: int, parts: list[tuple[np.ndarray, list[Any]]]) -> list[Any]:
    """One list of `n` values from each group's (indices, values)."""
    if len(parts) == 1:  # one layout: its items are all the items, in order
        return list(parts[0][1])
    out: list[Any] = [None] * n
    for index, values in parts:
        for k, v in zip(index.tolist(), values, strict=True):
            out[k] = v
    return out


def _loads(c: Checker, groups: list[_Group]) -> LoadTable:
    """Force and torque loads with constant components; `_Bail` for anything else."""
    n = sum(len(g.index) for g in groups)
    names_all: list[tuple[np.ndarray, list[str]]] = []
    types_all: list[tuple[np.ndarray, list[str]]] = []
    frames_all: list[tuple[np.ndarray, list[str]]] = []
    body = np.zeros(n, dtype=np.intp)
    vector = np.zeros((n, 3))
    at_all = np.zeros((n, 3))
    dim = c.dim
    for g in groups:
        cols = g.columns
        kind = "force" if ("force",) in cols else "torque"
        if not set(cols) <= LOAD_PATHS[kind] or ("name",) not in cols:
            raise _Bail  # a generated name depends on the others: the located path
        if any(t != kind for t in _names(g, ("type",))):
            raise _Bail
        names = _names(g, ("name",))
        k = len(names)
        body[g.index] = _bodies_of(g, ("body",))
        frames = _names(g, ("frame",)) if ("frame",) in cols else [FRAMES[0]] * k
        if kind == "force":
            vector[g.index] = _pad3(_numbers(g, ("force",), dim))
            if ("at",) in cols:  # else at the mass centre: at_all's zeros
                at_all[g.index] = _pad3(_numbers(g, ("at",), dim))
        elif dim == cv.PLANAR:
            vector[g.index, 2] = _numbers(g, ("torque",), None)
        else:
            vector[g.index] = _numbers(g, ("torque",), 3)
        names_all.append((g.index, names))
        types_all.append((g.index, [kind] * k))
        frames_all.append((g.index, frames))
    names_list = _placed(n, names_all)
    if len(set(names_list)) != n:
        raise _Bail  # a duplicate load name
    return LoadTable(names_list, _placed(n, types_all), body, _placed(n, frames_all), vector,
                     at_all)


def _joints(c: Checker, groups: list[_Group]) -> JointSpecTable:
    """Joints between bodies (no particles in a fast-path model), checked as
    `validate._joints` checks them; `_Bail` for anything it would refuse."""
    n = sum(len(g.index) for g in groups)
    dim = c.dim
    names_all: list[tuple[np.ndarray, list[str]]] = []
    types_all: list[tuple[np.ndarray, list[str]]] = []
    parent = np.zeros(n, dtype=np.intp)
    child = np.zeros(n, dtype=np.intp)
    at = np.zeros((n, 3))
    axis = np.zeros((n, 3))
    axis2 = np.zeros((n, 3))
    has_axis = np.zeros(n, dtype=bool)
    has_axis2 = np.zeros(n, dtype=bool)
    for g in groups:
        cols = g.columns
        if not set(cols) <= JOINT_PATHS:
            raise _Bail
        first, second = ("axis",) in cols, ("axis2",) in cols  # before they are taken
        names = _names(g, ("name",))
        kinds = _names(g, ("type",))
        p, ch = _bodies_of(g, ("parent",)), _bodies_of(g, ("child",))
        if np.any(p == ch) or np.any(ch < 0):
            raise _Bail  # a body joined to itself
        i = g.index
        parent[i], child[i] = p, ch
        at[i] = _pad3(_numbers(g, ("at",), dim))
        if first:
            axis[i] = _unit(_pad3(_numbers(g, ("axis",), dim)))
            has_axis[i] = True
        elif not set(kinds).isdisjoint(cv.AXIS_REQUIRED[dim]):
            raise _Bail
        if second or not AXIS2_TYPES[dim].isdisjoint(kinds):
            if not (first and second and set(kinds) <= AXIS2_TYPES[dim]):
                raise _Bail
            unit2 = _unit(_pad3(_numbers(g, ("axis2",), dim)))
            if not np.all(np.abs(np.einsum("ij,ij->i", axis[i], unit2)) <= 0.5 * PERPENDICULAR_TOL):
                raise _Bail  # perpendicular (with a margin: near the limit, the located path)
            axis2[i] = unit2
            has_axis2[i] = True
        names_all.append((i, names))
        types_all.append((i, kinds))
    names_list = _placed(n, names_all)
    types_list = _placed(n, types_all)
    if len(set(names_list)) != n:
        raise _Bail  # a duplicate joint name
    if "reactions" in c.doc.data or "drivers" in c.doc.data:  # they name joints
        c.joint_types.update(zip(names_list, types_list, strict=True))
    return JointSpecTable(names_list, types_list, parent, child, at, axis, has_axis, axis2,
                          has_axis2, [""] * n, np.zeros(n))


def _unit(v: np.ndarray) -> np.ndarray:
    """Rows of `v` normalised as `validate._axis` normalises one; `_Bail` for a zero one."""
    norm = vec_norm(v)
    if not np.all(norm >= MIN_NORM):
        raise _Bail
    return v / norm[:, None]
