"""The registry of joint types: one module per type in this folder, each defining its
planar and/or spatial `JointType` (`PLANAR_TYPE`, `SPATIAL_TYPE`) and its place in the
listing (`ORDER`). Validation, labels, the compiled core's components, symbolic rows,
`verify`, free-body diagrams, exports and interop all ask this registry; adding a type is
adding a module (docs/joint-types.md).
"""

from __future__ import annotations

import importlib
import pkgutil

from mbody.joint_types.base import (
    BALL,
    FORCE,
    MOMENT,
    PLANAR,
    ROTATION,
    SPATIAL,
    TRANSLATION,
    UNITS,
    WRENCH,
    Component,
    JointType,
    Motion,
    Param,
)

__all__ = ["BALL", "FORCE", "MOMENT", "PLANAR", "ROTATION", "SPATIAL", "TRANSLATION",
           "WRENCH", "Component", "JointType", "Motion", "Param", "TYPES", "ALIASES",
           "joint_type", "type_names", "what", "unit", "is_moment", "COMPONENT_NAMES",
           "COMPONENT_CODE", "WHATS", "docs_table"]


def _collect() -> dict[int, dict[str, JointType]]:
    found: list[tuple[int, str, JointType]] = []
    for info in pkgutil.iter_modules(__path__):
        if info.name == "base":
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")  # this package's own
        order = getattr(module, "ORDER", 100)
        for attr in ("PLANAR_TYPE", "SPATIAL_TYPE"):
            jt = getattr(module, attr, None)
            if isinstance(jt, JointType):
                found.append((order, jt.name, jt))
    out: dict[int, dict[str, JointType]] = {PLANAR: {}, SPATIAL: {}}
    for _, _, jt in sorted(found, key=lambda f: (f[0], f[1])):
        out[jt.dimension][jt.name] = jt
    return out


TYPES = _collect()
"""dimension (2, 3) -> type name -> `JointType`, in listing order."""

ALIASES: dict[int, dict[str, str]] = {
    d: {alias: jt.name for jt in types.values() for alias in jt.aliases}
    for d, types in TYPES.items()}
"""dimension -> another program's name for a type (hinge, slide, ball...) -> mbody's."""


def joint_type(dimension: int, name: str) -> JointType:
    """The type `name` of a `dimension` (2 or 3) model; KeyError when there is none."""
    return TYPES[dimension][name]


def type_names(dimension: int) -> tuple[str, ...]:
    """The joint type names of a planar (2) or spatial (3) model, in listing order."""
    return tuple(TYPES[dimension])


def _whats() -> dict[str, str]:
    out: dict[str, str] = {}
    for types in TYPES.values():
        for jt in types.values():
            for c in (*jt.components, *(c for cs in jt.particle.values() for c in cs)):
                if out.setdefault(c.name, c.what) != c.what:  # a name means one thing
                    raise RuntimeError(f"joint component {c.name!r} is both "
                                       f"{out[c.name]} and {c.what}")
    # a driver's effort (mbody.model drivers): a moment about, or a force along, its axis
    out.setdefault("M", MOMENT)
    out.setdefault("F", FORCE)
    return out


WHATS = _whats()
"""component name (the label's suffix) -> `FORCE`, `MOMENT` or `WRENCH`."""

COMPONENT_NAMES = tuple(WHATS)
"""Every component name, in a fixed order: `mbody.model.ReactionTable.component` indexes it."""
COMPONENT_CODE = {name: k for k, name in enumerate(COMPONENT_NAMES)}


def docs_table() -> str:
    """The joint types and their reaction components as docs/model-format.md shows them
    (a markdown table; tests/test_joint_types.py holds the page to it)."""
    rows = ["| type | planar components | spatial components |", "| --- | --- | --- |"]
    for name in dict.fromkeys((*TYPES[PLANAR], *TYPES[SPATIAL])):
        cells = []
        for d in (PLANAR, SPATIAL):
            jt = TYPES[d].get(name)
            cells.append(f"`{', '.join(jt.component_names)}`" if jt else "—")
        rows.append(f"| `{name}` | {cells[0]} | {cells[1]} |")
    return "\n".join(rows)


def what(label: str) -> str:
    """`FORCE`, `MOMENT` or `WRENCH` for a reaction label (``A.Mx``) or component name."""
    return WHATS[label.rpartition(".")[2]]


def unit(label: str) -> str:
    """The unit of a reaction label's value: ``N`` or ``N m``."""
    return UNITS[what(label)]


def is_moment(label: str) -> bool:
    """Whether a reaction label's value is a moment (N m)."""
    return what(label) == MOMENT
