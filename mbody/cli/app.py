"""The `mbody` command: parse arguments, call the API, print. Nothing else lives here.

Exit codes: 0 success; 1 the request cannot be met (e.g. reactions still unknown);
2 bad input (model file, arguments); 70 an internal error (a bug: please report it).
"""

from __future__ import annotations

import argparse
import os
import re
import stat
import sys
import traceback
from collections.abc import Sequence

from mbody import __version__
from mbody.cli import (
    animate,
    core,
    draw,
    drive,
    export,
    interop,
    lagrange,
    mechanism,
    sim,
    statics,
    sweep,
    verify,
)
from mbody.cli.common import (
    EXIT_INPUT,
    EXIT_INTERNAL,
    EXIT_OK,
    EXIT_UNMET,
    IMPORT_FLAGS,
    PICTURE_FORMATS,
    add_import_options,
    byte_size,
)
from mbody.cli.near_miss import options_hint, unknown_options, unrecognized_message
from mbody.errors import (
    MbodyError,
    ModelError,
    UnknownReactionsError,
    did_you_mean,
    options_named,
)
from mbody.util.atomic import refuse_overwriting_inputs
from mbody.util.budget import DATA_BYTES, MAX_BYTES, byte_budget

COMMAND_MODULES = (core, export, sim, drive, draw, animate, mechanism, statics, verify,
                   interop, lagrange, sweep)
"""Modules of `mbody.cli`, in help order; each has `register(subparsers)` adding its
commands (importing one loads only argparse: each command imports what it runs when it
runs)."""

def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="mbody", description="Per-body Newton-Euler equations for multibody "
                "models: M v_dot + b = Q + G lambda.", allow_abbrev=False,
                epilog="Start with: mbody check MODEL, then mbody assemble MODEL. "
                "Each command has --help.")
    p.add_argument("--version", action="version", version=f"mbody {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for module in COMMAND_MODULES:
        module.register(sub)
    for command in sub.choices.values():  # every command that reads a model or run file
        inputs = {a.dest for a in command._get_positional_actions()}
        runs = bool(inputs & {"trajectory", "source"}) or "--state" in \
            command._option_string_actions
        models = bool(inputs & {"model", "source"})
        if models or runs:
            read = " and ".join(filter(None, (
                f"largest model file read (default {MAX_BYTES // 2**20}M)" if models else "",
                f"most data a run file may hold once inflated (default {DATA_BYTES // 2**30}G)"
                if runs else "")))
            command.add_argument(
                "--max-bytes", type=byte_size, metavar="SIZE",
                help=f"{read}, in bytes or with a unit (200M, 2G): a guard against reading a "
                "wrong or hostile file whole")
        if models:
            add_import_options(command)  # --format, --keyframe, --q: MJCF and URDF input
        writes = [o for dest in OUTPUTS for o in _options(command, dest)]
        if writes and "--force" not in command._option_string_actions:
            command.add_argument(
                "--force", action="store_true",
                help=f"write {' or '.join(writes)} even when it is one of this command's "
                "input files (the same file, however named), replacing that input, or when "
                "its suffix names another format than the one written")
    return p


INPUTS = {"model": "the model", "source": "the input", "trajectory": "the run file",
          "answers": "the answers file", "state": "the run file"}
"""Argument destinations that name a file a command reads, and how a message calls it."""
OUTPUTS = {"output": "-o", "latex": "--latex", "csv": "--csv", "summary": "--summary",
           "picture": "--picture", "answers_key": "--answers-key"}
"""Argument destinations that name a file (or folder) a command writes, and its option."""


def _options(command: argparse.ArgumentParser, dest: str) -> list[str]:
    """The option strings (or metavar, for a positional) of `command`'s `dest`."""
    return [a.option_strings[0] if a.option_strings else str(a.metavar)
            for a in command._actions if a.dest == dest]


def option_flags(command: argparse.ArgumentParser | None,
                 args: argparse.Namespace) -> dict[str, str]:
    """What messages call an argument within `command` (`mbody.errors.options_named`):
    each of its options by destination, by its long name (``t_end`` -> ``--t-end``,
    ``known`` -> ``--known``); the Python keywords that are not the destination of their
    option (``args.keywords``, from the command's ``set_defaults``: sweep's ``values`` is
    ``--set``); and those of an imported model (`IMPORT_FLAGS`: ``joint_positions`` is
    ``--q``)."""
    flags: dict[str, str] = {}
    for action in command._actions if command is not None else ():
        names = action.option_strings
        if names and action.dest != "help":
            flags[action.dest] = next((n for n in names if n.startswith("--")), names[0])
    return {**flags, **getattr(args, "keywords", {}), **IMPORT_FLAGS}


def _commands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """The sub-commands' parsers of `parser`, by name ({} when it has none)."""
    sub = next((a for a in parser._actions if a.dest == "command"), None)
    return dict(getattr(sub, "choices", None) or {})


def _subcommand(parser: argparse.ArgumentParser,
                args: argparse.Namespace) -> argparse.ArgumentParser | None:
    """The parser of the command `args` were read by."""
    return _commands(parser).get(getattr(args, "command", None) or "")


def _paths(value: object) -> list[str]:
    values = value if isinstance(value, list) else [value]
    return [v for v in values if isinstance(v, str) and v and v != "-"]


def check_paths(args: argparse.Namespace,
                command: argparse.ArgumentParser | None = None) -> None:
    """Refuse an empty file name (an output '' would be no output, or the current folder;
    an input '' the current folder), then an output of the command that is one of its
    input files, unless --force (`mbody.util.atomic.refuse_overwriting_inputs`). An output
    is named by `command`'s own first option for it (sweep's ``--out``), else OUTPUTS'.
    A command's ``output_suffixes`` and ``output_resumed`` defaults say where --force
    cannot help."""
    for dest, what in (*OUTPUTS.items(), *INPUTS.items()):
        values = getattr(args, dest, None)
        if "" in (values if isinstance(values, list) else [values]):
            raise MbodyError(f"an empty name for {what}; give a file name")
    inputs = [(INPUTS[dest], p) for dest in INPUTS for p in _paths(getattr(args, dest, None))]
    def flag(dest: str) -> str:
        own = _options(command, dest) if command is not None else []
        return own[0] if own else OUTPUTS[dest]

    outputs = [(flag(dest), p) for dest in OUTPUTS for p in _paths(getattr(args, dest, None))]
    folders = {a.option_strings[0] for a in (command._actions if command is not None else ())
               if a.dest in OUTPUTS and a.option_strings and a.metavar == "DIR"}
    refuse_overwriting_inputs(outputs, inputs, getattr(args, "force", False), folders,
                              getattr(args, "output_suffixes", None),
                              getattr(args, "output_resumed", ()))


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)  # --know must not silently mean --known
        super().__init__(*args, **kwargs)

    def parse_known_args(self, args=None, namespace=None):
        self._words = list(sys.argv[1:] if args is None else args)  # for `error`
        return super().parse_known_args(args, namespace)

    def parse_args(self, args=None, namespace=None):
        """As argparse's, but words no command took are reported by that command's
        parser (its usage line) with what they were probably meant to be."""
        known, extras = self.parse_known_args(args, namespace)
        if extras:
            commands = _commands(self)
            name = getattr(known, "command", None) or ""
            command = commands.get(name, self)
            command.error(unrecognized_message(name, command, extras, commands,
                                               getattr(command, "_words", ())))
        return known

    def error(self, message: str):  # one paragraph, exit 2, as for any bad input
        # argparse stops at a missing argument before it reports a misspelt option
        # (`convert M --ouput F`, `mbody --verison`): name that too, it is often the cause
        unknown = unknown_options(self, getattr(self, "_words", []))
        if "required: COMMAND" in message and unknown:
            message = unrecognized_message("", self, unknown, _commands(self))
        elif "required: COMMAND" in message:  # bare `mbody`: show what there is to do
            self.print_help(sys.stderr)
            raise SystemExit(EXIT_INPUT)
        elif message.startswith("the following arguments are required") and unknown:
            name = self.prog.split()[-1]
            message += "; also " + unrecognized_message(name, self, unknown, {})
        bad = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if bad:  # argparse of Python 3.11 offers no suggestion for a misspelt command
            hint = did_you_mean(bad.group(1), re.findall(r"'([^']*)'", bad.group(2)))
            if message.startswith("argument --format") and not hint:
                hint = self._picture_format_hint(bad.group(1))
            words = getattr(self, "_words", [])
            before = words[:words.index(bad.group(1))] if bad.group(1) in words else []
            misplaced = unknown_options(self, before)  # `mbody --t-end 3 simulate ...`
            if message.startswith("argument COMMAND") and misplaced:
                hint = "; ".join(filter(None, [hint, options_hint("", self, misplaced,
                                                                  _commands(self))]))
            message += f"; {hint}" if hint else ""
        self.print_usage(sys.stderr)
        sys.stderr.write(f"mbody: error: {message}\n")
        raise SystemExit(EXIT_INPUT)

    def _picture_format_hint(self, value: str) -> str:
        """`--format png` meant a picture's format (fbd's --format before 0.3): say where
        that goes now."""
        fmt = value.strip().lower().lstrip(".")
        if fmt not in PICTURE_FORMATS:
            return ""
        if "--image-format" in self._option_string_actions:
            return f"--format is the model file's format: did you mean --image-format {fmt}?"
        if "--output" in self._option_string_actions:
            return ("--format is the model file's format; a picture's format follows the "
                    f"output file's extension (-o NAME.{fmt})")
        return "--format is the model file's format"


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    out = _Stdout(sys.stdout)
    sys.stdout = out
    try:
        command = _subcommand(parser, args)
        check_paths(args, command)
        limit = getattr(args, "max_bytes", None)
        with byte_budget(limit), options_named(option_flags(command, args)):
            code = args.run(args)
        out.flush()  # a full device is reported here, not at exit
        return code
    except ModelError as exc:
        return _error(f"mbody: error: {exc}\n", EXIT_INPUT)
    except UnknownReactionsError as exc:
        return _error(f"mbody: cannot solve: {exc}\n", EXIT_UNMET)
    except StdoutError as exc:
        out.discard()
        return _error(f"mbody: error: {exc}\n", EXIT_INPUT)
    except MbodyError as exc:
        return _error(f"mbody: error: {exc}\n", EXIT_INPUT)
    except KeyboardInterrupt:
        return _error("mbody: interrupted\n", 130)
    except BrokenPipeError:  # `mbody ... | head`: the reader has all it wanted
        out.discard(truncate=False)
        return EXIT_OK
    except OSError as exc:  # the system refused a read or a write no command foresaw
        where = f" ({exc.filename})" if exc.filename else ""
        return _error(f"mbody: error: {exc.strerror or exc}{where}\n", EXIT_INPUT)
    except Exception as exc:  # a bug: say so in one paragraph, traceback only on request
        if os.environ.get("MBODY_DEBUG"):
            traceback.print_exc()
        return _error(f"mbody: internal error: {type(exc).__name__}: {exc}. This is a bug "
                      "in mbody; run with MBODY_DEBUG=1 for details and report it.\n",
                      EXIT_INTERNAL)
    finally:
        sys.stdout = out.inner


def _error(text: str, code: int) -> int:
    """Write `text` to stderr (if stderr itself cannot be written, the code still says it)."""
    try:
        sys.stderr.write(text)
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    return code


class StdoutError(MbodyError):
    """Standard output could not be written (a full disk or device, an I/O error)."""


class _Stdout:
    """sys.stdout during a command: a write that fails becomes one `StdoutError`, and
    `discard` leaves nothing partial behind where that can be undone (standard output
    redirected to a regular file is cut back to where the command started writing)."""

    def __init__(self, inner):
        self.inner = inner
        self.start: int | None = None
        try:
            fd = inner.fileno()
            inner.flush()
            st = os.fstat(fd)
            if stat.S_ISREG(st.st_mode):
                import fcntl

                appending = fcntl.fcntl(fd, fcntl.F_GETFL) & os.O_APPEND
                self.start = st.st_size if appending else os.lseek(fd, 0, os.SEEK_CUR)
        except (AttributeError, OSError, ValueError, ImportError):
            pass  # not a file descriptor (a test's capture), or no fcntl: nothing to undo

    def write(self, text: str) -> int:
        try:
            return self.inner.write(text)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise StdoutError(_stdout_message(exc)) from None

    def flush(self) -> None:
        try:
            self.inner.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise StdoutError(_stdout_message(exc)) from None

    def discard(self, truncate: bool = True) -> None:
        """Drop what could not be written: cut a regular file back to where this command
        started, and point the descriptor at /dev/null so that the interpreter's own flush
        at exit neither fails again nor prints a second message."""
        try:
            fd = self.inner.fileno()
        except (AttributeError, OSError, ValueError):
            return
        try:
            if truncate and self.start is not None:
                os.ftruncate(fd, self.start)
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, fd)
            os.close(null)
        except OSError:
            pass

    def __getattr__(self, name: str):
        return getattr(self.inner, name)


def _stdout_message(exc: OSError) -> str:
    return (f"cannot write to standard output: {exc.strerror or exc}; the output is "
            "incomplete and was discarded")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
