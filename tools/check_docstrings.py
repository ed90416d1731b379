"""Check the public API's docstrings with numpydoc's validator.

    python tools/check_docstrings.py

The public API is what docs/reference.md documents (its ``::: path`` lines, rendered by
mkdocstrings), with the public methods and properties of its classes. Each must have a
docstring (numpydoc GL08) that documents every parameter (PR01) and no parameter the
signature lacks (PR02), and a Returns section where a function returns something (RT01;
properties are exempt: their summary says what they are). Exit code 1 lists what fails.
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
from collections.abc import Iterator
from pathlib import Path

from numpydoc.validate import validate

ROOT = Path(__file__).resolve().parent.parent
REFERENCE = ROOT / "docs" / "reference.md"
CHECKED = ("GL08", "PR01", "PR02", "RT01")


def public_paths(reference: Path = REFERENCE) -> Iterator[tuple[str, bool]]:
    """(dotted path, is a property) of every documented object and its public members."""
    for path in re.findall(r"^::: (\S+)", reference.read_text("utf-8"), re.M):
        module, _, name = path.rpartition(".")
        obj = getattr(importlib.import_module(module), name)
        yield path, False
        if inspect.isclass(obj):
            for key, value in vars(obj).items():
                if key.startswith("_"):
                    continue
                if isinstance(value, property) or type(value).__name__ == "cached_property":
                    yield f"{path}.{key}", True
                elif callable(value) or isinstance(value, classmethod | staticmethod):
                    yield f"{path}.{key}", False


def problems() -> list[str]:
    out = []
    for path, is_property in public_paths():
        codes = [(code, text) for code, text in validate(path)["errors"] if code in CHECKED
                 and not (is_property and code == "RT01")]
        out += [f"{path}: {code} {text}" for code, text in codes]
    return out


def main() -> int:
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    found = problems()
    for line in found:
        print(line)
    print(f"{len(found)} docstring problem(s) in the public API (docs/reference.md)")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
