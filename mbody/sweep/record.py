"""What a sweep's row records of how it was computed (its ``settings`` cell), and how an
earlier row's record differs from this sweep's.

A row's numbers depend on its case's values (its own columns), on the run and those of
its settings that change them, and on the model the cases are built from. The record
holds the last two, as ``name=value`` pairs joined by ``; ``::

    run=kinematics; t-end=1 rev; steps=360; model=sha256:2c4f0e9b61d7a835

- ``run``: always; ``t-end`` (seconds, or ``N rev``) for ``kinematics`` and
  ``simulate``; ``steps`` for ``kinematics`` (the number given, or the default
  sampling, ``360 a turn`` or ``100 a second``: `sampling`); ``fps`` for ``simulate``;
  ``equilibrium`` (``yes`` or ``no``) for ``modes``. A setting a run does not use is
  not recorded, so it can change without making the rows another sweep's.
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
OPTIONS = {"run": "--run", "t-end": "--t-end", "steps": "--steps", "fps": "--fps",
           "equilibrium": "--equilibrium", "model": "the model"}
"""How a message names each recorded setting (the command's options)."""


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
    if settings.run == "kinematics":
        pairs.append(("steps", sampling(settings, model)))
    if settings.run == "simulate":
        pairs.append(("fps", _number(settings.fps)))
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


def differences(earlier: str, ours: str) -> list[str]:
    """How the record `earlier` (a row's) differs from `ours` (this sweep's), one phrase
    per setting: ``--t-end 0.1 (this sweep: 0.2)``, ``another model``... Another run is
    said alone (with the model): its other settings are other settings anyway."""
    theirs, mine = parse(earlier), parse(ours)
    out = []
    names = [*mine, *(k for k in theirs if k not in mine)]
    if theirs.get("run") != mine.get("run"):
        names = [k for k in names if k in ("run", "model")]
    for name in names:
        a, b = theirs.get(name), mine.get(name)
        if a == b:
            continue
        option = OPTIONS.get(name, name or "a setting")
        if name == "model":
            out.append("another model (another file, the file changed since, or other "
                       "values set for every case)" if a is not None
                       else "no record of the model")
        elif a is None:
            out.append(f"no {option} recorded (this sweep: {option} {b})")
        elif b is None:
            out.append(f"{option} {a} (this sweep has none)")
        else:
            out.append(f"{option} {a} (this sweep: {b})")
    return out
