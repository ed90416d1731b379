"""verify: check a student's equations against each body's Newton-Euler pair."""

from __future__ import annotations

import argparse
import math
import sys

from mbody.cli.common import EXIT_OK, EXIT_UNMET, MODEL_HELP, load_model, regular_file


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser(
        "verify", help="check a student's equations (an answers file) against the model",
        description="Read ANSWERS, a YAML file of equations (equations: - {body: NAME, eq: "
        "\"2*a_y = O.Fy - 19.62\"}), and say for each whether it is one of the body's "
        "Newton-Euler rows (any scaling or rearrangement counts) or which mistake of the "
        "course explains the difference: missing_gyroscopic_term, gyroscopic_term_sign, "
        "missing_products_of_inertia, single_inertia_in_space, wrong_moment_point, "
        "missing_reaction, reaction_sign, missing_applied_load, reaction_treated_as_known, "
        "not_an_equation_of_this_body. "
        "Then list the rows no correct equation gave. Exit code 0 when every equation is "
        "correct, 1 when some are not, 2 for a bad model or answers file.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("answers", metavar="ANSWERS", help="a YAML answers file")
    s.add_argument("--json", action="store_true",
                   help="machine-readable output: one entry per equation, in file order")
    s.add_argument("--tol", type=_tolerance, default=1e-3, metavar="REL",
                   help="relative tolerance on each coefficient (default 1e-3: numbers "
                   "written to about four significant figures match)")
    s.set_defaults(run=verify)


def _tolerance(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a number such as 1e-3, got {text!r}") from None
    if not (math.isfinite(x) and 0.0 < x < 1.0):
        raise argparse.ArgumentTypeError(f"expected a relative tolerance between 0 and 1, "
                                         f"got {text!r}")
    return x


def verify(a: argparse.Namespace) -> int:
    from mbody.answers.verify import verify as _verify
    from mbody.util import jsontext

    regular_file(a.answers, "a YAML answers file")
    model = load_model(a.model)
    result = _verify(model, a.answers, tol=a.tol)
    if a.json:
        jsontext.dump(result.to_dict(), sys.stdout)
    else:
        print(result.text())
    return EXIT_OK if result.ok else EXIT_UNMET
