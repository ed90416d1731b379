"""Drivers: a joint coordinate prescribed as a function of time (a motor at constant
speed, a press following a law), read from the model file's ``drivers:`` section.

    drivers:
      - {name: motor, joint: O, speed: "100 rpm"}                      # from the file's pose
      - {name: press, joint: P, displacement: "0.05*sin(2*pi*t)"}      # m, along the axis
      - {name: arm, joint: S, angle: "20 deg + 12.566*t"}              # rad (deg allowed)

A driver adds one constraint, time-dependent, to its joint: the coordinate of one motion
its type allows (`mbody.joint_types`: an ``angle`` about, or a ``displacement`` along, a
joint-frame axis) equals the law f(t). For a planar revolute (and a planar pin in a slot)
the angle is the child's angle minus the parent's, in the terms of the bodies' ``angle``
keys; otherwise the coordinate is measured from the file's pose. ``speed`` is a constant
rate from the file's pose. The driver's effort is an unknown like a reaction,
``<driver>.M`` (N m, on the child about the axis) or ``<driver>.F`` (N, along it): a
component of the compiled core's TURN or FORCE primitive with a law (kernel.h), whose
f′ and f″ come from `mbody.model.calculus`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mbody import conventions as cv
from mbody import joint_types
from mbody.errors import closest, did_you_mean
from mbody.model.calculus import derivative
from mbody.model.checks import MAX_MAGNITUDE, RATE_UNITS, prefixed
from mbody.model.expressions import Expression, ExpressionError, compile_expression

if TYPE_CHECKING:
    from mbody.model.checks import Checker, Path_

DRIVER_KEYS = ("name", "joint", "angle", "displacement", "speed")
LAWS = ("angle", "displacement", "speed")
EFFORT = {joint_types.ROTATION: "M", joint_types.TRANSLATION: "F"}
"""A driver's effort component: a moment about a rotation's axis, a force along a slide."""

_DEG = re.compile(r"(?<![\w.])((?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*deg\b")
"""A number followed by ``deg`` inside a law: the number in degrees."""
_SPEED_UNITS = {"m/s": 1.0, "mm/s": 1e-3, "cm/s": 1e-2}
SPEED_UNITS = (*RATE_UNITS, *_SPEED_UNITS)
"""The units a driver's ``speed`` may be written in (a rotation's, a translation's)."""
_UNIT_NUMBER = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S.*?)?\s*")


@dataclass(frozen=True)
class DriverSpec:
    """One driver as the file gives it (validated): its joint, the motion it drives
    (`joint_types.Motion`: which axis, rotation or translation), and its law f(t) (rad
    or m; None for ``speed``, whose rate is `speed`)."""

    name: str
    joint: str
    motion: joint_types.Motion
    law: Expression | None
    speed: float
    where: tuple[int, int]


def read_drivers(c: Checker, value: Any, joints: dict[str, str]) -> list[DriverSpec]:
    """The ``drivers:`` section, checked: each names a joint (`joints`: name -> type) and
    one motion of its type; a joint's motion is driven once; laws are expressions of t."""
    out: list[DriverSpec] = []
    if value is None:
        return out
    if not isinstance(value, list):
        c.err(("drivers",), f"expected a list of drivers, got {type(value).__name__}")
        return out
    names: dict[str, int] = {}
    driven: dict[tuple[str, str], str] = {}
    for i, d in enumerate(value):
        p: Path_ = ("drivers", i)
        if not c.mapping(p, d, DRIVER_KEYS, ("joint",), "a driver mapping"):
            continue
        name = c.name((*p, "name"), d["name"], "driver") if "name" in d else f"driver{i + 1}"
        if name is not None and name in names:
            c.err((*p, "name"), f"duplicate driver name '{name}'",
                  f"first used by drivers[{names[name]}]")
            continue
        if name is not None:
            names[name] = i
        given = [k for k in LAWS if k in d]
        if len(given) != 1:
            c.err(p, "a driver gives exactly one of angle, displacement, speed"
                  + (f" (this one gives {' and '.join(given)})" if given else ""),
                  "angle: an expression of t (rad, or with deg); displacement: one in m; "
                  "speed: a constant rate from the file's pose")
            continue
        joint = d.get("joint")
        if not isinstance(joint, str) or joint not in joints:
            hint = did_you_mean(str(joint), list(joints)) if isinstance(joint, str) else ""
            c.err((*p, "joint"), f"no joint named '{joint}'",
                  hint or (f"the joints are: {', '.join(list(joints)[:12])}" if joints
                           else "the model has no joints"))
            continue
        motion = _motion(c, p, joint, joints[joint], given[0])
        if motion is None or name is None:
            continue
        key = (joint, motion.name)
        if key in driven:
            c.err((*p, "joint"), f"joint '{joint}''s {motion.name} is driven twice",
                  f"driver '{driven[key]}' drives it already")
            continue
        driven[key] = name
        law, speed = _law(c, p, d, given[0], motion)
        if law is None and given[0] != "speed":
            continue
        if given[0] == "speed" and speed is None:
            continue
        out.append(DriverSpec(name, joint, motion, law, speed or 0.0, c.doc.where(p)))
    return out


def _motion(c: Checker, p: Path_, joint: str, typ: str, key: str) -> joint_types.Motion | None:
    """The motion of the joint's type that `key` (angle, displacement, speed) drives."""
    jt = joint_types.joint_type(c.dim, typ)
    kinds = {"angle": (joint_types.ROTATION,), "displacement": (joint_types.TRANSLATION,),
             "speed": (joint_types.ROTATION, joint_types.TRANSLATION)}[key]
    choices = [m for m in jt.motions if m.what in kinds]
    if len(choices) == 1 and not (key == "speed" and len([
            m for m in jt.motions if m.what != joint_types.BALL]) > 1):
        return choices[0]
    allowed = [m.name for m in jt.motions if m.what in (joint_types.ROTATION,
                                                        joint_types.TRANSLATION)]
    if not jt.motions:
        why = f"a {typ} joint allows no motion to drive"
    elif any(m.what == joint_types.BALL for m in jt.motions):
        why = f"a {typ} joint turns about three axes; a driver prescribes one coordinate"
    elif key == "speed":
        why = f"a {typ} joint allows {' and '.join(allowed)}: say which one the speed is of"
    elif not choices:
        why = f"a {typ} joint has no {key}"
    else:
        why = f"a {typ} joint has {len(choices)} {key}s ({', '.join(m.name for m in choices)})"
    hint = (f"drive its {' or its '.join(allowed)} with "
            + " or ".join(f"'{'angle' if m.what == joint_types.ROTATION else 'displacement'}:'"
                          for m in jt.motions if m.name in allowed)
            if allowed and len(allowed) == len(set(m.what for m in jt.motions
                                                    if m.name in allowed))
            else "drive a revolute, prismatic, cylindrical, helical or slot joint")
    c.err((*p, key), f"cannot drive joint '{joint}': {why}", hint)
    return None


def _law(c: Checker, p: Path_, d: dict, key: str, motion: joint_types.Motion
         ) -> tuple[Expression | None, float | None]:
    """(law, speed): the expression of the coordinate (rad or m), or the constant rate."""
    value = d[key]
    rotation = motion.what == joint_types.ROTATION
    if key == "speed":
        units = RATE_UNITS if rotation else _SPEED_UNITS
        if isinstance(value, str):
            m = _UNIT_NUMBER.fullmatch(value)
            unit = (m.group(2) or "") if m else ""
            what = "rate" if rotation else "speed"
            if not m or (unit and unit not in units):
                example = ("10.47, '100 rpm' or '90 deg/s'" if rotation
                           else "0.2 or '200 mm/s'")
                converted = prefixed(value, units)
                meant = _unit_meant(unit, units) if m and converted is None else None
                c.err((*p, key), f"expected a {what} like {example}, got '{value}'",
                      (f"did you mean '{m.group(1)} {meant}'? " if m and meant else "")
                      + (f"units take no prefix: {converted}; " if converted else "")
                      + f"units: {', '.join(units)}")
                return None, None
            factor = units.get(unit, 1.0)
            rate = float(m.group(1)) * factor
            if not abs(rate) <= MAX_MAGNITUDE:  # its law f(0) + rate*t must hold it
                si = next(iter(units))
                c.err((*p, key), f"the {what} '{value}' is out of range: expected a "
                      f"magnitude of at most {MAX_MAGNITUDE:g} {si}"
                      + (f" ({MAX_MAGNITUDE / factor:.3g} {unit})" if unit != si and unit
                         else ""))
                return None, None
            return None, rate
        x = c.number((*p, key), value)
        return None, x
    if isinstance(value, str):
        text = _DEG.sub(lambda m: f"({m.group(1)}*pi/180)", value) if rotation else value
        try:
            e = compile_expression(text)
        except ExpressionError as exc:
            c.err((*p, key), f"invalid law: {exc.reason} in \"{value}\"",
                  exc.hint or "an expression of t: see docs/expressions.md")
            return None, None
        return Expression(value, e.tree), None  # shown as written (deg and all)
    x = c.number((*p, key), value)
    return (compile_expression(repr(float(x))) if x is not None else None), None


def _unit_meant(unit: str, units: dict[str, float]) -> str | None:
    """The unit of `units` a misspelt `unit` stands for: the same in another case first
    ('RPM'), a common abbreviation the table writes otherwise ('rps': 'rev/s', which
    spelling alone would take for 'rpm', 60 times slower), else the closest spelling."""
    same = _UNIT_ABBREVIATIONS.get(unit.casefold())
    if same in units and not any(u.casefold() == unit.casefold() for u in units):
        return same
    return closest(unit, units)


_UNIT_ABBREVIATIONS = {"rps": "rev/s", "r/s": "rev/s", "r/min": "rpm", "1/s": "Hz"}
"""Rate units written otherwise, read as the table's (in a did-you-mean only)."""


@dataclass(frozen=True, eq=False)
class DriverTable:
    """The model's drivers as arrays (k of them), in file order.

    names: (k,) driver names; joint: (k,) the driven joint's index; kind: (k,) the core's
    primitive of the effort (TURN for an angle, FORCE_ALONG for a displacement); axis:
    (k,) its joint-frame axis; component: (k,) "M" or "F"; offset: (k,) the coordinate's
    value at the file's pose (a planar angle: the child's angle minus the parent's, from
    the bodies' ``angle`` keys; 0 otherwise); laws: per driver (f, f′, f″) of t;
    where: (line, column) of each entry in the file.
    """

    names: tuple[str, ...]
    joint: np.ndarray
    kind: np.ndarray
    axis: np.ndarray
    component: tuple[str, ...]
    offset: np.ndarray
    laws: tuple[tuple[Expression, Expression, Expression], ...]
    where: tuple[tuple[int, int], ...]
    speed: tuple[float | None, ...] = ()

    def __len__(self) -> int:
        return len(self.names)

    @property
    def labels(self) -> tuple[str, ...]:
        """``<driver>.M`` or ``<driver>.F``: the efforts' labels."""
        return tuple(f"{n}.{c}" for n, c in zip(self.names, self.component, strict=True))

    def labels_of(self, joint: int) -> tuple[str, ...]:
        """The efforts' labels of the drivers of joint `joint` (its index): they act on
        that joint's two bodies, as its reactions do."""
        return tuple(lab for lab, j in zip(self.labels, self.joint, strict=True)
                     if int(j) == joint)

    def __repr__(self) -> str:
        return f"<DriverTable: {len(self)} driver(s) ({', '.join(self.labels[:4])})>"


def driver_table(specs: list[DriverSpec], joint_index: dict[str, int], dimension: int,
                 joint_parent_child: tuple[np.ndarray, np.ndarray], angles: np.ndarray
                 ) -> DriverTable | None:
    """The table of `specs` (None without drivers). `angles`: each body's planar angle in
    the terms of its ``angle`` key (about z), for the planar angles' offsets."""
    if not specs:
        return None
    parent, child = joint_parent_child
    names, joint, kind, axis, comp, offset, laws, where = [], [], [], [], [], [], [], []
    speed: list[float | None] = []
    for s in specs:
        j = joint_index[s.joint]
        rotation = s.motion.what == joint_types.ROTATION
        off = 0.0
        if dimension == cv.PLANAR and rotation:
            p, c = int(parent[j]), int(child[j])
            off = float(angles[c] - (angles[p] if p >= 0 else 0.0))
        law = s.law if s.law is not None else compile_expression(
            f"{off!r} + {s.speed!r}*t")
        f1 = derivative(law)
        names.append(s.name)
        joint.append(j)
        kind.append(joint_types.base.TURN if rotation else joint_types.base.FORCE_ALONG)
        axis.append(s.motion.axis)
        comp.append(EFFORT[s.motion.what])
        offset.append(off)
        laws.append((law, f1, derivative(f1)))
        where.append(s.where)
        speed.append(s.speed if s.law is None else None)
    return DriverTable(tuple(names), np.array(joint, dtype=np.intp),
                       np.array(kind, dtype=np.intp), np.array(axis, dtype=np.intp),
                       tuple(comp), np.array(offset), tuple(laws), tuple(where),
                       tuple(speed))
