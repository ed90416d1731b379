"""Text without matplotlib's text layout: advances, kerning and glyph outlines of the
fonts matplotlib ships (DejaVu Sans, Sans Mono), read once per character and cached.

matplotlib lays out every text again at each draw and for each backend (most of a
diagram's cost). A diagram's texts use a few dozen distinct characters, so measuring
and outlining each character once makes a label's layout a handful of dict look-ups.
Glyphs are measured at `UNIT` points and scaled to each text's size, as matplotlib's
`TextToPath` does, so an SVG from here draws the same outlines matplotlib would.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from matplotlib import font_manager
from matplotlib.font_manager import FontProperties
from matplotlib.ft2font import FT2Font, GlyphIndexType, Kerning, LoadFlags
from matplotlib.textpath import text_to_path

UNIT = 100.0
"""Glyphs are measured and outlined at this size (points, at 72 dpi)."""

GLYPHS: dict[str, str] = {}
"""Glyph id -> its outline as SVG path data, at UNIT points, y up."""

_ID = re.compile(r"[^A-Za-z0-9_-]")


@dataclass(frozen=True, slots=True)
class Layout:
    """One text laid out: width, height and descent (points); glyphs as (glyph id, x, y,
    scale) with x, y from the lower left corner of the text's box (points, y up)."""

    width: float
    height: float
    descent: float
    glyphs: tuple[tuple[str, float, float, float], ...]


class _Font:
    """One face at UNIT size: per-character glyph index, advance and outline."""

    def __init__(self, family: str, weight: str) -> None:
        self.prop = FontProperties(family=[family], weight=weight, size=UNIT)
        self.ft: FT2Font = font_manager.get_font(font_manager.findfont(self.prop))
        self.name = _ID.sub("_", self.ft.postscript_name)
        self.chars: dict[str, tuple[int, float, str]] = {}  # char -> (index, advance, id)
        self.kern: dict[tuple[int, int], float] = {}
        # matplotlib's line metrics: the height and descent of "lp"
        _, self.lp_h, self.lp_d = text_to_path.get_text_width_height_descent(
            "lp", self.prop, False)

    def char(self, c: str) -> tuple[int, float, str]:
        got = self.chars.get(c)
        if got is None:
            ft = self.ft  # shared with matplotlib: set its size before every use
            ft.set_size(UNIT, 72)
            g = ft.load_char(ord(c), flags=LoadFlags.NO_HINTING)
            index = ft.get_char_index(ord(c))
            gid = f"{self.name}-{index:x}"
            if gid not in GLYPHS:
                verts, codes = ft.get_path()
                GLYPHS[gid] = path_data(verts, codes)
            got = self.chars[c] = (index, g.linearHoriAdvance / 65536.0, gid)
        return got

    def kerning(self, left: int, right: int) -> float:
        k = self.kern.get((left, right))
        if k is None:
            self.ft.set_size(UNIT, 72)
            k = self.kern[left, right] = self.ft.get_kerning(
                GlyphIndexType(left), GlyphIndexType(right), Kerning.DEFAULT) / 64.0
        return k


@lru_cache(maxsize=8)
def _font(family: str, weight: str) -> _Font:
    return _Font("DejaVu Sans Mono" if family == "mono" else "DejaVu Sans", weight)


def path_data(verts: np.ndarray, codes: np.ndarray) -> str:
    """SVG path data of a matplotlib path (MOVETO 1, LINETO 2, CURVE3 3, CURVE4 4,
    CLOSEPOLY 79)."""
    out, i, n = [], 0, len(codes)
    while i < n:
        c = codes[i]
        if c == 1:
            out.append(f"M{verts[i][0]:.2f} {verts[i][1]:.2f}")
            i += 1
        elif c == 2:
            out.append(f"L{verts[i][0]:.2f} {verts[i][1]:.2f}")
            i += 1
        elif c == 3:
            out.append("Q" + " ".join(f"{v:.2f}" for v in verts[i:i + 2].ravel()))
            i += 2
        elif c == 4:
            out.append("C" + " ".join(f"{v:.2f}" for v in verts[i:i + 3].ravel()))
            i += 3
        else:
            out.append("Z")
            i += 1
    return "".join(out)


def layout(s: str, size: float, *, family: str = "sans", weight: str = "normal",
           math: bool = False, linespacing: float = 1.2, align: float = 0.0) -> Layout:
    """Lay out text `s` at `size` points (lines split at newlines).

    Parameters
    ----------
    s : str
        Plain text, or one mathtext formula when `math`.
    size : float
        Font size in points.
    family, weight : str
        'sans' or 'mono'; 'normal' or 'bold'.
    math : bool
        Parse `s` as mathtext (matplotlib's parser; cached per string).
    linespacing : float
        Line pitch in multiples of the font's line height, as matplotlib's.
    align : float
        Where shorter lines sit: 0 left, 0.5 centred, 1 right.

    Returns
    -------
    Layout
    """
    if math:
        return _math(s, family, weight, size)
    return _plain(s, family, weight, size, linespacing, align)


@lru_cache(maxsize=4096)
def _plain(s: str, family: str, weight: str, size: float, linespacing: float,
           align: float) -> Layout:
    f = _font(family, weight)
    k = size / UNIT
    h, d = f.lp_h, f.lp_d
    pitch = (h - d) * linespacing
    lines = s.split("\n")
    height = (h - d) + (len(lines) - 1) * pitch + d
    rows: list[tuple[float, list[tuple[str, float, float, float]]]] = []
    for i, line in enumerate(lines):
        base = height - (h - d) - i * pitch
        x, prev = 0.0, -1
        row = []
        for c in line:
            index, adv, gid = f.char(c)
            if prev >= 0:
                x += f.kerning(prev, index)
            if not c.isspace():
                row.append((gid, x * k, base * k, k))
            x += adv
            prev = index
        rows.append((x * k, row))
    width = max(w for w, _ in rows)
    glyphs = tuple(((g, x + align * (width - w), y, s) for w, row in rows
                    for g, x, y, s in row))
    return Layout(width, height * k, d * k, glyphs)


@lru_cache(maxsize=256)
def _math(s: str, family: str, weight: str, size: float) -> Layout:
    prop = _font(family, weight).prop
    w, h, d = text_to_path.get_text_width_height_descent(s, prop, True)
    info, gmap, _ = text_to_path.get_glyphs_mathtext(prop, s)
    k = size / UNIT
    glyphs = []
    for rep, x, y, scale in info:
        gid = "m" + _ID.sub("_", rep)
        if gid not in GLYPHS:
            verts, codes = gmap[rep]
            GLYPHS[gid] = path_data(np.asarray(verts), np.asarray(codes))
        glyphs.append((gid, float(x) * k, (float(y) + d) * k, scale * k))
    return Layout(w * k, h * k, d * k, tuple(glyphs))
