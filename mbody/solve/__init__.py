"""Accelerations and unknown reactions from the stacked equations.

`dynamics` (v̇ at one state when no reaction is unknown), `kkt` (the constrained system:
Schur complement, or the KKT matrix when it is rank deficient), `nullspace` (the robust
route near singular positions), `blockplan` (the Schur complement from per-body blocks)
and `compiled` (the numba path that does all of it for small models in one call).
"""

from mbody._moved import submodule as _submodule


def __getattr__(name: str):
    return _submodule(__name__, name)
