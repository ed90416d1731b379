"""Other robot formats: MJCF (MuJoCo) and URDF read into mbody models (and written back).

`read_document` picks the reader by the file's extension (``.xml``/``.mjcf``: MJCF,
``.urdf``: URDF) or by ``format``; each returns the plain values a YAML model file parses
to, located at the XML's lines, so `mbody.model.validate` checks them as it checks YAML.
This package imports defusedxml: `mbody.load` imports it only for such files.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from mbody.errors import MbodyError, MbodyTypeError, did_you_mean, option_name
from mbody.io.interop.mjcf import read_mjcf
from mbody.io.interop.tree import ImportedDocument, validate_imported
from mbody.io.interop.urdf import read_urdf
from mbody.model.validate import Spec
from mbody.util.budget import byte_budget

FORMATS = ("yaml", "mjcf", "urdf")
"""The model formats `mbody.load` and every command read."""
EXTENSIONS = {".xml": "mjcf", ".mjcf": "mjcf", ".urdf": "urdf"}
"""File extensions read as MJCF or URDF; every other file is read as YAML."""
OPTIONS = ("keyframe", "joint_positions", "joint_velocities", "floating_base")


def format_of(path: str | os.PathLike[str], format: str | None = None) -> str:
    """The format of the model at `path`: `format` if given, else from its extension.

    Parameters
    ----------
    path : str or os.PathLike
        The model file.
    format : {"yaml", "mjcf", "urdf"}, optional
        Overrides the extension.

    Returns
    -------
    str
        One of `FORMATS`.
    """
    if format is not None:
        if format not in FORMATS:
            hint = did_you_mean(format, FORMATS)
            raise MbodyError(f"unknown model format '{format}'; expected one of "
                             f"{', '.join(FORMATS)}{'; ' + hint if hint else ''}")
        return format
    return EXTENSIONS.get(Path(path).suffix.lower(), "yaml")


def read_document(path: str | os.PathLike[str], format: str | None = None,
                  **options: Any) -> ImportedDocument:
    """Read an MJCF or URDF model file into a located document.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    format : {"mjcf", "urdf"}, optional
        Default: from the extension.
    **options
        MJCF: ``keyframe`` (default ``initial`` when the file has such a key, else
        the reference pose at rest: `mbody.io.interop.mjcf_state.chosen`). URDF:
        ``joint_positions``, ``joint_velocities`` (dicts of joint name to value),
        ``floating_base``.

    Returns
    -------
    ImportedDocument
    """
    fmt = format_of(path, format)
    _check_options(fmt, options)
    if fmt == "mjcf":
        return read_mjcf(Path(path), keyframe=options.get("keyframe"), file=str(path))
    if fmt == "urdf":
        return read_urdf(Path(path), file=str(path),
                         joint_positions=options.get("joint_positions"),
                         joint_velocities=options.get("joint_velocities"),
                         floating_base=bool(options.get("floating_base", False)))
    raise MbodyError(f"{path}: read_document reads MJCF and URDF; a YAML model goes "
                     "through mbody.load")


def _check_options(fmt: str, options: dict[str, Any]) -> None:
    allowed = {"mjcf": ("keyframe",), "yaml": (),
               "urdf": ("joint_positions", "joint_velocities", "floating_base")}[fmt]
    for k, v in options.items():
        if k == "floating_base" and not isinstance(v, bool | None):  # "false" is truthy
            raise MbodyTypeError(f"floating_base must be True or False, got "
                                 f"{type(v).__name__} {v!r}")
        if v is None or (k == "floating_base" and v is False):
            continue
        if k not in OPTIONS:
            hint = did_you_mean(k, OPTIONS)
            raise MbodyError(f"unknown option '{k}'{'; ' + hint if hint else ''}")
        if k not in allowed:
            which = {"keyframe": "an MJCF model's", "joint_positions": "a URDF model's",
                     "joint_velocities": "a URDF model's",
                     "floating_base": "a URDF model's"}[k]
            raise MbodyError(f"{option_name(k)} sets {which} state; this model is read as "
                             f"{fmt.upper()}")


def import_spec(path: str | os.PathLike[str], format: str | None = None, *,
                max_bytes: int | None = None, **options: Any) -> Spec | None:
    """The validated specification of an MJCF or URDF model; None for a YAML file.

    What `mbody.load` calls first: the import's warnings come first in the model's.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    format : {"yaml", "mjcf", "urdf"}, optional
        Default: from the extension.
    max_bytes : int, optional
        The largest file read (as for YAML models).
    **options
        As for `read_document`.

    Returns
    -------
    Spec or None
    """
    fmt = format_of(path, format)
    if fmt == "yaml":
        _check_options(fmt, options)
        return None
    with byte_budget(max_bytes):
        doc = read_document(path, fmt, **options)
    spec = validate_imported(doc)
    spec.warnings[:0] = doc.warnings
    spec.document = doc  # its YAML form, where Model.with_values sets values
    return spec
