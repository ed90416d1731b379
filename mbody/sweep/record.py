"""What a sweep's row records of how it was computed (its ``settings`` cell), and how an
earlier row's record differs from this sweep's.

A row's numbers depend on its case's values (its own columns), on the run and those of
its settings that change them, and on the model the cases are built from. The record
holds the last two, as ``name=value`` pairs joined by ``; ``::

    run=kinematics; t-end=1 rev; steps=360; model=sha256:2c4f0e9b61d7a835

- ``run``: always; ``t-end`` (seconds, or ``N rev``) for ``kinematics`` and
  ``simulate``; ``steps`` for ``kinematics`` (the number given, or the default
  sampling, ``360 a turn`` or ``100 a second``: `sampling`), or ``fps`` when given
  instead; ``fps`` for ``simulate``; ``equilibrium`` (``yes`` or ``no``) for ``modes``.
  A run is given only the settings it uses (`mbody.sweep.runs.check_run`).
- ``model``: the first 16 hexadecimal digits of the SHA-256 of the model's document
  (the file as parsed: comments and layout aside) with the values set for every case
  (``--set PATH=VALUE``, `Model.with_values`) written in, and the step `mbody.load`
  takes after building it. A value set for every case and the same value written in the
  file give the same record.

Numbers are written as Python writes them (read back, the same double), without a
trailing ``.0``.
"""

from __future__ import annotations

import hashlib
from typing import TYPE_CHECKING

from mbody.errors import option_name
from mbody.model.values import apply, edits, entry_names
from mbody.simulate.kinematic import DEFAULT_FPS, SAMPLES_A_TURN, revolution
from mbody.sweep.runs import Settings

if TYPE_CHECKING:
    from mbody.model.model import Model

SETTINGS = "settings"
"""The results' column of each row's record (the last one)."""
DIGITS = 16
"""Hexadecimal digits of the model's digest kept (64 bits: a changed model is told apart
from the earlier one but for a chance of 1 in 10^19)."""
KEYWORDS = {"run": "run", "t-end": "t_end", "steps": "steps", "fps": "fps",
            "equilibrium": "equilibrium"}
"""The keyword argument of `mbody.run_sweep` (the command's option's destination) that
sets each recorded setting; ``t-end`` in turns is ``revolutions``."""


def _number(x: float) -> str:
    text = repr(float(x))
    return text[:-2] if text.endswith(".0") else text


def model_digest(model: Model) -> str:
    """``sha256:`` and `DIGITS` hexadecimal digits of what the cases of `model` are built
    from (module doc)."""
    source = model.source
    if source is None:  # run_sweep refuses such a model before it asks
        return "unknown"
    doc = source.read()
    apply(doc, edits(doc, source.values, entry_names(model)))
    finish = getattr(source.finish, "__qualname__", "") if source.finish else ""
    digest = hashlib.sha256(repr((doc.data, finish)).encode("utf-8")).hexdigest()
    return f"sha256:{digest[:DIGITS]}"


def sampling(settings: Settings, model: Model) -> str:
    """A ``kinematics`` run's instants as recorded: ``--steps`` given (``360``), else
    ``mbody kinematics``' sampling of the model (`mbody.sweep.runs.instants`):
    ``360 a turn`` of its first driver, or ``100 a second`` when it does not turn at a
    constant rate."""
    if settings.steps is not None:
        return str(int(settings.steps))
    if revolution(model) is not None:
        return f"{SAMPLES_A_TURN} a turn"
    return f"{_number(DEFAULT_FPS)} a second"


def record(settings: Settings, model: Model) -> str:
    """The ``settings`` cell of the rows of a sweep of `model` run with `settings`."""
    pairs = [("run", settings.run)]
    if settings.run in ("kinematics", "simulate"):
        end = (f"{_number(settings.revolutions)} rev" if settings.revolutions is not None
               else _number(settings.t_end) if settings.t_end is not None else "")
        pairs.append(("t-end", end))
    if settings.run == "kinematics":  # its instants: by --fps, or by --steps or default
        pairs.append(("fps", _number(settings.fps)) if settings.fps is not None
                     else ("steps", sampling(settings, model)))
    if settings.run == "simulate":
        pairs.append(("fps", _number(settings.frame_rate)))
    if settings.run == "modes":
        pairs.append(("equilibrium", "yes" if settings.equilibrium else "no"))
    pairs.append(("model", model_digest(model)))
    return "; ".join(f"{k}={v}" for k, v in pairs)


def parse(text: str) -> dict[str, str]:
    """A record's pairs, by name (a part without ``=`` is kept whole, under '')."""
    out: dict[str, str] = {}
    for part in text.split(";"):
        name, eq, value = part.strip().partition("=")
        if part.strip():
            out[name.strip() if eq else ""] = value.strip() if eq else part.strip()
    return out


def _python(name: str, value: str) -> str:
    """The recorded setting `name` with its recorded `value` as `mbody.run_sweep` takes it:
    ``t_end=0.1``, ``revolutions=1`` (``1 rev``), ``run='kinematics'``, ``steps=None
    (360 a turn)`` (the default sampling), ``equilibrium=True``."""
    if name == "run":
        return f"run={value!r}"
    if name == "t-end":
        if value.endswith(" rev"):
            return f"revolutions={value[:-len(' rev')]}"
        return f"t_end={value or None}"
    if name == "steps" and not value.isdigit():
        return f"steps=None ({value})"
    if name == "equilibrium":
        return f"equilibrium={value == 'yes'}"
    return f"{KEYWORDS.get(name, name)}={value}"


def _said(name: str, value: str, flag: str) -> str:
    """The recorded setting `name` at `value` as the caller gives it: ``--steps 11`` by
    the command line's `flag`, ``steps=11`` in Python (`_python`)."""
    return _python(name, value) if flag == KEYWORDS.get(name, name) else f"{flag} {value}"


def differences(earlier: str, ours: str) -> list[str]:
    """How the record `earlier` (a row's) differs from `ours` (this sweep's), one phrase
    per setting, named as the caller names it (`mbody.errors.option_name`): on the command
    line ``--t-end 0.1 (this sweep: 0.2)``, in Python ``t_end=0.1 (this sweep:
    t_end=0.2)``; ``another model``... Another run is said alone (with the model): its
    other settings are other settings anyway."""
    theirs, mine = parse(earlier), parse(ours)
    out = []
    names = [*mine, *(k for k in theirs if k not in mine)]
    if theirs.get("run") != mine.get("run"):
        names = [k for k in names if k in ("run", "model")]
    for name in names:
        a, b = theirs.get(name), mine.get(name)
        if a == b:
            continue
        if name == "model":
            out.append("another model (another file, the file changed since, or other "
                       "values set for every case)" if a is not None
                       else "no record of the model")
            continue
        keyword = KEYWORDS.get(name, name or "a setting")
        flag = option_name(keyword)  # the command's flag; the keyword itself in Python
        if a is None:
            out.append(f"no {flag} recorded (this sweep: {_said(name, b or '', flag)})")
        elif b is None:
            out.append(f"{_said(name, a, flag)} (this sweep has none)")
        else:  # the command line's value as typed; Python's keyword again, as a call says it
            again = b if flag != keyword else _said(name, b, flag)
            out.append(f"{_said(name, a, flag)} (this sweep: {again})")
    return out
