"""`Frozen`: the base of a dataclass whose instances never change after their own
``__init__``, which sets the fields through ``__dict__``.

``@dataclass(frozen=True)`` makes the same guarantee, but it compiles a ``__setattr__``
and a ``__delattr__`` from their source when the class is made: 0.1–0.2 ms of every
process that imports the class. These two are read from the bytecode cache instead. A
class that uses this writes its ``__init__`` out (``self.__dict__.update(...)``) and is
decorated ``@dataclass(init=False)`` without ``frozen``, so that `dataclasses.fields`
and `dataclasses.replace` still work on it.
"""

from __future__ import annotations

from dataclasses import FrozenInstanceError


class Frozen:
    """Refuses any assignment or deletion of an attribute, as a frozen dataclass does
    (`dataclasses.FrozenInstanceError`)."""

    __slots__ = ()

    def __setattr__(self, name: str, value: object) -> None:
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise FrozenInstanceError(f"cannot delete field {name!r}")
