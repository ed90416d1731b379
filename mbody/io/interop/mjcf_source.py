"""The MJCF file as one element tree: ``<include>`` files expanded in place, every element
and attribute name checked against MuJoCo's schema (with did-you-means)."""

from __future__ import annotations

from pathlib import Path

from mbody.errors import Issue, ModelError
from mbody.io.interop.mjcf_schema import SCHEMA
from mbody.io.interop.xmlsource import Element, read_xml, unknown_name

MAX_INCLUDES = 100
"""Most ``<include>`` files read for one model."""


def expand_includes(e: Element, base: Path, budget: list[int], count: list[int],
                    chain: tuple[str, ...] = ()) -> None:
    """Replace each ``<include file=...>`` by the children of that file's root."""
    out: list[Element] = []
    for c in e.children:
        if c.tag != "include":
            expand_includes(c, base, budget, count, chain)
            out.append(c)
            continue
        rel = c.get("file")
        if not rel:
            raise ModelError([c.issue("an <include> needs a 'file'")])
        path = (base / rel).resolve()
        count[0] += 1
        if count[0] > MAX_INCLUDES:
            raise ModelError([c.issue(f"more than {MAX_INCLUDES} included files")])
        if str(path) in chain:
            raise ModelError([c.issue(f"'{rel}' includes itself (through "
                                      f"{' -> '.join(chain)})", attr="file")])
        if not path.is_file():
            raise ModelError([c.issue(f"the included file '{rel}' does not exist",
                                      f"looked for {path}", attr="file")])
        sub = read_xml(path, str(path), budget)
        if sub.tag != "mujoco":
            raise ModelError([sub.issue(f"an included file's root must be <mujoco>, got "
                                        f"<{sub.tag}>")])
        expand_includes(sub, path.parent, budget, count, (*chain, str(path)))
        out.extend(sub.children)
    e.children = out


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
                    issues.append(unknown_name(el, a, attrs, f"attribute of <{el.tag}>", a))
        for c in el.children:
            if p in SCHEMA and c.tag not in kids and not (p == "mujoco/body" and
                                                           c.tag == "frame"):
                issues.append(unknown_name(c, c.tag, kids, f"element in <{el.tag}>"))
                continue
            stack.append((c, _schema_path(p, c.tag)))
    issues.sort(key=lambda i: (i.line, i.column))

