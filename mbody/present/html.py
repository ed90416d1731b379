"""Small builders of well-formed XHTML fragments for the notebook displays.

Every piece of text goes through `e` (``html.escape``); markup that is already built
(a table, an inline SVG) is wrapped in `Markup` so that it is not escaped twice. The
output is XML as well as HTML (every element closed, attributes quoted, no named
entities but XML's), so tests can parse it with ``xml.etree``.
"""

from __future__ import annotations

import html
from collections.abc import Iterable, Sequence

STYLE = (
    ".mbody{font-family:sans-serif;font-size:13px;line-height:1.35}"
    ".mbody table{border-collapse:collapse;margin:4px 0 8px 0}"
    ".mbody th,.mbody td{border:1px solid #ccd;padding:2px 6px;text-align:left;"
    "vertical-align:top}"
    ".mbody th{background:#eef1f5}"
    ".mbody td.num{text-align:right;font-variant-numeric:tabular-nums}"
    ".mbody .muted{color:#667}"
    ".mbody code,.mbody pre{font-family:monospace;font-size:12px}"
    ".mbody pre{margin:2px 0 6px 0}"
    ".mbody .warn{color:#a30}"
    ".mbody figure{margin:4px 0}"
    ".mbody svg{max-width:100%;height:auto}"
)
"""One style block, scoped to the displays' outer ``div.mbody``."""


VOID = frozenset({"img", "br", "hr"})
"""Elements without content, written ``<img .../>`` (valid HTML and XML)."""


class Markup(str):
    """Text that is already HTML: `e` and the builders leave it as it is."""


def e(text: object) -> str:
    """`text` escaped for HTML and XML (``&<>"'``); `Markup` passes through.

    Parameters
    ----------
    text : object
        Anything; its ``str()`` is escaped.

    Returns
    -------
    str
    """
    return text if isinstance(text, Markup) else html.escape(str(text), quote=True)


def tag(name: str, *content: object, **attrs: object) -> Markup:
    """``<name attrs>content</name>``: content escaped unless `Markup`.

    Parameters
    ----------
    name : str
        The element's name.
    *content : object
        Its children, in order.
    **attrs : object
        Attributes; ``class_`` is written ``class``; None values are left out.
        An element of `VOID` (``img``...) takes no content.

    Returns
    -------
    Markup
    """
    at = "".join(f' {k.rstrip("_")}="{e(v)}"' for k, v in attrs.items() if v is not None)
    if name in VOID:
        return Markup(f"<{name}{at}/>")
    return Markup(f"<{name}{at}>" + "".join(e(c) for c in content) + f"</{name}>")


def table(header: Sequence[object], rows: Iterable[Sequence[object]],
          numeric: Iterable[int] = ()) -> Markup:
    """A table with one header row; columns whose index is in `numeric` align right.

    Parameters
    ----------
    header : sequence
        The column titles.
    rows : iterable of sequences
        The cells, row by row (escaped unless `Markup`).
    numeric : iterable of int
        Columns of numbers.

    Returns
    -------
    Markup
    """
    num = set(numeric)
    head = tag("tr", *(tag("th", h) for h in header))
    body = [tag("tr", *(tag("td", c, class_="num" if k in num else None)
                        for k, c in enumerate(r))) for r in rows]
    return tag("table", head, *body)


def block(title: str, *parts: object, note: str = "") -> Markup:
    """The outer ``div.mbody`` of one display: style, a bold title, the parts, and a
    closing line (`note`, e.g. what to call next) in grey.

    Parameters
    ----------
    title : str
        The first line.
    *parts : object
        The content (escaped unless `Markup`).
    note : str
        The last line.

    Returns
    -------
    Markup
    """
    tail = [tag("p", note, class_="muted")] if note else []
    return tag("div", tag("style", Markup(STYLE)), tag("p", tag("b", title)), *parts, *tail,
               class_="mbody")
