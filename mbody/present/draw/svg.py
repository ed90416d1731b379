"""A scene written as SVG directly: one element per item, texts as glyph outlines.

Text is drawn as outlines (`<use>` of one `<path>` per glyph in `<defs>`, as
matplotlib's SVG backend does by default), so a picture looks the same in every viewer
whatever fonts it has. Glyph ids carry a prefix, so that several pictures inline in
one HTML page never clash.
"""

from __future__ import annotations

import math
import re
from html import escape

import numpy as np

from mbody.present.draw.fonts import GLYPHS, layout
from mbody.present.draw.scene import Disc, Item, Line, Panel, Poly, Scene, Text, Wedge

_HA = {"left": 0.0, "center": 0.5, "right": 1.0}
_VA = {"bottom": 0.0, "center": 0.5, "top": 1.0}


def text_box(t: Text, anchor: np.ndarray) -> tuple[float, float, float, float]:
    """(x0, y0, width, height) in points of text `t` whose anchor sits at `anchor`
    (points, offset not yet added)."""
    lay = layout(t.s, t.size, family=t.family, weight=t.weight, math=t.math,
                 linespacing=t.linespacing)
    x = anchor[0] + t.offset[0] - _HA[t.ha] * lay.width
    if t.va == "baseline":
        y = anchor[1] + t.offset[1] - lay.descent
    else:
        y = anchor[1] + t.offset[1] - _VA[t.va] * lay.height
    return x, y, lay.width, lay.height


def _n(v: float) -> str:
    s = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if s == "-0" else s


def _points(xy: np.ndarray, H: float) -> str:
    return " ".join(f"{_n(x)},{_n(H - y)}" for x, y in xy)


_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")
"""Characters XML 1.0 does not allow anywhere, not even escaped."""


def _xml(s: str) -> str:
    """`s` escaped for an attribute, a comment or a title: a character XML does not allow
    (a control character in a body's name) as ``<U+XXXX>``."""
    return escape(_NOT_XML.sub(lambda m: f"<U+{ord(m.group()):04X}>", s))


def _gid(gid: str | None) -> str:
    return f' id="{_xml(gid)}"' if gid else ""


class _Writer:
    def __init__(self, scene: Scene, prefix: str) -> None:
        self.H = scene.height
        self.prefix = prefix
        self.used: set[str] = set()
        self.hatch = False
        self.out: list[str] = []

    def stroke(self, color: str | None, lw: float, dash: tuple[float, ...] | None) -> str:
        if color is None or lw <= 0:
            return ' stroke="none"'
        s = f' stroke="{color}" stroke-width="{_n(lw)}"'
        if dash:
            s += ' stroke-dasharray="' + ",".join(_n(d * lw) for d in dash) + '"'
        return s

    def item(self, p: Panel, it: Item) -> None:
        H, o = self.H, self.out
        if isinstance(it, Line):
            o.append(f'<polyline{_gid(it.gid)} points="{_points(p.to_pt(it.xy), H)}" '
                     f'fill="none"{self.stroke(it.color, it.lw, it.dash)} '
                     'stroke-linejoin="round" stroke-linecap="butt"/>')
        elif isinstance(it, Poly):
            fill = it.face or "none"
            pts = _points(p.to_pt(it.xy), H)
            o.append(f'<polygon{_gid(it.gid)} points="{pts}" fill="{fill}"'
                     f'{self.stroke(it.edge, it.lw, None)} stroke-linejoin="miter"/>')
            if it.hatch:
                self.hatch = True
                o.append(f'<polygon points="{pts}" fill="url(#{self.prefix}hatch)" '
                         'stroke="none"/>')
        elif isinstance(it, Disc):
            c = p.to_pt(it.center)
            o.append(f'<circle{_gid(it.gid)} cx="{_n(c[0])}" cy="{_n(H - c[1])}" '
                     f'r="{_n(it.r * p.scale)}" fill="{it.face or "none"}"'
                     f'{self.stroke(it.edge, it.lw, None)}/>')
        elif isinstance(it, Wedge):
            c, r = p.to_pt(it.center), it.r * p.scale
            a0, a1 = math.radians(it.a0), math.radians(it.a1)
            x0, y0 = c[0] + r * math.cos(a0), H - (c[1] + r * math.sin(a0))
            x1, y1 = c[0] + r * math.cos(a1), H - (c[1] + r * math.sin(a1))
            large = 1 if (it.a1 - it.a0) % 360 > 180 else 0
            o.append(f'<path d="M{_n(c[0])} {_n(H - c[1])}L{_n(x0)} {_n(y0)}'
                     f'A{_n(r)} {_n(r)} 0 {large} 0 {_n(x1)} {_n(y1)}Z" fill="{it.face}"/>')
        else:
            self.text(p, it)

    def text(self, p: Panel, t: Text) -> None:
        lay = layout(t.s, t.size, family=t.family, weight=t.weight, math=t.math,
                     linespacing=t.linespacing, align=_HA[t.align or t.ha])
        x0, y0, w, h = text_box(t, p.to_pt(t.xy))
        o, H = self.out, self.H
        # the string beside its glyphs, as matplotlib writes it: searchable, diffable
        o.append(f"<g{_gid(t.gid)}>" + "".join(
            f"<!-- {_xml(line).replace('--', '- -')} -->" for line in t.s.split("\n")))
        if t.box is not None:
            pad = t.box.pad * t.size
            r = pad if t.box.round else 0.0
            o.append(f'<rect x="{_n(x0 - pad)}" y="{_n(H - (y0 + h + pad))}" '
                     f'width="{_n(w + 2 * pad)}" height="{_n(h + 2 * pad)}" rx="{_n(r)}" '
                     f'fill="{t.box.face}"{self.stroke(t.box.edge, t.box.lw, None)}/>')
        o.append(f'<g fill="{t.color}">')
        for g, gx, gy, s in lay.glyphs:
            self.used.add(g)
            o.append(f'<use xlink:href="#{self.prefix}{g}" transform="translate('
                     f'{_n(x0 + gx)} {_n(H - (y0 + gy))}) scale({s:.4g} {-s:.4g})"/>')
        o.append("</g></g>")


def scene_svg(scene: Scene, prefix: str = "", standalone: bool = False) -> str:
    """The scene as an SVG document (`standalone`: with an XML prolog) or element.

    Parameters
    ----------
    scene : Scene
    prefix : str
        Put before every id the picture defines (glyphs, patterns): use a different one
        for each picture inlined in one page.
    standalone : bool
        Start with ``<?xml ...?>`` (a file of its own).

    Returns
    -------
    str
    """
    w = _Writer(scene, prefix)
    body = w.out
    body.append(f'<rect width="{_n(scene.width)}" height="{_n(scene.height)}" '
                'fill="white"/>')
    for panel in (scene.root, *scene.panels):
        body.append(f"<g{_gid(panel.gid)}>")
        for it in sorted(panel.items, key=lambda i: i.zorder):  # stable: file order kept
            w.item(panel, it)
        body.append("</g>")
    defs = [f'<path id="{prefix}{g}" d="{GLYPHS[g]}"/>' for g in sorted(w.used)]
    if w.hatch:
        defs.append(f'<pattern id="{prefix}hatch" patternUnits="userSpaceOnUse" width="6" '
                    'height="6"><path d="M-1,1 l2,-2 M0,6 l6,-6 M5,7 l2,-2" '
                    'stroke="black" stroke-width="0.8"/></pattern>')
    head = ('<svg xmlns="http://www.w3.org/2000/svg" '
            'xmlns:xlink="http://www.w3.org/1999/xlink" '
            f'width="{_n(scene.width)}pt" height="{_n(scene.height)}pt" '
            f'viewBox="0 0 {_n(scene.width)} {_n(scene.height)}" version="1.1">')
    title = f"<title>{_xml(scene.title)}</title>" if scene.title else ""
    doc = "\n".join([head + title, "<defs>", *defs, "</defs>", *body, "</svg>"])
    if standalone:
        doc = '<?xml version="1.0" encoding="utf-8" standalone="no"?>\n' + doc + "\n"
    return doc
