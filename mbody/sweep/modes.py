"""The ``modes`` run: a case's natural frequencies, the rates at which its modes that
grow grow, and what `mbody modes` says with them: whether the state linearised about is
an equilibrium (or a steady motion), and if so whether it is stable (``true`` or
``false`` in the results, empty when there is no verdict).

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

FREQUENCY = "frequency:"
"""The prefix of the natural frequencies' columns, ``frequency:1`` ... (rad/s,
ascending; empty beyond the oscillations)."""
GROWTH = "growth:"
"""The prefix of the growth rates' columns, ``growth:1`` ... (1/s, largest first; empty
beyond the modes that grow, so all empty when none does): Re λ of each mode that grows,
a small motion's e-folding rate (`growth_rates`)."""
STEADY = "steady"
"""The column: true when the state is an equilibrium or a steady motion (`Linearization.
steady`), false when not (no verdict: the tangent system at that instant)."""
STABLE = "stable"
"""The column: true stable, false unstable (a mode grows), empty when there is no
verdict (`Linearization.stable` None)."""
FLAGS = (STEADY, STABLE)
"""The columns written ``true`` or ``false`` (or empty), not as numbers."""
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
    degrees of freedom less its drivers), the columns ``frequency:1`` ... of a sweep, and
    as many ``growth:`` columns."""
    return len(free_coordinates(model))


def columns(model: Model) -> list[str]:
    """The ``modes`` run's columns before the equilibrium's pose: ``frequency:k``,
    ``growth:k``, `STEADY`, `STABLE`."""
    k = mode_count(model)
    return ([f"{FREQUENCY}{i + 1}" for i in range(k)] + [f"{GROWTH}{i + 1}" for i in range(k)]
            + [STEADY, STABLE])


def growth_rates(lin: Linearization) -> np.ndarray:
    """Re λ (1/s) of each mode that grows, largest first: a real λ > 0 (a motion that
    runs away, as a spin about the intermediate axis) or an oscillation whose amplitude
    grows, each beyond its eigenvalue's error bound (what makes `Linearization.stable`
    False). A small motion of that mode grows as e^(Re λ t)."""
    rates = [m.eigenvalue.real for m in lin.modes if m.eigenvalue.real > 0.0]
    return np.array(sorted(rates, reverse=True), dtype=float)


def verdict_values(lin: Linearization) -> tuple[float, float]:
    """(steady, stable) as a row holds them: 1.0 (true) or 0.0 (false), NaN for no
    verdict; the results write them as `FLAGS`."""
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
    count = sum(1 for r in rows if r[at] == "false")
    if not count:
        return None
    about = "the equilibrium found" if equilibrium else "the initial state"
    hint = "" if equilibrium else (f"; {option_name('equilibrium', 'True')} linearises each "
                                   "about the static equilibrium nearest its initial pose")
    return (f"{about} of {count} of {len(rows)} cases is not an equilibrium or a steady "
            f"motion ({STEADY} = false): their frequencies are those of the tangent system at "
            f"that instant, and there is no verdict ({STABLE} empty){hint}")
