"""A driven mechanism's reactions and drivers' efforts at chosen instants: where a driver's
coordinate has a given value (the crank at 90 deg) or at given times, each solved exactly
there, not interpolated between a run's samples.

An instant asked by a driver's coordinate is the first time in the run at which the
driver's law reaches that value: an angle modulo a turn (the crank at 90 deg is also at
450 deg; reduced in the unit it is written in, so that 1e20 deg is exactly 280 deg), a
displacement as it is. It is found between the two samples that bracket it,
then by bisection on the law itself, to the rounding of the time. The mechanism is then
carried there from the sample just before it, as the run carries one sample to the next
(`mbody.simulate.kinematic.carry`: the Taylor step, Newton's method on the sample's
branch, the solve), so its positions, velocities, reactions and efforts are those of
that instant.

Each row is labelled with each driver's coordinate there, one way whichever way the
instant was asked (a time, a coordinate, a step of ``every``): the law's value at that
instant, less whole turns, 0 <= angle < 360 deg, for an angle driver the run turns through
a whole turn or more (whose every angle it reaches); else the law's value as it is (a
driver that swings between -30 and 30 deg reads -30, not 330).

    table = kinematic_at(model, ["90 deg", "180 deg"], axes="world")
    table["motor.M"]                  # (2,) N m, at 90 and 180 deg
    kinematic_at(model, every="30 deg").write_csv("table.csv")
"""

from __future__ import annotations

import csv
import io
import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mbody.conventions import check_axes
from mbody.errors import (
    MbodyError,
    not_found,
    option_name,
    option_setting,
    real_number,
    wrong_type,
)
from mbody.model.arguments import checked_model
from mbody.model.checks import MAX_ANGLE, angle_spelling, si_quantity, written_quantity
from mbody.model.model import Model
from mbody.simulate.axes import sample_states, world_series
from mbody.simulate.kinematic import carry, default_sampling, kinematic_run
from mbody.simulate.peaks import reaction_unit
from mbody.simulate.trajectory import MAX_SAMPLES, Trajectory
from mbody.solve.kinematics import require_fully_driven
from mbody.util.atomic import write_atomic
from mbody.util.formatting import NOISE, num, number, rounded_to, spreadsheet_text
from mbody.util.frozen import Frozen

MAX_INSTANTS = 100_000
"""Rows at most in one table (``every`` a tiny step): each row is a Newton solve."""
TURN = 2.0 * math.pi
TURN_IN = {"deg": 360.0, "rev": 1.0}
"""Angle units whose turn is a whole number: an angle written in one is reduced modulo a
turn there, exactly (`math.fmod`), whatever its size. One in rad (or a bare number) is at
most `mbody.model.checks.MAX_ANGLE`, a model file's bound: a double's rounding of 2 pi
would shift a larger angle's reduction by more than 4e-8 rad."""
UNITS = {"angle": "deg, rad or rev", "displacement": "m, mm or cm", "time": "s or ms"}
"""The units an instant is asked in, as the messages list them (any that
`mbody.model.checks.si_quantity` reads is taken)."""
QUANTITY = {"rad": "angle", "m": "displacement", "s": "time"}
"""`si_quantity`'s SI unit -> what an instant asked in it gives."""


class Instants(Frozen):
    """Reactions and drivers' efforts at some instants of a driven mechanism: the rows
    `kinematic_at` solves, or every sample of a run (`of_run`).

    Attributes
    ----------
    t : (K,) array
        The instants' times (s).
    drivers : tuple of str
        The model's drivers; ``kinds`` says of each "angle" or "displacement".
    coordinates : (K, k) array
        Each driver's coordinate at each instant (rad or m), the rows' labels: its law's
        value there, less whole turns (0 <= angle < 2 pi) for an angle driver that the
        run turns through a whole turn (module doc); the same however the instant was
        asked. `of_run` keeps the law's values, as the run does.
    labels : tuple of str
        The reactions and drivers' efforts (``O.Fx``, ``motor.M``), in ``axes``.
    values : (K, m) array
        Their values (N, or N m for a moment: ``units``).
    axes : str
        "joint" or "world" (`mbody.equations.world`).
    asked : tuple of str
        How each instant was asked (``"90 deg"``, ``"t = 0.01 s"``); '' for a run's
        samples.
    """

    t: np.ndarray
    drivers: tuple[str, ...]
    kinds: tuple[str, ...]
    coordinates: np.ndarray
    labels: tuple[str, ...]
    values: np.ndarray
    axes: str
    asked: tuple[str, ...]
    model_name: str

    def __init__(self, t: np.ndarray, drivers: Sequence[str], kinds: Sequence[str],
                 coordinates: np.ndarray, labels: Sequence[str], values: np.ndarray,
                 axes: str, asked: Sequence[str], model_name: str = "") -> None:
        arrays = {"t": np.array(t, dtype=float), "coordinates": np.array(coordinates, dtype=float),
                  "values": np.array(values, dtype=float)}
        for a in arrays.values():
            a.flags.writeable = False
        self.__dict__.update(arrays, drivers=tuple(drivers), kinds=tuple(kinds),
                             labels=tuple(labels), axes=axes, asked=tuple(asked),
                             model_name=model_name)

    def __len__(self) -> int:
        return len(self.t)

    def __getitem__(self, label: str) -> np.ndarray:
        """(K,) one reaction's or effort's values at the instants, by its label."""
        if label not in self.labels:
            raise not_found("reaction or effort", label, self.labels, "reactions and efforts")
        return self.values[:, self.labels.index(label)]

    @property
    def units(self) -> tuple[str, ...]:
        """Each label's unit: "N", or "N m" for a moment."""
        return tuple(reaction_unit(label) for label in self.labels)

    def __repr__(self) -> str:
        return (f"<Instants of {self.model_name!r}: {len(self)} instant(s), "
                f"{len(self.labels)} reactions and efforts ({self.axes} axes); "
                "['O.Fx'], .t, .coordinates, .text(), .write_csv(path)>")

    @classmethod
    def of_run(cls, model: Model, run: Trajectory) -> Instants:
        """Every sample of a kinematic run (or any run with drivers) as a table."""
        d = model.drivers
        names = tuple(d.names) if d is not None else ()
        coords = (np.stack([np.asarray(law[0](run.t), dtype=float) * np.ones(len(run.t))
                            for law in d.laws], axis=1)
                  if d is not None and len(names) else np.zeros((len(run.t), 0)))
        return cls(run.t, names, _kinds(model), coords, run.reaction_labels, run.reactions,
                   str(run.info.get("reaction_axes", "joint")), [""] * len(run.t),
                   run.model_name)

    def header(self) -> list[tuple[str, str]]:
        """(name, unit) of each column: each driver's coordinate (deg for an angle), the
        time, then each reaction and effort."""
        return ([(n, "deg" if k == "angle" else "m")
                 for n, k in zip(self.drivers, self.kinds, strict=True)]
                + [("t", "s")] + list(zip(self.labels, self.units, strict=True)))

    def rows(self) -> np.ndarray:
        """(K, k + 1 + m) the columns of `header` as numbers. The drivers' columns, which
        label the rows, are rounded at `NOISE` of the column's scale (at least a turn
        for an angle, as `text` takes it): a law's 30 deg reads 30.0, not its conversion
        from radians, 29.999999999999996 (what `csv` and `json` write too)."""
        coords = self.coordinates.copy()
        for i, kind in enumerate(self.kinds):
            if kind == "angle":
                coords[:, i] = np.degrees(coords[:, i])
            scale = float(np.abs(coords[:, i]).max(initial=360.0 if kind == "angle" else 0.0))
            coords[:, i] = rounded_to(coords[:, i], scale)
        return np.column_stack((coords, self.t, self.values))

    def text(self) -> str:
        """The table as `mbody kinematics --at` prints it: a row per instant, the columns'
        names over their units; values at 6 significant digits, those below `NOISE` of
        the largest (rounding beside it) as 0: of the reactions and efforts in the table,
        or of a driver's column, at least a turn for an angle (a law's 1.5e-13 deg at its
        360 deg, less a turn)."""
        head = self.header()
        data = self.rows()
        big = float(np.abs(self.values).max(initial=0.0))
        scale = [float(np.abs(data[:, c]).max(initial=360.0 if kind == "angle" else 0.0))
                 for c, kind in enumerate(self.kinds)] + [0.0] \
            + [big] * len(self.labels)  # an angle's scale at least a turn; the time as it is
        cells = [[num(x, NOISE * s) for x, s in zip(r, scale, strict=True)] for r in data]
        table = [[n for n, _ in head], [u for _, u in head], *cells]
        widths = [max(len(r[c]) for r in table) for c in range(len(head))]
        return "\n".join("  " + "  ".join(x.ljust(w) for x, w in zip(r, widths, strict=True))
                         .rstrip() for r in table)

    def csv(self) -> str:
        """The table as CSV: a header of ``name (unit)`` cells, then a row per instant,
        numbers to 17 significant digits (a double read back is the same double)."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow([spreadsheet_text(f"{n} ({u})") for n, u in self.header()])
        w.writerows([repr(float(x)) for x in r] for r in self.rows())
        return buf.getvalue()

    def write_csv(self, path: str | Path) -> Path:
        """Write `csv` to `path` atomically (`mbody.util.atomic.write_atomic`)."""
        return write_atomic(path, self.csv())

    def json(self) -> list[dict]:
        """The rows as `mbody kinematics --json` gives them: t, asked, each driver's
        coordinate (deg or m), and each label's value."""
        data = self.rows()
        k = len(self.drivers)
        return [{"t": float(r[k]), "asked": a,
                 "drivers": {n: float(x) for n, x in zip(self.drivers, r[:k], strict=True)},
                 "values": {lb: float(x) for lb, x in zip(self.labels, r[k + 1:], strict=True)}}
                for r, a in zip(data, self.asked, strict=True)]


def _kinds(model: Model) -> tuple[str, ...]:
    d = model.drivers
    if d is None:
        return ()
    return tuple("angle" if c == "M" else "displacement" for c in d.component)


@dataclass(frozen=True)
class Asked:
    """One instant asked: a time (`driver` None, `value` in s) or a driver's coordinate
    (`value` rad or m); `text` the value as shown, `source` the option and entry as given
    (``"--at '90 deg'"``), for messages."""

    text: str
    driver: int | None
    value: float
    source: str = ""
    t: float | None = None  # its time in the run, once found


def kinematic_at(model: Model, at: object = None, *, every: object = None,
                 times: object = None, driver: str | None = None, axes: str = "joint",
                 run: Trajectory | None = None, t_start: float = 0.0) -> Instants:
    """The reactions and drivers' efforts of a driven mechanism at chosen instants (module
    doc), each solved there.

    Parameters
    ----------
    model : Model
        A fully driven mechanism (as `kinematic_run` takes).
    at : str, number or a sequence of them
        The instants: a driver's coordinate with its unit (``"90 deg"``, ``"0.5 rev"``,
        ``"20 mm"``), or a time (``"0.01 s"``, ``"10 ms"``), as ``mbody kinematics --at``
        takes them; ``"NAME=90 deg"`` names the driver (default `driver`, else the
        model's first). A number is that driver's coordinate in rad or m. An angle is
        taken less whole turns in the unit it is written in (exact: ``"1e20 deg"`` is 280
        deg); one in rad (or a number) is at most `MAX_ANGLE`, 1e9 rad.
    every : str or number, optional
        Instead of `at`, a table over one cycle with a row every step of the driver's
        coordinate (``"30 deg"``: 0, 30, ... 330 deg when the run turns it a full turn;
        else the multiples of the step the run reaches, smallest first) or of time
        (``"0.01 s"``: from the run's start to its end).
    times : number or a sequence of numbers, optional
        Instants given as times (s), after those of `at`.
    driver : str, optional
        The driver whose coordinate a value without ``NAME=`` is (default: the first).
    axes : {"joint", "world"}
        The reactions' axes (`mbody.equations.world`).
    run : Trajectory, optional
        A kinematic run of this model (`kinematic_run`) to find the instants in and carry
        the mechanism from; default one made here from `t_start` over `default_sampling`'s
        span (a revolution of a driver turning at a constant rate, at a sample a degree),
        longer when a time asked is later.
    t_start : float
        The start of the run made here (s).

    Returns
    -------
    Instants
        A row per instant, in the order asked.

    Raises
    ------
    MbodyError
        An instant without a unit, in a unit that is not the driver's quantity, on a
        driver the model does not have, an angle in rad beyond `MAX_ANGLE`, or that the
        run does not reach (its range is said), or a time later than a run made here can
        reach; a step giving more than `MAX_INSTANTS` rows; a run of another model or
        other drivers' laws; not fully driven.
    KinematicsError
        The loops cannot close at an instant.
    """
    if not isinstance(model, Model):
        model = checked_model(model)
    check_axes(axes)
    t_start = real_number(t_start, "t_start", "a number of seconds")
    asked, step = asked_instants(model, at, every=every, times=times, driver=driver)
    if run is None:
        span, fps = default_sampling(model)
        late = max([a.value for a in asked if a.driver is None], default=t_start)
        _check_reachable(late, t_start, fps, [a for a in asked if a.value == late])
        run = kinematic_run(model, max(t_start + span, late), fps, t_start=t_start,
                            axes=axes)
    else:
        _check_run(model, run)
    if step is not None:
        asked = _every(model, run, step)
    t = np.array([_time(model, run, a) for a in asked], dtype=float)
    Y_run = sample_states(model, run)
    k = np.clip(np.searchsorted(run.t, t, side="right") - 1, 0, len(run.t) - 1)
    Y, lam = carry(model, run.t[k], Y_run[k], t)
    labels: tuple[str, ...] = tuple(model.reactions)
    values = lam
    if axes == "world":
        labels, values = world_series(model, t, Y, lam)
    d = model.drivers
    assert d is not None  # fully driven
    return Instants(t, d.names, _kinds(model), _labels(model, run, t, asked), labels, values,
                    axes, [a.text for a in asked], model.name)


def _labels(model: Model, run: Trajectory, t: np.ndarray, asked: Sequence[Asked]
            ) -> np.ndarray:
    """(K, k) each driver's coordinate at the instants `t` (rad or m), as the rows are
    labelled (module doc): the law's value, less whole turns for an angle driver the run
    turns through a whole turn; for the driver an instant was asked by, the value asked
    (already less whole turns) plus the turns the law has made there, so that the label
    is the exact value asked rather than the law's rounding of it."""
    d = model.drivers
    assert d is not None
    if not len(t):
        return np.zeros((0, len(d.names)))
    coords = np.stack([np.asarray(law[0](t), dtype=float) * np.ones(len(t))
                       for law in d.laws], axis=1)
    whole = [kind == "angle" and _turns_fully(law[0], run.t)
             for kind, law in zip(_kinds(model), d.laws, strict=True)]
    for i, w in enumerate(whole):
        if w:
            coords[:, i] = [_turn_part(x, TURN) for x in coords[:, i]]
    for r, a in enumerate(asked):
        j = a.driver
        if j is None:
            continue
        angle = d.component[j] == "M"
        turns = round((coords[r, j] - a.value) / TURN) if angle and not whole[j] else 0
        coords[r, j] = a.value + turns * TURN
    return coords


def _turns_fully(law, t: np.ndarray) -> bool:
    """Whether the angle `law` turns through a whole turn or more over the times `t` (then
    it reaches every angle, and a table over one cycle runs 0 .. 360 deg)."""
    F = np.asarray(law(t), dtype=float) * np.ones(len(t))
    return bool(F.max() - F.min() >= TURN * (1 - 1e-12))


def _turn_part(x: float, turn: float) -> float:
    """`x` less whole `turn`s: 0 <= result < turn (Python's float % is exact), where a
    result within `NOISE` of a turn below it is 0 (a tiny negative `x` gives `turn` itself,
    rounded; a law's rounding of its 360 deg, 359.99999999999994)."""
    r = x % turn
    return 0.0 if r >= turn * (1.0 - NOISE) else r


def asked_instants(model: Model, at: object = None, *, every: object = None,
                   times: object = None, driver: str | None = None
                   ) -> tuple[list[Asked], Asked | None]:
    """`kinematic_at`'s instants read and checked against `model` before any run (what
    the command line does first): the instants of `at` and `times`, or `every`'s step.

    Raises
    ------
    MbodyError
        As `kinematic_at` for what is asked; `model` not fully driven.
    """
    require_fully_driven(model)
    if every is not None and (at is not None or times is not None):
        raise MbodyError("give the instants either as at (values of a driver's coordinate, "
                         "such as '90 deg', or times such as '0.01 s') and times, or as "
                         "every (a step, such as '30 deg', for a table over one cycle), not "
                         "both")
    if at is None and every is None and times is None:
        raise MbodyError("give the instants: at=['90 deg'] (a driver's coordinate or a "
                         "time), every='30 deg' (a table over one cycle) or times=[0.01]")
    first = (_driver_index(model, driver, option_setting("driver", driver))
             if driver is not None else 0)
    if every is not None:
        return [], _asked(model, every, first, "every", step=True)
    asked = [_asked(model, x, first, "at") for x in _entries(at, "at")]
    asked += [Asked(f"t = {x:g} s", None, real_number(x, "times", "a number of seconds"),
                    option_setting("times", x)) for x in _entries(times, "times")]
    return asked, None


def _entries(value: object, name: str) -> list:
    """`value` as a list of entries: one text or number, or a sequence of them."""
    if value is None:
        return []
    if isinstance(value, str | numbers.Real) and not isinstance(value, bool):
        return [value]
    if isinstance(value, Sequence | np.ndarray):
        out = list(value)
        if len(out) > MAX_INSTANTS:
            raise MbodyError(f"{name}: {len(out)} instants is more than {MAX_INSTANTS}")
        return out
    raise wrong_type(name, "a value such as '90 deg' or '0.01 s', or a list of them", value)


def _driver_index(model: Model, name: str, where: str) -> int:
    """The index of the driver `name` of `model`; asked at `where` (an option and its
    entry, for the message)."""
    d = model.drivers
    names = list(d.names) if d is not None else []
    if name not in names:
        raise MbodyError(f"{where}: " + not_found("driver named", name, names, "drivers",
                                                  f"{model.name!r} has no drivers").args[0])
    return names.index(name)


def _asked(model: Model, entry: object, first: int, option: str, step: bool = False
           ) -> Asked:
    """One entry of `at` (or `every`'s step): ``"[NAME=]VALUE UNIT"`` or a number (the
    driver's coordinate, rad or m), checked against the driver's kind."""
    d = model.drivers
    assert d is not None
    kinds = _kinds(model)
    where = option_setting(option, entry)
    if isinstance(entry, numbers.Real) and not isinstance(entry, bool):
        x = real_number(entry, option, "a number")
        quantity, index = kinds[first], first
        shown = (f"{math.degrees(x):g} deg" if kinds[first] == "angle" else f"{x:g} m")
        written: tuple[float, str] | None = None  # in rad or m
    elif isinstance(entry, str):
        name, sep, rest = entry.partition("=")
        index, text = (_driver_index(model, name.strip(), where), rest) if sep else \
            (first, entry)
        got = si_quantity(text)
        if got is None:
            raise MbodyError(f"{where}: {_unit_expected(model, index, text, step)}")
        x, si = got
        quantity = QUANTITY.get(si, "")
        if quantity == "time" and sep:
            raise MbodyError(f"{where}: a time is the same for every driver; write it "
                             f"without {name.strip()}=")
        if quantity not in ("time", kinds[index]):
            raise MbodyError(f"{where}: driver {d.names[index]!r} drives "
                             f"{'an angle' if kinds[index] == 'angle' else 'a displacement'}"
                             f" ({UNITS[kinds[index]]}), and {text.strip()!r} is "
                             + (f"a quantity in {si}" if not quantity else f"a {quantity}")
                             + f"; or give a time ({UNITS['time']})")
        shown = " ".join(text.split())
        written = written_quantity(text)
    else:
        raise wrong_type(option, "a value such as '90 deg' or '0.01 s', or a number (the "
                         "driver's coordinate, rad or m)", entry)
    if not math.isfinite(x):
        raise MbodyError(f"{where}: expected a finite value")
    if step and not x > 0:
        raise MbodyError(f"{where}: expected a step above 0")
    if quantity == "time":
        return Asked(shown if step else f"t = {shown}", None, x, where)
    if quantity == "angle" and not step:
        x = _angle_in_turn(x, written, where)
    return Asked(shown, index, x, where)


def _angle_in_turn(x: float, written: tuple[float, str] | None, where: str) -> float:
    """The angle asked, `x` rad (`written`: its number and unit as given), less whole
    turns: 0 <= result < 2 pi. Reduced in the unit it was written in when a turn is a
    whole number there (`TURN_IN`), which is exact however large the value; in rad, at
    most `MAX_ANGLE` (else refused, saying so)."""
    if written is not None and written[1] in TURN_IN:
        value, unit = written
        part = _turn_part(value, TURN_IN[unit])
        x = math.radians(part) if unit == "deg" else part * TURN
    elif abs(x) > MAX_ANGLE:
        raise MbodyError(f"{where}: expected an angle of at most {number(MAX_ANGLE)} rad in "
                         "magnitude (beyond it a double's 2 pi puts the angle asked off by "
                         "more than 4e-8 rad once whole turns are taken off); write it in deg "
                         "or rev, which are taken modulo a turn exactly, however large")
    return _turn_part(x, TURN)


def _unit_expected(model: Model, index: int, text: str, step: bool) -> str:
    """What a value without a unit it can be read in was expected to be, and how that
    looks (`at`'s or `every`'s)."""
    d = model.drivers
    assert d is not None
    kind = _kinds(model)[index]
    spelt = angle_spelling(text.strip()) if kind == "angle" else None
    if spelt:
        return f"write {spelt!r}"
    example = ("'30 deg'" if step else "'90 deg'") if kind == "angle" else "'20 mm'"
    time = "'0.005 s'" if step else "'0.01 s'"
    return (("give its unit: " if _is_number(text) else "expected a number and its unit: ")
            + f"{'an angle' if kind == 'angle' else 'a displacement'} of driver "
            f"{d.names[index]!r} ({UNITS[kind]}, such as {example}) or a time "
            f"({UNITS['time']}, such as {time})")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_run(model: Model, run: object) -> None:
    """`run` is a kinematic run of `model` with its drivers' laws."""
    if not isinstance(run, Trajectory):
        raise wrong_type("run", "a Trajectory (mbody.kinematic_run)", run)
    if (tuple(run.body_names) != tuple(model.body_names) or run.dimension != model.dimension
            or not run.info.get("kinematic") or not len(run.t)):
        raise MbodyError(f"run: not a kinematic run of {model.name!r} (the run is of "
                         f"{run.model_name!r}, {len(run.t)} samples; make it with "
                         "mbody.kinematic_run(model, ...))")
    d = model.drivers
    assert d is not None
    for name, law in zip(d.names, d.laws, strict=True):
        had = run.series.get(f"driver:{name}")
        now = np.asarray(law[0](run.t), dtype=float) * np.ones(len(run.t))
        scale = max(float(np.abs(now).max(initial=0.0)), 1.0)
        if had is None or not np.allclose(had, now, rtol=0.0, atol=1e-9 * scale):
            raise MbodyError(f"run: driver {name!r} of {model.name!r} moves otherwise than "
                             "in this run (made with other values of the model?); make the "
                             "run with this model")


def _time(model: Model, run: Trajectory, a: Asked) -> float:
    """The time of instant `a` in the run: as asked, or the first at which its driver's
    coordinate is the value asked (an angle modulo a turn)."""
    if a.t is not None:
        return a.t
    t = run.t
    lo, hi = float(t[0]), float(t[-1])
    if a.driver is None:
        slack = 1e-9 * max(hi - lo, 1e-300)
        if not lo - slack <= a.value <= hi + slack:
            raise MbodyError(f"{a.source}: {a.text} is outside the run, t = {lo:g} .. "
                             f"{hi:g} s; {_longer()}")
        return min(max(a.value, lo), hi)
    d = model.drivers
    assert d is not None
    law = d.laws[a.driver][0]
    angle = d.component[a.driver] == "M"
    found = first_reach(law, t, a.value, TURN if angle else None)
    if found is None:
        F = np.asarray(law(t), dtype=float) * np.ones(len(t))
        unit, scale = ("deg", 180.0 / math.pi) if angle else ("m", 1.0)
        raise MbodyError(f"{a.source}: {d.names[a.driver]} = {a.text} is not reached in "
                         f"the run: {d.names[a.driver]} goes from {F.min() * scale:.6g} to "
                         f"{F.max() * scale:.6g} {unit} over t = {lo:g} .. {hi:g} s; "
                         f"{_longer()}, or ask for a time ('0.01 s')")
    return found


def _check_reachable(late: float, t_start: float, fps: float, asked: Sequence[Asked]
                     ) -> None:
    """Refuse, before making it, a run to the time `late` (asked by `asked`) that would
    take more than `MAX_SAMPLES` samples at `fps` (`kinematic_at` without a run)."""
    if not asked or (late - t_start) * fps < MAX_SAMPLES:
        return
    reach = t_start + (MAX_SAMPLES - 1) / fps
    raise MbodyError(f"{asked[0].source}: {asked[0].text} is later than the run made here "
                     f"reaches (at most {number(MAX_SAMPLES)} samples at {number(fps)} a "
                     f"second, to t = {number(reach)} s); give a run that reaches it "
                     "(run=mbody.kinematic_run(model, t_end, fps) with a lower fps)")


def _longer() -> str:
    """How to make the run longer: --t-end on the command line, else a longer run."""
    flag = option_name("t_end")
    return (f"lengthen the run ({flag})" if flag != "t_end" else
            "give a longer run (run=mbody.kinematic_run(model, t_end, fps))")


def first_reach(law, t: np.ndarray, target: float, period: float | None) -> float | None:
    """The first time in [t[0], t[-1]] at which ``law(time)`` equals `target` (plus a
    whole number of `period`s, an angle's turn, when given), or None: the first interval
    of the samples `t` that brackets it, then bisection on the law to the rounding of the
    time. A value the law reaches only between two samples and leaves again before the
    next (a peak between them) is not found, as a run's sampled peak would miss it."""
    F = np.asarray(law(t), dtype=float) * np.ones(len(t))
    u = (F - target) / period if period else F - target
    a, b = u[:-1], u[1:]
    if period:
        inside = np.ceil(np.minimum(a, b)) <= np.maximum(a, b)
    else:
        inside = (np.minimum(a, b) <= 0.0) & (np.maximum(a, b) >= 0.0)
    hits = np.flatnonzero(inside)
    if not len(hits):
        if len(t) == 1 and (u[0] == round(u[0]) if period else u[0] == 0.0):
            return float(t[0])
        return None
    k = int(hits[0])
    n = (math.ceil(a[k]) if b[k] >= a[k] else math.floor(a[k])) if period else 0
    shift = target + n * (period or 0.0)

    def g(x: float) -> float:
        return float(np.asarray(law(np.array([x])), dtype=float).reshape(-1)[0]) - shift

    return _bisect(g, float(t[k]), float(t[k + 1]))


def _bisect(g, lo: float, hi: float) -> float:
    """A root of g in [lo, hi] where g changes sign (or vanishes at an end), to the
    rounding of the argument."""
    g_lo, g_hi = g(lo), g(hi)
    if g_lo == 0.0:
        return lo
    if g_hi == 0.0:
        return hi
    for _ in range(200):  # ~60 halvings reach adjacent doubles
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            break
        g_mid = g(mid)
        if g_mid == 0.0:
            return mid
        if (g_mid < 0.0) == (g_lo < 0.0):
            lo, g_lo = mid, g_mid
        else:
            hi, g_hi = mid, g_mid
    return lo if abs(g_lo) <= abs(g_hi) else hi


def _every(model: Model, run: Trajectory, step: Asked) -> list[Asked]:
    """The instants of a table with a row every `step` over the run's cycle (`kinematic_at`'s
    ``every``)."""
    t = run.t
    if step.driver is None:  # the quotients are checked as floats: a tiny step's is inf
        q = (float(t[-1]) - float(t[0])) / step.value * (1 + 1e-12)
        _check_count(q + 1, step)
        steps = math.floor(q) + 1
        return [Asked(f"t = {float(t[0]) + k * step.value:g} s", None,
                       min(float(t[0]) + k * step.value, float(t[-1])))
                for k in range(steps)]
    d = model.drivers
    assert d is not None
    angle = d.component[step.driver] == "M"
    F = np.asarray(d.laws[step.driver][0](t), dtype=float) * np.ones(len(t))
    lo, hi = float(F.min()), float(F.max())
    if angle and _turns_fully(d.laws[step.driver][0], t):  # a full turn: 0 up to 360 deg
        first = 0  # the rows 0, step, ... below a turn: a step of a whole turn has one
        last = math.ceil(_check_count(max(TURN / step.value * (1 - 1e-12), 1.0), step)) - 1
    else:
        a, b = lo / step.value - 1e-9, hi / step.value + 1e-9
        _check_count(b - a + 1, step)
        first, last = math.ceil(a), math.floor(b)
        _check_count(last - first + 1, step)
    out = []
    for k in range(first, last + 1):
        x = k * step.value
        found = first_reach(d.laws[step.driver][0], t, x, TURN if angle else None)
        if found is None:
            continue  # an end of the range the samples reach only to its rounding
        shown = f"{math.degrees(x):.10g} deg" if angle else f"{x:.10g} m"
        out.append(Asked(shown, step.driver, x, step.source, found))
    _check_count(len(out), step)
    return out


def _check_count(count: float, step: Asked) -> float:
    """`count`, the rows of a table with a row every `step` (a quotient of floats, which a
    tiny step makes infinite, or nan), if it is at least 1 and at most `MAX_INSTANTS`."""
    if not count <= MAX_INSTANTS:
        rows = number(count) if math.isfinite(count) else "more than 1e308"
        raise MbodyError(f"{step.source}: {rows} rows, and a table has at most "
                         f"{number(MAX_INSTANTS)}; take a larger step")
    if count < 1:
        raise MbodyError(f"{step.source}: the run reaches no multiple of it; "
                         f"{_longer()}")
    return count
