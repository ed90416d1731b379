"""The `mbody` command: `app` parses the arguments and reports errors; one module per
group of sub-commands (`core`: check, assemble, solve; `export`; `sim`: simulate, plot;
`drive`: kinematics; `statics`: equilibrium; `draw`: fbd, graph, report; `animate`;
`mechanism`: jacobian; `verify`; `interop`: convert), each with ``register(subparsers)``;
`common` holds what they share."""

from mbody.cli.app import build_parser, main

__all__ = ["build_parser", "main"]
