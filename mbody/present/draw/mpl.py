"""Scenes as matplotlib figures, and the writing of pictures (svg, png, pdf).

Figures are plain `matplotlib.figure.Figure` objects on the Agg canvas: no pyplot, no
global state, no display needed. Each panel becomes an Axes with the panel's gid and
limits; every item keeps its gid, so tests and tools can find it in the figure.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Polygon
from matplotlib.patches import Wedge as MplWedge
from matplotlib.text import Text as MplText
from matplotlib.transforms import Affine2D, Transform, offset_copy

from mbody.errors import MbodyError
from mbody.present.draw.fonts import drawable
from mbody.present.draw.scene import IN, Disc, Item, Line, Poly, Scene, Wedge
from mbody.present.draw.style import FORMATS
from mbody.present.draw.svg import scene_svg
from mbody.util.atomic import write_atomic

_FAMILY = {"sans": "DejaVu Sans", "mono": "DejaVu Sans Mono"}


def tex_safe(s: str) -> str:
    """Plain text for matplotlib: a '$' in a user's name must not start mathtext."""
    return s.replace("$", r"\$")


def _artist(it: Item, fig: Figure, trans: Transform) -> Artist:
    if isinstance(it, Line):
        ls = (0, it.dash) if it.dash else "-"
        return Line2D(it.xy[:, 0], it.xy[:, 1], color=it.color, lw=it.lw, ls=ls,
                      zorder=it.zorder, gid=it.gid, solid_capstyle="butt", transform=trans)
    if isinstance(it, Poly):
        return Polygon(it.xy, closed=True, facecolor=it.face or "none",
                       edgecolor=it.edge or "none", lw=it.lw, zorder=it.zorder, gid=it.gid,
                       hatch="///" if it.hatch else None, transform=trans)
    if isinstance(it, Disc):
        return Circle(tuple(it.center), it.r, facecolor=it.face or "none",
                      edgecolor=it.edge or "none", lw=it.lw, zorder=it.zorder, gid=it.gid,
                      fill=it.face is not None, transform=trans)
    if isinstance(it, Wedge):
        return MplWedge(tuple(it.center), it.r, it.a0, it.a1, facecolor=it.face,
                        zorder=it.zorder, transform=trans)
    t = it
    bbox = None
    if t.box is not None:
        bbox = {"boxstyle": f"{'round' if t.box.round else 'square'},pad={t.box.pad}",
                "fc": t.box.face, "ec": t.box.edge, "lw": t.box.lw}
    shown = t.s if t.math else tex_safe(drawable(t.s, t.family, t.weight))
    return MplText(t.xy[0], t.xy[1], shown, color=t.color,
                   fontsize=t.size, ha=t.ha, va=t.va, weight=t.weight,
                   family=_FAMILY[t.family], zorder=t.zorder, gid=t.gid, clip_on=False,
                   bbox=bbox, linespacing=t.linespacing, multialignment=t.align,
                   transform=offset_copy(trans, fig=fig, x=t.offset[0], y=t.offset[1],
                                         units="points"))


def scene_figure(scene: Scene) -> Figure:
    """The scene as a matplotlib `Figure` (Agg canvas, 100 dpi), one Axes per panel.

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    matplotlib.figure.Figure
    """
    W, H = scene.width, scene.height
    fig = Figure(figsize=(W / IN, H / IN), dpi=100)
    FigureCanvasAgg(fig)
    for p in scene.panels:
        x0, y0, w, h = p.rect
        ax: Axes = fig.add_axes((x0 / W, y0 / H, w / W, h / H), gid=p.gid)
        ax.set_axis_off()
        ax.set_xlim(float(p.lo[0]), float(p.hi[0]))
        ax.set_ylim(float(p.lo[1]), float(p.hi[1]))
        for it in p.items:
            ax.add_artist(_artist(it, fig, ax.transData))  # listed in ax.lines, .texts...
    points = Affine2D().scale(1 / IN) + fig.dpi_scale_trans
    for it in scene.root.items:
        a = _artist(it, fig, points)
        if isinstance(a, MplText):  # in fig.texts, as fig.text() puts them
            a.set_figure(fig)
            fig.texts.append(a)
        else:
            fig.add_artist(a)
    return fig


_SVG_PREAMBLE = re.compile(r"<\?xml.*?\?>\s*|<!DOCTYPE.*?>\s*|<metadata>.*?</metadata>\s*",
                           re.S)


def figure_bytes(fig: Figure | Scene, fmt: str = "svg", dpi: int = 150) -> bytes:
    """The picture encoded as svg, png or pdf (no dates inside: output is repeatable).

    Parameters
    ----------
    fig : matplotlib.figure.Figure or Scene
        A scene's SVG is written directly; other formats go through matplotlib.
    fmt : str
        'svg', 'png' or 'pdf'.
    dpi : int
        Resolution of png pictures.

    Returns
    -------
    bytes
    """
    if fmt not in FORMATS:
        raise MbodyError(f"unknown picture format {fmt!r}; use one of {', '.join(FORMATS)}")
    if isinstance(fig, Scene):
        if fmt == "svg":
            return scene_svg(fig, standalone=True).encode("utf-8")
        fig = scene_figure(fig)
    buf = io.BytesIO()
    meta = {"svg": {"Date": None}, "pdf": {"CreationDate": None}, "png": {}}[fmt]
    fig.savefig(buf, format=fmt, dpi=dpi, metadata=meta, facecolor="white")
    return buf.getvalue()


def figure_svg(fig: Figure | Scene, prefix: str = "") -> str:
    """The picture as an SVG element (no XML prolog or metadata: ready to inline in HTML).

    Parameters
    ----------
    fig : matplotlib.figure.Figure or Scene
    prefix : str
        A scene only: put before its ids (glyphs), unique per picture in one page.

    Returns
    -------
    str
    """
    if isinstance(fig, Scene):
        return scene_svg(fig, prefix=prefix)
    return _SVG_PREAMBLE.sub("", figure_bytes(fig, "svg").decode("utf-8")).strip()


def save_figure(fig: Figure | Scene, path: str | Path, fmt: str | None = None,
                dpi: int = 150) -> Path:
    """Write the picture atomically; the format is `fmt` or the file's extension.

    Parameters
    ----------
    fig : matplotlib.figure.Figure or Scene
    path : str or Path
    fmt : str, optional
        'svg', 'png' or 'pdf'; default: from the extension.
    dpi : int
        Resolution of png pictures.

    Returns
    -------
    Path
        The file written.
    """
    path = Path(path)
    fmt = fmt or path.suffix.lstrip(".").lower()
    if fmt not in FORMATS:
        raise MbodyError(f"cannot tell the picture format of {str(path)!r}; "
                         f"use a file name ending in {', '.join('.' + f for f in FORMATS)}")
    return write_atomic(path, figure_bytes(fig, fmt, dpi))
