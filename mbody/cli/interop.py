"""convert: a model between mbody YAML, MuJoCo's MJCF and URDF."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from mbody.cli.common import (
    EXIT_OK,
    add_format_option,
    load_model,
    output_stream,
    output_suffix,
    regular_file,
)
from mbody.errors import MbodyError, did_you_mean

FORMATS = {".yaml": "yaml", ".yml": "yaml", ".xml": "mjcf", ".mjcf": "mjcf", ".urdf": "urdf"}
"""File extension -> format."""
WRITTEN = ("yaml", "mjcf")
"""Formats `mbody convert` writes (URDF is read only)."""
NAMES = {"yaml": "mbody YAML", "mjcf": "MJCF", "urdf": "URDF"}
SUFFIXES = {"yaml": (".yaml", ".yml"), "mjcf": (".xml", ".mjcf")}
"""The suffixes of each format written, the usual first."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `convert` command to the command line's subparsers."""
    s = sub.add_parser(
        "convert", help="convert a model between mbody YAML, MJCF (MuJoCo) and URDF",
        description="Convert SOURCE to OUTPUT; the formats follow the extensions: .yaml "
        "(mbody), .xml (MuJoCo's MJCF), .urdf (read only). YAML -> MJCF writes the model "
        "along its joint tree with the initial state as the keyframe 'initial' (closed "
        "loops as equality constraints, soft in MuJoCo; the file's header lists what MJCF "
        "cannot hold). MJCF or URDF -> YAML writes an ordinary, readable mbody model whose "
        "header names its source. YAML -> YAML rewrites a model in the shipped models' "
        "layout (comments are not kept).")
    s.add_argument("source", metavar="SOURCE", help="the model to read (.yaml, .xml, .urdf)")
    s.add_argument("-o", "--output", metavar="OUTPUT", required=True,
                   help="the file to write (.yaml or .xml)")
    s.add_argument("--to", choices=WRITTEN, metavar="{yaml,mjcf}",
                   help="the output's format, when OUTPUT's extension does not say it")
    add_format_option(s, ("--from",), what="SOURCE")
    s.add_argument("--keyframe", metavar="NAME", help="MJCF input: the keyframe whose "
                   "qpos/qvel give the initial state (default, as on every command: "
                   "'initial' when the file has it, as mbody's export writes; else the "
                   "reference pose at rest)")
    s.add_argument("--force", action="store_true", help="replace OUTPUT if it exists (never "
                   "SOURCE itself: write the converted model beside it), or write it when "
                   "its extension names another format than --to")
    s.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                   dest="set_values", help="change a value of SOURCE's model (paths of its "
                   "YAML form, as for every command: bodies.<name>.<key>...) before it is "
                   "written; repeatable")
    s.set_defaults(run=convert)


def convert(a: argparse.Namespace) -> int:
    """`mbody convert SOURCE -o OUTPUT`: read, convert, write atomically, say what."""
    from mbody.util.atomic import ensure_writable

    _old_format_meaning(a)
    src_format = a.model_format or _format(a.source, "SOURCE", "--format",
                                           (".yaml", ".xml", ".urdf"))
    ensure_writable(a.output)  # the rules of every command's output: a folder refused
    if not a.to and Path(a.output).suffix.lower() == ".urdf":
        raise MbodyError(f"{a.output}: mbody reads URDF but does not write it; write "
                         ".yaml (mbody) or .xml (MJCF)")
    out_format = a.to or _format(a.output, "OUTPUT", "--to", (".yaml", ".xml"))
    output_suffix(a.output, "-o", f"{NAMES[out_format]} (--to {out_format})",
                  SUFFIXES[out_format], a.force)
    if not os.path.exists(a.source):
        raise MbodyError(f"{a.source}: no such file")
    regular_file(a.source, f"a model file ({NAMES[src_format]})")
    if _replaces_a_file(a.output) and not a.force:
        raise MbodyError(f"{a.output}: exists; give --force to replace it, or another "
                         "OUTPUT")
    if a.set_values:
        return _convert_with_values(a, src_format, out_format)
    if src_format == "yaml":
        model = load_model(a.source)
        if out_format == "mjcf":
            from mbody.io.interop.mjcf_write import write_mjcf

            write_mjcf(model, a.output, source=a.source)
        else:
            from mbody.model.loader import load_text, read_file
            from mbody.model.yaml_write import write_document

            document = load_text(read_file(a.source), a.source).data
            write_document(document, a.output, source=a.source)
    else:
        document = _read(a.source, src_format, a.keyframe)
        model = _model(document, a.source)
        notes = [str(w) for w in getattr(document, "warnings", ())]
        for note in notes:
            sys.stderr.write(f"mbody: warning: {note}\n")
        if out_format == "mjcf":
            from mbody.io.interop.mjcf_write import write_mjcf

            write_mjcf(model, a.output, source=a.source)
        else:
            from mbody.model.yaml_write import write_document

            write_document(getattr(document, "data", document), a.output, source=a.source,
                           notes=notes)
    say = output_stream(a.output)
    print(f"wrote {a.output} ({NAMES[out_format]} of {model.name!r} from "
          f"{NAMES[src_format]}: {_summary(model)})", file=say)
    if out_format == "mjcf":
        print("the header comment of the file lists what MJCF cannot hold", file=say)
    return EXIT_OK


def _convert_with_values(a: argparse.Namespace, src_format: str, out_format: str) -> int:
    """convert with --set: the model read as every command reads it, the values set and
    checked (`Model.with_values`), then its document (values in place) or its MJCF
    written."""
    from mbody.cli.common import set_values
    from mbody.loading import load
    from mbody.model.values import apply, edits, entry_names

    values = set_values(a.set_values)
    keyframe = a.keyframe if src_format == "mjcf" else None
    base = load(a.source, format=src_format if src_format != "yaml" else None,
                **({"keyframe": keyframe} if keyframe is not None else {}))
    model = base.with_values(values)  # every rule of the file checked, located
    if out_format == "mjcf":
        from mbody.io.interop.mjcf_write import write_mjcf

        write_mjcf(model, a.output, source=a.source)
    else:
        from mbody.model.yaml_write import write_document

        src = model.source
        assert src is not None  # a model read from a file keeps its source
        doc = src.read()
        apply(doc, edits(doc, src.values, entry_names(base)))
        write_document(doc.data, a.output, source=a.source)
    print(f"wrote {a.output} ({NAMES[out_format]} of {model.name!r} from "
          f"{NAMES[src_format]} with {len(values)} value(s) set: {_summary(model)})",
          file=output_stream(a.output))
    return EXIT_OK


def _replaces_a_file(output: str) -> bool:
    """Whether writing `output` replaces an existing file, which convert does only with
    --force (a model file may be the only copy of someone's work). A device or a named
    pipe (``-o /dev/null``) and standard output (``-o /dev/stdout``) are written through,
    as by every command (`mbody.util.atomic`): nothing there is replaced."""
    from mbody.util.atomic import is_standard_output

    return os.path.isfile(output) and not is_standard_output(output)


def _old_format_meaning(a: argparse.Namespace) -> None:
    """Before 0.3, `convert --format` named the output's format: `--format mjcf` with a
    .yaml SOURCE most likely still means that. Say so rather than read the YAML file as
    MJCF."""
    given = a.model_format
    ext = FORMATS.get(Path(a.source).suffix.lower())
    if given and ext and given != ext and given in WRITTEN:
        raise MbodyError(f"--format {given}: --format is SOURCE's format, and {a.source} is "
                         f"{NAMES[ext]} by its extension; did you mean --to {given} (the "
                         "output's format)?")


def _format(path: str, what: str, option: str, choices: tuple[str, ...]) -> str:
    """The format `path`'s extension names (`FORMATS`; `choices` are the main ones, for
    the message), or a clear refusal with a did-you-mean."""
    ext = Path(path).suffix.lower()
    if ext in FORMATS and FORMATS[ext] in {FORMATS[c] for c in choices}:
        return FORMATS[ext]
    hint = did_you_mean(ext, choices) if ext else ""
    shown = ext or "no extension"
    listed = ", ".join(choices)
    raise MbodyError(f"{path}: cannot tell the format of {what} from {shown!r}"
                     f"{'; ' + hint if hint else ''} (extensions: {listed}; or give "
                     f"{option})")


def _read(path: str, fmt: str, keyframe: str | None) -> Any:
    """The model document of an MJCF or URDF file (`mbody.io.interop.read_document`),
    in the state every command reads it in (`mbody.io.interop.mjcf_state.chosen`)."""
    from mbody.io.interop import read_document as read

    return read(path, format=fmt, keyframe=keyframe)  # None: not given (its default)


def _model(document: Any, source: str):
    """The validated model of a document read from `source` (its issues name it), at
    its assembled pose when it gives joint points per body or drivers (`mbody.load`)."""
    from mbody.io.interop.tree import validate_imported
    from mbody.loading import assembled
    from mbody.model.loader import Document
    from mbody.model.model import Model

    if not isinstance(document, Document):  # plain data: no lines to point at
        document = Document(document, source)
    return assembled(Model.from_spec(validate_imported(document)))


def _summary(model) -> str:
    from mbody.model.model import count

    kind = "planar" if model.dimension == 2 else "spatial"
    return (f"{kind}, {count(model.n, 'body', 'bodies')}, {count(len(model.joints), 'joint')}, "
            f"{count(len(model.loads), 'load')}")
