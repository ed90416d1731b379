"""mbody's compiled core: the one numeric path of the physics (`src/kernel.h`).

The C extension `mbody.kernel._core` is built by ``pip install`` (a C compiler and
Python's headers are needed, as for any package with a C extension).
"""

from __future__ import annotations

try:
    from mbody.kernel import _core
except ImportError as exc:  # pragma: no cover - a source tree that was never installed
    raise ImportError(
        "mbody's compiled core (mbody.kernel._core) is not built: install the package "
        "with `pip install -e .` (or `pip install .`) from the source folder; it needs a C "
        "compiler and Python's headers") from exc

__all__ = ["_core"]
