"""MJCF's ``<default>`` classes: each class's attributes per element, its parent's
included, and an element's attributes over its class's (``class``, or the ``childclass``
of a body around it, or ``main``)."""

from __future__ import annotations

from mbody.errors import Issue, did_you_mean
from mbody.io.interop.xmlsource import Element


class Defaults:
    """The ``<default>`` classes of one model, by name (``main``: the top level)."""

    def __init__(self) -> None:
        self.classes: dict[str, dict[str, dict[str, str]]] = {}

    def read(self, d: Element, parent: str | None, issues: list[Issue]) -> None:
        """Add the class ``d`` (a ``<default>``) and the classes nested in it."""
        name = d.get("class") or ("main" if parent is None else None)
        if name is None:
            issues.append(d.issue("a nested <default> needs a 'class'"))
            return
        base = self.classes.get(parent or "", {}) if parent is not None else {}
        own: dict[str, dict[str, str]] = {k: dict(v) for k, v in base.items()}
        if name in self.classes and parent is not None:
            issues.append(d.issue(f"the default class '{name}' is defined twice",
                                  attr="class"))
        for c in d.children:
            if c.tag == "default":
                continue
            own.setdefault(c.tag, {}).update(c.attrib)
        if name in self.classes:  # a second top-level <default>: adds to main
            for k, v in own.items():
                self.classes[name].setdefault(k, {}).update(v)
        else:
            self.classes[name] = own
        for c in d.findall("default"):
            self.read(c, name, issues)

    def values(self, e: Element, childclass: str | None, issues: list[Issue]
               ) -> dict[str, str]:
        """The element's attributes over its default class's."""
        cls = e.get("class") or childclass or "main"
        if cls not in self.classes and cls != "main":
            issues.append(e.issue(f"unknown default class '{cls}'",
                                  did_you_mean(cls, self.classes), "class" if e.get("class")
                                  else None))
            cls = "main"
        out = dict(self.classes.get(cls, {}).get(e.tag, {}))
        out.update(e.attrib)
        return out
