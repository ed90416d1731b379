"""The cases of a sweep: each ``--set PATH=START:STOP:COUNT`` an axis, the Cartesian grid
of the axes (the last one varying fastest), or N random samples (seeded).

    bodies.rod.mass=0.3:1.2:10         10 values from 0.3 to 1.2, both included, evenly
                                       spaced (to 15 significant digits: 0.4:0.8:3 is
                                       0.4, 0.6, 0.8)
    drivers.motor.speed=100 rpm:3000 rpm:30     a unit, as the file reads it
    joints.P.axis.1=0,0.1,0.25         the values listed (commas, as Hydra's multirun)
    bodies.crank.mass=0.5              one value, the same in every case (not a column)
    gravity=[0, -1.62]                 one value too: a list is a vector

With ``--samples N --seed S`` each axis is a range ``START:STOP`` drawn uniformly (or a
list drawn from), N cases. From Python the same texts serve, or a mapping path -> values
(`grid_of`). A case is found from its index alone (`Grid.values`), so a
process evaluating a chunk of cases needs only the indices.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from mbody.errors import MbodyError, given_twice, option_entry, option_name
from mbody.model.values import parse_assignment, parse_value, plain

MAX_CASES = 100_000_000
"""Most cases one sweep holds (a grid's size is the product of its axes' counts)."""
_NUMBER = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*"
                     r"([A-Za-z°µ][\w°µ²/^ ]*?)?\s*")
"""A number, and the unit written after it (``300 rpm``, ``2 kg m^2``; a unit starts with a
letter: ``2*t`` is an expression, not 2 in a unit ``*t``)."""


@dataclass(frozen=True)
class Axis:
    """One varied path.

    Parameters
    ----------
    path : str
        The path as given (the results' column name).
    values : tuple
        The values listed, or (start, stop) of a range.
    count : int
        A range's number of grid values (0: drawn at random, or a listed axis).
    unit : str
        The unit the values were written in (``rpm``: a range ``300 rpm:1200 rpm:4``, or
        values listed each with it, ``300 rpm,600 rpm``), '' for none: the values are
        then numbers, the unit in the column's name (`column`).
    listed : bool
        The values are listed (``[a, b, c]``), not a range.
    """

    path: str
    values: tuple[Any, ...]
    count: int = 0
    unit: str = ""
    listed: bool = False

    @property
    def column(self) -> str:
        """The results' column of the axis: its path as given, with the unit its values
        were written in, ``drivers.motor.speed [rpm]`` (the column holds numbers)."""
        return f"{self.path} [{self.unit}]" if self.unit else self.path

    @property
    def size(self) -> int:
        """How many grid values the axis has (known without making them)."""
        return len(self.values) if self.listed else self.count

    def value(self, k: int) -> Any:
        """The axis's k-th grid value (as the results' column shows it), made alone: a
        grid of many values is never held as a list."""
        if self.listed:
            return self.values[k]
        lo, hi = self.values
        if self.count == 1:
            return lo
        # numpy's linspace's k-th value (k step + start, the last exactly stop), to 15
        # significant digits, as written: 0.4:0.8:3 gives 0.6, not 0.6000000000000001 (a
        # double holds 15 digits exactly)
        x = hi if k == self.count - 1 else float(k) * ((hi - lo) / (self.count - 1)) + lo
        return float(f"{x:.15g}")

    def drawn(self, u: float) -> Any:
        """The value a uniform number u in [0, 1) draws (a random sample)."""
        if self.listed:
            return self.values[min(int(u * len(self.values)), len(self.values) - 1)]
        lo, hi = self.values
        return lo + (hi - lo) * u

    def for_file(self, number: Any) -> Any:
        """A column's value as the file would hold it (with the axis's unit)."""
        if self.unit and isinstance(number, float | int):
            return f"{number!r} {self.unit}"
        return number


@dataclass(frozen=True)
class Grid:
    """Every case of a sweep (module doc).

    Parameters
    ----------
    axes : tuple of Axis
        The varied paths, in the order given.
    fixed : dict
        Paths set to one value in every case (applied to the model, not columns).
    samples : int or None
        N random cases instead of the grid.
    seed : int
        The random samples' seed.
    """

    axes: tuple[Axis, ...]
    fixed: dict[str, Any] = field(default_factory=dict)
    samples: int | None = None
    seed: int = 0

    @property
    def paths(self) -> tuple[str, ...]:
        return tuple(a.path for a in self.axes)

    @property
    def columns(self) -> tuple[str, ...]:
        """The results' columns of the axes (`Axis.column`: a unit in the name)."""
        return tuple(a.column for a in self.axes)

    def shown(self, index: int) -> str:
        """Case `index`'s values in a message: ``drivers.motor.speed=3000.0 rpm, ...``."""
        return ", ".join(f"{a.path}={a.for_file(x)}" for a, x in
                         zip(self.axes, self.numbers(index), strict=True))

    @property
    def cases(self) -> int:
        """How many cases (from the axes' counts; any size, as a file may ask)."""
        if self.samples is not None:
            return self.samples
        return math.prod(a.size for a in self.axes)

    def __len__(self) -> int:
        return self.cases

    @cached_property
    def _draws(self) -> np.ndarray:
        """(N, axes) uniform numbers in [0, 1), one column per axis (the same in every
        process: numpy's PCG64 from the seed)."""
        rng = np.random.default_rng(self.seed)
        return rng.random((len(self), len(self.axes)))

    def numbers(self, index: int) -> list[Any]:
        """Case `index`'s value of each axis, as the results' columns show it."""
        if self.samples is not None:
            return [a.drawn(u) for a, u in zip(self.axes, self._draws[index].tolist(),
                                               strict=True)]
        out = []
        for axis in reversed(self.axes):
            index, r = divmod(index, axis.size)
            out.append(axis.value(r))
        return out[::-1]

    def values(self, index: int) -> dict[str, Any]:
        """Case `index` as `Model.with_values` takes it (path -> value for the file)."""
        return {a.path: a.for_file(x) for a, x in zip(self.axes, self.numbers(index),
                                                         strict=True)}


def parse_grid(specs: Sequence[str], samples: int | None = None, seed: int = 0) -> Grid:
    """The `Grid` of ``--set`` options (module doc).

    Parameters
    ----------
    specs : sequence of str
        ``PATH=START:STOP:COUNT``, ``PATH=[a, b, ...]`` or ``PATH=VALUE`` each.
    samples : int, optional
        N random cases (then ranges are ``START:STOP``).
    seed : int
        Their seed.

    Returns
    -------
    Grid

    Raises
    ------
    MbodyError
        A malformed range (with what was expected), a path given twice, no varied path,
        or more than `MAX_CASES` cases.
    """
    # each spec read as it comes: its errors in the order given
    return _grid(((*parse_assignment(spec, option_name("values")), None)
                  for spec in specs), samples, seed)


def grid_of(values: Mapping[str, Any] | Sequence[str] | str, samples: int | None = None,
            seed: int = 0) -> Grid:
    """The `Grid` of a sweep's values given in Python: ``--set`` options (`parse_grid`),
    or a mapping path -> values.

    In a mapping, a list, tuple or array is the values one per case, each as the file
    would hold it (``[0.4, 0.8]``, ``["300 rpm", "600 rpm"]``, ``[[0, -9.81], [0,
    -1.62]]``); text is what follows ``PATH=`` in ``--set`` (``"0.3:1.2:10"``, ``"300
    rpm:1200 rpm:4"``, ``"[0, -1.62]"``: a range, or one value for every case); any other
    value (a number, a mapping) is one value for every case.

    Parameters
    ----------
    values : mapping, sequence of str, or str
        The values (above).
    samples : int, optional
        N random cases (then ranges are ``START:STOP``).
    seed : int
        Their seed.

    Returns
    -------
    Grid

    Raises
    ------
    MbodyError
        As `parse_grid`; also a path that is not text, or an empty list of values.
    """
    if isinstance(values, str):
        values = [values]
    if not isinstance(values, Mapping):
        if not (isinstance(values, Sequence) and all(isinstance(v, str) for v in values)):
            bad = (next(v for v in values if not isinstance(v, str))
                   if isinstance(values, Sequence) else values)
            raise MbodyError("the sweep's values: expected a mapping path -> values (such as "
                             "{'bodies.rod.mass': [0.4, 0.8]}) or --set texts (such as "
                             f"['bodies.rod.mass=0.3:1.2:10']), got {_shown(bad)}")
        return parse_grid(values, samples, seed)
    entries: list[tuple[str, Any, str]] = []
    for path, value in values.items():
        if not isinstance(path, str) or not path.strip():
            raise MbodyError(f"the sweep's values: a path is text such as 'bodies.rod.mass', "
                             f"got {_shown(path)}")
        if isinstance(value, Sequence | np.ndarray) and not isinstance(value, str):
            value = plain(list(value))  # the values one per case (a range, an array too)
        elif not isinstance(value, str):
            value = plain(value)
        entries.append((path.strip(), value, path))
    return _grid(entries, samples, seed)


def _shown(value: Any) -> str:
    """`value` in a message: its repr, cut short, and its type."""
    text = repr(value)
    return f"{text[:60]}{'...' if len(text) > 60 else ''} ({type(value).__name__})"


def _grid(entries: Iterable[tuple[str, Any, str | None]], samples: int | None, seed: int
          ) -> Grid:
    """The `Grid` of (path, value, key) triples: text as ``--set`` writes it after the
    ``=``, or a Python value; `key` is a mapping's key as given (`grid_of`), None for a
    ``--set`` text. Messages name an entry as the caller gives it (``--set PATH`` on the
    command line, ``values['PATH']`` in Python: `mbody.errors.option_entry`)."""
    axes: list[Axis] = []
    fixed: dict[str, Any] = {}
    seen: dict[str, str | None] = {}
    for path, value, key in entries:
        if path in seen:
            # keys of a mapping that differ only in the spaces around them
            how = f"as {seen[path]!r} and {key!r}" if key is not None else ""
            raise given_twice(option_entry("values", path), how)
        seen[path] = key
        if not isinstance(value, str):
            if not isinstance(value, list):
                fixed[path] = value
            elif not value:
                raise MbodyError(f"{option_entry('values', path)}: no values (an empty list)")
            else:
                axes.append(_listed(path, _finite(value, path)))
            continue
        text = value
        parts = _top_level(text, ",")
        if ":" in text and len(_top_level(text, ":")) > 1:
            axes.append(_range(path, text, samples is not None))
        elif len(parts) > 1:
            if any(not p.strip() for p in parts):
                raise MbodyError(f"{option_entry('values', path)}: an empty value in the list "
                                 f"{text!r}")
            listed = [parse_value(p, path) for p in parts]
            axes.append(_listed(path, _finite(listed, path)))
        else:
            fixed[path] = parse_value(text, path)
    if not axes:
        raise MbodyError(f"a sweep varies at least one value: "
                         f"{option_entry('values', 'PATH')}=START:STOP:COUNT (for example "
                         "bodies.rod.mass=0.3:1.2:10)")
    if samples is not None and samples < 1:
        raise MbodyError(f"{option_name('samples')}: expected at least 1 case, got {samples}")
    grid = Grid(tuple(axes), fixed, samples, seed)
    size = grid.cases  # from the counts: no value is made before this bound
    if size > MAX_CASES:
        raise MbodyError(f"the sweep has {_spaced(size)} cases; at most "
                         f"{_spaced(MAX_CASES)} are run (fewer values per axis, or "
                         f"{option_name('samples', 'N', 'N')})")
    return grid


def _listed(path: str, values: list[Any]) -> Axis:
    """The axis of values listed for `path`: each written with one unit (``300 rpm``,
    ``600 rpm``) is that number, the unit in the column's name, as a range's; else the
    values as given (numbers, vectors, expressions, units that differ)."""
    units, numbers = set(), []
    for value in values:
        m = _NUMBER.fullmatch(value) if isinstance(value, str) else None
        if m is None or not m.group(2):
            return Axis(path, tuple(values), listed=True)
        units.add(m.group(2))
        numbers.append(float(m.group(1)))
    if len(units) != 1 or not all(map(math.isfinite, numbers)):
        return Axis(path, tuple(values), listed=True)
    return Axis(path, tuple(numbers), unit=units.pop(), listed=True)


def _finite(values: list[Any], path: str) -> list[Any]:
    """`values` (one per case) of `path`, refused at the first number in one that is not
    finite (NaN, inf; also inside a vector), as a range's end is: such a case could only
    fail."""
    def bad(x: Any) -> Any:
        if isinstance(x, float) and not math.isfinite(x):
            return x
        items = x.values() if isinstance(x, dict) else x if isinstance(x, list) else ()
        return next((b for b in map(bad, items) if b is not None), None)

    for k, value in enumerate(values):
        x = bad(value)
        if x is not None:
            where = (f" (value {k + 1} of {len(values)}"
                     + (f": {value!r}" if value is not x else "") + ")"
                     if len(values) > 1 else "")
            raise MbodyError(f"{option_entry('values', path)}: expected a finite number, got "
                             f"{x!r}{where}")
    return values


def _spaced(n: int) -> str:
    """n with its thousands apart: 100 000 000."""
    return f"{n:,}".replace(",", " ")


def _top_level(text: str, sep: str) -> list[str]:
    """`text` split at each `sep` outside brackets and quotes (``[0, 1]`` is one value)."""
    parts, depth, quote, start = [], 0, "", 0
    for i, ch in enumerate(text):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == sep and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    return [*parts, text[start:]]


def _range(path: str, text: str, random: bool) -> Axis:
    entry = option_entry("values", path)  # --set PATH on the command line
    parts = text.split(":")
    form = "START:STOP" if random else "START:STOP:COUNT"
    example = f"{path}=0.3:1.2" if random else f"{path}=0.3:1.2:10"
    if len(parts) != (2 if random else 3):
        extra = (f" (with {option_name('samples')}, the count is the number of samples)"
                 if random else "")
        raise MbodyError(f"{entry}: expected {form}, such as {example}; got {text!r}"
                         + extra)
    ends, units = [], []
    for part in parts[:2]:
        m = _NUMBER.fullmatch(part)
        if not m:
            raise MbodyError(f"{entry}: {part.strip()!r} is not a number (a range is "
                             f"{form}, such as {example})")
        x = float(m.group(1))
        if not math.isfinite(x):
            raise MbodyError(f"{entry}: expected a finite number, got {part.strip()!r}")
        ends.append(x)
        units.append(m.group(2) or "")
    if units[0] != units[1]:
        raise MbodyError(f"{entry}: the range's ends have different units "
                         f"({units[0] or 'none'} and {units[1] or 'none'})")
    count = 0
    if not random:
        try:
            count = int(parts[2].strip())
        except ValueError:
            raise MbodyError(f"{entry}: the count {parts[2].strip()!r} is not a whole "
                             f"number (a range is {form})") from None
        if count < 1:
            raise MbodyError(f"{entry}: expected a count of at least 1, got {count}")
        if count == 1 and ends[0] != ends[1]:  # one value cannot span both ends
            raise MbodyError(f"{entry}: a count of 1 is one value, and {parts[0].strip()}"
                             f" and {parts[1].strip()} are two; give a count of 2 or more, or "
                             f"the value alone ({entry}={parts[0].strip()})")
    return Axis(path, (ends[0], ends[1]), count, units[0])
