"""Motion over time: `simulate(model, t_end, fps) -> Trajectory`.

`simulation` (the run: sampling, budgets, progress, summary), `budget` (what a run over
its budget, or failing, is told), `stepping` (the integrator classes, and the compiled
DOP853 steps), `mechanism` (accelerations with the reactions solved at every step, the
state moved back onto its joints, the figures at the samples), `trajectory` (the
`Trajectory`) and `run_file` (its file).

The names below are imported on first use: reading a saved `Trajectory` must not import
scipy's integrators.
"""

import importlib

from mbody._moved import submodule as _submodule

_PUBLIC = {
    "DEFAULT_ATOL": "simulation", "DEFAULT_MAX_STEPS": "simulation",
    "DEFAULT_RTOL": "simulation", "METHODS": "simulation",
    "known_reaction_dynamics": "simulation", "potential_energy": "simulation",
    "simulate": "simulation", "state_derivative": "simulation", "summary": "simulation",
    "Trajectory": "trajectory",
}
__all__ = sorted(_PUBLIC)


def __getattr__(name: str):
    if name in _PUBLIC:
        return getattr(importlib.import_module(f"mbody.simulate.{_PUBLIC[name]}"), name)
    return _submodule(__name__, name)
