"""Print a pip constraints file pinning every dependency of pyproject.toml to its floor.

    python tools/lowest_constraints.py [pyproject.toml] > lowest.txt
    pip install -c lowest.txt -e ".[symbolic]"

pip has no "lowest versions" resolution; pinning each ``name>=X`` of
``[project.dependencies]`` (and of the extras in `EXTRAS`) to ``name==X`` gives the
oldest install pyproject allows, which .ci/run tests (so that a floor cannot silently
stop being true). A dependency without a ``>=`` floor is an error: every one must say
which oldest version works.
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
_FLOOR = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)\s*(\[[^\]]*\])?\s*>=\s*([0-9][^,;\s]*)")


EXTRAS = ("symbolic",)
"""Optional features tested at their floors too (`assemble --symbolic`)."""


def floors(pyproject: Path = ROOT / "pyproject.toml") -> dict[str, str]:
    """{name: oldest version} of the runtime dependencies and of the `EXTRAS`."""
    project = tomllib.loads(pyproject.read_text())["project"]
    deps = list(project["dependencies"])
    for extra in EXTRAS:
        deps += project.get("optional-dependencies", {}).get(extra, [])
    out = {}
    for dep in deps:
        m = _FLOOR.match(dep)
        if not m:
            raise SystemExit(f"{pyproject}: dependency {dep!r} has no '>=' floor")
        out[m.group(1)] = m.group(3)
    return out


def main(argv: list[str]) -> int:
    path = Path(argv[1]) if len(argv) > 1 else ROOT / "pyproject.toml"
    for name, version in floors(path).items():
        print(f"{name}=={version}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
