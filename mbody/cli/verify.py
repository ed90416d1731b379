"""verify: check a student's equations against each body's Newton-Euler pair."""

from __future__ import annotations

import argparse
import math
import sys

from mbody.cli.common import EXIT_OK, EXIT_UNMET, MODEL_HELP, load_model, regular_file
from mbody.errors import MbodyError

SUMMARY_SUFFIXES = (".csv", ".html", ".htm")
"""A class summary's file name ends in one of these: it chooses the format."""


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser(
        "verify", help="check a student's equations (an answers file) against the model",
        description="Read ANSWERS, a YAML file of equations (equations: - {body: NAME, eq: "
        "\"2*a_y = O.Fy - 19.62\"}), and say for each whether it is one of the body's "
        "Newton-Euler rows (any scaling or rearrangement counts) or which mistake of the "
        "course explains the difference: missing_gyroscopic_term, gyroscopic_term_sign, "
        "missing_products_of_inertia, single_inertia_in_space, wrong_moment_point, "
        "missing_reaction, reaction_sign, lever_arm_sign, missing_applied_load, "
        "applied_load_sign, reaction_treated_as_known, solved_value_not_an_equation, "
        "rounded_too_coarsely, "
        "not_an_equation_of_this_body (an entry without a body is a Lagrange equation: "
        "not_an_equation_of_this_model). "
        "Then list the rows no correct equation gave. An answers file may set its own "
        "values of the model (set: {bodies.rod.mass: 2.5}, the paths of --set). Several "
        "answers files (a class): each checked in turn, an entry that cannot be read "
        "reported as that entry's problem; --summary writes one row per file (with the "
        "rows asked for and given) and the class's most frequent mistakes. Exit code 0 "
        "when every equation is correct (in a class, or with --require: and every row "
        "asked for given), 1 when not (or a class's file cannot be read), 2 for a bad "
        "model, option or answers file.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("answers", metavar="ANSWERS", nargs="+",
                   help="a YAML answers file, or several (answers/*.yaml)")
    s.add_argument("--summary", metavar="FILE",
                   help="a class's summary: .csv (one row per answers file: file, student, "
                   "equations, correct, each wrong equation's diagnosis, rows covered, rows "
                   "asked, duplicates, set, error; then the most frequent mistakes with "
                   "counts) or .html (the same as a page)")
    s.add_argument("--require", action="append", metavar="ROWS",
                   help="the rows each file must give to be all correct: all (every row of "
                   "every body; for a file in generalized coordinates, every Lagrange "
                   "equation), answered (the rows of the bodies it answers), lagrange, a "
                   "body's name or a row's label (upper.theta); comma-separated or "
                   "repeated. Default: all for a class (several files or --summary), "
                   "answered for one file")
    s.add_argument("--allow-set", action="append", metavar="PATHS",
                   help="the model paths an answers file's set: may name, comma-separated, "
                        "fnmatch wildcards allowed (bodies.*.mass); repeatable; default: any "
                        "(a set: can change gravity too: give this when grading)")
    s.add_argument("--json", action="store_true",
                   help="machine-readable output: one entry per equation, in file order")
    s.add_argument("--tol", type=_tolerance, default=1e-3, metavar="REL",
                   help="relative tolerance on each coefficient (default 1e-3: numbers "
                   "written to about four significant figures match)")
    s.set_defaults(run=verify, output_suffixes={"--summary": SUMMARY_SUFFIXES})


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

    if a.summary is not None or len(a.answers) > 1:
        return _class(a)
    answers = a.answers[0]
    regular_file(answers, "a YAML answers file")
    model = load_model(a.model)
    result = _verify(model, answers, tol=a.tol, require=a.require, allow_set=a.allow_set)
    if a.json:
        jsontext.dump(result.to_dict(), sys.stdout)
    else:
        print(result.text())
    passed = result.all_correct if a.require else result.ok
    return EXIT_OK if passed else EXIT_UNMET


def _class(a: argparse.Namespace) -> int:
    """Several answers files: each in turn, and with --summary the class's table."""
    from pathlib import Path

    from mbody.answers.summary import grade
    from mbody.util import jsontext
    from mbody.util.atomic import ensure_writable, write_atomic

    kind = None
    if a.summary is not None:
        kind = Path(a.summary).suffix.lower()
        if kind not in SUMMARY_SUFFIXES:
            raise MbodyError(f"--summary {a.summary}: the summary is written as .csv or "
                             f".html; got {kind or 'no extension'}")
        ensure_writable(a.summary)
    # a file that is not an answers file (missing, a folder, a device, a pipe with no
    # writer, not YAML) is about one student: the reader makes it a row, the class goes on
    model = load_model(a.model)
    summary = grade(model, a.answers, tol=a.tol, require=a.require or "all",
                    allow_set=a.allow_set)
    if a.json:
        jsontext.dump([{"file": g.file, "student": g.student, "error": g.error,
                        **(g.verification.to_dict() if g.verification else {})}
                       for g in summary.graded], sys.stdout)
    elif a.summary is None:
        for g in summary.graded:
            print(f"== {g.file} ==")
            print(g.verification.text() if g.verification else f"not checked: {g.error}")
            print()
    if a.summary is not None:
        if kind == ".csv":
            write_atomic(a.summary, summary.csv())
        else:
            from mbody.present.summary import class_summary_html

            write_atomic(a.summary, class_summary_html(summary))
        say = sys.stderr if a.json else sys.stdout
        print(summary.text(), file=say)
        print(f"wrote {a.summary}", file=say)
    every = all(g.all_correct for g in summary.graded)
    return EXIT_OK if every else EXIT_UNMET
