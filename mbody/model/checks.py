"""Checking primitives: one value against what the contract expects, as a located issue.

`Checker` holds the document being checked and the issues found so far; its methods
check one value each (a mapping's keys with a did-you-mean, a number and its range, an
angle with its unit, a vector of given length, a name, a choice, a reference to a body)
and report what is wrong at the value's file, line and column. The contract's rules
(what a body, a load, a joint is) are in `mbody.model.validate`, built from these.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from mbody import conventions as cv
from mbody.errors import Issue, did_you_mean
from mbody.model.loader import Document, Path_, Unrepresentable, dotted

_REQUIRED_HINTS = {
    ("", "dimension"): "2 for a planar model, 3 for a spatial one; the rest of the file is "
                       "checked once it is given, since every vector's length depends on it",
    ("", "bodies"): "a list of bodies, each with at least name, mass and inertia",
    ("bodies", "name"): "a name without spaces or dots",
    ("bodies", "mass"): "the mass in kg, a number > 0",
    ("loads", "body"): "the name of the body it acts on",
    ("loads", "force"): "the force components, N",
    ("loads", "torque"): "the couple, N m",
    ("loads", "bodies"): "the two ends: [body, body] or [ground, body]",
    ("loads", "at"): "the two attachment points: body axes, or world for ground",
    ("loads", "stiffness"): "N/m, a number >= 0",
    ("joints", "name"): "a name without spaces or dots; reactions are <name>.Fx ...",
    ("joints", "type"): "the kind of joint, such as revolute",
    ("joints", "parent"): "a body name or ground",
    ("joints", "child"): "a body name",
    ("joints", "at"): "the joint point, world coordinates at the initial pose",
}
"""Hints for missing required keys, by (top-level section, key)."""
_ANGLE = re.compile(r"\s*([-+]?[0-9.eE+-]+)\s*(deg|rad)\s*")
RATE_UNITS = {"rad/s": 1.0, "deg/s": math.pi / 180.0, "rpm": 2.0 * math.pi / 60.0,
              "rev/min": 2.0 * math.pi / 60.0, "rev/s": 2.0 * math.pi, "Hz": 2.0 * math.pi}
"""The units an angular rate may be written in, a body's `angular_velocity` and a turning
driver's `speed` alike: rad/s per one."""
_RATE = re.compile(r"\s*([-+]?[0-9.eE+-]+)\s*("
                   + "|".join(re.escape(u) for u in RATE_UNITS) + r")\s*")
_TOL = 1e-6
MAX_MAGNITUDE = 1e100
"""Largest number accepted: squares and triple products must stay finite in float64."""
MIN_MAGNITUDE = 1e-100
"""Smallest nonzero magnitude accepted: reciprocals (1/m, J^-1) and products of three such
numbers stay normal doubles (a denormal mass such as 5e-324 has no reciprocal)."""
MIN_NORM = 1e-12
"""A quaternion or an axis shorter than this is zero: it gives no attitude or direction."""
UNIT_TOL = 1e-6
"""A quaternion whose norm differs from 1 by more is normalised with a warning."""
PERPENDICULAR_TOL = 1e-6
"""Largest |axis . axis2| of a universal joint's two (unit) axes."""
MAX_ANGLE = 1e9
"""Largest angle accepted, rad (about 160 million turns): a double resolves 1e9 to 1e-7
rad, and sin/cos of a larger number say little about the pose meant."""
BARE_ANGLE_LIMIT = 2.0 * math.pi
"""A bare number (no unit) as an angle of a pose beyond this many radians, one turn, is
read as radians with a warning (did you mean degrees?): no pose needs more than a turn,
while 45 or 90 is what a student who thinks in degrees writes. Angular velocities are
never warned about (a wheel spins at 100 rad/s), and a bare 5 meant as degrees cannot be
told from 5 rad."""


def vec_norm(v: np.ndarray) -> np.ndarray:
    """‖v‖ of 3-vectors over the last axis, summed in the order x, y, z (see `quat_norm`)."""
    return np.sqrt((v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1]) + v[..., 2] * v[..., 2])


def quat_norm(q: np.ndarray) -> np.ndarray:
    """‖q‖ over the last axis, summed in the order w, x, y, z.

    Written out, not ``np.linalg.norm``, so that one quaternion and a stack of them give
    the same bits: the located path checks one body at a time, the fast path
    (`mbody.model.fast`) all at once, and both must build the same `Model`.
    """
    return np.sqrt(((q[..., 0] * q[..., 0] + q[..., 1] * q[..., 1]) + q[..., 2] * q[..., 2])
                   + q[..., 3] * q[..., 3])


def asymmetry(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How far inertia tensors are from symmetric, and the scale that is judged against.

    Parameters
    ----------
    J : (..., 3, 3) array
        Inertia tensors.

    Returns
    -------
    off, scale : (...) arrays
        max |J - Jᵀ|, and the largest |entry| (1 for a zero tensor): a tensor is
        symmetric when ``off <= _TOL * scale``.
    """
    scale = np.abs(J).max(axis=(-2, -1))
    return np.abs(J - np.swapaxes(J, -2, -1)).max(axis=(-2, -1)), np.where(scale == 0, 1.0,
                                                                           scale)


def realisable(principal: np.ndarray, tol: float = _TOL) -> np.ndarray:
    """Whether principal moments meet the triangle inequality (a rigid body's do).

    Parameters
    ----------
    principal : (..., 3) array
        Principal moments of inertia.
    tol : float, optional
        Relative slack: each moment may exceed the sum of the other two by `tol` times
        the largest.

    Returns
    -------
    (...) bool array
    """
    a, b, d = np.moveaxis(np.sort(principal, axis=-1), -1, 0)
    return a + b >= d * (1 - tol)


class Checker:
    def __init__(self, doc: Document):
        self.doc = doc
        self.issues: list[Issue] = []
        self.warnings: list[Issue] = []
        self.dim = cv.SPATIAL
        self.body_names: dict[str, int] = {}
        """Every body with a valid name, even one with other problems (for references)."""
        self.joint_types: dict[str, str] = {}
        self.particle_joints: dict[str, str] = {}  # joint name -> "pin" or "link"
        """Every joint with a valid name and type, even one with other problems."""
        self.particles: set[str] = set()
        """Names of the bodies given `inertia: 0` (point masses)."""
        self.meant: set[tuple[Path_, str]] = set()
        """(mapping's path, key) of each key an unknown key's hint names: a rule that
        asks for the key says nothing more there (the hint said it)."""

    # -- reporting -------------------------------------------------------------------
    def err(self, path: Path_, message: str, hint: str = "", *, key: bool = False) -> None:
        line, col = self.doc.where(path, key=key)
        self.issues.append(Issue(self.doc.file, line, col, dotted(path), message, hint))

    def warn(self, path: Path_, message: str, hint: str = "") -> None:
        line, col = self.doc.where(path)
        self.warnings.append(Issue(self.doc.file, line, col, dotted(path), message, hint))

    # -- shapes of values --------------------------------------------------------------
    def mapping(self, path: Path_, value: Any, allowed: tuple[str, ...],
                required: tuple[str, ...] = (), what: str = "a mapping") -> bool:
        if not isinstance(value, dict):
            self.err(path, f"expected {what}, got {_kind(value)}")
            return False
        meant = set()  # keys a misspelling points at: their "missing" would repeat it
        for k in value:
            if k not in allowed:
                hint = did_you_mean(k, allowed)
                if hint:
                    meant.add(hint.split("'")[1])
                    self.meant.add((tuple(path), hint.split("'")[1]))
                self.err((*path, k), f"unknown key '{k}'",
                         hint or f"expected one of: {', '.join(allowed)}", key=True)
        for k in required:
            if k not in value and k not in meant:
                section = str(path[0]) if path else ""
                self.err(path, f"missing required key '{k}'",
                         _REQUIRED_HINTS.get((section, k), ""))
        return True

    def number(self, path: Path_, value: Any, *, positive: bool = False,
               nonneg: bool = False, scale: bool = False, sign_hint: str = "") -> float | None:
        """A finite number within ±`MAX_MAGNITUDE`; with `scale` (a mass or a size, which
        is divided by) also 0 or at least `MIN_MAGNITUDE` in magnitude. `sign_hint`: what
        to say when `positive` or `nonneg` refuses it."""
        if isinstance(value, Unrepresentable):  # 1e400, 1e-400, a 5 000-digit integer
            self._out_of_range(path, value.shown, value.large)  # never silently 0 or inf
            return None
        if isinstance(value, bool) or not isinstance(value, int | float):
            self.err(path, f"expected a number, got {_kind(value)}",
                     number_hint(value, key_unit(path)))
            return None
        try:
            x = float(value)
        except OverflowError:  # an integer with hundreds of digits (from a dictionary)
            self._out_of_range(path, _show(value), True)
            return None
        if not math.isfinite(x):
            self.err(path, f"expected a finite number, got {x}")
            return None
        if abs(x) > MAX_MAGNITUDE:
            self._out_of_range(path, _show(value), True)
            return None
        if scale and 0 < abs(x) < MIN_MAGNITUDE:
            self._too_small(path, _show(value))
            return None
        if positive and x <= 0:
            self.err(path, f"expected a number > 0, got {_show(value)}", sign_hint)
            return None
        if nonneg and x < 0:
            self.err(path, f"expected a number >= 0, got {_show(value)}", sign_hint)
            return None
        return x

    def _out_of_range(self, path: Path_, shown: str, large: bool) -> None:
        if large:
            self.err(path, f"expected a number of magnitude at most {MAX_MAGNITUDE:g}, got "
                     f"{shown}", "products of such numbers (r x F, m r^2) would overflow")
        else:  # written in the file: not even a double holds it
            self.err(path, f"expected a number a double can hold, got {shown}",
                     "below about 5e-324 it would be read as 0; write 0 if that is meant")

    def _too_small(self, path: Path_, shown: str) -> None:
        self.err(path, f"expected a magnitude of at least {MIN_MAGNITUDE:g}, got {shown}",
                 "masses and sizes are divided by; a smaller one would leave double precision")

    def angle(self, path: Path_, value: Any, rate: bool = False) -> float | None:
        """An angle (rad, or a string with deg/rad), or with `rate` an angular rate."""
        if isinstance(value, str):
            m = (_RATE if rate else _ANGLE).fullmatch(value)
            unit = "deg/s" if rate else "deg"
            if not m:
                like = "'30 deg/s' or '100 rpm'" if rate else "'30 deg'"
                hint = (prefixed(value, RATE_UNITS) if rate else None) or _angle_hint(value,
                                                                                      unit)
                self.err(path, f"expected a number (radians{'/s' if rate else ''}) or a string "
                         f"like {like}, got '{_show(value)}'", hint)
                return None
            try:
                written = float(m.group(1))
            except ValueError:
                self.err(path, f"'{_show(value)}' is not a number followed by a unit")
                return None
            y = self.number(path, Unrepresentable(m.group(1)) if math.isinf(written)
                            else written)
            if y is None:
                return None
            unit_written = m.group(2)
            x = (math.radians(y) if unit_written.startswith("deg") else
                 y * RATE_UNITS[unit_written] if rate and unit_written != "rad/s" else y)
        else:
            z = self.number(path, value)
            if z is None:
                return None
            x = z
        if not rate and abs(x) > MAX_ANGLE:
            self.err(path, f"expected an angle of at most {MAX_ANGLE:g} rad in magnitude, got "
                     f"{x:g} rad", "a double cannot resolve the pose of a larger angle; "
                     "reduce it by whole turns")
            return None
        if not rate and not isinstance(value, str) and abs(x) > BARE_ANGLE_LIMIT:
            self.warn(path, f"the angle {_show(value)} is read as {_show(value)} rad, "
                      f"{abs(x) / (2 * math.pi):.3g} turns (a number without a unit is in "
                      "radians)", f"did you mean '{_show(value)} deg'?")
        return x

    def vector(self, path: Path_, value: Any, n: int, *, angles: bool = False,
               rates: bool = False, scale: bool = False) -> np.ndarray | None:
        if not isinstance(value, list):
            self.err(path, f"expected a list of {n} numbers, got {_kind(value)}")
            return None
        if len(value) != n:
            self.err(path, f"expected {n} components, got {len(value)}",
                     "planar models use 2-D vectors" if n == 2 and len(value) == 3 else
                     "spatial models use 3-D vectors" if n == 3 and len(value) == 2 else "")
            return None
        out = []
        for i, v in enumerate(value):
            x = (self.angle((*path, i), v, rate=rates) if angles or rates
                 else self.number((*path, i), v, scale=scale))
            if x is None:
                return None
            out.append(x)
        return np.array(out, dtype=float)

    def vec3(self, path: Path_, value: Any, rates: bool = False) -> np.ndarray | None:
        """A d-vector from the file, returned padded to 3-D (planar z = 0)."""
        v = self.vector(path, value, self.dim, rates=rates)
        if v is None:
            return None
        return np.append(v, 0.0) if self.dim == cv.PLANAR else v

    def matrix3(self, path: Path_, value: Any) -> np.ndarray | None:
        if not (isinstance(value, list) and len(value) == 3
                and all(isinstance(r, list) for r in value)):
            self.err(path, f"expected a 3x3 matrix (a list of 3 rows), got {_kind(value)}")
            return None
        rows = [self.vector((*path, i), r, 3) for i, r in enumerate(value)]
        if any(r is None for r in rows):
            return None
        return np.array(rows)

    def name(self, path: Path_, value: Any, what: str) -> str | None:
        if not isinstance(value, str) or not value.strip():
            self.err(path, f"expected a {what} name (text), got {_kind(value)}")
            return None
        if "." in value or any(c.isspace() for c in value):
            self.err(path, f"the {what} name '{_show(value)}' may not contain '.' or spaces",
                     "reaction labels are written <joint>.<component>")
            return None
        return value

    def choice(self, path: Path_, value: Any, choices: tuple[str, ...], what: str,
               synonyms: Mapping[str, str] | None = None) -> str | None:
        """`value` if it is one of `choices`, else None and an error with a hint
        (`did_you_mean`; `synonyms`: other programs' names of the choices)."""
        if not isinstance(value, str) or value not in choices:
            hint = did_you_mean(value, choices, synonyms)
            self.err(path, f"unknown {what} {_quoted(value)}",
                     hint or f"expected one of: {', '.join(choices)}")
            return None
        return value

    def body_ref(self, path: Path_, value: Any, names: dict[str, int],
                 allow_ground: bool) -> str | None:
        if isinstance(value, str) and (value in names or allow_ground and value == cv.GROUND):
            return value  # the common case first: a dict lookup, not a list of every name
        choices = list(names) + ([cv.GROUND] if allow_ground else [])
        if value == cv.GROUND and not allow_ground:
            self.err(path, "'ground' is not allowed here", "name a body of the model")
            return None
        hint = did_you_mean(value, choices) if isinstance(value, str) else ""
        self.err(path, f"no body named {_quoted(value)}",
                 hint or f"bodies are: {', '.join(choices[:12])}"
                 + (" ..." if len(choices) > 12 else ""))
        return None


def _kind(value: Any) -> str:
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        return f"a boolean ({str(value).lower()})"
    if isinstance(value, int | float | Unrepresentable):
        return f"the number {_show(value)}"
    if isinstance(value, str):
        return f"the text '{_show(value)}'"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, dict):
        return "a mapping"
    return type(value).__name__


_DECIMAL_COMMA = re.compile(r"\s*([-+]?\d+),(\d+)\s*")
# \d+(?:\.\d*)? rather than \d+\.?\d*, which splits a run of digits every way before
# failing (a 20 000-digit mass ending in '}': half a minute)
_WITH_UNIT = re.compile(r"\s*([-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)\s*"
                        r"([A-Za-zµ°][A-Za-z0-9µ°/^·²³ .-]*)")
_ANGLE_WORDS = re.compile(r"\s*([-+]?[\d.eE+-]+)\s*(°|degrees?|degs|grad|radians?)(\s*/\s*s)?\s*",
                          re.IGNORECASE)


def number_hint(value: Any, expected: str | None = None) -> str:
    """What was probably meant by text where a number goes: '1,5', '1.5 kg'. `expected`
    is the SI unit the key's number is in (`key_unit`: '' for a pure number), None when
    not known: a unit of another quantity is then named as such, never converted into
    a value of the wrong kind (gravity '-1 g' is -9.80665 m/s^2, not -0.001 kg)."""
    if not isinstance(value, str):
        return ""
    m = _DECIMAL_COMMA.fullmatch(value)
    if m:
        return f"a decimal comma? write {m.group(1)}.{m.group(2)}"
    m = _WITH_UNIT.fullmatch(value)
    if not (m and len(value) < 40):
        return ""
    number, unit = m.group(1), " ".join(m.group(2).replace("·", " ").split())
    bare = "numbers are in SI units, written without the unit"
    si = _SI_UNITS.get(unit)
    conversion = _BY_QUANTITY.get((unit, expected or "")) or _TO_SI.get(unit)
    measured = si if si is not None else conversion[1] if conversion else None
    if expected == "":
        return f"this is a pure number: write {number} without '{unit}'"
    if expected is not None and measured is not None and measured != expected:
        return (f"this number is {_QUANTITY[expected]} in {expected}, written without the "
                f"unit; {unit} measures {_QUANTITY[measured]}")
    if si is not None:
        return f"{bare}: {number}"
    if conversion is not None:
        factor, to = conversion
        return f"{bare}: {number} {unit} is {float(number) * factor:.6g} {to}"
    return (f"numbers are in SI units (kg, m, s, N, rad), written without the unit: "
            f"convert {value.strip()!r} to SI first")


SI_PREFIXES = {"k": 1e3, "M": 1e6, "G": 1e9, "m": 1e-3, "µ": 1e-6, "u": 1e-6}
"""The SI prefixes a newcomer puts before a unit that takes none (``'0.6 krpm'``)."""


def prefixed(value: str, units: Iterable[str]) -> str | None:
    """`value` converted when its unit is one of `units` with an SI prefix, which mbody
    does not read: ``'0.6 krpm'`` -> ``'0.6 krpm is 600 rpm'`` (a close spelling, 'rpm',
    would be 1000 times off); None otherwise."""
    written = written_quantity(value)
    if written is None:
        return None
    x, unit = written
    factor = SI_PREFIXES.get(unit[:1])
    if factor is None or unit[1:] not in units or unit in units:
        return None
    return f"{x:g} {unit} is {x * factor:.6g} {unit[1:]}"


def key_unit(path: Path_) -> str | None:
    """The SI unit of the number at `path` in a model file, by its key (the last name in
    the path: ``bodies[0].inertia[1]`` is in kg m^2), '' for a pure number, None when the
    key does not say (a known reaction's value, a driver's parameter)."""
    key = next((k for k in reversed(path) if isinstance(k, str)), None)
    return _KEY_UNITS.get(key) if key is not None else None


def written_quantity(text: str) -> tuple[float, str] | None:
    """A number followed by a unit, as written: ``"90 deg"`` -> (90.0, 'deg'), ``"1e20
    deg"`` -> (1e+20, 'deg'), the unit's spaces made single (``"N·m"`` -> 'N m'); None
    for text that is not a number and a unit (`si_quantity` says which units it knows)."""
    m = _WITH_UNIT.fullmatch(text) if len(text) < 80 else None
    if not m:
        return None
    return float(m.group(1)), " ".join(m.group(2).replace("·", " ").split())


def si_quantity(text: str) -> tuple[float, str] | None:
    """A number followed by its unit, in SI: ``"90 deg"`` -> (1.5708, 'rad'), ``"20 mm"``
    -> (0.02, 'm'), ``"10 ms"`` -> (0.01, 's'), ``"0.25 rev"`` -> (1.5708, 'rad'). The
    units are those this module's hints know (the SI ones, and the common others
    `_TO_SI` converts) and ``deg``, as a model file writes an angle. None for text that is
    not a number with such a unit (a bare number, a misspelt unit): the caller says what
    it expected."""
    written = written_quantity(text)
    if written is None:
        return None
    x, unit = written
    if unit == "deg":
        return math.radians(x), "rad"
    if unit in _SI_UNITS:
        return x, _SI_UNITS[unit]
    factor, si = _TO_SI.get(unit, (None, ""))
    return (x * factor, si) if factor is not None else None


# Units a newcomer writes after a number. An SI one is dropped as it is; a common other
# one is converted in the hint (its bare number would be off by its factor: 500 g is
# 0.5, not 500). Each is mapped to its SI unit as the hints write it.
_SI_UNITS: dict[str, str] = {
    "kg": "kg", "m": "m", "s": "s", "N": "N", "N m": "N m", "Nm": "N m", "m/s": "m/s",
    "m/s^2": "m/s^2", "m/s²": "m/s^2", "rad": "rad", "rad/s": "rad/s",
    "rad/s^2": "rad/s^2", "rad/s²": "rad/s^2", "kg m^2": "kg m^2", "kg m²": "kg m^2",
    "kgm^2": "kg m^2", "kgm²": "kg m^2", "N/m": "N/m", "N s/m": "N s/m", "Ns/m": "N s/m",
    "J": "J", "W": "W", "Pa": "Pa"}
_TO_SI: dict[str, tuple[float, str]] = {
    "g": (1e-3, "kg"), "mg": (1e-6, "kg"), "lb": (0.45359237, "kg"),
    "lbs": (0.45359237, "kg"), "mm": (1e-3, "m"), "cm": (1e-2, "m"), "km": (1e3, "m"),
    "in": (0.0254, "m"), "ft": (0.3048, "m"), "ms": (1e-3, "s"), "min": (60.0, "s"),
    "h": (3600.0, "s"), "kN": (1e3, "N"), "mN": (1e-3, "N"), "N mm": (1e-3, "N m"),
    "N cm": (1e-2, "N m"), "Nmm": (1e-3, "N m"), "kN m": (1e3, "N m"),
    "rpm": (2 * math.pi / 60, "rad/s"), "rev/min": (2 * math.pi / 60, "rad/s"),
    "rev/s": (2 * math.pi, "rad/s"), "rev": (2 * math.pi, "rad"), "Hz": (2 * math.pi, "rad/s"),
    "km/h": (1 / 3.6, "m/s"), "mm/s": (1e-3, "m/s"), "cm/s": (1e-2, "m/s"),
    "kg mm^2": (1e-6, "kg m^2"), "kg mm²": (1e-6, "kg m^2"), "kg cm^2": (1e-4, "kg m^2"),
    "kg cm²": (1e-4, "kg m^2"), "g cm^2": (1e-7, "kg m^2"), "g cm²": (1e-7, "kg m^2"),
    "N/mm": (1e3, "N/m"),
}
_BY_QUANTITY: dict[tuple[str, str], tuple[float, str]] = {
    ("g", "m/s^2"): (9.80665, "m/s^2"),  # standard gravity, where an acceleration goes
}
"""(unit, the key's SI unit) -> a meaning of the unit for that quantity alone."""
_QUANTITY = {
    "kg": "a mass", "m": "a length", "s": "a time", "N": "a force", "N m": "a moment",
    "m/s": "a velocity", "m/s^2": "an acceleration", "rad": "an angle",
    "rad/s": "an angular rate", "rad/s^2": "an angular acceleration",
    "kg m^2": "a moment of inertia", "N/m": "a stiffness", "N s/m": "a damping rate",
    "J": "an energy", "W": "a power", "Pa": "a pressure"}
_LENGTH_KEYS = ("position", "at", "rest_length", "pitch", "box", "disc", "sphere",
                "cylinder", "ellipsoid", "radius", "length")
_KEY_UNITS: dict[str, str] = {
    "mass": "kg", "inertia": "kg m^2", "velocity": "m/s", "gravity": "m/s^2",
    "force": "N", "torque": "N m", "stiffness": "N/m", "damping": "N s/m",
    "angular_velocity": "rad/s", "axis": "", "axis2": "", "quaternion": "",
    "matrix": "", **dict.fromkeys(_LENGTH_KEYS, "m")}
"""A model file's keys whose numbers have one unit (docs/model-format.md's tables)."""


def _angle_hint(value: str, unit: str) -> str:
    """'30°', '30 degrees' -> write '30 deg'."""
    written = angle_spelling(value, unit)
    return f"write '{written}'" if written else number_hint(
        value, "rad" if unit == "deg" else "rad/s")


def angle_spelling(value: str, unit: str = "deg") -> str | None:
    """An angle (or with `unit` 'deg/s', a rate) written another way, as mbody reads it:
    ``'30°'``, ``'30 degrees'`` -> ``'30 deg'``, ``'2 radians'`` -> ``'2 rad'``; None for
    anything else."""
    m = _ANGLE_WORDS.fullmatch(value) if len(value) < 80 else None
    if not m:
        return None
    word = "rad" if m.group(2).lower().startswith("rad") else "deg"
    return f"{m.group(1)} {word}{unit[3:]}"


def _quoted(value: Any) -> str:
    """`value` as repr() shows it, cut short (text is quoted, numbers are not)."""
    return repr(_show(value)) if isinstance(value, str) else _show(value)


def _show(value: Any, limit: int = 60) -> str:
    """`value` for a message: long text cut short, huge integers by their size."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**15:
        if value.bit_length() > 1000:  # beyond a double: its size says enough
            return f"an integer of about {int(value.bit_length() * 0.30103) + 1} digits"
        return f"{value:.6g}"
    text = value if isinstance(value, str) else repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."
