"""The MJCF file as one element tree: ``<include>`` files expanded in place (bounded in
number and in bytes read together), every element and attribute name checked against
MuJoCo's schema (with did-you-means)."""

from __future__ import annotations

import stat
from dataclasses import dataclass
from pathlib import Path

from mbody.errors import Issue, ModelError
from mbody.io.interop.mjcf_schema import SCHEMA, UNIQUE
from mbody.io.interop.xmlsource import Element, parse_xml, second, unknown_name
from mbody.model.loader import file_kind, read_file
from mbody.util.formatting import sizes_apart

MAX_INCLUDES = 100
"""Most ``<include>`` files read for one model."""
MAX_INCLUDED_BYTES = 64 * 2**20
"""Most bytes read over all the ``<include>`` files of one model together (each file is
also under the size limit of any model file). The largest robot models (MuJoCo
Menagerie's, dm_control's) are under 2 MB with everything they include; without this
bound, 100 includes of one 30 MB file took 3.8 GB before running out of memory."""


@dataclass
class Included:
    """What the ``<include>``s of one model have read so far: files and bytes."""

    files: int = 0
    bytes: int = 0


def expand_includes(e: Element, base: Path, budget: list[int], included: Included,
                    chain: tuple[str, ...] = ()) -> None:
    """Replace each ``<include file=...>`` by the children of that file's root."""
    out: list[Element] = []
    for c in e.children:
        if c.tag != "include":
            expand_includes(c, base, budget, included, chain)
            out.append(c)
            continue
        rel = c.get("file")
        if not rel:
            raise ModelError([c.issue("an <include> needs a 'file'")])
        path = (base / rel).resolve()
        included.files += 1
        if included.files > MAX_INCLUDES:
            raise ModelError([c.issue(f"more than {MAX_INCLUDES} included files")])
        if str(path) in chain:
            raise ModelError([c.issue(f"'{rel}' includes itself (through "
                                      f"{' -> '.join(chain)})", attr="file")])
        try:
            st = path.stat()
        except FileNotFoundError:
            raise ModelError([c.issue(f"the included file '{_short(rel)}' does not exist",
                                      f"looked for {_short(str(path))}", attr="file")]
                             ) from None
        except OSError as exc:  # a name too long, a folder that cannot be read...
            raise ModelError([c.issue(f"cannot read the included file '{_short(rel)}': "
                                      f"{exc.strerror}", attr="file")]) from None
        # what the model file itself may be, less a pipe: reading one would wait for it
        kind = "a named pipe" if stat.S_ISFIFO(st.st_mode) else file_kind(st.st_mode)
        if kind:
            raise ModelError([c.issue(f"the included file '{_short(rel)}' is {kind}, not a "
                                      "file", f"it is {_short(str(path))}; an <include> "
                                      "names an MJCF file", attr="file")])
        size = st.st_size
        _count(c, rel, included, size)  # refused before it is read
        try:
            text = read_file(path)
        except ModelError as exc:  # too large, unreadable...: said at the include
            (problem,) = exc.issues
            if problem.line:  # (not UTF-8: at its own place in the included file)
                raise
            why = problem.message.removeprefix("cannot read the file: ")
            raise ModelError([c.issue(f"cannot read the included file '{_short(rel)}': "
                                      f"{why}", attr="file")]) from None
        included.bytes += len(text.encode("utf-8"))
        _count(c, rel, included, 0)  # it grew since
        sub = parse_xml(text, str(path), budget)
        if sub.tag != "mujoco":
            raise ModelError([sub.issue(f"an included file's root must be <mujoco>, got "
                                        f"<{sub.tag}>")])
        expand_includes(sub, path.parent, budget, included, (*chain, str(path)))
        out.extend(sub.children)
    e.children = out


def _count(c: Element, rel: str, included: Included, more: int) -> None:
    """Refuse the include `c` of `rel` if `more` bytes bring the included files over
    `MAX_INCLUDED_BYTES`."""
    total = included.bytes + more
    if total > MAX_INCLUDED_BYTES:
        size, most = sizes_apart(total, MAX_INCLUDED_BYTES)
        raise ModelError([c.issue(
            f"including '{rel}' brings the included files to {size} together "
            f"(include number {included.files}); at most {most} "
            "of included files is read for one model",
            "include each file once, or merge the model into fewer, smaller files",
            "file")])


def _short(text: str) -> str:
    return text if len(text) <= 200 else text[:100] + "..." + text[-40:]


def _schema_path(path: str, tag: str) -> str:
    if tag in ("worldbody", "body") and path in ("mujoco", "mujoco/body"):
        return "mujoco/body"
    if tag == "default" and path in ("mujoco", "mujoco/default"):
        return "mujoco/default"
    return f"{path}/{tag}"


def check_names(e: Element, path: str, issues: list[Issue]) -> None:
    """Every element and attribute name against MuJoCo's schema, with did-you-means."""
    stack = [(e, path)]
    while stack:
        el, p = stack.pop()
        attrs, kids = SCHEMA.get(p, (frozenset(), frozenset()))
        if p in SCHEMA:
            for a in el.attrib:
                if a not in attrs:
                    issues.append(unknown_name(el, a, attrs, f"attribute of <{el.tag}>", a,
                                               len(issues) < ModelError.SHOWN))
        later = []
        first: dict[str, Element] = {}  # a child MuJoCo allows once -> where it is
        for c in el.children:
            if p in SCHEMA and c.tag not in kids and not (p == "mujoco/body" and
                                                           c.tag == "frame"):
                issues.append(unknown_name(c, c.tag, kids, f"element in <{el.tag}>",
                                           hint=len(issues) < ModelError.SHOWN))
                continue
            child = _schema_path(p, c.tag)
            if child in UNIQUE:
                if c.tag in first:
                    issues.append(second(c, el, first[c.tag], "MuJoCo"))
                first.setdefault(c.tag, c)
            later.append((c, child))
        stack.extend(reversed(later))  # in file order: the issues come sorted
    issues.sort(key=lambda i: (i.line, i.column))

