"""A picture of a linearisation's mode shapes: one panel per mode, the mechanism at its
reference configuration (grey) and at the mode's two extremes (blue, red).

Each body is drawn as a stick figure: lines from its mass centre to its joint points, its
box outline where the file gives a box, a dot at its mass centre; springs dashed. A planar
model is seen in its plane; a spatial one in a view (`mbody.present.draw.views`). The
extremes are q0 ± a φ with 0.15 of the model's size as the largest displacement
(`mbody.simulate.modes`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from mbody import conventions as cv
from mbody.model.model import Model, State
from mbody.present.draw.style import BODY_EDGE
from mbody.present.draw.views import View, projection
from mbody.simulate.modes import mode_configurations
from mbody.solve.linearize import Linearization, Mode

SHOWN = 6
"""Panels at most (the lowest modes)."""
TONES = ("#9aa3ad", "#1f4e9c", "#c62828")
"""Reference, +a φ, −a φ."""


def _segments(model: Model, state: State) -> tuple[list[np.ndarray], list[np.ndarray],
                                                   np.ndarray]:
    """(body polylines, spring segments, mass centres), world coordinates (n, 3)."""
    R, x = state.W_R_B, state.position
    jt, sp = model.joint_table, model.springs
    lines = []
    for j in range(len(jt.child)):
        c, p = int(jt.child[j]), int(jt.parent[j])
        P = x[c] + R[c] @ jt.B_r_child[j]
        lines.append(np.array([x[c], P]))
        if p >= 0:
            lines.append(np.array([x[p], x[p] + R[p] @ jt.B_r_parent[j]]))
    for i, name in enumerate(model.body_names):
        shape = model.bodies[name].shape or {}
        box = shape.get("box") if isinstance(shape, dict) else None
        if box is not None and model.dimension == cv.PLANAR:
            hx, hy = float(box[0]) / 2, float(box[1]) / 2
            corners = np.array([[-hx, -hy, 0], [hx, -hy, 0], [hx, hy, 0], [-hx, hy, 0],
                                [-hx, -hy, 0]])
            lines.append(x[i] + corners @ R[i].T)
    springs = []
    for s in range(len(sp.names)):
        ends = []
        for b, r in ((int(sp.a[s]), sp.r_a[s]), (int(sp.b[s]), sp.r_b[s])):
            ends.append(np.asarray(r, float) if b < 0 else x[b] + R[b] @ r)
        springs.append(np.array(ends))
    return lines, springs, x


def _title(k: int, mode: Mode) -> str:
    if mode.kind == "oscillation":
        zeta = f", ζ = {mode.damping_ratio:.3g}" if mode.damping_ratio else ""
        return f"mode {k}: {mode.frequency_hz:.4g} Hz ({mode.frequency:.4g} rad/s){zeta}"
    if mode.kind == "neutral":
        return f"mode {k}: neutral (λ = 0)"
    return f"mode {k}: {mode.kind}, λ = {mode.eigenvalue.real:.4g} 1/s"


def modes_figure(lin: Linearization, *, view: View = None, shown: int = SHOWN) -> Figure:
    """The mode shapes of `lin` as a matplotlib `Figure` (module doc).

    Parameters
    ----------
    lin : Linearization
        The linearisation.
    view : str or (float, float), optional
        For a spatial model (default iso); a planar one is seen in its plane.
    shown : int
        Panels at most: the modes that move (not neutral), lowest first.

    Returns
    -------
    matplotlib.figure.Figure
    """
    model = lin.model
    numbered = [(k + 1, m) for k, m in enumerate(lin.modes) if m.kind != "neutral"][:shown]
    if not numbered:
        numbered = [(k + 1, m) for k, m in enumerate(lin.modes)][:shown]
    P = (np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]) if model.dimension == cv.PLANAR
         else projection(view))
    cols = min(3, max(1, len(numbered)))
    rows = max(1, int(np.ceil(len(numbered) / cols)))
    fig = Figure(figsize=(4.2 * cols, 3.8 * rows))
    for idx, (k, mode) in enumerate(numbered):
        ax = fig.add_subplot(rows, cols, idx + 1)
        configs = mode_configurations(lin, mode)
        for state, tone, width in zip(configs, TONES, (2.6, 1.6, 1.6), strict=True):
            lines, springs, G = _segments(model, state)
            for pts in lines:
                uv = pts @ P.T
                ax.plot(uv[:, 0], uv[:, 1], color=tone, lw=width, solid_capstyle="round")
            for pts in springs:
                uv = pts @ P.T
                ax.plot(uv[:, 0], uv[:, 1], color=tone, lw=1.0, ls=(0, (3, 2)))
            uv = G @ P.T
            ax.plot(uv[:, 0], uv[:, 1], "o", color=tone, ms=4)
        ax.set_title(_title(k, mode), fontsize=9)
        ax.set_aspect("equal", adjustable="datalim")
        ax.tick_params(labelsize=7, colors=BODY_EDGE)
        for side in ("top", "right"):
            ax.spines[side].set_visible(False)
    fig.suptitle(f"{model.name}: mode shapes (grey: reference; blue, red: ± the shape)",
                 fontsize=10)
    fig.tight_layout()
    return fig
