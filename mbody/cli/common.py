"""Sub-commands of `mbody`, one module per group; each module has `register(sub)`.

A command handler takes the parsed namespace and returns an exit code; it raises
`MbodyError` (or a subclass) for bad input, which `mbody.cli.main` turns into one
paragraph on stderr and a non-zero exit code.
"""

from __future__ import annotations

import argparse
import functools
import math
import re
from collections.abc import Callable, Sequence
from contextvars import ContextVar
from pathlib import Path
from typing import Any, TextIO

from mbody.errors import MbodyError, given_twice
from mbody.util.formatting import number

EXIT_OK, EXIT_UNMET, EXIT_INPUT, EXIT_INTERNAL = 0, 1, 2, 70


_IMPORT: ContextVar[dict[str, Any] | None] = ContextVar("mbody_import_options",
                                                     default=None)
"""The command's ``--format``, ``--keyframe``, ``--q``... as `mbody.load` options."""
_VALUES: ContextVar[dict[str, Any] | None] = ContextVar("mbody_set_values", default=None)
"""The command's ``--set PATH=VALUE`` values (`Model.with_values`)."""


def load_model(path: str, *, warn: bool = True):
    """The validated model at `path`; its warnings (e.g. a quaternion that was normalised)
    go to stderr, so that a questionable input never passes unseen. The file size limit
    is the command's ``--max-bytes`` (set around the command by `mbody.cli.app.main`);
    the format and an imported model's state are its ``--format``, ``--keyframe``,
    ``--q``, ``--qd`` and ``--floating-base``, and its ``--set PATH=VALUE`` values are
    set in it (`add_import_options`)."""
    import sys

    from mbody.loading import load

    model = load(path, **(_IMPORT.get() or {}))
    values = _VALUES.get()
    if values:
        model = model.with_values(values)
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


def bounded(what: str, lo: float, hi: float, *, integer: bool = False,
            lo_open: bool = False, zero: str | None = None) -> Callable[[str], float]:
    """An argparse type: `what` (``"a number of seconds"``), from `lo` to `hi` (`lo`
    itself excluded when `lo_open`; both infinite: any finite number), a whole number
    when `integer`; `zero` names what 0 means when 0 is also allowed outside the range
    (``--max-steps 0``: no limit). Anything else (a word, nan, inf, a number out of
    range) is refused with the range, exit 2."""
    def fmt(x: float) -> str:
        return number(int(x)) if integer else number(x)

    shown = what
    if not (math.isinf(lo) and math.isinf(hi)):
        shown += (f" {'above' if lo_open else 'from'} {fmt(lo)} {'up ' if lo_open else ''}"
                  f"to {fmt(hi)}" + (f" (0: {zero})" if zero else ""))

    def parse(text: str) -> float:
        try:
            x: float = int(text.strip()) if integer else float(text)
        except (ValueError, OverflowError):
            raise argparse.ArgumentTypeError(f"expected {shown}, got {text!r}") from None
        if zero and x == 0:
            return x
        if not (math.isfinite(x) and (lo < x if lo_open else lo <= x) and x <= hi):
            raise argparse.ArgumentTypeError(f"expected {shown}, got {text!r}")
        return x

    parse.__name__ = what  # argparse names the type in some messages
    return parse


def seconds(what: str, lo: float, hi: float, *, lo_open: bool = False
            ) -> Callable[[str], float]:
    """An argparse type for a time in seconds (`what`: ``"a number of seconds"``): a
    number from `lo` to `hi`, as `bounded` reads it, or a time with its unit as
    ``kinematics --at`` reads one (``'2 s'``, ``'100 ms'``, ``'1 min'``:
    `mbody.model.checks.si_quantity`), held to the same range in seconds."""
    number_of_seconds = bounded(what, lo, hi, lo_open=lo_open)

    def parse(text: str) -> float:
        try:
            return number_of_seconds(text)
        except argparse.ArgumentTypeError as exc:
            from mbody.model.checks import si_quantity

            if _is_number(text):
                raise  # out of range
            quantity = si_quantity(text)
            if quantity is None or quantity[1] != "s":
                expected = str(exc).rsplit(", got ", 1)[0]
                raise argparse.ArgumentTypeError(
                    f"{expected} (or with its unit, such as '100 ms'), got {text!r}"
                ) from None
            try:
                return number_of_seconds(repr(quantity[0]))
            except argparse.ArgumentTypeError:
                raise exc from None

    parse.__name__ = what
    return parse


def _is_number(text: str) -> bool:
    """Whether `text` is a number as float() reads it (nan and inf too)."""
    try:
        float(text)
    except (ValueError, OverflowError):
        return False
    return True


_TURNS = re.compile(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(rev|revs|revolutions?)\s*")
TURNS_MAX = 1e6
"""Most turns an end time may be given in (``--t-end '1e6 rev'``)."""


def seconds_or_turns(lo: float, hi: float, *, lo_open: bool = False,
                     turns_max: float = TURNS_MAX) -> Callable[[str], tuple[str, float]]:
    """An argparse type for an end time (``--t-end`` of simulate, kinematics and sweep):
    seconds from `lo` to `hi` (as `seconds`: ``'0.5'``, ``'500 ms'``), or turns of the
    mechanism's turning driver written ``'1 rev'`` (also ``revs``, ``revolution(s)``),
    above 0 up to `turns_max`. Gives
    ``("s", seconds)`` or ``("rev", turns)``; each command says which driver's turn."""
    in_seconds = seconds("a time in seconds", lo, hi, lo_open=lo_open)

    def parse(text: str) -> tuple[str, float]:
        m = _TURNS.fullmatch(text)
        if m:
            x = float(m.group(1))
            if not 0 < x <= turns_max:
                raise argparse.ArgumentTypeError(
                    f"expected a number of turns above 0 up to {number(turns_max)}, got "
                    f"{text!r}")
            return ("rev", x)
        try:
            return ("s", in_seconds(text))
        except argparse.ArgumentTypeError as exc:  # seconds' "expected ..., got ..."
            expected = str(exc).rsplit(", got ", 1)[0]
            raise argparse.ArgumentTypeError(
                f"{expected}, or turns such as '1 rev', got {text!r}") from None

    parse.__name__ = "an end time"
    return parse


def output_stream(*targets: str | None) -> TextIO:
    """Where a command prints what it did: standard output, or standard error when one
    of `targets` (its output files) is standard output itself (``-o /dev/stdout``), so
    that the data written there is not mixed with text."""
    import sys

    from mbody.util.atomic import is_standard_output

    if any(t is not None and t != "-" and is_standard_output(t) for t in targets):
        return sys.stderr
    return sys.stdout


SUFFIX_FORMATS = {
    ".tex": "LaTeX", ".pdf": "PDF", ".png": "PNG", ".svg": "SVG", ".jpg": "JPEG",
    ".jpeg": "JPEG", ".gif": "GIF", ".html": "HTML", ".htm": "HTML", ".yaml": "YAML",
    ".yml": "YAML", ".xml": "XML", ".mjcf": "MJCF", ".urdf": "URDF", ".json": "JSON",
    ".csv": "CSV", ".npz": "NumPy .npz", ".npy": "NumPy .npy", ".mat": "MATLAB",
    ".txt": "text", ".md": "Markdown", ".parquet": "Parquet", ".py": "Python"}
"""Suffixes that name a format, as programs open files by them."""


def output_suffix(path: str | None, option: str, written: str,
                  suffixes: Sequence[str], force: bool) -> None:
    """Refuse, before any work, an output whose suffix names another format than the
    `written` one the command puts there (`assemble --latex x.pdf`: LaTeX source in a
    file every program opens as a PDF), with the name it was probably meant to have
    (`suffixes[0]`), unless `force` (``--force``: written under that name). A name
    without a suffix, or with one that names no format (`eqs`, `run.dat`), is written as
    asked, as are standard output (``-``) and devices. Commands whose suffix chooses
    the format (`export`, `graph`, `plot`) refuse an unknown one themselves."""
    if path is None or path == "-" or force:
        return
    suffix = Path(path).suffix.lower()
    if not suffix or suffix in suffixes or suffix not in SUFFIX_FORMATS:
        return
    meant = str(Path(path).with_suffix(suffixes[0]))
    raise MbodyError(f"{option} {path}: the name says {SUFFIX_FORMATS[suffix]} ({suffix}), "
                     f"but {option} writes {written}; did you mean {meant!r}? (or --force "
                     "to write it under that name)")


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


def parse_known(pairs: Sequence[str]) -> dict[str, float | str]:
    """``["A.Fx=3", "A.Fy=2*sin(t)", ...]`` -> ``{"A.Fx": 3.0, "A.Fy": "2*sin(t)"}``: a
    number as `assignments` reads it, anything else kept as text, an expression of t that
    the function it goes to reads as its Python ``known=`` (`mbody.model.arguments.
    known_values`: the labels checked with a did-you-mean, the expression parsed, taken at
    the state's time), naming it ``--known LABEL`` in its messages."""
    return assignments(pairs, "--known", "LABEL=VALUE (for example A.Fx=3)",
                       expressions=True)


def assignments(pairs: Sequence[str], flag: str, form: str, degrees: str | None = None,
                expressions: bool = False) -> dict[str, Any]:
    """``NAME=VALUE`` options -> ``{NAME: value}``; a value ending in `degrees` (``deg``,
    ``deg/s``) is converted to radians. Anything else is a clear `MbodyError`, and so is
    a number beyond a model file's bound (`mbody.model.checks.MAX_MAGNITUDE`); with
    `expressions`, a value that is not a number is kept as its text (stripped), for the
    caller to read as an expression of t."""
    from mbody.model.checks import MAX_MAGNITUDE

    out: dict[str, Any] = {}
    for p in pairs:
        name, sep, value = p.partition("=")
        if not sep or not name.strip():
            raise MbodyError(f"{flag} expects {form}, got {p!r}")
        text, scale = value.strip(), 1.0
        if degrees and text.endswith(degrees):
            text, scale = text[:-len(degrees)], math.pi / 180
        x: float | str
        try:
            x = float(text) * scale
        except ValueError:
            if not expressions:
                raise MbodyError(f"{flag} {name}: {value!r} is not a number") from None
            x = text
        if isinstance(x, float) and not math.isfinite(x):
            raise MbodyError(f"{flag} {name}: expected a finite number, got {value!r}")
        if isinstance(x, float) and abs(x) > MAX_MAGNITUDE:
            raise MbodyError(f"{flag} {name}: expected a number of magnitude at most "
                             f"{number(MAX_MAGNITUDE)}, as in a model file, got {value!r}")
        if name.strip() in out:
            raise given_twice(f"{flag} {name.strip()}")
        out[name.strip()] = x
    return out


def add_known_option(command: argparse.ArgumentParser, use: str, when: str) -> None:
    """``--known LABEL=VALUE`` (repeatable): a known reaction value, a number or an
    expression of t (`parse_known`); `use` says what the command does with it, `when`
    at which time an expression is taken."""
    command.add_argument(
        "--known", metavar="LABEL=VALUE", action="append", default=[],
        help=f"a known reaction value (N or N m), {use}: a number, or an expression of t "
        f"{when} (docs/expressions.md), e.g. --known A.Fx=3 or --known 'A.Fx=2*sin(t)'; "
        "repeatable")


def add_axes_option(command: argparse.ArgumentParser, saved: bool = False) -> None:
    """--axes {joint,world}: the axes reactions are given in (docs/reactions.md); `saved`:
    a command that reads a saved run, whose reactions stay as saved by default."""
    words = ("each component along its joint frame, fixed to the parent; 'world' each "
             "joint's force and moment on its child along world x, y, z (as a hand solution "
             "in world axes writes them)")
    command.add_argument(
        "--axes", choices=("joint", "world"), default=None if saved else "joint",
        help=(f"axes of the joint reactions shown: 'joint' {words}; default: as the run "
              "was saved (a run saved in joint axes is turned into world axes with the "
              "model it carries)") if saved else
        f"axes of the joint reactions: 'joint' (default) {words}")


MODEL_HELP = "a model file: mbody YAML, MuJoCo's MJCF (.xml) or URDF (.urdf)"
"""The MODEL argument's help on every command that reads one."""

VIEW_HELP = ("spatial models: iso (default), front, top, side, or ELEV,AZIM in degrees "
             "(for example 30,-60)")
"""The --view option's help: how a spatial model's picture is seen (fbd, report, modes)."""


def add_progress_options(command: argparse.ArgumentParser, what: str = "the progress bar"
                         ) -> None:
    """``--progress`` and ``--no-progress``: a long command's bars on standard error
    (`mbody.util.progress`), by default when it is a terminal (`show_progress`)."""
    command.add_argument("--progress", action="store_true",
                         help=f"show {what} on stderr even when it is not a terminal")
    command.add_argument("--no-progress", action="store_true",
                         help=f"do not show {what} on stderr")


def show_progress(a: argparse.Namespace) -> bool:
    """Whether `add_progress_options`'s bars are drawn: ``--progress``, or standard error
    is a terminal, unless ``--no-progress``."""
    import sys

    return (a.progress or sys.stderr.isatty()) and not a.no_progress


def add_import_options(command: argparse.ArgumentParser) -> None:
    """Give a command that reads a model the options of MJCF and URDF input, and make its
    handler pass them to `load_model`. A command that has a ``--keyframe`` of its own
    (``convert``) reads its input itself and is left as it is. ``--format`` (or its
    alias ``--model-format``) is the model file's format on every command; a picture's
    format is ``fbd --image-format`` or the output's extension, a converted model's
    ``convert --to``."""
    taken = command._option_string_actions
    if "--keyframe" in taken:
        return
    g = command.add_argument_group("MJCF and URDF input")
    add_format_option(g)
    g.add_argument("--keyframe", metavar="NAME", help="MJCF: the <key> whose qpos and qvel "
                   "give the state (default: 'initial' when the file has it, as mbody's export "
                   "writes; else the reference pose, at rest)")
    g.add_argument("--q", action="append", default=[], metavar="JOINT=VALUE",
                   help="URDF: a joint's position, rad or m (30deg for degrees); repeatable; "
                   "other joints at 0")
    g.add_argument("--qd", action="append", default=[], metavar="JOINT=VALUE",
                   help="URDF: a joint's rate, rad/s or m/s; repeatable; others at rest")
    g.add_argument("--floating-base", action="store_true", help="URDF: the root link moves "
                   "freely (a legged robot) instead of being fixed to the world")
    if "--set" not in taken:
        command.add_argument(
            "--set", action="append", default=[], metavar="PATH=VALUE", dest="set_values",
            help="change a value of the model file before anything else: "
            "bodies.<name>.<key>, loads.<name>.<key>, joints.<name>.<key>, "
            "drivers.<name>.<key> or gravity, then a component's index "
            "(bodies.rod.position.1=0.05); the value as the file would hold it "
            "(2, '100 rpm', '[0, -9.81]'); repeatable; checked as the file is")
    run = command.get_default("run")
    if run is not None:
        command.set_defaults(run=_with_import_options(run))


PICTURE_FORMATS = ("svg", "png", "pdf")
"""`mbody.present.draw.FORMATS`, without importing matplotlib at start-up (a test keeps
them equal)."""
PICTURE_SUFFIXES = tuple(f".{f}" for f in PICTURE_FORMATS)
"""A picture's file name ends in one of these: it chooses the format."""
EXPORT_SUFFIXES = (".npz", ".mat", ".json")
"""What `export -o` and `lagrange -o` write, each format by its suffix
(`mbody.io.export.SUFFIXES`, without importing it at start-up: a test keeps them equal)."""
MODEL_FORMATS = ("yaml", "mjcf", "urdf")
"""What ``--format`` names on every command: the format of the model file read."""


def add_format_option(group: Any, extra: Sequence[str] = (), what: str = "model file") -> None:
    """``--format`` (alias ``--model-format``, and `extra` aliases): the input model's
    format, the one meaning it has on every command."""
    group.add_argument("--format", "--model-format", *extra, dest="model_format",
                       choices=MODEL_FORMATS, metavar="{yaml,mjcf,urdf}",
                       help=f"the {what}'s format, when its extension (.yaml, .xml, .urdf) "
                       "does not say it (alias: " + ", ".join(("--model-format", *extra))
                       + ")")


def _with_import_options(run: Callable[[argparse.Namespace], int]
                         ) -> Callable[[argparse.Namespace], int]:
    @functools.wraps(run)
    def wrapped(a: argparse.Namespace) -> int:
        # both read before either is set: a refused one (a --set path given twice) must
        # not leave the other set for whatever this process runs next (`mbody convert`
        # after it read a YAML model with the last command's --keyframe)
        options = import_options(a)
        values = set_values(getattr(a, "set_values", None) or [])
        token = _IMPORT.set(options)
        given = _VALUES.set(values)
        try:
            return run(a)
        finally:
            _IMPORT.reset(token)
            _VALUES.reset(given)
    return wrapped


def set_values(pairs: Sequence[str]) -> dict[str, Any]:
    """``--set`` options -> ``{path: value}``, each value read as the model file would
    read it (`mbody.model.values.parse_value`); a path given twice is refused."""
    from mbody.model.values import parse_assignment, parse_value

    out: dict[str, Any] = {}
    for pair in pairs:
        path, text = parse_assignment(pair)
        if path in out:
            raise given_twice(f"--set {path}")
        out[path] = parse_value(text, path)
    return out


IMPORT_FLAGS = {"keyframe": "--keyframe", "joint_positions": "--q",
                "joint_velocities": "--qd", "floating_base": "--floating-base"}
"""`mbody.load`'s options of an imported model -> the flags that give them (what the
messages say within a command: `mbody.errors.options_named`)."""


def import_options(a: argparse.Namespace) -> dict[str, Any]:
    """The `mbody.load` options given on the command line (only those given)."""
    out: dict[str, Any] = {}
    if getattr(a, "model_format", None):
        out["format"] = a.model_format
    if getattr(a, "keyframe", None) is not None:
        out["keyframe"] = a.keyframe
    for key in ("joint_positions", "joint_velocities"):
        flag = IMPORT_FLAGS[key]
        pairs = getattr(a, flag.removeprefix("--"), None) or []
        if pairs:
            out[key] = _joint_values(pairs, flag, rate=key == "joint_velocities")
    if getattr(a, "floating_base", False):
        out["floating_base"] = True
    return out


def _joint_values(pairs: Sequence[str], flag: str, rate: bool) -> dict[str, float]:
    """``["shoulder=0.5", "elbow=30deg"]`` -> ``{"shoulder": 0.5, "elbow": 0.5236}``."""
    return assignments(pairs, flag, "JOINT=VALUE (for example shoulder=0.5)",
                       "deg/s" if rate else "deg")
