"""States found by solving: the accelerations of a simulation's right-hand side
(`dynamics`); every solve itself is the compiled core's (`mbody.kernel`), reached
through `mbody.equations.workspace`.
"""

from mbody._moved import submodule as _submodule


def __getattr__(name: str):
    return _submodule(__name__, name)
