"""Colours, sizes and notes shared by every picture."""

from __future__ import annotations

from mbody.conventions import APPLIED, GRAVITY, REACTION

EFFORT = "effort"
"""What a picture draws a driver's effort as (`<driver>.M`, `<driver>.F`: the torque or
force an actuator gives to hold its joint to its law): a reaction in the equations, but
drawn apart from the joints' reactions, in its own colour and dash, with its own legend
entry. Its gids are ``arrow:effort:<label>`` and ``couple:effort:<label>``."""

COLORS = {APPLIED: "#1f4e9c", GRAVITY: "#2e7d32", REACTION: "#c62828", EFFORT: "#7b1fa2"}
"""Arrow colour per kind: applied blue, gravity green, reactions red, driver efforts
purple."""
BODY_FACE, BODY_EDGE, AXIS_COLOR = "#e3e6ea", "#4d5561", "#7a7a7a"

FORMATS = ("svg", "png", "pdf")
"""Picture formats `save_figure` writes."""
SCALE_NOTE = ("arrow length ∝ 1 + log10(|F| / F_min): each ×10 in force adds one step\n"
              "unknown reactions: fixed length, drawn in their positive direction")

DASHED = (4.0, 2.5)
"""Reaction arrows' dash pattern, in line widths (matplotlib's convention)."""
DASH_DOT = (4.0, 1.6, 1.0, 1.6)
"""Driver efforts' dash pattern (dash, dot), in line widths: unknown like a reaction, told
apart from one in grey print too."""
DASHES = {REACTION: DASHED, EFFORT: DASH_DOT}
"""The dash pattern of each kind of arrow drawn dashed (the unknowns' kinds); the others
are solid."""
DOTTED = (1.0, 1.65)
"""Hidden edges' dot pattern, in line widths (matplotlib's ':')."""
