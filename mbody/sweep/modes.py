"""The ``modes`` run: a case's natural frequencies and what `mbody modes` says with them:
whether the state linearised about is an equilibrium (or a steady motion), and if so
whether it is stable.

By default each case is linearised about its initial state (`mbody.linearize`), as
``mbody modes MODEL`` does: when that state is not at rest (a pendulum released from 30
degrees) the frequencies are those of the tangent system at that instant, and the
``steady`` column says so. With ``equilibrium`` each case is linearised about the static
equilibrium nearest its initial pose (`mbody.equilibrium`, then `mbody.linearize`), as
``mbody modes MODEL --equilibrium`` does, and the equilibrium's pose is in the row.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from mbody.errors import option_name
from mbody.model.model import Model
from mbody.solve.equilibrium import equilibrium as equilibrium_state
from mbody.solve.linearize import Linearization, free_coordinates, linearize

STEADY = "steady"
"""The column: 1 when the state is an equilibrium or a steady motion (`Linearization.
steady`), 0 when not (no verdict: the tangent system at that instant)."""
STABLE = "stable"
"""The column: 1 stable, 0 unstable (a mode grows), empty when there is no verdict
(`Linearization.stable` None)."""
POSE = "equilibrium:"
"""The prefix of the equilibrium's position coordinates (``equilibrium`` runs only)."""


def linearization(model: Model, equilibrium: bool = False) -> Linearization:
    """`model` linearised about its initial state, or with `equilibrium` about the
    static equilibrium nearest its initial pose: what ``mbody modes`` (``--equilibrium``)
    linearises about.

    Raises
    ------
    NoEquilibriumError
        `equilibrium` and Newton's method found none near the initial pose.
    """
    return linearize(model, equilibrium_state(model) if equilibrium else None)


def mode_count(model: Model) -> int:
    """How many natural frequencies the model can have: one per free coordinate (its
    degrees of freedom less its drivers), the columns ``frequency:1`` ... of a sweep."""
    return len(free_coordinates(model))


def verdict_values(lin: Linearization) -> tuple[float, float]:
    """(steady, stable) as a row holds them: 1.0 or 0.0, and NaN for no verdict."""
    stable = lin.stable
    return (1.0 if lin.steady else 0.0,
            np.nan if stable is None else (1.0 if stable else 0.0))


def not_steady_warning(header: Sequence[str], rows: Iterable[Sequence[str]],
                       equilibrium: bool) -> str | None:
    """What a modes sweep's rows need said: how many cases were linearised about a state
    that is not an equilibrium or a steady motion (their frequencies are the tangent
    system's at that instant), or None."""
    if STEADY not in header:
        return None
    at = list(header).index(STEADY)
    rows = list(rows)
    count = sum(1 for r in rows if r[at] not in ("", "1.0", "1"))
    if not count:
        return None
    about = "the equilibrium found" if equilibrium else "the initial state"
    hint = "" if equilibrium else (f"; {option_name('equilibrium', 'True')} linearises each "
                                   "about the static equilibrium nearest its initial pose")
    return (f"{about} of {count} of {len(rows)} cases is not an equilibrium or a steady "
            f"motion ({STEADY} = 0): their frequencies are those of the tangent system at "
            f"that instant, and there is no verdict ({STABLE} empty){hint}")
