"""YAML text -> plain Python values with a line mark for every key and value.

Only the YAML core types are accepted (mappings, sequences, strings, numbers, booleans,
null). The text is read as a stream of parser events (PyYAML's libyaml-backed parser
when available) and built here, in one loop with an explicit stack, so that:

- duplicate keys are errors (PyYAML's constructor silently keeps the last one);
- tags that would construct objects (``!!python/object``...) are refused;
- alias expansion ("billion laughs") and nesting depth are bounded, and deep nesting
  cannot overflow the C stack (PyYAML's composer recurses once per level);
- the file size is bounded before anything is parsed.

Building from events is also several times faster than PyYAML's `compose`, which
matters for models with tens of thousands of bodies.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from yaml.events import (
    AliasEvent,
    DocumentStartEvent,
    MappingEndEvent,
    MappingStartEvent,
    ScalarEvent,
    SequenceEndEvent,
    SequenceStartEvent,
    StreamEndEvent,
)

from .errors import Issue, ModelError

try:  # libyaml keeps line marks and is many times faster than the pure-Python parser
    _Loader = yaml.CSafeLoader
except AttributeError:  # pragma: no cover - PyYAML built without libyaml
    _Loader = yaml.SafeLoader

MAX_BYTES = 32 * 1024 * 1024
"""Largest model file read, in bytes (a 10 000-body model is about 2 MB)."""
MAX_ALIAS_NODES = 100_000
"""Most nodes that alias expansion may add before the file is refused."""
MAX_DEPTH = 64
"""Deepest nesting of mappings and sequences accepted."""

Path_ = tuple[str | int, ...]

_TAG = "tag:yaml.org,2002:"
_NUMBER = re.compile(r"[-+]?(\d[\d_]*\.?\d*|\.\d+)([eE][-+]?\d+)?")
_ALLOWED_SCALAR_TAGS = {_TAG + t for t in ("str", "int", "float", "bool", "null")}
_AS_TEXT_TAGS = {_TAG + "timestamp", _TAG + "binary"}
_NOT_ALLOWED_HINT = "only plain YAML mappings, lists, strings and numbers"
_CACHE_LIMIT = 20_000
_RESOLVER_FIRST = frozenset(c for c in yaml.resolver.Resolver.yaml_implicit_resolvers if c)
"""First characters of every plain scalar PyYAML's resolver may read as non-text."""


@dataclass
class Document:
    """A loaded YAML document: plain values plus where each came from.

    `marks[path]` is the 1-based (line, column) of the value at `path` (a tuple of mapping
    keys and sequence indices); `key_marks[path]` is that of the mapping key naming it.
    Values reached through an alias have no marks of their own: `where` falls back to
    the alias.
    """

    data: Any
    file: str
    marks: dict[Path_, tuple[int, int]] = field(default_factory=dict)
    key_marks: dict[Path_, tuple[int, int]] = field(default_factory=dict)

    def where(self, path: Path_, *, key: bool = False) -> tuple[int, int]:
        """The best known mark for `path`: itself, else its nearest marked parent."""
        table = self.key_marks if key else self.marks
        p = tuple(path)
        while p:
            if p in table:
                return table[p]
            if key and p in self.marks:
                return self.marks[p]
            p = p[:-1]
        return self.marks.get((), (0, 0))


def dotted(path: Path_) -> str:
    """``('bodies', 2, 'inertia')`` -> ``bodies[2].inertia``."""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def load_text(text: str, file: str = "<string>") -> Document:
    """Parse YAML text into a `Document`; raise `ModelError` on any YAML-level problem."""
    doc = Document(None, file)
    builder = _Builder(doc)
    loader = _Loader(text)
    try:
        builder.run(loader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (0, 0)
        msg = exc.problem or str(exc)
        if exc.context:
            cm = exc.context_mark
            started = (f" (started at line {cm.line + 1}, column {cm.column + 1})"
                       if cm is not None and mark is not None and cm.line != mark.line else "")
            msg = f"{exc.context}{started}: {msg}"
        raise ModelError([Issue(file, line, col, "", f"YAML syntax error: {msg}")]) from None
    except yaml.YAMLError as exc:
        raise ModelError([Issue(file, 0, 0, "", f"YAML error: {exc}")]) from None
    finally:
        loader.dispose()
    if builder.issues:
        raise ModelError(builder.issues)
    if not builder.has_root:
        raise ModelError([Issue(file, 1, 1, "", "the file is empty; expected a model mapping "
                                "with at least 'dimension' and 'bodies'")])
    return doc


def load_file(path: str | os.PathLike[str], max_bytes: int = MAX_BYTES) -> Document:
    """Read and parse a model file, refusing files over `max_bytes` before reading them."""
    p = Path(path)
    name = str(path)
    try:
        size = p.stat().st_size
    except FileNotFoundError:
        raise ModelError([Issue(name, 0, 0, "", "no such file")]) from None
    except OSError as exc:
        raise ModelError([Issue(name, 0, 0, "", f"cannot read the file: {exc.strerror}")]) from None
    if p.is_dir():
        raise ModelError([Issue(name, 0, 0, "", "this is a directory; expected a YAML model file")])
    more = "mbody.load(path, max_bytes=N) reads more"
    if size > max_bytes:
        raise ModelError([Issue(name, 0, 0, "", f"the file is {size / 2**20:.1f} MiB; at most "
                                f"{max_bytes / 2**20:.3g} MiB is read ({more})")])
    try:
        with open(p, "rb") as f:  # bounded: /dev/zero or a pipe reports size 0
            raw = f.read(max_bytes + 1)
    except OSError as exc:
        raise ModelError([Issue(name, 0, 0, "", f"cannot read the file: {exc.strerror}")]) from None
    if len(raw) > max_bytes:  # the file grew, or stat() lied (a pipe, /proc)
        raise ModelError([Issue(name, 0, 0, "", f"the file is larger than {max_bytes} bytes, "
                                f"the most that is read ({more})")])
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise ModelError([Issue(name, line, col, "", f"not UTF-8 text: byte "
                                f"0x{raw[exc.start]:02x} ({exc.reason}); save the file "
                                "as UTF-8")]) from None
    return load_text(text, name)


class _Frame:
    """An open mapping or sequence while its events stream past."""

    __slots__ = ("container", "is_map", "key", "path", "size", "anchor", "keep")

    def __init__(self, container, is_map: bool, path: Path_, anchor, keep: bool):
        self.container = container
        self.is_map = is_map
        self.key: Any = _NOKEY
        self.path = path
        self.size = 1
        self.anchor = anchor
        self.keep = keep  # False: a refused node, built only to consume its events


_NOKEY = object()  # the next node of a mapping is a key
_BADKEY = object()  # the key was refused: drop the value that follows
_KEYNODE = object()  # a refused list or mapping used as a key is being read


class _Builder:
    def __init__(self, doc: Document):
        self.doc = doc
        self.issues: list[Issue] = []
        self.anchors: dict[str, tuple[Any, int]] = {}
        self.expanded = 0
        self.stack: list[_Frame] = []
        self.has_root = False
        self.resolver = yaml.resolver.Resolver()
        self.constructor = yaml.constructor.SafeConstructor()
        self.cache: dict[str, Any] = {}

    def _issue(self, mark, path: Path_, message: str, hint: str = "") -> None:
        self.issues.append(Issue(self.doc.file, mark.line + 1, mark.column + 1, dotted(path),
                                 message, hint))

    def _fatal(self, mark, path: Path_, message: str) -> None:
        self._issue(mark, path, message)
        raise ModelError(self.issues)

    def run(self, loader) -> None:
        stack = self.stack
        marks = self.doc.marks
        documents = 0
        while True:
            ev = loader.get_event()
            t = type(ev)
            if t is ScalarEvent or t is MappingStartEvent or t is SequenceStartEvent \
                    or t is AliasEvent:
                if stack:
                    f = stack[-1]
                    if f.is_map and f.key is _NOKEY:
                        self._key(f, ev, t)
                        continue
                    if f.is_map:
                        path = (*f.path, f.key) if f.key is not _BADKEY else (*f.path, "?")
                    else:
                        path = (*f.path, len(f.container))
                else:
                    path = ()
                m = ev.start_mark
                marks[path] = (m.line + 1, m.column + 1)
                if t is ScalarEvent:
                    self._place(self._scalar(ev, path), 1, ev.anchor)
                elif t is AliasEvent:
                    self._alias(ev, path)
                else:
                    self._open(ev, path, t is MappingStartEvent)
            elif t is MappingEndEvent or t is SequenceEndEvent:
                f = stack.pop()
                self._place(f.container if f.keep else None, f.size, f.anchor)
            elif t is DocumentStartEvent:
                documents += 1
                if documents > 1:
                    self._fatal(ev.start_mark, (), "a second YAML document ('---'); a model "
                                "file holds exactly one")
            elif t is StreamEndEvent:
                return

    def _open(self, ev, path: Path_, is_map: bool) -> None:
        stack = self.stack
        if len(stack) >= MAX_DEPTH:
            self._fatal(ev.start_mark, path, f"nesting deeper than {MAX_DEPTH} levels")
        kind = "map" if is_map else "seq"
        keep = ev.tag in (None, "!", _TAG + kind)
        if not keep:
            self._issue(ev.start_mark, path, f"the tag {ev.tag!r} is not allowed",
                        _NOT_ALLOWED_HINT)
        if stack and not stack[-1].keep:
            keep = False
        stack.append(_Frame({} if is_map else [], is_map, path, ev.anchor, keep))

    def _place(self, value: Any, size: int, anchor) -> None:
        if anchor is not None:
            self.anchors[anchor] = (value, size)
        stack = self.stack
        if not stack:
            self.doc.data = value
            self.has_root = True
            return
        f = stack[-1]
        f.size += size
        if f.is_map:
            if f.key is _KEYNODE:  # a refused complex key closed: drop the value that follows
                f.key = _BADKEY
                return
            if f.key is not _BADKEY:
                f.container[f.key] = value
            f.key = _NOKEY
        else:
            f.container.append(value)

    def _alias(self, ev, path: Path_) -> None:
        if ev.anchor not in self.anchors:
            self._issue(ev.start_mark, path, f"the alias '*{ev.anchor}' names no anchor "
                        "defined before it")
            self._place(None, 1, None)
            return
        value, size = self.anchors[ev.anchor]
        self.expanded += size
        if self.expanded > MAX_ALIAS_NODES:
            self._fatal(ev.start_mark, path, f"alias expansion exceeds {MAX_ALIAS_NODES} "
                        "nodes (an 'alias bomb'); write the values out instead")
        self._place(value, size, None)

    def _key(self, f: _Frame, ev, t) -> None:
        """A mapping key: a plain scalar naming the entry; anything else is refused."""
        m = ev.start_mark
        if t is not ScalarEvent:
            self._issue(m, f.path, "a mapping key must be a plain name")
            if t is AliasEvent:
                f.key = _BADKEY
            else:  # a list or mapping as a key: build it to consume its events, then drop it
                f.key = _KEYNODE
                self._open(ev, (*f.path, "?"), t is MappingStartEvent)
                self.stack[-1].keep = False
                self.stack[-1].anchor = None
            return
        key = ev.value
        kpath = (*f.path, key)
        if ev.implicit[0] and key == "<<":
            self._issue(m, f.path, "merge keys ('<<') are not supported", "write the keys out")
            f.key = _BADKEY
            return
        if key in f.container:
            first = self.doc.key_marks.get(kpath, (0, 0))
            self._issue(m, kpath, f"duplicate key '{key}'", f"first given on line {first[0]}")
            f.key = _BADKEY
            return
        self.doc.key_marks[kpath] = (m.line + 1, m.column + 1)
        f.key = key

    def _scalar(self, ev, path: Path_) -> Any:
        tag = ev.tag
        value = ev.value
        plain = tag is None and ev.implicit[0]
        if plain:
            if value and value[0] not in _RESOLVER_FIRST:
                return value  # e.g. a body name: no YAML 1.1 type starts with this letter
            hit = self.cache.get(value, _NOKEY)
            if hit is not _NOKEY:
                return hit
        if tag is None or tag == "!":
            tag = self.resolver.resolve(yaml.ScalarNode, value, ev.implicit)
        if tag not in _ALLOWED_SCALAR_TAGS:
            if tag in _AS_TEXT_TAGS:
                return str(value)
            self._issue(ev.start_mark, path, f"the tag {tag!r} is not allowed",
                        _NOT_ALLOWED_HINT)
            return None
        if tag == _TAG + "str":
            out: Any = value
            if plain and _NUMBER.fullmatch(value):
                # YAML 1.1 reads "1e3" as a string; engineers mean a number.
                try:
                    out = float(value)
                except ValueError:  # e.g. "1__0": leave it as text, the checks will say
                    out = value
        elif tag == _TAG + "null":
            out = None
        else:
            node = yaml.ScalarNode(tag, value)
            if tag == _TAG + "int":
                out = self.constructor.construct_yaml_int(node)
            elif tag == _TAG + "float":
                out = self.constructor.construct_yaml_float(node)
            else:
                out = self.constructor.construct_yaml_bool(node)
        if plain and len(self.cache) < _CACHE_LIMIT:
            self.cache[value] = out
        return out
