"""Pictures: free-body diagrams (planar and spatial) and the body/joint graph.

Every picture is first built as a `Scene` (plain data: panels of lines, polygons,
circles and texts, in points), then written: SVG directly from the scene (fast: a
diagram's text is laid out from cached glyph metrics and outlines, see `fonts`), png and
pdf through matplotlib (`scene_figure`). `draw_fbd` and `draw_graph` return matplotlib
figures, as before, for users who want to edit them; `fbd_scene` and `graph_scene` are
the fast path the `fbd`, `graph` and `report` commands use.

Modules, each with one job: `views` (named views, projection), `outline` (body
outlines), `arrows` (the log length rule, one arrow per force), `labels` (label
placement), `diagram` (a free-body diagram's scene), `graph` (the graph's scene),
`scene` (the data), `fonts` (text metrics and glyphs), `svg` (the SVG writer), `mpl`
(matplotlib figures, writing files). This is the only package importing matplotlib for
pictures; it never imports pyplot.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from matplotlib.figure import Figure

from mbody.present.draw.arrows import arrow_lengths
from mbody.present.draw.diagram import END_ON, fbd_scene
from mbody.present.draw.graph import graph_scene
from mbody.present.draw.mpl import figure_bytes, figure_svg, save_figure, scene_figure
from mbody.present.draw.outline import PARTICLE_DOT
from mbody.present.draw.scene import Scene
from mbody.present.draw.style import COLORS, FORMATS, SCALE_NOTE
from mbody.present.draw.views import VIEWS, View, parse_view, projection

if TYPE_CHECKING:
    from mbody.equations.fbd import FreeBodyDiagram
    from mbody.model.model import Model

__all__ = ["COLORS", "END_ON", "FORMATS", "PARTICLE_DOT", "SCALE_NOTE", "VIEWS", "Scene",
           "arrow_lengths", "draw_fbd", "draw_graph", "fbd_scene", "figure_bytes",
           "figure_svg", "graph_scene", "parse_view", "projection", "save_figure",
           "scene_figure"]


def draw_fbd(fbd: FreeBodyDiagram, *, view: View = "iso", equations: bool = True,
             width: float = 8.0, title: str | None = None) -> Figure:
    """The free-body diagram of one body as a matplotlib `Figure` (Agg canvas).

    Parameters
    ----------
    fbd : FreeBodyDiagram
        Or a `BodyEquations`.
    view : str or (float, float)
        Spatial bodies only, see `projection`.
    equations : bool
        Write the body's Newton-Euler pair under the drawing.
    width : float
        Picture width (inches).
    title : str, optional
        Instead of the default title.

    Returns
    -------
    matplotlib.figure.Figure
        With the Axes 'drawing' (the body, arrows, labels), 'world-axes', and the title,
        legend and equations as figure texts. `fbd_scene` is the same picture, faster
        to write as SVG.
    """
    return scene_figure(fbd_scene(fbd, view=view, equations=equations, width=width,
                                  title=title))


def draw_graph(model: Model, topo: Any = None) -> Figure:
    """The body/joint graph as a matplotlib `Figure` (see `graph_scene`).

    Parameters
    ----------
    model : Model
    topo : Topology, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    return scene_figure(graph_scene(model, topo))
