"""Sub-commands of `mbody`, one module per group; each module has `register(sub)`.

A command handler takes the parsed namespace and returns an exit code; it raises
`MbodyError` (or a subclass) for bad input, which `mbody.cli.main` turns into one
paragraph on stderr and a non-zero exit code.
"""

from __future__ import annotations

import argparse
import functools
import math
from collections.abc import Callable, Sequence
from contextvars import ContextVar
from typing import Any

from mbody.errors import MbodyError

EXIT_OK, EXIT_UNMET, EXIT_INPUT, EXIT_INTERNAL = 0, 1, 2, 70


_IMPORT: ContextVar[dict[str, Any] | None] = ContextVar("mbody_import_options",
                                                     default=None)
"""The command's ``--format``, ``--keyframe``, ``--q``... as `mbody.load` options."""


def load_model(path: str, *, warn: bool = True):
    """The validated model at `path`; its warnings (e.g. a quaternion that was normalised)
    go to stderr, so that a questionable input never passes unseen. The file size limit
    is the command's ``--max-bytes`` (set around the command by `mbody.cli.app.main`);
    the format and an imported model's state are its ``--format``, ``--keyframe``,
    ``--q``, ``--qd`` and ``--floating-base`` (`add_import_options`)."""
    import sys

    from mbody.loading import load

    model = load(path, **(_IMPORT.get() or {}))
    if warn:
        for w in model.warnings:
            sys.stderr.write(f"mbody: warning: {w}\n")
    return model


_UNITS = {"": 1, "k": 2**10, "m": 2**20, "g": 2**30}


def byte_size(text: str) -> int:
    """``--max-bytes`` values: bytes, or with a binary unit (``200M``, ``1.5G``, ``64k``)."""
    import argparse
    import re

    m = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([kKmMgG]?)(?:i?B)?\s*", text)
    if not m:
        raise argparse.ArgumentTypeError(f"expected a size in bytes such as 100000000 or "
                                         f"200M, got {text!r}")
    size = int(float(m.group(1)) * _UNITS[m.group(2).lower()])
    if size < 1:
        raise argparse.ArgumentTypeError(f"expected a size of at least 1 byte, got {text!r}")
    return size


def regular_file(path: str, what: str) -> None:
    """Refuse, before anything opens it, a `path` that exists but is not a regular file: a
    named pipe without a writer would block numpy's open() forever, a device never end."""
    import os
    import stat

    try:
        mode = os.stat(path).st_mode
    except OSError:
        return  # missing or unreadable: the reader says so
    if not stat.S_ISREG(mode):
        kind = ("a directory" if stat.S_ISDIR(mode) else "a named pipe" if stat.S_ISFIFO(mode)
                else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "not a file")
        raise MbodyError(f"{path}: this is {kind}, not a file; expected {what}")


def parse_known(pairs: Sequence[str]) -> dict[str, float]:
    """``["A.Fx=3", ...]`` -> ``{"A.Fx": 3.0}`` (labels are checked later, with hints)."""
    return assignments(pairs, "--known", "LABEL=VALUE (for example A.Fx=3)")


def assignments(pairs: Sequence[str], flag: str, form: str,
                degrees: str | None = None) -> dict[str, float]:
    """``NAME=VALUE`` options -> ``{NAME: value}``; a value ending in `degrees` (``deg``,
    ``deg/s``) is converted to radians. Anything else is a clear `MbodyError`."""
    out = {}
    for p in pairs:
        name, sep, value = p.partition("=")
        if not sep or not name.strip():
            raise MbodyError(f"{flag} expects {form}, got {p!r}")
        text, scale = value.strip(), 1.0
        if degrees and text.endswith(degrees):
            text, scale = text[:-len(degrees)], math.pi / 180
        try:
            x = float(text) * scale
        except ValueError:
            raise MbodyError(f"{flag} {name}: {value!r} is not a number") from None
        if not math.isfinite(x):
            raise MbodyError(f"{flag} {name}: expected a finite number, got {value!r}")
        out[name.strip()] = x
    return out


MODEL_HELP = "a model file: mbody YAML, MuJoCo's MJCF (.xml) or URDF (.urdf)"
"""The MODEL argument's help on every command that reads one."""


def add_import_options(command: argparse.ArgumentParser) -> None:
    """Give a command that reads a model the options of MJCF and URDF input, and make its
    handler pass them to `load_model`. A command that has a ``--keyframe`` of its own
    (``convert``) reads its input itself and is left as it is; where ``--format`` names
    the output's format (``fbd``, ``export``), the model's is ``--model-format``."""
    taken = command._option_string_actions
    if "--keyframe" in taken:
        return
    g = command.add_argument_group("MJCF and URDF input")
    g.add_argument("--model-format" if "--format" in taken else "--format",
                   dest="model_format", choices=("yaml", "mjcf", "urdf"),
                   help="the model file's format, when its extension (.yaml, .xml, .urdf) "
                   "does not say it")
    g.add_argument("--keyframe", metavar="NAME", help="MJCF: the <key> whose qpos and qvel "
                   "give the state (default: the reference pose, at rest)")
    g.add_argument("--q", action="append", default=[], metavar="JOINT=VALUE",
                   help="URDF: a joint's position, rad or m (30deg for degrees); repeatable; "
                   "other joints at 0")
    g.add_argument("--qd", action="append", default=[], metavar="JOINT=VALUE",
                   help="URDF: a joint's rate, rad/s or m/s; repeatable; others at rest")
    g.add_argument("--floating-base", action="store_true", help="URDF: the root link moves "
                   "freely (a legged robot) instead of being fixed to the world")
    run = command.get_default("run")
    if run is not None:
        command.set_defaults(run=_with_import_options(run))


def _with_import_options(run: Callable[[argparse.Namespace], int]
                         ) -> Callable[[argparse.Namespace], int]:
    @functools.wraps(run)
    def wrapped(a: argparse.Namespace) -> int:
        token = _IMPORT.set(import_options(a))
        try:
            return run(a)
        finally:
            _IMPORT.reset(token)
    return wrapped


def import_options(a: argparse.Namespace) -> dict[str, Any]:
    """The `mbody.load` options given on the command line (only those given)."""
    out: dict[str, Any] = {}
    if getattr(a, "model_format", None):
        out["format"] = a.model_format
    if getattr(a, "keyframe", None) is not None:
        out["keyframe"] = a.keyframe
    for flag, key in (("q", "joint_positions"), ("qd", "joint_velocities")):
        pairs = getattr(a, flag, None) or []
        if pairs:
            out[key] = _joint_values(pairs, f"--{flag}", rate=flag == "qd")
    if getattr(a, "floating_base", False):
        out["floating_base"] = True
    return out


def _joint_values(pairs: Sequence[str], flag: str, rate: bool) -> dict[str, float]:
    """``["shoulder=0.5", "elbow=30deg"]`` -> ``{"shoulder": 0.5, "elbow": 0.5236}``."""
    return assignments(pairs, flag, "JOINT=VALUE (for example shoulder=0.5)",
                       "deg/s" if rate else "deg")
