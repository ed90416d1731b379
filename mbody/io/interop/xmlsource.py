"""XML text -> a light element tree where every element and attribute keeps its line and
column, parsed safely.

The parser is expat configured as defusedxml configures it: a document type declaration
(and with it every entity declaration: "billion laughs", external entities) is refused
before anything is expanded, so a hostile file costs no more than its size. Problems
become `mbody.errors.Issue`s with the file, line and column, like a bad YAML model's.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from defusedxml import DTDForbidden, EntitiesForbidden, ExternalReferenceForbidden

from mbody.errors import Issue, ModelError, did_you_mean
from mbody.model.loader import MODEL_FORMATS, read_as, read_file

MAX_DEPTH = 200
"""Deepest element nesting accepted (a robot's body tree is rarely 50 deep)."""
MAX_ELEMENTS = 1_000_000
"""Most elements read from one file and the files it includes."""


@dataclass
class Element:
    """One XML element: its tag, attributes and children, each with where it was written.

    Parameters
    ----------
    tag : str
        The element's name.
    attrib : dict of str to str
        Its attributes, in file order.
    file : str
        The file it was read from (an included file names itself).
    line, column : int
        1-based position of the ``<`` opening the element.
    attr_marks : dict of str to (int, int)
        1-based position of each attribute's name.
    children : list of Element
        Child elements in file order (text between elements is ignored).
    """

    tag: str
    attrib: dict[str, str]
    file: str
    line: int
    column: int
    attr_marks: dict[str, tuple[int, int]] = field(default_factory=dict)
    children: list[Element] = field(default_factory=list)

    def get(self, name: str, default: str | None = None) -> str | None:
        """The attribute `name`, or `default`."""
        return self.attrib.get(name, default)

    def where(self, attr: str | None = None) -> tuple[int, int]:
        """(line, column) of attribute `attr` if given and present, else of the element."""
        if attr is not None and attr in self.attr_marks:
            return self.attr_marks[attr]
        return self.line, self.column

    def issue(self, message: str, hint: str = "", attr: str | None = None) -> Issue:
        """An `Issue` located at this element (or at its attribute `attr`)."""
        line, col = self.where(attr)
        key = f"<{self.tag}{' ' + attr if attr else ''}>"
        return Issue(self.file, line, col, key, one_line(message), one_line(hint))

    def iter(self, tag: str | None = None) -> Iterator[Element]:
        """This element and every descendant (depth first), or those named `tag`."""
        stack = [self]
        while stack:
            e = stack.pop()
            if tag is None or e.tag == tag:
                yield e
            stack.extend(reversed(e.children))

    def find(self, tag: str) -> Element | None:
        """The first child named `tag`, or None."""
        return next((c for c in self.children if c.tag == tag), None)

    def findall(self, tag: str) -> list[Element]:
        """The children named `tag`."""
        return [c for c in self.children if c.tag == tag]


_ATTR = re.compile(rb"\s*([^\s=/>]+)\s*=\s*(?:\"[^\"]*\"|'[^']*')")
"""One attribute of a start tag, matched where the previous one ended: a name, '=', a
quoted value (which may hold '>'). Anchored, each byte of a tag is read once."""


class _Reader:
    """expat callbacks building `Element`s with their marks."""

    def __init__(self, data: bytes, file: str, budget: list[int], encoding: str | None):
        self.data, self.file, self.budget = data, file, budget
        self.root: Element | None = None
        self.stack: list[Element] = []
        # where the last mark was: attributes are marked in file order, so each mark
        # counts lines and characters only from the one before (linear in the file)
        self._at, self._line, self._line_start, self._column = 0, 1, 0, 0
        # decoded text re-encoded: its declared encoding no longer applies
        p = expat.ParserCreate(encoding)
        # as defusedxml's DefusedExpatParser: no DTD, hence no entity of any kind
        p.StartDoctypeDeclHandler = self._doctype
        p.EntityDeclHandler = self._entity
        p.UnparsedEntityDeclHandler = self._unparsed
        p.ExternalEntityRefHandler = self._external
        p.StartElementHandler = self._start
        p.EndElementHandler = self._end
        p.ordered_attributes = False
        self.parser = p

    def _doctype(self, name, sysid, pubid, has_internal_subset):
        raise DTDForbidden(name, sysid, pubid)

    def _entity(self, name, is_parameter_entity, value, base, sysid, pubid, notation_name):
        raise EntitiesForbidden(name, value, base, sysid, pubid, notation_name)

    def _unparsed(self, name, base, sysid, pubid, notation_name):
        raise EntitiesForbidden(name, None, base, sysid, pubid, notation_name)

    def _external(self, context, base, sysid, pubid):
        raise ExternalReferenceForbidden(context, base, sysid, pubid)

    def _mark(self, offset: int) -> tuple[int, int]:
        """1-based (line, column) of the byte at `offset` (a character's first byte)."""
        data = self.data
        if offset < self._at:  # out of file order (never, with expat): count afresh
            self._at, self._line, self._line_start, self._column = 0, 1, 0, 0
        lines = data.count(b"\n", self._at, offset)
        if lines:
            self._line += lines
            self._line_start = data.rfind(b"\n", self._at, offset) + 1
            self._at, self._column = self._line_start, 0
        self._column += len(data[self._at:offset].decode("utf-8", "replace"))
        self._at = offset
        return self._line, self._column + 1

    def _start(self, tag: str, attrib: dict[str, str]) -> None:
        p = self.parser
        self.budget[0] -= 1
        if self.budget[0] < 0:
            raise _Limit(f"more than {MAX_ELEMENTS} elements")
        if len(self.stack) >= MAX_DEPTH:
            raise _Limit(f"elements nested more than {MAX_DEPTH} deep")
        start = p.CurrentByteIndex
        line, col = p.CurrentLineNumber, p.CurrentColumnNumber + 1
        e = Element(tag, dict(attrib), self.file, line, col)
        if attrib:  # expat has read the whole tag: its attributes follow one another
            at = start + 1 + len(tag.encode())
            while (m := _ATTR.match(self.data, at)) is not None:
                name = m.group(1).decode("utf-8", "replace")
                if name in attrib and name not in e.attr_marks:
                    e.attr_marks[name] = self._mark(m.start(1))
                at = m.end()
        if self.stack:
            self.stack[-1].children.append(e)
        else:
            self.root = e
        self.stack.append(e)

    def _end(self, tag: str) -> None:
        self.stack.pop()


class _Limit(Exception):
    pass


def parse_xml(text: str | bytes, file: str = "<string>",
              budget: list[int] | None = None) -> Element:
    """Parse XML safely into an `Element` tree with line and column marks.

    Parameters
    ----------
    text : str or bytes
        The document.
    file : str, optional
        The name used in marks and error messages.
    budget : list of one int, optional
        Elements still allowed (shared by a file and the files it includes).

    Returns
    -------
    Element
        The root element.

    Raises
    ------
    ModelError
        On a syntax error (with its line and column), a document type declaration or an
        entity (refused, never expanded), or a document beyond the size limits.
    """
    data = text.encode("utf-8") if isinstance(text, str) else text
    reader = _Reader(data, file, budget if budget is not None else [MAX_ELEMENTS],
                     "utf-8" if isinstance(text, str) else None)
    try:
        reader.parser.Parse(data, True)
    except expat.ExpatError as exc:
        what = expat.ErrorString(exc.code) if exc.code else str(exc)
        raise ModelError([Issue(file, exc.lineno, exc.offset + 1, "",
                                f"XML syntax error: {what}", _syntax_hint(what))]) from None
    except DTDForbidden:
        line, col = reader.parser.CurrentLineNumber, reader.parser.CurrentColumnNumber + 1
        raise ModelError([Issue(file, line, col, "<!DOCTYPE>", "a document type declaration "
                                "is not accepted (it can declare entities that expand "
                                "without bound or read other files)",
                                "remove the <!DOCTYPE ...> line; MJCF and URDF need none")]
                         ) from None
    except (EntitiesForbidden, ExternalReferenceForbidden):
        line, col = reader.parser.CurrentLineNumber, reader.parser.CurrentColumnNumber + 1
        raise ModelError([Issue(file, line, col, "", "XML entities are not accepted",
                                "write the values out")]) from None
    except _Limit as exc:
        line, col = reader.parser.CurrentLineNumber, reader.parser.CurrentColumnNumber + 1
        raise ModelError([Issue(file, line, col, "", f"the document has {exc}")]) from None
    assert reader.root is not None  # expat refuses a document without one
    return reader.root


def _syntax_hint(what: str) -> str:
    if "mismatched tag" in what:
        return "an element closed with another element's name, or not closed"
    if "not well-formed" in what:
        return "a stray '<' or '&' (write &lt; or &amp;), or an unquoted attribute value"
    if "unclosed token" in what or "no element found" in what:
        return "the file ends inside an element: is a closing tag missing?"
    return ""


ROOTS = {"mjcf": "mujoco", "urdf": "robot"}
"""The root element of each XML model format."""
_YAML_KEY = re.compile(r"(?:[ \t]*(?:#[^\n]*)?\r?\n)*[ \t]*[\w-]+[ \t]*:(?:[ \t]|\r?\n|$)")
"""A YAML file's first entry ("model: pendulum"), after blank and comment lines."""


def read_model_xml(source: str | Path, file: str | None, budget: list[int],
                   fmt: str) -> tuple[Element, str]:
    """The root element of an MJCF or URDF model (`fmt`), and the name its messages give
    the file.

    `source` is a path, or XML text (starting with ``<``). A file that is no XML, or XML
    of the other format, is refused with the advice to read it as what it is.
    """
    text_given = not isinstance(source, Path) and str(source).lstrip().startswith("<")
    name = (("<string>" if text_given else str(source)) if file is None else file)
    text = str(source) if text_given else read_file(Path(source), None, fmt)
    start = len(text) - len(text.lstrip("\ufeff \t\r\n"))
    if start == len(text):
        raise ModelError([Issue(name, 1, 1, "", f"the file is empty; expected "
                                f"{MODEL_FORMATS[fmt][3]} (it starts with <{ROOTS[fmt]}>)")])
    if text[start] != "<":
        line = text.count("\n", 0, start) + 1
        column = start - (text.rfind("\n", 0, start) + 1) + 1
        raise ModelError([Issue(
            name, line, column, "", f"expected {MODEL_FORMATS[fmt][3]}, which is XML (it "
            f"starts with <{ROOTS[fmt]}>), got text that does not start with '<'",
            read_as("yaml") if _YAML_KEY.match(text, start) or text.startswith("#", start)
            else "")])
    root = parse_xml(text, name, budget)
    if root.tag != ROOTS[fmt]:
        other = next((f for f, tag in ROOTS.items() if tag == root.tag), None)
        raise ModelError([root.issue(
            f"expected <{ROOTS[fmt]}> as the root element, got <{root.tag}>",
            read_as(other) if other else f"{'an MJCF' if fmt == 'mjcf' else 'a URDF'} "
            f"model starts with <{ROOTS[fmt]}>")])
    return root, name


def unknown_name(e: Element, name: str, known: Iterable[str], what: str,
                 attr: str | None = None, hint: bool = True) -> Issue:
    """An issue for a name not in `known`, with a did-you-mean when one is close.

    Parameters
    ----------
    e : Element
        Where the name was written (the element itself, or its attribute `attr`).
    name : str
        The name as written.
    known : iterable of str
        The names accepted there.
    what : str
        What kind of name, for the message (``"element"``, ``"attribute of <joint>"``).
    attr : str, optional
        The attribute whose name is wrong.
    hint : bool, optional
        Look for a did-you-mean (False past the issues a message shows: a file of 200 000
        unknown names is refused without 200 000 searches).
    """
    said = ""
    if hint:
        choices = sorted(set(known))
        said = did_you_mean(name, choices)
        if not said and len(choices) <= 12:
            said = f"expected one of: {', '.join(choices)}" if choices else f"no {what} here"
    line, col = e.where(attr)
    key = f"<{e.tag}>" if attr is None else f"<{e.tag} {attr}>"
    return Issue(e.file, line, col, key, one_line(f"unknown {what} '{name}'"), one_line(said))


def second(e: Element, parent: Element, first: Element, allows: str) -> Issue:
    """The issue of `e`, a second child of `parent` like `first` where the format allows
    one: refused, never read in part (`allows` names who allows one: "URDF")."""
    at = (f"line {first.line}, column {first.column}" if first.file == e.file
          else f"{first.file}:{first.line}:{first.column}")
    return e.issue(f"a second <{e.tag}> in <{parent.tag}> (the first is at {at})",
                   f"{allows} allows one: merge them, or remove one")


_BREAKS = str.maketrans({"\n": "\\n", "\r": "\\r", "\x0b": "\\v", "\x0c": "\\f",
                         "\x1c": "\\x1c", "\x1d": "\\x1d", "\x1e": "\\x1e",
                         "\x85": "\\x85", "\u2028": "\\u2028", "\u2029": "\\u2029"})


def one_line(text: str) -> str:
    """`text` with its line breaks written as escapes: a value quoted in a message (a
    name written with ``&#10;``) must not start a line that looks like another problem."""
    return text.translate(_BREAKS)
