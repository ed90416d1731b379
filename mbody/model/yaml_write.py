"""A model document (the plain data a model file parses to) written as mbody YAML.

The layout is that of the shipped models: top-level keys in the contract's order, each
body a block mapping whose values are one-line flow collections, each load, joint and
driver one flow mapping per line when it fits, known reactions one per line. Numbers are
written so that they read back as the same double (``repr``, with a decimal point before
an exponent so that YAML 1.1 readers such as PyYAML see a number too); text is quoted
whenever a plain scalar could read as something else.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from mbody import __version__
from mbody.model.loader import resolve_plain
from mbody.util.atomic import write_atomic

TOP_ORDER = ("model", "description", "dimension", "gravity", "bodies", "loads", "joints",
             "drivers", "reactions")
BODY_ORDER = ("name", "mass", "inertia", "shape", "position", "angle", "orientation",
              "velocity", "angular_velocity", "color")
LOAD_ORDER = ("name", "type", "body", "bodies", "force", "torque", "at", "frame",
              "stiffness", "rest_length", "damping")
JOINT_ORDER = ("name", "type", "parent", "child", "at", "axis", "axis2", "pitch")
DRIVER_ORDER = ("name", "joint", "angle", "displacement", "speed")
FLOW_ORDER = {"loads": LOAD_ORDER, "joints": JOINT_ORDER, "drivers": DRIVER_ORDER}
"""The sections written one flow mapping per item, and the order of their keys."""

WIDTH = 92
"""Longest line of a load or joint, which continues on the next line beyond it."""

_PLAIN = r"[A-Za-z_][A-Za-z0-9_.\-]*|[-+]?[0-9.]+([eE][-+]?[0-9]+)? deg"
"""Text written without quotes when it reads back as itself. A pattern, compiled by `re`
on first use and kept in its cache: compiling it at import cost 0.2 ms of every
simulation's start (a run carries its model's YAML, and imports this writer)."""
_YAML11_WORDS = frozenset(("y", "n", "yes", "no", "on", "off"))
"""Words YAML 1.1 readers take as booleans (mbody reads YAML 1.2): quoted, for them."""


def dump_document(document: Mapping[str, Any], *, source: str | None,
                  notes: Sequence[str] = ()) -> str:
    """A model document as mbody YAML text, with a comment header naming its source.

    Parameters
    ----------
    document : mapping
        The plain structure a model file parses to (`mbody.model.loader.load_text`'s
        ``.data``, or what a reader of another format builds).
    source : str or None
        The file converted from, named in the header (None: not named).
    notes : sequence of str, optional
        More header lines (what the conversion changed or left out).

    Returns
    -------
    str
        YAML text; `mbody.loads` of it gives the same model as the document.
    """
    origin = f" from {source}" if source else ""
    head = [f"Converted by mbody {__version__} (mbody convert){origin}.",
            "Edit freely: this is an ordinary mbody model file (docs/model-format.md).",
            *notes]
    lines = ["# " + h if h else "#" for text in head for h in text.splitlines() or [""]]
    for key in _ordered(document, TOP_ORDER):
        value = document[key]
        if key == "bodies" and value and _is_list_of_maps(value):
            lines.append("bodies:")
            for body in value:
                lines += _block_item(body, BODY_ORDER)
        elif key in FLOW_ORDER and value and _is_list_of_maps(value):
            lines.append(f"{key}:")
            for item in value:
                lines += _wrapped_flow(item, FLOW_ORDER[key])
        elif key == "reactions" and isinstance(value, Mapping) and value:
            lines.append("reactions:")
            lines += [f"  {_scalar(k)}: {_flow(v)}" for k, v in value.items()]
        else:
            lines.append(f"{_scalar(key)}: {_flow(value)}")
    return "\n".join(lines) + "\n"


def write_document(document: Mapping[str, Any], path: str | os.PathLike[str], *,
                   source: str | None, notes: Sequence[str] = ()) -> Path:
    """Write `dump_document(document, ...)` to `path` atomically.

    Parameters
    ----------
    document : mapping
        As for `dump_document`.
    path : str or os.PathLike
        The ``.yaml`` file to write (replaced whole, or left as it was on failure).
    source : str or None
        The file converted from, named in the header.
    notes : sequence of str, optional
        More header lines.

    Returns
    -------
    Path
        `path`.
    """
    return write_atomic(path, dump_document(document, source=source, notes=notes))


def _wrapped_flow(item: Mapping[str, Any], order: Sequence[str]) -> list[str]:
    """One list item as a flow mapping, continued on further lines (indented under its
    opening brace) where it would pass `WIDTH`, as the shipped models write joints."""
    parts = [f"{_scalar(k)}: {_flow(item[k])}" for k in _ordered(item, order)]
    lines, cur = [], "  - {"
    for k, part in enumerate(parts):
        piece = part + ("}" if k == len(parts) - 1 else ",")
        if cur.strip(" -{") and len(cur) + 1 + len(piece) > WIDTH:
            lines.append(cur)
            cur = "     " + piece
        else:
            cur += ("" if cur.endswith("{") else " ") + piece
    return [*lines, cur if parts else "  - {}"]


def _block_item(item: Mapping[str, Any], order: Sequence[str]) -> list[str]:
    """One list item as a block mapping: ``  - name: ...`` then ``    key: value``; a
    3 x 3 matrix (an inertia tensor, a rotation) one row per line."""
    out = []
    for k, key in enumerate(_ordered(item, order)):
        lead = "  - " if k == 0 else "    "
        value = item[key]
        if _is_matrix(value):
            out.append(f"{lead}{_scalar(key)}:")
            out += [f"      - {_flow(row)}" for row in value]
        elif isinstance(value, Mapping) and any(_is_matrix(v) for v in value.values()):
            out.append(f"{lead}{_scalar(key)}:")  # orientation: {matrix: [[...], ...]}
            for sub in value:
                if _is_matrix(value[sub]):
                    out.append(f"      {_scalar(sub)}:")
                    out += [f"        - {_flow(row)}" for row in value[sub]]
                else:
                    out.append(f"      {_scalar(sub)}: {_flow(value[sub])}")
        else:
            out.append(f"{lead}{_scalar(key)}: {_flow(value)}")
    return out


def _flow(value: Any, order: Sequence[str] = ()) -> str:
    """`value` as one line of flow YAML."""
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_scalar(k)}: {_flow(value[k])}"
                               for k in _ordered(value, order)) + "}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_flow(v) for v in value) + "]"
    return _scalar(value)


def _scalar(x: Any) -> str:
    """A scalar that reads back as itself (YAML 1.2, and 1.1 where they differ)."""
    if x is None:
        return "null"
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        return _float(x)
    if hasattr(x, "item") and not isinstance(x, str):  # a numpy scalar
        return _scalar(x.item())
    text = str(x)
    if (re.fullmatch(_PLAIN, text) and text.lower() not in _YAML11_WORDS
            and _reads_as_text(text)):
        return text
    return json.dumps(text, ensure_ascii=False)  # a YAML double-quoted scalar


def _reads_as_text(text: str) -> bool:
    try:
        return resolve_plain(text) == text
    except Exception:  # a form mbody's reader refuses (0x1f, 1_000): quote it
        return False


def _float(x: float) -> str:
    if math.isnan(x):
        return ".nan"
    if math.isinf(x):
        return ".inf" if x > 0 else "-.inf"
    text = repr(x)
    if "e" in text and "." not in text.partition("e")[0]:
        mantissa, _, exponent = text.partition("e")
        text = f"{mantissa}.0e{exponent}"
    return text


def _ordered(mapping: Mapping[str, Any], order: Iterable[str]) -> list[str]:
    """The keys of `mapping`: those in `order` first, in that order, then the others."""
    known = [k for k in order if k in mapping]
    return known + [k for k in mapping if k not in known]


def _is_list_of_maps(value: Any) -> bool:
    return isinstance(value, list) and all(isinstance(v, Mapping) for v in value)


def _is_matrix(value: Any) -> bool:
    return (isinstance(value, list) and len(value) == 3
            and all(isinstance(r, list) and len(r) == 3 for r in value))
