"""`mbody.load` and `mbody.loads`: a model file read and validated (`mbody.model`), then,
when the file asks for it, its bodies moved onto their joints and drivers at t = 0
(`mbody.solve.kinematics.assembled`): joint points given on each body, or drivers. The
file's own state is kept as ``model.file_state``; `mbody check` says how far each body
moved."""

from __future__ import annotations

import os
from typing import Any

from mbody.model.model import Model
from mbody.model.model import load as read_model
from mbody.model.model import loads as read_model_text
from mbody.model.source import with_finish
from mbody.solve.kinematics import assembled


def load(source: str | os.PathLike[str] | dict, *, max_bytes: int | None = None,
         format: str | None = None, **options: Any) -> Model:
    """Read, validate and build a model, at its assembled pose.

    Parameters, errors: those of `mbody.model.model.load` (a file path or a dict;
    ``max_bytes``, ``format`` and the state options of MJCF and URDF imports), and
    `mbody.solve.kinematics.KinematicsError` when the joints and drivers cannot all close
    at t = 0.

    Returns
    -------
    Model
        Its `initial` state is the file's, or, for a file with joint points per body or
        drivers, the nearest state where every joint and driver holds.
    """
    return assembled(with_finish(read_model(source, max_bytes=max_bytes, format=format,
                                            **options), assembled))


def loads(text: str, file: str = "<string>") -> Model:
    """Like `load`, from YAML text (`file`: the name used in error messages)."""
    return assembled(with_finish(read_model_text(text, file), assembled))
