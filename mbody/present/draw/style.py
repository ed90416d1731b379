"""Colours, sizes and notes shared by every picture."""

from __future__ import annotations

from mbody.conventions import APPLIED, GRAVITY, REACTION

COLORS = {APPLIED: "#1f4e9c", GRAVITY: "#2e7d32", REACTION: "#c62828"}
"""Arrow colour per force kind: applied blue, gravity green, reactions red."""
BODY_FACE, BODY_EDGE, AXIS_COLOR = "#e3e6ea", "#4d5561", "#7a7a7a"

FORMATS = ("svg", "png", "pdf")
"""Picture formats `save_figure` writes."""
SCALE_NOTE = ("arrow length ∝ 1 + log10(|F| / F_min): each ×10 in force adds one step\n"
              "unknown reactions: fixed length, drawn in their positive direction")

DASHED = (4.0, 2.5)
"""Reaction arrows' dash pattern, in line widths (matplotlib's convention)."""
DOTTED = (1.0, 1.65)
"""Hidden edges' dot pattern, in line widths (matplotlib's ':')."""
