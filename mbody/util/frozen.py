"""`Frozen`: the base of a dataclass whose instances never change after their own
``__init__``, which sets the fields through ``__dict__``; and `dataclass_on_first_look`,
which makes such a class a dataclass when something first asks it for its fields.

``@dataclass(frozen=True)`` makes the same guarantee, but it compiles a ``__setattr__``
and a ``__delattr__`` from their source when the class is made: 0.1–0.2 ms of every
process that imports the class. These two are read from the bytecode cache instead. A
class that uses this writes its ``__init__`` out (``self.__dict__.update(...)``) and is
decorated ``@dataclass(init=False)`` without ``frozen``, so that `dataclasses.fields`
and `dataclasses.replace` still work on it.

Even without generated methods, ``@dataclass`` reads every field's annotation when the
class is made: 0.06–0.1 ms for a record of twenty fields, paid by every process that
imports it (`Trajectory`: every process that simulates), where few ever ask for the
fields. `dataclass_on_first_look` defers that to the first read of what the dataclasses
module and the ``match`` statement look for on a dataclass (``__dataclass_fields__``,
``__dataclass_params__``, ``__match_args__``): `dataclasses.fields`, `replace`,
`is_dataclass` and `asdict` then work as on the decorated class, and only they pay.
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable
from dataclasses import FrozenInstanceError
from typing import TYPE_CHECKING, Any, TypeVar


class Frozen:
    """Refuses any assignment or deletion of an attribute, as a frozen dataclass does
    (`dataclasses.FrozenInstanceError`)."""

    __slots__ = ()

    def __setattr__(self, name: str, value: object) -> None:
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise FrozenInstanceError(f"cannot delete field {name!r}")


_LOOKED_FOR = ("__dataclass_fields__", "__dataclass_params__", "__match_args__")
"""The class attributes through which a dataclass is recognised and read."""
_LOCK = threading.RLock()
_C = TypeVar("_C", bound=type)


class _OnFirstLook:
    """One of `_LOOKED_FOR` on a class not made a dataclass yet: reading it makes the
    class one (``dataclasses.dataclass(cls, **options)``, which sets the real
    attributes in place of these) and gives the real value."""

    def __init__(self, cls: type, name: str, options: dict[str, Any]):
        self.cls, self.name, self.options = cls, name, options

    def __get__(self, obj: object, owner: type | None = None) -> Any:
        cls = self.cls
        with _LOCK:  # two threads' first looks make it once
            if cls.__dict__.get(self.name) is self:
                for name in _LOOKED_FOR:  # the dataclass sets each only where absent
                    if isinstance(cls.__dict__.get(name), _OnFirstLook):
                        delattr(cls, name)
                dataclasses.dataclass(cls, **self.options)
        return cls.__dict__[self.name]


def _dataclass_on_first_look(**options: Any) -> Callable[[_C], _C]:
    def mark(cls: _C) -> _C:
        for name in _LOOKED_FOR:
            setattr(cls, name, _OnFirstLook(cls, name, options))
        return cls
    return mark


if TYPE_CHECKING:  # the type checker sees the dataclass the class becomes
    from dataclasses import dataclass as dataclass_on_first_look
else:
    dataclass_on_first_look = _dataclass_on_first_look
    """``@dataclass(**options)``, applied when the class is first asked for its fields
    (module doc). For a class whose methods are all written out (``init=False,
    repr=False, eq=False``): the decorator would add none later."""
