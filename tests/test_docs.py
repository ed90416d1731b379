"""The documentation builds without warnings, and every example in it runs.

Convention (docs/*.md): shell examples are ```console blocks whose command lines start
with `$ ` (run with bash from the repository root; they must exit 0, or N when the line
ends with `  # exits N`; other lines are sample output and are not compared). Python
examples are ```python blocks, run in order in one namespace per page, from the
repository root. Within a page, console lines and Python blocks run in document order,
so a Python block may read a file a command above it wrote.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[\w-]*)[^\n]*\n(?P<body>.*?)^(?P=indent)```",
                   re.M | re.S)
EXITS = re.compile(r"\s#\s*exits\s+(\d+)\s*$")


def _nav_pages() -> list[str]:
    def walk(node):
        if isinstance(node, str):
            yield node
        elif isinstance(node, list):
            for x in node:
                yield from walk(x)
        elif isinstance(node, dict):
            for v in node.values():
                yield from walk(v)

    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))
    return [p for p in walk(config.get("nav", [])) if p.endswith(".md")]


def _pages() -> list[str]:
    nav = [p for p in _nav_pages() if (DOCS / p).exists()]
    rest = sorted(p.name for p in DOCS.glob("*.md") if p.name not in nav)
    return nav + rest


def examples(text: str) -> list[tuple[str, str, int]]:
    """(kind, code, line) in document order: kind 'console' (one command) or 'python'."""
    out = []
    for m in FENCE.finditer(text):
        line = text.count("\n", 0, m.start("body")) + 1
        indent = len(m.group("indent"))
        body = "\n".join(s[indent:] for s in m.group("body").splitlines())
        if m.group("lang") == "console":
            for k, s in enumerate(body.splitlines()):
                if s.startswith("$ "):
                    out.append(("console", s[2:], line + k))
        elif m.group("lang") == "python":
            out.append(("python", body, line))
    return out


def test_examples_parser_finds_commands_blocks_and_exit_codes():
    text = ("x\n```console\n$ echo hi\nhi\n$ false  # exits 1\n```\n"
            "- item\n\n  ```python\n  a = 1\n  ```\n```sh\n$ not run\n```\n")
    assert examples(text) == [("console", "echo hi", 3), ("console", "false  # exits 1", 5),
                              ("python", "a = 1", 10)]
    assert int(EXITS.search("false  # exits 1").group(1)) == 1


def test_mkdocs_build_strict_has_no_warnings(tmp_path):
    pytest.importorskip("mkdocs")
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                        str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
                       timeout=300)
    log = r.stdout + r.stderr
    assert r.returncode == 0, log
    assert "WARNING" not in log, log
    assert (tmp_path / "site" / "index.html").exists()
    missing = sorted(set(p.name for p in DOCS.glob("*.md")) - set(_nav_pages()))
    assert missing == [], f"pages not in mkdocs.yml nav: {missing}"


@pytest.fixture
def docs_env(monkeypatch):
    bindir = str(Path(sys.executable).parent)
    monkeypatch.setenv("PATH", bindir + os.pathsep + os.environ.get("PATH", ""))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.chdir(ROOT)
    (ROOT / "out").mkdir(exist_ok=True)
    return dict(os.environ)


@pytest.mark.parametrize("page", _pages())
def test_every_example_in_the_page_runs(page, docs_env):
    text = (DOCS / page).read_text(encoding="utf-8")
    namespace: dict = {"__name__": f"docs_{Path(page).stem}"}
    ran = 0
    for kind, code, line in examples(text):
        where = f"docs/{page}:{line}"
        if kind == "console":
            m = EXITS.search(code)
            want = int(m.group(1)) if m else 0
            r = subprocess.run(["bash", "-c", code], cwd=ROOT, env=docs_env,
                               capture_output=True, text=True, timeout=300)
            assert r.returncode == want, (
                f"{where}: `{code}` exited {r.returncode}, expected {want}\n"
                f"stdout:\n{r.stdout[-2000:]}\nstderr:\n{r.stderr[-2000:]}")
            if want == 0:
                assert "Traceback" not in r.stderr, f"{where}: {r.stderr[-2000:]}"
        else:
            try:
                exec(compile(code, where, "exec"), namespace)  # noqa: S102 - the docs' own code
            except Exception as exc:
                raise AssertionError(f"{where}: the Python example raised "
                                     f"{type(exc).__name__}: {exc}") from exc
        ran += 1
    if "matplotlib.pyplot" in sys.modules:  # figures the examples drew
        sys.modules["matplotlib.pyplot"].close("all")
    if ran == 0:
        pytest.skip(f"docs/{page} has no examples")
