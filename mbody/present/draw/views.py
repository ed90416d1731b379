"""Views: named and numeric (elevation, azimuth) views and their orthographic projection."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mbody.errors import MbodyError, did_you_mean

View = str | Sequence[float] | None
"""'iso' | 'front' | 'top' | 'side' | 'ELEV,AZIM' (degrees) | (elev, azim) | None (iso)."""

VIEWS: dict[str, tuple[float, float]] = {
    "iso": (math.degrees(math.atan(1 / math.sqrt(2))), 45.0),
    "front": (0.0, -90.0),
    "top": (90.0, -90.0),
    "side": (0.0, 0.0),
}
"""Named views as (elevation, azimuth) in degrees; the eye looks from
(cos e cos a, cos e sin a, sin e) toward the origin, world z up. iso: the engineering
isometric (x to the lower left, y to the lower right, z up); front: x right, z up;
side: y right, z up; top: x right, y up."""


def parse_view(view: View) -> tuple[float, float]:
    """A view as (elevation, azimuth) in degrees.

    Parameters
    ----------
    view : str or (float, float) or None
        'iso' | 'front' | 'top' | 'side' | 'ELEV,AZIM' (degrees) | (elev, azim);
        None is 'iso'.

    Returns
    -------
    (float, float)
        Elevation and azimuth in degrees.

    Raises
    ------
    MbodyError
        For an unknown name or a value that is not two numbers.
    """
    if view is None:
        return VIEWS["iso"]
    if isinstance(view, str):
        key = view.strip().lower()
        if key in VIEWS:
            return VIEWS[key]
        parts = key.split(",")
        if len(parts) == 2:
            try:
                elev, azim = float(parts[0]), float(parts[1])
            except ValueError:
                pass
            else:
                if math.isfinite(elev) and math.isfinite(azim):
                    return elev, azim
        hint = did_you_mean(key, VIEWS)
        raise MbodyError(f"unknown view {view!r}" + (f"; {hint}" if hint else "")
                         + "; use one of " + ", ".join(VIEWS)
                         + ", or ELEV,AZIM in degrees (for example 30,-60)")
    try:
        elev, azim = (float(v) for v in view)
    except (TypeError, ValueError):
        raise MbodyError(f"a view is a name or (elevation, azimuth) in degrees, got {view!r}"
                         ) from None
    return elev, azim


def projection(view: View = "iso") -> np.ndarray:
    """(2, 3) orthographic projection P: page coordinates (right, up) = P @ W_p.

    Rows are the page's right and up directions in world axes, for an eye at elevation
    e and azimuth a: right = (−sin a, cos a, 0), up = (−sin e cos a, −sin e sin a, cos e).

    Parameters
    ----------
    view : str or (float, float) or None
        See `parse_view`.

    Returns
    -------
    numpy.ndarray
        (2, 3) matrix P.
    """
    e, a = (math.radians(v) for v in parse_view(view))
    right = [-math.sin(a), math.cos(a), 0.0]
    up = [-math.sin(e) * math.cos(a), -math.sin(e) * math.sin(a), math.cos(e)]
    P = np.array([right, up])
    P[np.abs(P) < 1e-15] = 0.0
    return P


def eye(P: np.ndarray) -> np.ndarray:
    """Unit vector from the scene toward the eye: right × up (P: (2, 3))."""
    return np.cross(P[0], P[1])


def view_name(view: View) -> str:
    """The view as written in a title: its name, or its elevation and azimuth."""
    if isinstance(view, str) and view.strip().lower() in VIEWS:
        return view.strip().lower()
    e, a = parse_view(view)
    return f"elev {e:g}°, azim {a:g}°"
