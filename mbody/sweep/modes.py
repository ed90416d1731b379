"""The ``modes`` run: a case's natural frequencies about its initial state
(`mbody.solve.linearize.linearize`), and how many a model can have."""

from __future__ import annotations

import numpy as np

from mbody.model.model import Model
from mbody.solve.linearize import linearize


def frequencies(model: Model) -> np.ndarray:
    """The natural frequencies (rad/s) of `model`'s oscillations about its initial state,
    ascending."""
    return np.sort(np.asarray(linearize(model).frequencies, dtype=float))


def mode_count(model: Model) -> int:
    """How many natural frequencies the model can have: one per free coordinate (its
    degrees of freedom less its drivers), the columns ``frequency:1`` ... of a sweep."""
    return len(linearize(model).coordinates)
