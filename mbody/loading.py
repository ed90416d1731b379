"""`mbody.load` and `mbody.loads`: a model file read and validated (`mbody.model` for
mbody YAML, `mbody.io.interop` for MJCF and URDF), then, when the file asks for it, its
bodies moved onto their joints and drivers at t = 0
(`mbody.solve.kinematics.assembled`): joint points given on each body, or drivers. The
file's own state is kept as ``model.file_state``; `mbody check` says how far each body
moved."""

from __future__ import annotations

import os
from typing import Any

from mbody.model.loader import check_source
from mbody.model.model import Model
from mbody.model.model import load as read_model
from mbody.model.model import loads as read_model_text
from mbody.model.source import Source, with_finish
from mbody.solve.kinematics import assembled


def load(source: str | os.PathLike[str] | dict, *, max_bytes: int | None = None,
         format: str | None = None, **options: Any) -> Model:
    """Read, validate and build a model, at its assembled pose.

    Parameters
    ----------
    source : str, os.PathLike or dict
        A path to a model file: mbody YAML, MJCF (``.xml``) or URDF (``.urdf``); or a
        dict with a YAML file's content (for scripts).
    max_bytes : int, optional
        The largest file read (default `mbody.util.budget.MAX_BYTES`, 32 MiB, or the
        command line's ``--max-bytes``); a larger file is refused before it is read.
    format : {"yaml", "mjcf", "urdf"}, optional
        The file's format, when its extension does not say it.
    **options
        The state of an imported model: ``keyframe="name"`` (MJCF; default the key
        ``initial`` when the file has one, as mbody's export writes it, else the
        reference pose at rest), ``joint_positions={...}``, ``joint_velocities={...}``
        and ``floating_base=True`` (URDF, a bool: text such as ``"false"`` is refused;
        default every joint at 0, the root fixed).
        See `mbody.io.interop.read_document`.

    Returns
    -------
    Model
        Its `initial` state is the file's, or, for a file with joint points per body or
        drivers, the nearest state where every joint and driver holds.

    Raises
    ------
    mbody.ModelError
        Listing every problem, each with its file, line and column; or `source` is YAML
        text rather than a path (`loads` reads text).
    mbody.errors.MbodyTypeError
        `source` is neither a path nor a dict (a `TypeError` too: for an open file, give
        its path or ``loads(f.read())``), or `max_bytes` is not a whole number.
    mbody.solve.kinematics.KinematicsError
        The joints and drivers cannot all close at t = 0.
    """
    max_bytes = check_source(source, max_bytes)
    if not isinstance(source, dict) and (
            format or options or str(source).lower().endswith((".xml", ".mjcf", ".urdf"))):
        from mbody.io.interop import import_spec  # MJCF, URDF: defusedxml, only for them

        spec = import_spec(source, format, max_bytes=max_bytes, **options)
        if spec is not None:  # None: the format is mbody YAML after all
            model = Model.from_spec(spec, Source(str(source), document=spec.document))
            return assembled(with_finish(model, assembled))
    return assembled(with_finish(read_model(source, max_bytes=max_bytes), assembled))


def loads(text: str | bytes, file: str = "<string>") -> Model:
    """Like `load`, from YAML text (bytes: UTF-8, as a file is read); `file` is the name
    used in error messages. A path is `load`'s; anything but text or bytes raises
    `mbody.errors.MbodyTypeError` (a `TypeError` too)."""
    return assembled(with_finish(read_model_text(text, file), assembled))
