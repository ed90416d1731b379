"""export: M, b, Q, G with their label maps to npz / .mat / JSON / CSV; LaTeX for assemble."""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from mbody.cli.common import (
    EXIT_OK,
    EXPORT_SUFFIXES,
    MODEL_HELP,
    add_known_option,
    bounded,
    load_model,
    output_stream,
    parse_known,
    regular_file,
)
from mbody.errors import MbodyError, OutputError

if TYPE_CHECKING:
    from mbody.equations.assemble import Assembly


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `export` command and its options to the command line's subparsers."""
    s = sub.add_parser(
        "export", help="write M, b, Q, G with row/column labels (npz, .mat, JSON, CSV)",
        description="Write the stacked equations M v_dot + b = Q + G lambda of MODEL at its "
        "initial state (or at a sample of a trajectory file) with the label of every row and "
        "column, each reaction column's joint, bodies, component, direction and sign, the "
        "body masses and inertias, and the conventions. The format follows the suffix: "
        ".npz (numpy; reload with mbody.load_export), .mat (MATLAB/Octave; M and G sparse), "
        ".json (validates against mbody/data/assembly.schema.json); --csv DIR writes tables.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("-o", "--output", metavar="FILE", action="append", default=[],
                   help="output file ending in .npz, .mat or .json (repeatable)")
    s.add_argument("--csv", metavar="DIR", help="write CSV tables into this folder")
    s.add_argument("--state", metavar="RUN", help="take the state from this trajectory file "
                   "(written by 'mbody simulate -o RUN.npz')")
    s.add_argument("--time", metavar="T",
                   type=bounded("a finite number of seconds", -math.inf, math.inf),
                   help="with --state: use the stored "
                   "sample nearest to time T in seconds (default: the last sample); samples "
                   "are not interpolated")
    add_known_option(s, "recorded in the export", "taken at the state's time (the run's "
                     "sample with --state)")
    s.add_argument("--axes", choices=("joint", "world"), default="joint",
                   help="'world': add the map T (world = T lambda) from the joint-frame "
                   "reaction values, the columns of G, to each joint's force and moment on "
                   "its child along world x, y, z at the state, with their labels (T.csv "
                   "in a CSV folder); 'joint' (default): M, b, Q, G alone")
    s.set_defaults(run=export, output_suffixes={"-o": EXPORT_SUFFIXES})


def export(a: argparse.Namespace) -> int:
    """`mbody export MODEL -o FILE... [--csv DIR]`: write the exports, print their sizes."""
    from mbody.equations.assemble import assemble
    from mbody.io.export import (
        SUFFIXES,
        assembly_from_trajectory,
        exported,
        write_csv,
        write_export,
    )
    from mbody.util.atomic import atomic_folder, atomic_path

    if not a.output and not a.csv:
        raise MbodyError("nothing to write: give -o FILE (.npz, .mat or .json) and/or "
                         "--csv DIR")
    if a.time is not None and not a.state:
        raise MbodyError("--time needs --state RUN (a trajectory file)")
    model = load_model(a.model)
    if a.state:
        regular_file(a.state, "a run file written by 'mbody simulate -o RUN.npz'")
        asm, source = assembly_from_trajectory(model, a.state, a.time)
    else:
        asm, source = assemble(model), ""
    exp = exported(asm, parse_known(a.known), source, axes=a.axes)
    N, m = len(exp.coordinates), len(exp.reactions)
    for out in a.output:  # an unknown suffix is refused before anything is written
        if Path(out).suffix.lower() not in SUFFIXES:
            write_export(exp, out)
    with contextlib.ExitStack() as staged:  # every output, or none: each is written to a
        for out in a.output:  # temporary file, and all are put in place at the end
            tmp = staged.enter_context(atomic_path(out))
            with _writing(out):
                write_export(exp, tmp)
        if a.csv:
            folder = staged.enter_context(atomic_folder(a.csv))
            with _writing(a.csv, "folder"):
                write_csv(exp, folder)
    say = output_stream(*a.output)
    for out in a.output:
        print(f"wrote {out}", file=say)
    if a.csv:
        print(f"wrote {a.csv}/ (M.csv, G.csv, vectors.csv, columns.csv, bodies.csv, "
              f"info.csv{', T.csv' if exp.T is not None else ''})", file=say)
    world = (f", T {len(exp.world_reactions)}x{m} ({exp.T.nnz} non-zeros; world axes = "
             "T lambda)" if exp.T is not None else "")
    print(f"M {N}x{N} ({exp.M.nnz} non-zeros), b {N}, Q {N}, G {N}x{m} "
          f"({exp.G.nnz} non-zeros){world}; state: {exp.state_source}", file=say)
    return EXIT_OK


def latex(asm: Assembly, target: str, body: str | None = None) -> int:
    """`mbody assemble MODEL --latex [FILE]`: the LaTeX document to FILE (or stdout for -)."""
    from mbody.present.latex import document
    from mbody.util.atomic import write_atomic

    if body is not None and body not in asm.model.index:
        try:
            asm.bodies[body]
        except KeyError as exc:
            raise MbodyError(exc.args[0]) from None
    text = document(asm, bodies=None if body is None else [body])
    if target == "-":
        sys.stdout.write(text)
    else:
        with _writing(target):
            print(f"wrote {write_atomic(target, text)}", file=output_stream(target))
    return EXIT_OK


@contextlib.contextmanager
def _writing(target: str, kind: str = "file") -> Iterator[None]:
    """An operating-system error while writing `target` (or its temporary `kind`, file or
    folder) becomes one clear message naming `target`."""
    try:
        yield
    except OSError as exc:
        if isinstance(exc, OutputError) and exc.filename == target:
            raise  # already one message naming the file
        raise OutputError(f"cannot write {target!r}: {exc.strerror or exc}; nothing was "
                          f"written (the temporary {kind} is removed, and "
                          f"{Path(target).name!r} is as it was)", exc, target) from None
