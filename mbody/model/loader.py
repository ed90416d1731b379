"""YAML text -> plain Python values with a line mark for every key and value.

Only the YAML core types are accepted (mappings, sequences, strings, numbers, booleans,
null). The text is read as a stream of parser events (PyYAML's libyaml-backed parser
when available) and built here, in one loop with an explicit stack, so that:

- duplicate keys are errors (PyYAML's constructor silently keeps the last one);
- tags that would construct objects (``!!python/object``...) are refused;
- alias expansion ("billion laughs") and nesting depth are bounded, and deep nesting
  cannot overflow the C stack (PyYAML's composer recurses once per level);
- the file size is bounded before anything is parsed;
- plain scalars are typed by the YAML 1.2 core schema, not PyYAML's YAML 1.1 rules, and
  the forms the two read differently (``010``, ``1:20``, ``0x1F``, ``1_000``) are refused
  with what each would mean (`resolve_plain`);
- a number too large or too small for a double (``1e400``, a 5 000-digit integer,
  ``1e-400``) is kept as an `Unrepresentable` for validation to report, never rounded to
  inf or 0 and never converted digit by digit.

Building from events is also several times faster than PyYAML's `compose`, which
matters for models with tens of thousands of bodies.
"""

from __future__ import annotations

import math
import os
import re
import select
import stat
import time
from dataclasses import dataclass, field
from decimal import Decimal
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

from mbody.errors import Issue, ModelError, did_you_mean, wrong_type
from mbody.util.budget import MAX_BYTES, byte_limit, checked_max_bytes
from mbody.util.formatting import sizes_apart

# libyaml keeps line marks and is many times faster than the pure-Python parser
_Loader: type[yaml.SafeLoader] | type[yaml.CSafeLoader] = getattr(
    yaml, "CSafeLoader", yaml.SafeLoader)

MAX_ALIAS_NODES = 100_000
"""Most nodes that alias expansion may add before the file is refused."""
MAX_DEPTH = 64
"""Deepest nesting of mappings and sequences accepted."""
MAX_NODES = 1_000_000
"""Most keys and values read from one file (each costs a few microseconds and a few
hundred bytes with its line mark): over 1.5 times a 10 000-body model. A file larger
than `MAX_BYTES` (read only with a raised size limit) may hold more: `value_limit`."""


def value_limit(size: int) -> int:
    """Most keys and values read from a text of `size` characters: `MAX_NODES`; for a text
    larger than `MAX_BYTES` (read only when the caller raised the size limit), one per 8
    characters (a model file written by ``yaml.dump`` holds one per 12 or 13)."""
    return MAX_NODES if size <= MAX_BYTES else max(MAX_NODES, size // 8)

Path_ = tuple[str | int, ...]

MAX_INT_DIGITS = 101
"""Longest integer converted (10^100 has 101 digits): a longer one is beyond the number
range anyway, and Python's conversion grows with the square of the length (it refuses
more than 4 300 digits outright)."""

_TAG = "tag:yaml.org,2002:"
_ALLOWED_SCALAR_TAGS = {_TAG + t for t in ("str", "int", "float", "bool", "null")}
_AS_TEXT_TAGS = {_TAG + "timestamp", _TAG + "binary"}
_NOT_ALLOWED_HINT = "only plain YAML mappings, lists, strings and numbers"
_CACHE_LIMIT = 20_000

# The YAML 1.2 core schema (https://yaml.org/spec/1.2.2/#1032-tag-resolution), decimal only.
_NULLS = frozenset(("", "~", "null", "Null", "NULL"))
_BOOLS = {"true": True, "True": True, "TRUE": True,
          "false": False, "False": False, "FALSE": False}
_INT = re.compile(r"[-+]?[0-9]+")
_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?")
_INF = re.compile(r"[-+]?\.(inf|Inf|INF)")
_NAN = re.compile(r"\.(nan|NaN|NAN)")
# Forms YAML 1.1 (PyYAML, many other tools) reads as numbers and YAML 1.2 does not, or
# reads differently: refused, with what each reading gives.
_RADIX = re.compile(r"([-+]?)0([xX][0-9a-fA-F_]+|[oO][0-7_]+|[bB][01_]+)")
_SEXAGESIMAL = re.compile(r"[-+]?[0-9][0-9_]*(:[0-5]?[0-9])+(\.[0-9_]*)?")
# a run of digits and underscores with a digit in it: "the first character that is not an
# underscore is a digit" (a lookahead) keeps the match linear; [0-9_]*[0-9][0-9_]* tried
# every split of a long run (80 kB of digits ending in '_x': minutes)
_UNDERSCORED = re.compile(r"[-+]?(?=_*[0-9])[0-9_]+(\.[0-9_]*)?([eE][-+]?[0-9]+)?")
_FIRST = frozenset("0123456789+-.~tTfFnN")
_NON_PRINTABLE = re.compile("[^\x09\x0a\x0d\x20-\x7e\x85\xa0-\ud7ff\ue000-\ufffd"
                            "\U00010000-\U0010ffff]")
"""Characters YAML does not allow in a file (PyYAML's reader refuses them)."""
"""First characters of every plain scalar that is not simply text."""


class Unrepresentable:
    """A number written in the file that a double cannot hold: beyond ~1.8e308 (``1e400``,
    an integer of 5 000 digits) or nonzero below ~5e-324 (``1e-400``). Kept as written, so
    that validation reports it as out of range instead of reading inf or 0."""

    __slots__ = ("text",)

    def __init__(self, text: str):
        self.text = text

    @property
    def shown(self) -> str:
        digits = self.text.lstrip("+-")
        if digits.isdigit() and len(digits) > 30:
            return f"an integer of {len(digits)} digits"
        return self.text if len(self.text) <= 30 else self.text[:27] + "..."

    @property
    def large(self) -> bool:
        """True beyond the largest double; False for a nonzero value below the smallest."""
        # the decimal exponent of the leading digit, exact at any length ("0.<400 zeros>1"
        # has no exponent and is tiny); only nonzero values are ever unrepresentable
        return Decimal(self.text).adjusted() >= 0

    def __repr__(self) -> str:
        return self.shown


class _Refused(Exception):
    """A scalar that is refused, with the message and the hint of its issue."""

    def __init__(self, message: str, hint: str = ""):
        super().__init__(message)
        self.message, self.hint = message, hint


def _number(text: str) -> int | float | Unrepresentable:
    """A decimal integer or float as written (matched by `_INT` or `_FLOAT`)."""
    if _INT.fullmatch(text):
        digits = text.lstrip("+-")
        if len(digits) > 1 and digits[0] == "0":
            value = int(digits.lstrip("0") or "0") * (-1 if text[0] == "-" else 1)
            octal = (f"the octal number {int(text, 8)}" if set(digits) <= set("01234567")
                     else "text")
            raise _Refused(f"'{text}' has a leading zero: YAML 1.1 reads it as {octal}, "
                           f"YAML 1.2 as {value}", f"write {value}, without the leading "
                           "zero, or quote it for text")
        if len(digits) > MAX_INT_DIGITS:
            return Unrepresentable(text)
        return int(text)
    x = float(text)
    if math.isinf(x) or (x == 0.0 and text.lower().partition("e")[0].strip("+-0.") != ""):
        return Unrepresentable(text)
    return x


def resolve_plain(text: str) -> Any:
    """The value of a plain (unquoted, untagged) scalar under mbody's rules: the YAML 1.2
    core schema (null, true/false, decimal integers and floats, .inf, .nan; ``1e3`` is a
    number; ``yes``, ``on``, ``2001-12-14`` are text). Forms that YAML 1.1 reads as a
    number and YAML 1.2 does not, or differently, raise `_Refused`."""
    if text in _NULLS:
        return None
    if text in _BOOLS:
        return _BOOLS[text]
    if _FLOAT.fullmatch(text):  # decimal integers too
        return _number(text)
    if _INF.fullmatch(text):
        return -math.inf if text[0] == "-" else math.inf
    if _NAN.fullmatch(text):
        return math.nan
    m = _RADIX.fullmatch(text)
    if m:
        base = m.group(2)[0].lower()
        kind = {"x": "a hexadecimal", "o": "an octal", "b": "a binary"}[base]
        digits = m.group(2)[1:].replace("_", "")
        if digits and len(digits) <= 64:
            value = f"{m.group(1).replace('+', '')}{int(digits, {'x': 16, 'o': 8, 'b': 2}[base])}"
            raise _Refused(f"'{text}' is {kind} number ({value}); model files take decimal "
                           "numbers", f"write {value}, or quote it for text")
        raise _Refused(f"'{_short(text)}' is {kind} number; model files take decimal "
                       "numbers", "write it in decimal, or quote it for text")
    if _SEXAGESIMAL.fullmatch(text):
        value = _sexagesimal(text)
        raise _Refused(f"'{_short(text)}' is a base-60 number ({value}) in YAML 1.1 and "
                       "text in YAML 1.2", f"write {value} if that is meant, or quote it "
                       "for text")
    if "_" in text and _UNDERSCORED.fullmatch(text):
        plain = text.replace("_", "")
        raise _Refused(f"'{_short(text)}' has underscores: YAML 1.1 reads it as the number "
                       f"{_short(plain)}, YAML 1.2 as text", f"write {_short(plain)}, or "
                       "quote it for text")
    return text


def _short(text: str) -> str:
    return text if len(text) <= 40 else text[:37] + "..."


def _sexagesimal(text: str) -> str:
    """YAML 1.1's reading of ``1:20`` (80) or ``1:20.5`` (80.5), as text."""
    sign = -1 if text[0] == "-" else 1
    *head, last = text.lstrip("+-").replace("_", "").split(":")
    value = 0
    for part in head:
        value = value * 60 + int(part)
    if "." in last:
        return f"{sign * (value * 60 + float(last)):g}"
    return str(sign * (value * 60 + int(last)))


def _tagged(tag: str, text: str) -> Any:
    """A scalar with an explicit core tag (``!!float 3``): the text must fit the tag."""
    if tag == _TAG + "str":
        return text
    if tag == _TAG + "null":
        if text in _NULLS:
            return None
        raise _Refused(f"'{_short(text)}' is not null", "!!null takes null, ~ or nothing")
    if tag == _TAG + "bool":
        if text in _BOOLS:
            return _BOOLS[text]
        raise _Refused(f"'{_short(text)}' is not a boolean", "!!bool takes true or false")
    if tag == _TAG + "int":
        if _INT.fullmatch(text):
            return _number(text)
        raise _Refused(f"'{_short(text)}' is not an integer",
                       "!!int takes a decimal integer such as 42")
    if _FLOAT.fullmatch(text) or _INF.fullmatch(text) or _NAN.fullmatch(text):
        x = resolve_plain(text)
        return x if isinstance(x, Unrepresentable) else float(x)
    raise _Refused(f"'{_short(text)}' is not a number",
                   "!!float takes a decimal number such as 1.5, -2e-3 or .inf")


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
    builder = _Builder(doc, value_limit(len(text)))
    bad = _NON_PRINTABLE.search(text)
    if bad:  # PyYAML's reader would say so with a character offset, not a line
        at = bad.start()
        line = text.count("\n", 0, at) + 1
        col = at - (text.rfind("\n", 0, at) + 1) + 1
        what = (f"the character U+{ord(bad.group()):04X}" if not 0xD800 <= ord(bad.group())
                <= 0xDFFF else "a lone surrogate")
        raise ModelError([Issue(file, line, col, "", f"{what} is not allowed in a YAML "
                                "file", "remove it; inside double quotes a control character "
                                "may be written escaped, such as \\t")])
    loader = _Loader(text)
    try:
        builder.run(loader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (0, 0)
        tab = _tab_at(text, mark)
        if tab:
            raise ModelError([Issue(file, line, col, "", f"YAML syntax error: {tab}",
                                    "replace tabs with spaces")]) from None
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


def _tab_at(text: str, mark) -> str:
    """What is wrong when a YAML error points at a tab (or a line indented with one)."""
    if mark is None:
        return ""
    lines = text.split("\n")
    if not 0 <= mark.line < len(lines):
        return ""
    row = lines[mark.line]
    indent = row[:len(row) - len(row.lstrip(" \t"))]
    if "\t" in indent and mark.column <= len(indent):
        return "a tab in the indentation; YAML indents with spaces only"
    if row[mark.column:mark.column + 1] == "\t":
        return "a tab character where YAML allows only spaces"
    return ""


FIFO_WAIT = 1.0
"""Seconds a named pipe with no writer is given for one to appear before it is refused."""


def _near_file(path: Path, most: int = 2000) -> str:
    """A did-you-mean among the files beside a missing `path` (at most `most` entries of
    its folder are looked at: a huge folder costs no more), or ''."""
    try:
        with os.scandir(path.parent) as entries:
            names = [e.name for _, e in zip(range(most), entries, strict=False)]
    except OSError:
        return ""
    # names compared without the suffix they share (".yaml" would make any two alike)
    stems = {Path(n).stem: n for n in names if Path(n).suffix == path.suffix}
    close = did_you_mean(path.stem, stems)
    if not close:
        return ""
    found = path.parent / stems[close.split("'")[1]]
    return f"did you mean '{found}'?"


SOURCE_KINDS = ("a path to a model file (str or os.PathLike) or a dict with a model file's "
                "content")
"""What `mbody.load`'s `source` accepts, in words (its error messages)."""
_YAML_START = re.compile(r"\s*(\{|[\w-]+\s*:\s)")


def check_source(source: object, max_bytes: object = None, call: str = "mbody.load"
                 ) -> int | None:
    """Refuse, before anything is read, what `call` cannot read from: a `source` that is
    neither a path nor a dict (`MbodyTypeError`), YAML text given where a path goes
    (`ModelError`: text is `mbody.loads`'), or a `max_bytes` that is not a whole number of
    bytes, at least 1 (`mbody.util.budget.checked_max_bytes`, every reader's check).

    Returns
    -------
    int or None
        `max_bytes` as an int (None: the current limit).
    """
    if isinstance(source, bytes | bytearray):
        raise wrong_type("source", SOURCE_KINDS, source, "for a model file's content "
                         "use mbody.loads(text); for a path in bytes, os.fsdecode(path)")
    if not isinstance(source, str | os.PathLike | dict):
        hint = ("for an open file, give its path (f.name), or its text to mbody.loads(f.read())"
                if hasattr(source, "read") else "for YAML text use mbody.loads(text)")
        raise wrong_type("source", SOURCE_KINDS, source, hint)
    if isinstance(source, str) and looks_like_yaml(source) and not os.path.exists(source):
        line = "holds a line break" if "\n" in source else "starts as a YAML mapping does"
        raise ModelError([Issue(call, 0, 0, "source", f"this looks like YAML text ({line}), "
                                "not a path to a model file", "use mbody.loads(text)")])
    return checked_max_bytes(max_bytes)


def looks_like_yaml(text: str) -> bool:
    """Whether `text`, given as a path, is rather a model file's text: it holds a line
    break, or starts as a YAML mapping does (``dimension: 2``, ``{``)."""
    return "\n" in text or _YAML_START.match(text) is not None


MODEL_FORMATS = {"yaml": ("mbody YAML", ".yaml", "an mbody YAML file", "a YAML model file"),
                 "mjcf": ("MJCF", ".xml", "an MJCF file", "an MJCF model file"),
                 "urdf": ("URDF", ".urdf", "a URDF file", "a URDF model file")}
"""Each model format: its name, its file extension, what a file of it is called, and
what a model file of it is called where one was expected."""


def read_as(fmt: str) -> str:
    """The advice for a file of model format `fmt` ("yaml", "mjcf", "urdf") read as
    another: ``this is a URDF file: read it as URDF (a .urdf name, or --format urdf)``."""
    name, ext, a_file, _ = MODEL_FORMATS[fmt]
    return f"this is {a_file}: read it as {name} (a {ext} name, or --format {fmt})"


_LEADING_SPACE = re.compile(r"[\ufeff \t\r\n]*")
_XML_NAME = re.compile(r"<([A-Za-z_][\w:.-]*)")
_XML_ROOTS = {"mujoco": "mjcf", "robot": "urdf"}


def _past_space(text: str, at: int) -> int:
    """The index of the first character of `text` from `at` that is no space (or BOM)."""
    m = _LEADING_SPACE.match(text, at)
    return m.end() if m else at


def refuse_xml(text: str, file: str) -> None:
    """Refuse `text` read as an mbody YAML model when it is XML (its first character is
    '<', which no YAML mapping starts with), naming the format its root element says:
    YAML's own message ("mapping values are not allowed here") would not.

    Raises
    ------
    ModelError
        At the root element, with the advice to read it as MJCF or URDF.
    """
    at = _past_space(text, 0)
    if not text.startswith("<", at):
        return
    while text.startswith(("<?", "<!"), at):  # the declaration, comments, a doctype
        end = text.find("-->" if text.startswith("<!--", at) else ">", at)
        if end < 0:
            break
        at = _past_space(text, text.index(">", end) + 1)
    m = _XML_NAME.match(text, at)
    tag = m.group(1) if m else ""
    fmt = _XML_ROOTS.get(tag)
    line = text.count("\n", 0, at) + 1
    column = at - (text.rfind("\n", 0, at) + 1) + 1
    raise ModelError([Issue(file, line, column, "", "expected an mbody YAML model, got XML"
                            + (f" (<{tag}>)" if tag else ""),
                            read_as(fmt) if fmt else
                            "an MJCF model starts with <mujoco>, a URDF model with <robot>")])


def read_file(path: str | os.PathLike[str], max_bytes: int | None = None,
              fmt: str = "yaml") -> str:
    """The text of a model file, refusing files over `max_bytes` before reading them.

    `max_bytes` defaults to `MAX_BYTES`, or the budget set by
    `mbody.util.budget.byte_budget` (the command line's ``--max-bytes``); `fmt`
    is the model format the file is read as (what a refusal says was expected).

    A regular file or a pipe (``/dev/stdin`` fed by ``<`` or ``|``, ``<(command)``, a named
    pipe with a writer) is read; anything else (a directory, a terminal, a device, a
    socket) is refused without reading, so that nothing can block forever.
    """
    max_bytes = byte_limit(max_bytes, MAX_BYTES)
    p = Path(path)
    name = str(path)
    _, ext, _, expected = MODEL_FORMATS[fmt]

    def refuse(message: str, hint: str = "") -> ModelError:
        return ModelError([Issue(name, 0, 0, "", message, hint)])

    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise refuse("no such file", _near_file(p)) from None
    except OSError as exc:
        raise refuse(f"cannot read the file: {exc.strerror}") from None
    kind = file_kind(st.st_mode)
    if kind == "a directory":
        raise refuse(f"this is a directory; expected {expected}")
    if kind:
        given = f" --format {fmt}" if fmt != "yaml" else ""
        raise refuse(f"this is {kind}, not a file; expected {expected} (to read a model "
                     f"from a pipe: mbody check /dev/stdin{given} < model{ext})")
    more = "--max-bytes N on the command line, or mbody.load(path, max_bytes=N), reads more"
    if st.st_size > max_bytes:
        size, most = sizes_apart(st.st_size, max_bytes)
        raise refuse(f"the file is {size}; mbody reads at most {most} ({more})")
    try:  # never blocks in open(): a named pipe with no writer would wait forever there
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise refuse(f"cannot read the file: {exc.strerror}") from None
    try:
        mode = os.fstat(fd).st_mode
        kind = file_kind(mode)
        if kind:  # replaced since the stat() above
            raise refuse(f"this is {kind}, not a file; expected {expected}")
        if stat.S_ISFIFO(mode):
            raw = _read_pipe(fd, max_bytes + 1)
            if raw is None:
                raise refuse(f"nothing came through this pipe in {FIFO_WAIT:g} s (no writer, or "
                             "an empty one); start the writer first, or give a model file")
        else:
            if getattr(os, "O_NONBLOCK", 0):
                os.set_blocking(fd, True)
            with os.fdopen(fd, "rb", closefd=False) as f:
                raw = _read_bounded(f, max_bytes + 1, os.fstat(fd).st_size)
    except OSError as exc:
        raise refuse(f"cannot read the file: {exc.strerror}") from None
    finally:
        os.close(fd)
    if len(raw) > max_bytes:  # the file grew, or stat() lied (a pipe, /proc)
        raise refuse(f"the file is larger than {max_bytes} bytes, the most that is read "
                     f"({more})")
    return decode(raw, name)


def decode(raw: bytes, name: str) -> str:
    """A model file's bytes as text; `ModelError` at the line and column of the first byte
    that is not UTF-8."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise ModelError([Issue(name, line, col, "", f"not UTF-8 text: byte "
                                f"0x{raw[exc.start]:02x} ({exc.reason}); save the file "
                                "as UTF-8")]) from None


def _read_bounded(f: Any, limit: int, size: int) -> bytes:
    """Up to `limit` bytes of `f`, whose size is said to be `size`.

    ``f.read(limit)`` would allocate `limit` bytes up front (32 MiB for any model); the
    said size (plus one byte, to see growth) is read first, then any more in chunks,
    since some files say less than they hold (/proc files say 0).
    """
    first = min(limit, size + 1)
    raw = f.read(first)
    if len(raw) < first:
        return raw
    chunks = [raw]
    total = len(raw)
    while total < limit:
        chunk = f.read(min(1 << 20, limit - total))
        if not chunk:
            break
        chunks.append(chunk)
        total += len(chunk)
    return b"".join(chunks)


def file_kind(mode: int) -> str:
    """'' for what may be read (a regular file or a pipe), else what it is."""
    if stat.S_ISREG(mode) or stat.S_ISFIFO(mode):
        return ""
    return ("a directory" if stat.S_ISDIR(mode) else "a character device (a terminal, /dev/null...)"
            if stat.S_ISCHR(mode) else "a block device" if stat.S_ISBLK(mode)
            else "a socket" if stat.S_ISSOCK(mode) else "not a regular file")


def _read_pipe(fd: int, limit: int) -> bytes | None:
    """Up to `limit` bytes from a pipe opened without blocking, until its writers close it.

    Without blocking, read() on a pipe says EAGAIN while a writer is connected and has not
    written yet, and end-of-file while no writer is connected. End-of-file before any data
    may be a writer that is about to connect: one is awaited for `FIFO_WAIT` seconds, then
    None (nothing came).
    """
    chunks: list[bytes] = []
    size = 0
    deadline = None
    while size < limit:
        try:
            chunk = os.read(fd, min(1 << 20, limit - size))
        except BlockingIOError:  # a writer is connected: wait for its data or its close
            _wait_readable(fd, None)
            continue
        if chunk:
            chunks.append(chunk)
            size += len(chunk)
        elif size:
            break  # end of file after data: the writers are done
        else:
            if deadline is None:
                deadline = time.monotonic() + FIFO_WAIT
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            _wait_readable(fd, min(left, 0.02))
    return b"".join(chunks)


def _wait_readable(fd: int, timeout: float | None) -> None:
    try:
        select.select([fd], [], [], timeout)
    except (ValueError, OSError):  # a descriptor select() cannot watch: poll instead
        time.sleep(0.01 if timeout is None else timeout)


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
    def __init__(self, doc: Document, max_nodes: int = MAX_NODES):
        self.doc = doc
        self.max_nodes = max_nodes
        self.issues: list[Issue] = []
        self.anchors: dict[str, tuple[Any, int]] = {}
        self.expanded = 0
        self.stack: list[_Frame] = []
        self.has_root = False
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
        nodes = 0
        while True:
            ev = loader.get_event()
            t = type(ev)
            if t is ScalarEvent or t is MappingStartEvent or t is SequenceStartEvent \
                    or t is AliasEvent:
                nodes += 1
                if nodes > self.max_nodes:
                    limit = f"{self.max_nodes:_}".replace("_", " ")
                    self._fatal(ev.start_mark, (), f"the file holds more than {limit} values "
                                "(keys, numbers, lists...), the most that is read (a "
                                "10 000-body model holds about 650 000)")
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
            if value and value[0] not in _FIRST:
                return value  # e.g. a body name: no YAML 1.2 type starts with this letter
            hit = self.cache.get(value, _NOKEY)
            if hit is not _NOKEY:
                return hit
        elif tag is None or tag == "!":  # quoted, or the non-specific tag: text
            return value
        try:
            if plain:
                out = resolve_plain(value)
            elif tag in _ALLOWED_SCALAR_TAGS:
                out = _tagged(tag, value)
            elif tag in _AS_TEXT_TAGS:
                return str(value)
            else:
                self._issue(ev.start_mark, path, f"the tag {tag!r} is not allowed",
                            _NOT_ALLOWED_HINT)
                return None
        except _Refused as exc:
            if not plain:
                shown = "!!" + tag[len(_TAG):] if tag.startswith(_TAG) else tag
                exc.message = f"the tag {shown} does not fit: {exc.message}"
            self._issue(ev.start_mark, path, exc.message, exc.hint)
            return None
        if plain and len(self.cache) < _CACHE_LIMIT:
            self.cache[value] = out
        return out
