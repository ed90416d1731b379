"""Text without matplotlib's text layout: advances, kerning and glyph outlines of the
fonts matplotlib ships (DejaVu Sans, Sans Mono), read once per character and cached.

matplotlib lays out every text again at each draw and for each backend (most of a
diagram's cost). A diagram's texts use a few dozen distinct characters, so measuring
and outlining each character once makes a label's layout a handful of dict look-ups.
Glyphs are measured at `UNIT` points and scaled to each text's size, as matplotlib's
`TextToPath` does, so an SVG from here draws the same outlines matplotlib would.
"""

from __future__ import annotations

import math
import re
import unicodedata
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
        # char -> (index, advance, id, ink bottom, ink top; (inf, -inf) without ink)
        self.chars: dict[str, tuple[int, float, str, float, float]] = {}
        self.kern: dict[tuple[int, int], float] = {}
        # matplotlib's line height (>= 3.11; 3.10 measured "lp"): linespacing ×
        # (ascender + descender) of the font's OS/2 (else hhea) table, whatever the line
        # holds
        self.line = _font_height(self.ft)
        self.codes = frozenset(self.ft.get_charmap())  # the characters it can draw

    def char(self, c: str) -> tuple[int, float, str, float, float]:
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
            x0, y0, x1, y1 = g.bbox  # 26.6 fixed point; all 0 for a glyph without ink
            lo, hi = (y0 / 64.0, y1 / 64.0) if (x0, y0, x1, y1) != (0, 0, 0, 0) else (
                math.inf, -math.inf)
            got = self.chars[c] = (index, g.linearHoriAdvance / 65536.0, gid, lo, hi)
        return got

    def kerning(self, left: int, right: int) -> float:
        k = self.kern.get((left, right))
        if k is None:
            self.ft.set_size(UNIT, 72)
            k = self.kern[left, right] = self.ft.get_kerning(
                GlyphIndexType(left), GlyphIndexType(right), Kerning.DEFAULT) / 64.0
        return k


def _font_height(ft: FT2Font) -> float:
    """Ascender + descender (points at UNIT size), as matplotlib's text layout reads
    them: OS/2 typo metrics, else hhea."""
    head = ft.get_sfnt_table("head")
    units = head["unitsPerEm"] if head is not None else 2048
    os2 = ft.get_sfnt_table("OS/2")
    if os2 is not None:
        return (os2["sTypoAscender"] - os2["sTypoDescender"]) * UNIT / units
    hhea = ft.get_sfnt_table("hhea")
    if hhea is not None:
        return (hhea["ascent"] - hhea["descent"]) * UNIT / units
    return 1.2 * UNIT


def _line_box(ink_top: float, ink_bottom: float, line: float) -> tuple[float, float]:
    """A line's (ascent, descent) in matplotlib's fixed-spacing layout: its ink (top
    and bottom above the baseline) centred in a box `line` high."""
    if ink_top < ink_bottom:  # no ink: matplotlib measures 0 high
        ink_top = ink_bottom = 0.0
    lead = (line - (ink_top - ink_bottom)) / 2
    return ink_top + lead, -ink_bottom + lead


@lru_cache(maxsize=8)
def _font(family: str, weight: str) -> _Font:
    return _Font("DejaVu Sans Mono" if family == "mono" else "DejaVu Sans", weight)


_UNSEEN = frozenset(("Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"))
"""Unicode categories drawn as nothing, or not at all (controls, format characters such
as U+200B, surrogates, private use, unassigned, line and paragraph separators)."""


@lru_cache(maxsize=4096)
def drawable(s: str, family: str = "sans", weight: str = "normal") -> str:
    """`s` as a picture shows it: each character the font cannot draw (杆 in DejaVu Sans,
    an emoji in DejaVu Sans Mono), or that would draw as nothing (a control or format
    character such as U+200B), written as ``<U+XXXX>``; newlines stay.

    DejaVu has no CJK glyphs, and a missing glyph is an error in FreeType, a box or a
    warning in matplotlib: the code point keeps a name recognisable, and two names that
    differ only there different, while text outputs keep every name exact.

    Parameters
    ----------
    s : str
    family, weight : str
        The font: 'sans' or 'mono'; 'normal' or 'bold'.

    Returns
    -------
    str
    """
    codes = _font(family, weight).codes
    if s.isascii() and s.replace("\n", "").isprintable():  # the usual case: nothing to do
        return s
    return "".join(c if c == "\n" or (ord(c) in codes and unicodedata.category(c)
                                      not in _UNSEEN) else f"<U+{ord(c):04X}>" for c in s)


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
        return _math(s, family, weight, size, linespacing)
    return _plain(s, family, weight, size, linespacing, align)


@lru_cache(maxsize=4096)
def _plain(s: str, family: str, weight: str, size: float, linespacing: float,
           align: float) -> Layout:
    """matplotlib's layout of a plain text (`Text._get_layout`, fixed line spacing):
    each line a box linespacing × the font height high with its ink centred in it,
    the lines stacked; width from the advances and kerning."""
    f = _font(family, weight)
    s = drawable(s, family, weight)
    k = size / UNIT
    box = linespacing * f.line
    rows: list[tuple[float, float, float, list[tuple[str, float]]]] = []
    for line in s.split("\n"):
        x, prev, lo, hi = 0.0, -1, math.inf, -math.inf
        row = []
        for c in line:
            index, adv, gid, g_lo, g_hi = f.char(c)
            if prev >= 0:
                x += f.kerning(prev, index)
            if g_lo <= g_hi:
                row.append((gid, x))
                lo, hi = min(lo, g_lo), max(hi, g_hi)
            x += adv
            prev = index
        a, d = _line_box(hi, lo, box)
        rows.append((x, a, d, row))
    width = max(w for w, _, _, _ in rows)
    height = sum(a + d for _, a, d, _ in rows)
    glyphs = []
    top = height
    for w, a, d, row in rows:
        base = top - a
        dx = align * (width - w)
        glyphs += [(g, (x + dx) * k, base * k, k) for g, x in row]
        top -= a + d
    return Layout(width * k, height * k, rows[-1][2] * k, tuple(glyphs))


@lru_cache(maxsize=256)
def _math(s: str, family: str, weight: str, size: float, linespacing: float) -> Layout:
    f = _font(family, weight)
    prop = f.prop
    w, h, d = text_to_path.get_text_width_height_descent(s, prop, True)
    # its box as matplotlib lays out one line: the formula centred in linespacing ×
    # the font height
    a, d_box = _line_box(h - d, -d, linespacing * f.line)
    info, gmap, _ = text_to_path.get_glyphs_mathtext(prop, s)
    k = size / UNIT
    glyphs = []
    for rep, x, y, scale in info:
        gid = "m" + _ID.sub("_", rep)
        if gid not in GLYPHS:
            verts, codes = gmap[rep]
            GLYPHS[gid] = path_data(np.asarray(verts), np.asarray(codes))
        glyphs.append((gid, float(x) * k, (float(y) + d_box) * k, scale * k))
    return Layout(w * k, (a + d_box) * k, d_box * k, tuple(glyphs))
