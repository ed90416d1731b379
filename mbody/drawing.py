"""`mbody.draw_fbd`: a body's free-body diagram as a matplotlib figure, matplotlib loaded
when a diagram is drawn (not when the name is looked up: `import mbody` stays light)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from mbody.equations.fbd import FreeBodyDiagram


def draw_fbd(fbd: FreeBodyDiagram, **kwargs: Any) -> Figure:
    """The free-body diagram of one body as a matplotlib `Figure` (Agg canvas, no pyplot).

    Parameters
    ----------
    fbd : FreeBodyDiagram
        A body's free body, ``asm.bodies[name].fbd``.
    **kwargs
        ``view`` (spatial bodies: "iso", "front", "top"... or (azimuth, elevation)),
        ``equations`` (write the body's Newton-Euler pair under the drawing, default
        True), ``width`` (inches), ``title``: see `mbody.present.draw.draw_fbd`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from mbody.present.draw import draw_fbd as draw  # matplotlib: loaded on the first call

    return draw(fbd, **kwargs)
