"""MJCF's ``<default>`` classes: each class's attributes per element, its parent's
included, and an element's attributes over its class's (``class``, or the ``childclass``
of a body around it, or ``main``). Each value keeps the element it was written in, so a
bad value in a class is reported at the class's line; and every value an attribute took
on the way from the top class down is kept, since MuJoCo lets a shorter ``size`` keep
the trailing numbers of the class's."""

from __future__ import annotations

from mbody.errors import Issue, did_you_mean
from mbody.io.interop.xmlsource import Element

ORIENTATIONS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")
"""MJCF's five ways to give a frame's orientation: a class or element giving one of them
replaces whichever its class gave (MuJoCo refuses two on one element)."""
Layers = list[tuple[str, Element]]
"""An attribute's values from the outermost class down to the element, each with the
element it was written in (the last one is the value in force)."""


class Values(dict[str, str]):
    """An element's attributes over its default class's: name -> the value in force.

    `origin(name)` is the element the value was written in (the element itself, or a
    ``<default>`` class's child); `layers(name)` every value it took on the way."""

    def __init__(self, layers: dict[str, Layers]):
        super().__init__((k, v[-1][0]) for k, v in layers.items())
        self._layers = layers

    def origin(self, name: str) -> Element | None:
        """Where the value of `name` was written (None when it is not given)."""
        layers = self._layers.get(name)
        return layers[-1][1] if layers else None

    def layers(self, name: str) -> Layers:
        """Every value of `name`, outermost class first (empty when it is not given)."""
        return self._layers.get(name, [])


class Defaults:
    """The ``<default>`` classes of one model, by name (``main``: the top level)."""

    def __init__(self) -> None:
        self.classes: dict[str, dict[str, dict[str, Layers]]] = {}

    def read(self, d: Element, parent: str | None, issues: list[Issue]) -> None:
        """Add the class ``d`` (a ``<default>``) and the classes nested in it."""
        name = d.get("class") or ("main" if parent is None else None)
        if name is None:
            issues.append(d.issue("a nested <default> needs a 'class'"))
            return
        base = self.classes.get(parent or "", {}) if parent is not None else {}
        own: dict[str, dict[str, Layers]] = {
            tag: {k: list(v) for k, v in attrs.items()} for tag, attrs in base.items()}
        if name in self.classes and parent is not None:
            issues.append(d.issue(f"the default class '{name}' is defined twice",
                                  attr="class"))
        for c in d.children:
            if c.tag == "default":
                continue
            attrs = own.setdefault(c.tag, {})
            _add(attrs, c)
        if name in self.classes:  # a second top-level <default>: adds to main
            for tag, attrs in own.items():
                into = self.classes[name].setdefault(tag, {})
                for k, layers in attrs.items():
                    into.setdefault(k, []).extend(layers)
        else:
            self.classes[name] = own
        for c in d.findall("default"):
            self.read(c, name, issues)

    def values(self, e: Element, childclass: str | None, issues: list[Issue]) -> Values:
        """The element's attributes over its default class's."""
        cls = e.get("class") or childclass or "main"
        if cls not in self.classes and cls != "main":
            issues.append(e.issue(f"unknown default class '{cls}'",
                                  did_you_mean(cls, self.classes), "class" if e.get("class")
                                  else None))
            cls = "main"
        layers = {k: list(v) for k, v in self.classes.get(cls, {}).get(e.tag, {}).items()}
        _add(layers, e)
        return Values(layers)


def _add(layers: dict[str, Layers], e: Element) -> None:
    """`e`'s attributes over `layers` (in place)."""
    if any(k in e.attrib for k in ORIENTATIONS):
        for k in ORIENTATIONS:
            layers.pop(k, None)
    for k, v in e.attrib.items():
        layers.setdefault(k, []).append((v, e))
