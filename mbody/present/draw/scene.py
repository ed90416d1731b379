"""A picture as plain data: panels of lines, polygons, circles, wedges and texts.

Every picture is built once as a `Scene` and then written: as SVG by `svg.py` (directly,
fast) or as a matplotlib `Figure` by `mpl.py` (for png, pdf and for users who want to
edit it). Sizes are in points (1/72 inch); a scene's origin is its lower left corner.
A `Panel` maps its own data coordinates onto a rectangle of the scene with one scale
for x and y (equal aspect), as a matplotlib Axes with fixed limits would.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

IN = 72.0
"""Points per inch: scenes are sized in points, figures in inches."""


@dataclass(slots=True)
class Line:
    """A polyline; xy (k, 2) data coordinates; lw in points; dash in line widths."""

    xy: np.ndarray
    color: str
    lw: float = 1.0
    dash: tuple[float, ...] | None = None
    gid: str | None = None
    zorder: float = 2.0


@dataclass(slots=True)
class Poly:
    """A closed polygon; xy (k, 2) data coordinates; hatch: diagonal lines inside."""

    xy: np.ndarray
    face: str | None
    edge: str | None = None
    lw: float = 0.0
    gid: str | None = None
    zorder: float = 1.0
    hatch: bool = False


@dataclass(slots=True)
class Disc:
    """A circle of radius r (data units) about `center`; face None: a ring only."""

    center: np.ndarray
    r: float
    face: str | None
    edge: str | None = None
    lw: float = 1.0
    gid: str | None = None
    zorder: float = 2.0


@dataclass(slots=True)
class Wedge:
    """A filled sector from angle a0 to a1 (degrees, counter-clockwise)."""

    center: np.ndarray
    r: float
    a0: float
    a1: float
    face: str
    zorder: float = 2.0


@dataclass(frozen=True, slots=True)
class Box:
    """A frame around a text: pad in font sizes (matplotlib's boxstyle pad)."""

    face: str
    edge: str
    lw: float = 1.0
    pad: float = 0.3
    round: bool = True


@dataclass(slots=True)
class Text:
    """A text anchored at xy (data) and moved by `offset` (points), aligned by ha, va.

    s is plain text (no TeX) unless `math`, which holds one mathtext formula ``$...$``.
    `align` places the lines of a multi-line text within its box (left, center, right;
    None: as ha), as matplotlib's multialignment.
    """

    s: str
    xy: np.ndarray
    size: float
    color: str = "black"
    ha: str = "left"  # left, center, right
    va: str = "baseline"  # bottom, center, top, baseline
    offset: tuple[float, float] = (0.0, 0.0)
    weight: str = "normal"
    family: str = "sans"  # sans or mono
    math: bool = False
    gid: str | None = None
    zorder: float = 3.0
    box: Box | None = None
    linespacing: float = 1.2
    align: Literal["left", "center", "right"] | None = None


Item = Line | Poly | Disc | Wedge | Text


@dataclass(slots=True)
class Panel:
    """Items in data coordinates shown in `rect` (x0, y0, width, height; points) with
    data limits lo..hi (each (2,)), equal scale on both axes."""

    gid: str | None
    rect: tuple[float, float, float, float]
    lo: np.ndarray
    hi: np.ndarray
    items: list[Item] = field(default_factory=list)

    @property
    def scale(self) -> float:
        """Points per data unit."""
        return self.rect[2] / float(self.hi[0] - self.lo[0])

    def to_pt(self, xy: np.ndarray) -> np.ndarray:
        """Data coordinates (..., 2) to scene points."""
        s = self.scale
        return (np.asarray(xy, dtype=float) - self.lo) * s + self.rect[:2]

    def set_limits(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """Limits covering [lo, hi], widened to the rectangle's shape so that one unit is
        as long across as up."""
        box = self.rect[2] / self.rect[3]
        c, half = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-9)
        if half[0] / half[1] < box:
            half[0] = half[1] * box
        else:
            half[1] = half[0] / box
        self.lo, self.hi = c - half, c + half

    def add(self, *items: Item) -> None:
        self.items.extend(items)

    def __repr__(self) -> str:  # the dataclass's printed every item's arrays (kilobytes)
        x0, y0, w, h = self.rect
        return (f"<Panel {self.gid!r}: {len(self.items)} items in {w:.0f} x {h:.0f} pt at "
                f"({x0:.0f}, {y0:.0f}); .items, .to_pt(xy)>")


@dataclass(slots=True)
class Scene:
    """A whole picture: width × height points; `root` holds items placed in points."""

    width: float
    height: float
    title: str = ""
    panels: list[Panel] = field(default_factory=list)
    root: Panel = field(init=False)

    def __post_init__(self) -> None:
        self.root = Panel(None, (0.0, 0.0, self.width, self.height), np.zeros(2),
                          np.array([self.width, self.height]))

    def panel(self, gid: str | None, rect: tuple[float, float, float, float],
              lo: np.ndarray | None = None, hi: np.ndarray | None = None) -> Panel:
        """A new panel in `rect` (points); limits lo..hi (default: 0..1)."""
        p = Panel(gid, rect, np.zeros(2), np.ones(2))
        p.set_limits(np.zeros(2) if lo is None else np.asarray(lo, dtype=float),
                     np.ones(2) if hi is None else np.asarray(hi, dtype=float))
        self.panels.append(p)
        return p

    def __repr__(self) -> str:  # the dataclass's printed every panel's items (12 KB)
        title = self.title if len(self.title) <= 80 else self.title[:77] + "..."
        names = ", ".join(str(p.gid) for p in self.panels[:6])
        more = f" +{len(self.panels) - 6}" if len(self.panels) > 6 else ""
        n = len(self.panels)
        return (f"<Scene {title!r}: {self.width:.0f} x {self.height:.0f} pt, {n} panel"
                f"{'' if n == 1 else 's'} ({names}{more}); figure_svg(scene), "
                "scene_figure(scene)>")

    def find(self, gid: str) -> list[Item]:
        """Items whose gid is `gid` (for tests and tools)."""
        return [it for p in (self.root, *self.panels) for it in p.items
                if getattr(it, "gid", None) == gid]
