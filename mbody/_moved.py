"""Old flat module paths (``mbody.dynamics``, ``mbody.commands.sim``...) kept for one
release as aliases of the modules' new homes, with a DeprecationWarning on import.

The alias is the same module object, so a name patched through the old path is patched
where the code reads it.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings
from types import ModuleType

MOVED = {
    "loader": "model.loader", "validate": "model.validate", "expr": "model.expressions",
    "graph": "model.graph",
    "spatial": "util.spatial", "equations.spatial": "util.spatial",
    "loads": "equations.loads", "joints": "equations.joints",
    "constraints": "equations.constraints", "fbd": "equations.fbd",
    "assemble": "equations.assemble", "dynamics": "solve.dynamics",
    "mechanism": "simulate.mechanism", "projection": "simulate.mechanism",
    "simulate.projection": "simulate.mechanism",
    "stepping": "simulate.stepping", "trajectory": "simulate.trajectory",
    "text": "present.text", "latex": "present.latex", "draw": "present.draw",
    "report": "present.report", "plot": "present.plot", "animate": "present.animate",
    "export": "io.export", "atomic": "util.atomic", "io.atomic": "util.atomic",
    "io.jsontext": "util.jsontext", "io.interop.yaml_write": "model.yaml_write",
    "commands": "cli.common", "commands.animate": "cli.animate", "commands.core": "cli.core",
    "commands.draw": "cli.draw", "commands.export": "cli.export",
    "commands.mechanism": "cli.mechanism", "commands.sim": "cli.sim",
}
"""Old path under mbody -> new path under mbody (release 0.2, the shared utilities' move
to `mbody.util` in 0.3, and `simulate.projection`'s into `simulate.mechanism`, which holds
both ways of keeping a run on its joints; the aliases go in 0.4).
``mbody.model`` and ``mbody.simulate`` are packages now that export the old modules'
public names; ``mbody.cli.main`` is still the command's entry point. The numeric modules
that the compiled core replaced (``kernels``, ``plan``, ``blockplan``, ``kkt``,
``nullspace``, ``compiled``) are gone, not moved: see docs/codebase.md."""


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def __init__(self) -> None:
        self._specs: dict[str, importlib.machinery.ModuleSpec | None] = {}

    def find_spec(self, fullname, path=None, target=None):
        old = fullname.removeprefix("mbody.")
        if not fullname.startswith("mbody.") or old not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self, is_package=old == "commands")

    def create_module(self, spec) -> ModuleType:
        new = f"mbody.{MOVED[spec.name.removeprefix('mbody.')]}"
        warnings.warn(f"{spec.name} moved to {new}; the old path goes in mbody 0.4",
                      DeprecationWarning, stacklevel=2)
        module = importlib.import_module(new)
        self._specs[spec.name] = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        # the import system set the alias's spec on the real module: give its own back
        alias = module.__spec__
        assert alias is not None  # the import system has just set it
        module.__spec__ = self._specs.pop(alias.name)


def install() -> None:
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        # first: a leftover folder of an old checkout (mbody/commands/) must not shadow
        # an alias as an empty namespace package
        sys.meta_path.insert(0, _Alias())


def submodule(package: str, name: str) -> ModuleType:
    """A subpackage's `__getattr__`: its submodules as attributes, imported on first use
    (``mbody.solve.dynamics`` without importing it first), as for the package itself."""
    if not name.startswith("__"):
        try:
            return importlib.import_module(f"{package}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{package}.{name}":
                raise
    raise AttributeError(f"module {package!r} has no attribute {name!r}")
