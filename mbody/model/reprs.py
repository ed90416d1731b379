"""The short text pieces the model's reprs share: counts, name lists, vectors."""

from __future__ import annotations

import numpy as np

from mbody.errors import name_list

__all__ = ["count", "name_list", "vector_text"]


def count(k: int, word: str, plural: str = "") -> str:
    """'1 body', '3 bodies' (for short reprs)."""
    return f"{k} {word if k == 1 else plural or word + 's'}"


def vector_text(x: np.ndarray) -> str:
    """'(1, 0, 2.5)' (for short reprs)."""
    return "(" + ", ".join(f"{0.0 if abs(v) < 1e-12 else v:.4g}" for v in x) + ")"
