"""YAML text -> plain Python values with a line mark for every key and value.

Only the YAML core types are accepted (mappings, sequences, strings, numbers, booleans,
null). The text is composed into a node graph by PyYAML's libyaml-backed safe composer
(when available) and converted here, so that:

- duplicate keys are errors (PyYAML's constructor silently keeps the last one);
- tags that would construct objects (``!!python/object``...) are refused;
- alias expansion ("billion laughs") and nesting depth are bounded;
- the file size is bounded before anything is parsed.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

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


@dataclass
class Document:
    """A loaded YAML document: plain values plus where each came from.

    `marks[path]` is the 1-based (line, column) of the value at `path` (a tuple of mapping
    keys and sequence indices); `key_marks[path]` is that of the mapping key naming it.
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
    try:
        node = yaml.compose(text, Loader=_Loader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (0, 0)
        msg = exc.problem or str(exc)
        if exc.context:
            msg = f"{exc.context}: {msg}"
        raise ModelError([Issue(file, line, col, "", f"YAML syntax error: {msg}")]) from None
    except yaml.YAMLError as exc:
        raise ModelError([Issue(file, 0, 0, "", f"YAML error: {exc}")]) from None
    doc = Document(None, file)
    if node is None:
        raise ModelError([Issue(file, 1, 1, "", "the file is empty; expected a model mapping")])
    conv = _Converter(doc)
    doc.data = conv.convert(node, (), 0)
    if conv.issues:
        raise ModelError(conv.issues)
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
    if size > max_bytes:
        raise ModelError(
            [Issue(name, 0, 0, "", f"the file is {size / 2**20:.1f} MiB; at most "
                   f"{max_bytes / 2**20:.0f} MiB is read")]
        )
    try:
        raw = p.read_bytes()
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ModelError([Issue(name, 0, 0, "", f"not UTF-8 text ({exc.reason} at byte "
                                f"{exc.start})")]) from None
    except OSError as exc:
        raise ModelError([Issue(name, 0, 0, "", f"cannot read the file: {exc.strerror}")]) from None
    return load_text(text, name)


class _Converter:
    def __init__(self, doc: Document):
        self.doc = doc
        self.issues: list[Issue] = []
        self.seen: set[int] = set()
        self.alias_nodes = 0
        self.constructor = yaml.constructor.SafeConstructor()

    def _issue(self, node: yaml.Node, path: Path_, message: str, hint: str = "") -> None:
        m = node.start_mark
        self.issues.append(Issue(self.doc.file, m.line + 1, m.column + 1, dotted(path), message,
                                 hint))

    def convert(self, node: yaml.Node, path: Path_, depth: int) -> Any:
        if depth > MAX_DEPTH:
            self._issue(node, path, f"nesting deeper than {MAX_DEPTH} levels")
            raise ModelError(self.issues)
        if id(node) in self.seen and not isinstance(node, yaml.ScalarNode):
            # A second visit means an alias: bound how much it may expand.
            self.alias_nodes += 1
            if self.alias_nodes > MAX_ALIAS_NODES:
                self._issue(node, path, f"alias expansion exceeds {MAX_ALIAS_NODES} nodes "
                            "(an 'alias bomb'); write the values out instead")
                raise ModelError(self.issues)
        self.seen.add(id(node))
        m = node.start_mark
        self.doc.marks[path] = (m.line + 1, m.column + 1)
        if isinstance(node, yaml.MappingNode):
            if node.tag != _TAG + "map":
                self._issue(node, path, f"the tag {node.tag!r} is not allowed",
                            "only plain YAML mappings, lists, strings and numbers")
                return None
            out: dict[str, Any] = {}
            for knode, vnode in node.value:
                if not isinstance(knode, yaml.ScalarNode):
                    self._issue(knode, path, "a mapping key must be a plain name")
                    continue
                if knode.tag == _TAG + "merge":
                    self._issue(knode, path, "merge keys ('<<') are not supported",
                                "write the keys out")
                    continue
                key = str(knode.value)
                kpath = (*path, key)
                if key in out:
                    first = self.doc.key_marks.get(kpath, (0, 0))
                    self._issue(knode, kpath, f"duplicate key '{key}'",
                                f"first given on line {first[0]}")
                    continue
                self.doc.key_marks[kpath] = (knode.start_mark.line + 1,
                                             knode.start_mark.column + 1)
                out[key] = self.convert(vnode, kpath, depth + 1)
            return out
        if isinstance(node, yaml.SequenceNode):
            if node.tag != _TAG + "seq":
                self._issue(node, path, f"the tag {node.tag!r} is not allowed",
                            "only plain YAML mappings, lists, strings and numbers")
                return None
            return [self.convert(v, (*path, i), depth + 1) for i, v in enumerate(node.value)]
        return self._scalar(node, path)

    def _scalar(self, node: yaml.ScalarNode, path: Path_) -> Any:
        tag = node.tag
        if tag not in _ALLOWED_SCALAR_TAGS:
            if tag in (_TAG + "timestamp", _TAG + "binary"):
                return str(node.value)
            self._issue(node, path, f"the tag {tag!r} is not allowed",
                        "only plain YAML mappings, lists, strings and numbers")
            return None
        if tag == _TAG + "str":
            value = node.value
            if node.style is None:
                # YAML 1.1 reads "1e3" as a string; engineers mean a number.
                if _NUMBER.fullmatch(value):
                    return float(value)
                return value
            return value
        if tag == _TAG + "int":
            return self.constructor.construct_yaml_int(node)
        if tag == _TAG + "float":
            return self.constructor.construct_yaml_float(node)
        if tag == _TAG + "bool":
            return self.constructor.construct_yaml_bool(node)
        return None
