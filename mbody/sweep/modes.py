"""The ``modes`` run's adapter to the linearisation (`mbody.linearize`, issue 26): a case's
natural frequencies about its initial state, and how many a model can have.

ADAPTER: `mbody.linearize(model, state=None)` (``mbody/solve/linearize.py``, returning a
`Linearization` whose ``frequencies`` are the oscillations' natural frequencies |λ| in
rad/s, ascending, and whose ``coordinates`` are the free generalized coordinates) is
being built on another branch. This module is the one place the sweep calls it: until
it lands, `available` is False and the ``modes`` run says so; when it lands, nothing here
changes (it is looked up on the package, where it will be registered).
"""

from __future__ import annotations

from typing import Any

import numpy as np

import mbody
from mbody.errors import MbodyError
from mbody.model.model import Model

NOT_YET = ("the modes run needs mbody.linearize (natural frequencies about the initial "
           "state), which this version of mbody does not have yet")


def _linearize() -> Any:
    try:
        return mbody.linearize  # lands with issue 26 (mbody/solve/linearize.py)
    except AttributeError:
        return None


def available() -> bool:
    """Whether this version of mbody can linearise (the ``modes`` run can run)."""
    return _linearize() is not None


def frequencies(model: Model) -> np.ndarray:
    """The natural frequencies (rad/s) of `model` about its initial state, ascending."""
    linearize = _linearize()
    if linearize is None:
        raise MbodyError(NOT_YET)
    return np.sort(np.asarray(linearize(model).frequencies, dtype=float))


def mode_count(model: Model) -> int:
    """How many natural frequencies the model can have: one per free coordinate (its
    degrees of freedom less its drivers), the columns ``frequency:1`` ... of a sweep."""
    linearize = _linearize()
    if linearize is None:
        raise MbodyError(NOT_YET)
    lin = linearize(model)
    free = getattr(lin, "coordinates", None)
    return len(free) if free is not None else len(lin.frequencies)
