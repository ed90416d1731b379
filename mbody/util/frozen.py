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
module, `copy.replace` and the ``match`` statement look for on a dataclass
(``__dataclass_fields__``, ``__dataclass_params__``, ``__match_args__``,
``__replace__``): `dataclasses.fields`, `replace`, `is_dataclass`, `asdict` and
`copy.replace` (Python 3.13) then work as on the decorated class, and only they pay.
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


_LOOKED_FOR = ("__dataclass_fields__", "__dataclass_params__", "__match_args__",
               "__replace__")
"""What the dataclasses module adds to a class with ``eq=False, init=False, repr=False``
(``__replace__`` from Python 3.13, for `copy.replace`), and the first look reads."""
_OPTIONS = {"eq": False, "init": False, "repr": False}
_LOCK = threading.RLock()
_C = TypeVar("_C", bound=type)


class _OnFirstLook:
    """One of `_LOOKED_FOR` on a class not made a dataclass yet: reading it makes the
    class one, and gives what the class then has (the value, a bound method, or
    AttributeError where the dataclass adds nothing by that name)."""

    def __init__(self, cls: type, name: str, body: dict[str, Any]):
        self.cls, self.name, self.body = cls, name, body

    def __get__(self, obj: object, owner: type | None = None) -> Any:
        _make(self.cls, self.body)
        return getattr(self.cls if obj is None else obj, self.name)


def _make(cls: type, body: dict[str, Any]) -> None:
    """Makes `cls` the dataclass it was declared, once: the dataclass is made of a twin
    (a class of the same name, bases and body, the `dataclasses.Field` defaults
    included), and what it adds replaces the descriptors on `cls` one by one. A thread
    that looks meanwhile finds either the final value or a descriptor, which waits for
    this to end: never a class half made."""
    with _LOCK:
        if not any(isinstance(cls.__dict__.get(name), _OnFirstLook) for name in _LOOKED_FOR):
            return
        twin: type = type(cls)(cls.__name__, cls.__bases__, dict(body))
        dataclasses.dataclass(twin, **_OPTIONS)
        for name in _LOOKED_FOR:
            if name in twin.__dict__:
                setattr(cls, name, twin.__dict__[name])
        for name in _LOOKED_FOR:  # those the dataclass did not add (__replace__ < 3.13)
            if isinstance(cls.__dict__.get(name), _OnFirstLook):
                delattr(cls, name)


def _dataclass_on_first_look(**options: Any) -> Callable[[_C], _C]:
    if options != _OPTIONS:
        raise TypeError("dataclass_on_first_look takes eq=False, init=False, repr=False "
                        f"(a class that writes its methods out), not {options}")

    def mark(cls: _C) -> _C:
        if not cls.__doc__:  # the dataclass would write one, after the first look
            raise TypeError(f"{cls.__name__}: dataclass_on_first_look needs a docstring")
        body = {k: v for k, v in cls.__dict__.items() if k not in ("__dict__", "__weakref__")}
        body["__qualname__"] = cls.__qualname__
        for name, value in body.items():
            # the class attributes the dataclass leaves, now: a Field's default, or none
            if isinstance(value, dataclasses.Field):
                if value.default is dataclasses.MISSING:
                    delattr(cls, name)
                else:
                    setattr(cls, name, value.default)
        for name in _LOOKED_FOR:
            setattr(cls, name, _OnFirstLook(cls, name, body))
        return cls
    return mark


if TYPE_CHECKING:  # the type checker sees the dataclass the class becomes
    from dataclasses import dataclass as dataclass_on_first_look
else:
    dataclass_on_first_look = _dataclass_on_first_look
    """``@dataclass(eq=False, init=False, repr=False)``, applied when the class is first
    asked for its fields (module doc): for a class with a docstring that writes its
    ``__init__`` and ``__repr__`` out and has no ``==``, to which the decorator would
    add no method later. Until then the class is as the decorator leaves it otherwise
    (its `dataclasses.field` defaults made plain class attributes, or none)."""
