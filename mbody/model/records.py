"""The model's records: one `Body`, `Load` or `Joint` as given in the file, made on first use.

A record views the model's arrays; `Records` (a sequence) and `BodyRecords` (a mapping by
name) make each record when it is first asked for, so that a large model's file is read
without making one per body, load or joint.
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any, TypeVar, overload

import numpy as np

from mbody.errors import not_found, wrong_type
from mbody.model.expressions import Expression
from mbody.model.reprs import count, name_list, vector_text


@dataclass(frozen=True)
class Body:
    """One rigid body as given in the file (a read-only view of the model's arrays).

    Parameters
    ----------
    name : str
        As in the file.
    index : int
        Its place in the stacking order (`Model.body_names`).
    mass : float
        kg.
    inertia : (3, 3) array
        About the mass centre, body axes (kg m²); planar: I_G at ``[2, 2]``.
    shape : dict or None
        The drawing shape from the file (``{box: [...]}``...).
    color : str or None
        The drawing colour from the file.
    particle : bool, optional
        A point mass (``inertia: 0``): translation rows only; `inertia` holds a dummy.
    """

    name: str
    index: int
    mass: float  # kg
    inertia: np.ndarray  # (3, 3) body axes about the mass centre, kg m^2 (planar: I_G at [2, 2])
    shape: dict[str, Any] | None
    color: str | None
    particle: bool = False
    """A point mass (`inertia: 0`): translation rows only; `inertia` holds a dummy."""

    @property
    def I_G(self) -> float:
        """Planar moment of inertia about the mass centre (the z-z entry)."""
        return float(self.inertia[2, 2])

    def __repr__(self) -> str:  # the dataclass's would print the inertia tensor
        J = "particle" if self.particle else (
            "I " + vector_text(np.diag(self.inertia)) + " kg m^2" + (
                "" if np.count_nonzero(self.inertia - np.diag(np.diag(self.inertia))) == 0
                else " (and products)"))
        return f"<Body {self.name!r} (#{self.index}): m {self.mass:g} kg, {J}; .inertia, .shape>"


@dataclass(frozen=True)
class Load:
    """An applied load as given in the file: force, torque or spring.

    Parameters
    ----------
    name : str
        As in the file.
    type : str
        ``force``, ``torque`` or ``spring``.
    bodies : tuple of str
        The body it acts on (a spring: its two ends, ``ground`` allowed).
    vector : (3,) array or None
        Force (N) or torque (N m) components in `frame`; None for a spring.
    frame : str
        ``world`` or ``body``: the axes `vector` is given in.
    at : tuple of (3,) arrays
        Attachment points, body axes from the mass centre (world for ground) (m).
    stiffness, rest_length, damping : float, optional
        A spring's k (N/m), rest length (m) and damping (N s/m).
    expressions : dict, optional
        Components of `vector` that vary in time (index 0-2 -> expression of t);
        `vector` holds their values at t = 0.
    """

    name: str
    type: str
    bodies: tuple[str, ...]
    vector: np.ndarray | None  # force or torque, in `frame`, 3-D
    frame: str
    at: tuple[np.ndarray, ...]  # attachment points: body axes (world for ground)
    stiffness: float = 0.0
    rest_length: float = 0.0
    damping: float = 0.0
    expressions: dict[int, Expression] = field(default_factory=dict)
    """Components of `vector` that vary in time (3-D index -> expression of t);
    `vector` holds their values at t = 0."""

    def __repr__(self) -> str:  # the dataclass's would print its arrays
        on = " - ".join(self.bodies)
        if self.type == "spring":
            what = f"k {self.stiffness:g} N/m, rest {self.rest_length:g} m"
        else:
            unit = "N m" if self.type == "torque" else "N"
            what = f"{vector_text(np.zeros(3) if self.vector is None else self.vector)} {unit} " \
                   f"({self.frame} axes)" + (", varies in time" if self.expressions else "")
        return f"<Load {self.name!r}: {self.type} on {on}, {what}>"


@dataclass(frozen=True)
class Joint:
    """A joint: its reaction components and its frame at the initial pose.

    Parameters
    ----------
    name : str
        As in the file; reaction labels are ``<name>.<component>``.
    type : str
        ``revolute``, ``prismatic``, ``spherical``, ``universal``, ``fixed``...
    parent, child : str
        The bodies it joins (``ground`` for the world).
    at : (3,) array
        The joint point at the file's pose, world axes (m) (with points given on each
        body: the child's); `Model.joint_table` has it in each body's axes.
    W_E0 : (3, 3) array
        The joint frame at the initial pose, axes as columns (world): the file's pose, or
        the assembled one when `mbody.load` assembled the model.
    components : tuple of str
        Its reaction components (``Fx``, ``Fy``, ``Mz``...), the columns of G in order.
    axis, axis2 : (3,) array, optional
        The joint's axis (and a universal joint's second axis), where it has one.
    particle_joint : str, optional
        With a particle at an end: ``pin`` or ``link`` (docs "Particles"); else "".
    """

    name: str
    type: str
    parent: str
    child: str
    at: np.ndarray  # (3,) world, the file's pose
    W_E0: np.ndarray  # (3, 3) joint frame at the initial pose, axes as columns (world)
    components: tuple[str, ...]
    axis: np.ndarray | None = None
    axis2: np.ndarray | None = None
    particle_joint: str = ""
    """With a particle at an end: "pin" or "link" (see docs "Particles"); else ""."""

    @property
    def labels(self) -> list[str]:
        """Its reaction labels, ``<name>.<component>``."""
        return [f"{self.name}.{k}" for k in self.components]

    def __repr__(self) -> str:  # the dataclass's would print its frame
        return (f"<Joint {self.name!r}: {self.type}, {self.parent} -> {self.child} at "
                f"{vector_text(self.at)} m; reactions {', '.join(self.labels)}>")


def field_names(cls: type) -> list[str]:
    """The names of the dataclass `cls`'s fields, in order (for `record`)."""
    return [f.name for f in fields(cls)]


def record(cls: type, names: list[str], row: tuple[Any, ...]) -> Any:
    """An instance of the frozen dataclass `cls` from a tuple of all its fields.

    A frozen dataclass's ``__init__`` sets each field through ``object.__setattr__``;
    filling the instance's ``__dict__`` at once is about 4x faster (the class must take
    every field from the tuple: no ``__post_init__``, no slots).
    """
    obj: Any = object.__new__(cls)
    obj.__dict__.update(zip(names, row, strict=True))
    return obj


T = TypeVar("T")


class Records(Sequence[T]):
    """A read-only sequence of records, each made on first use and then kept; a record is
    found by its index or by its name (``model.joints["A"]``, as ``model.joints[0]``).

    A large model's file is read without making a record per load or joint (a few
    hundred bytes and about a microsecond each); the arrays they view are the model's.

    Parameters
    ----------
    names : sequence of str
        The records' names, in order (their number is the sequence's length).
    make : callable
        Index -> its record.
    noun : tuple of str
        What a record is, singular and plural (``("joint", "joints")``), for messages.
    """

    __slots__ = ("_n", "_make", "_made", "_names", "_noun", "_index")

    def __init__(self, names: Sequence[str], make: Callable[[int], T],
                 noun: tuple[str, str] = ("record", "records")):
        self._n = len(names)
        self._names = names
        self._make = make
        self._noun = noun
        self._made: list[T | None] = [None] * self._n
        self._index: dict[str, int] | None = None

    def __len__(self) -> int:
        return self._n

    @overload
    def __getitem__(self, i: int | str) -> T: ...

    @overload
    def __getitem__(self, i: slice) -> tuple[T, ...]: ...

    def __getitem__(self, i: int | str | slice) -> T | tuple[T, ...]:
        if isinstance(i, slice):
            return tuple(self[k] for k in range(*i.indices(self._n)))
        if isinstance(i, str):
            k = self.where(i)
        else:
            k = self._position(i)
        made = self._made[k]
        if made is None:
            made = self._made[k] = self._make(k)
        return made

    def _position(self, i: object) -> int:
        """`i` as an index 0 .. n - 1 (negative counts from the end): IndexError out of
        range, TypeError for what is neither an index nor a name."""
        n, noun = self._n, self._noun
        if isinstance(i, bool) or not hasattr(i, "__index__"):
            raise wrong_type(f"{noun[1]}[key]", "a name (str) or an index (int)", i)
        k = operator.index(i)
        if not -n <= k < n:
            raise IndexError(f"{noun[0]} index {k} out of range ({count(n, *noun)}"
                             + (f": {name_list(self._names)}" if n else "") + ")")
        return k + n if k < 0 else k

    def where(self, name: str) -> int:
        """The index of the record named `name`; KeyError with the closest name, or the
        names there are."""
        k = self._named(name)
        if k is None:
            one, many = self._noun
            raise not_found(f"{one} named", name, self._names, many, f"this model has no {many}")
        return k

    def _named(self, name: str) -> int | None:
        if self._index is None:  # made on the first look-up by name
            self._index = {nm: k for k, nm in enumerate(self._names)}
        return self._index.get(name)

    def __contains__(self, item: object) -> bool:  # a name, or a record
        if isinstance(item, str):
            return self._named(item) is not None
        return super().__contains__(item)

    def __iter__(self) -> Iterator[T]:
        for k in range(self._n):
            yield self[k]

    def __repr__(self) -> str:
        if not self._n:
            return f"<no {self._noun[1]}>"
        return f"<{count(self._n, *self._noun)}: {name_list(self._names)}>"


class BodyRecords(Mapping[str, Body]):
    """Each body's `Body` record by name, in the stacking order, made on first use.

    Parameters
    ----------
    names : tuple of str
        The stacking order.
    mass : (n,) array
    inertia : (n, 3, 3) array
        Read-only: each record's ``inertia`` is a view of its row.
    shape, color : list
        Per body, or None.
    particle : (n,) bool array
        The point masses.
    """

    __slots__ = ("_names", "_mass", "_inertia", "_shape", "_color", "particle", "_records")

    def __init__(self, names: tuple[str, ...], mass: np.ndarray, inertia: np.ndarray,
                 shape: list[dict[str, Any] | None], color: list[str | None],
                 particle: np.ndarray):
        self._names = names
        self._mass = mass
        self._inertia = inertia
        self._shape = shape
        self._color = color
        self.particle = particle
        fields_ = field_names(Body)

        def make(i: int) -> Body:
            return record(Body, fields_, (names[i], i, float(mass[i]), inertia[i], shape[i],
                                          color[i], bool(particle[i])))

        self._records = Records(names, make, ("body", "bodies"))

    @property
    def shapes(self) -> tuple[dict[str, Any] | None, ...]:
        """Each body's `shape` as the file gives it (None: not given), in the stacking
        order, without making a record per body (what a run keeps to be drawn)."""
        return tuple(self._shape)

    @property
    def colors(self) -> tuple[str | None, ...]:
        """Each body's `color` as the file gives it (None: not given), in the stacking
        order, without making a record per body."""
        return tuple(self._color)

    def __getitem__(self, name: str | int) -> Body:
        """The body named `name`, or at index `name` in the stacking order
        (``model.bodies[0]``); KeyError with a did-you-mean, IndexError with the range."""
        return self._records[name]

    def __contains__(self, name: object) -> bool:  # a name: the mapping's keys
        return isinstance(name, str) and name in self._records

    def get(self, name: object, default: Any = None) -> Any:
        """The body named `name`, else `default`: a mapping's `get`, by name only (its keys
        are the names; ``model.bodies[0]`` is by index)."""
        return self._records[name] if isinstance(name, str) and name in self else default

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)

    def __repr__(self) -> str:
        return repr(self._records)
