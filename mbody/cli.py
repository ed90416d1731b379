"""The `mbody` command: parse arguments, call the API, print. Nothing else lives here.

Exit codes: 0 success; 1 the request cannot be met (e.g. reactions still unknown);
2 bad input (model file, arguments); 70 an internal error (a bug: please report it).
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import sys
import traceback
from collections.abc import Sequence

from . import __version__
from .commands import EXIT_INPUT, EXIT_INTERNAL, EXIT_OK, EXIT_UNMET
from .errors import MbodyError, ModelError, UnknownReactionsError, did_you_mean

COMMAND_MODULES = ("core", "export", "sim", "draw", "animate", "mechanism")
"""Modules of `mbody.commands`; each has `register(subparsers)` adding its commands."""

def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="mbody", description="Per-body Newton-Euler equations for multibody "
                "models: M v_dot + b = Q + G lambda.", allow_abbrev=False,
                epilog="Start with: mbody check MODEL, then mbody assemble MODEL. "
                "Each command has --help.")
    p.add_argument("--version", action="version", version=f"mbody {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(f".commands.{name}", __package__).register(sub)
    return p


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)  # --know must not silently mean --known
        super().__init__(*args, **kwargs)

    def error(self, message: str):  # one paragraph, exit 2, as for any bad input
        if "required: COMMAND" in message:  # bare `mbody`: show what there is to do
            self.print_help(sys.stderr)
            raise SystemExit(EXIT_INPUT)
        bad = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if bad:  # argparse of Python 3.11 offers no suggestion for a misspelt command
            hint = did_you_mean(bad.group(1), re.findall(r"'([^']*)'", bad.group(2)))
            message += f"; {hint}" if hint else ""
        self.print_usage(sys.stderr)
        sys.stderr.write(f"mbody: error: {message}\n")
        raise SystemExit(EXIT_INPUT)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except ModelError as exc:
        sys.stderr.write(f"mbody: error: {exc}\n")
        return EXIT_INPUT
    except UnknownReactionsError as exc:
        sys.stderr.write(f"mbody: cannot solve: {exc}\n")
        return EXIT_UNMET
    except MbodyError as exc:
        sys.stderr.write(f"mbody: error: {exc}\n")
        return EXIT_INPUT
    except KeyboardInterrupt:
        sys.stderr.write("mbody: interrupted\n")
        return 130
    except BrokenPipeError:
        return EXIT_OK
    except Exception as exc:  # a bug: say so in one paragraph, traceback only on request
        if os.environ.get("MBODY_DEBUG"):
            traceback.print_exc()
        sys.stderr.write(f"mbody: internal error: {type(exc).__name__}: {exc}. This is a bug "
                         "in mbody; run with MBODY_DEBUG=1 for details and report it.\n")
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
