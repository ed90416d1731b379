"""mbody: per-body Newton-Euler equations for multibody models.

    model = mbody.load("models/double_pendulum.yaml")
    asm = mbody.assemble(model)          # M v̇ + b = Q + G λ at the model's state
    sol = asm.solve()                    # accelerations and the reactions λ
    sol = asm.solve(known={"A.Fx": 0})   # or with a reaction component given

A sweep over values of the file, as ``mbody sweep`` runs it: ``mbody.run_sweep(model,
{"bodies.upper.mass": [1, 2]}, "out.csv")`` (docs/sweeps.md).

The public names below are imported on first use (PEP 562), so that `import mbody` and
the `mbody` command load only what they need (scipy, matplotlib, meshcat and networkx
are slow to import). Submodules are reachable as attributes too (``mbody.solve.dynamics``),
except under a name that is also a public function (`assemble`, `animate`, `simulate`,
`loads`): ``mbody.simulate`` is the function, so a module of its folder is imported from
it (``from mbody.simulate import peaks``).

The package's folders follow the flow: `model` (file -> validated `Model`), `equations`
(free bodies and the stacked equations), `solve` (accelerations and reactions),
`simulate`, `present` (text, LaTeX, pictures, report, animation), `io` (exports) and
`cli` (the command).
"""

import importlib as _importlib
import sys as _sys
import types as _types

from mbody import _moved
from mbody.errors import Issue, MbodyError, ModelError, UnknownReactionsError

__version__ = "0.2.0"
"""The one version string (pyproject.toml reads it from here)."""

_LAZY = {
    "animate": "present.animate", "draw_fbd": "drawing",
    "Assembly": "equations.assemble", "Solution": "equations.assemble",
    "assemble": "equations.assemble",
    "ExportedAssembly": "io.export", "load_export": "io.export",
    "BodyEquations": "equations.fbd", "Equation": "equations.fbd",
    "ForceOnBody": "equations.fbd", "FreeBodyDiagram": "equations.fbd",
    "Body": "model.model", "Joint": "model.model", "Load": "model.model",
    "Model": "model.model", "State": "model.model", "load": "loading",
    "loads": "loading", "kinematics": "solve.kinematics",
    "equilibrium": "solve.equilibrium", "kinematic_run": "simulate.kinematic",
    "kinematic_at": "simulate.instants", "Instants": "simulate.instants",
    "linearize": "solve.linearize", "Linearization": "solve.linearize",
    "Generalized": "equations.generalized",
    "simulate": "simulate.simulation",
    "Trajectory": "simulate.trajectory",
    "verify": "answers.verify",
    "solve_many": "solve.batch", "Solutions": "solve.batch",
    "run_sweep": "sweep.study", "SweepResult": "sweep.study",
}
"""Public name -> the submodule defining it."""

__all__ = [
    "Assembly", "Body", "BodyEquations", "Equation", "ExportedAssembly", "ForceOnBody",
    "FreeBodyDiagram", "Generalized", "Instants", "Linearization", "linearize", "load_export",
    "Issue", "Joint", "Load", "MbodyError", "Model", "ModelError", "Solution", "State",
    "Trajectory", "simulate",
    "Solutions", "SweepResult", "UnknownReactionsError", "animate", "assemble", "draw_fbd",
    "equilibrium", "kinematic_at", "kinematic_run", "kinematics", "load", "loads",
    "run_sweep", "solve_many",
    "verify",
]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(_importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    # a submodule not imported yet (mbody.solve), or an old flat path (mbody.dynamics)
    return _moved.submodule(__name__, name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


class _Package(_types.ModuleType):
    """Keeps the public functions `assemble`, `animate`, `simulate` and `loads` when their
    namesake submodules are first imported: the import system sets the package attribute
    of a submodule to the module, which would hide the function (as it did not when every
    submodule was imported here, before the functions were bound)."""

    def __setattr__(self, name: str, value) -> None:
        if name in _LAZY and isinstance(value, _types.ModuleType):
            return
        super().__setattr__(name, value)


_sys.modules[__name__].__class__ = _Package
_moved.install()
