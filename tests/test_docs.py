"""The documentation builds without warnings, every example in it runs, and every output
it shows is the real output.

Convention (docs/*.md): shell examples are ```console blocks. A line starting with `$ ` is
a command (run with bash from the repository root; it must exit 0, or N when the line ends
with `  # exits N`; a line ending in `\\` goes on on the next); the lines after it, up to
the next command or the block's end, are exactly what it prints (stdout and stderr
together, as a terminal shows them). Only what cannot be the same on every run is left
open, and visibly so:

- `…` within a line stands for any text on that line (a time, a size, a path);
- a line that is only `…` stands for any number of lines (output cut short);
- a wall-clock duration in the output (`0.42 s`, `12 ms` after "in", "took" or "wall")
  compares as `…`, and trailing spaces and blank lines at the end are ignored.

Python examples are ```python blocks, run in order in one namespace per page, from the
repository root. Within a page, console lines and Python blocks run in document order, so
a Python block may read a file a command above it wrote. A `$ ` line outside a console
block is refused: it would escape the test.
"""

from __future__ import annotations

import difflib
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


ELLIPSIS = "…"
DURATION = re.compile(r"\b(in|took|wall) \d+(?:\.\d+)?(?:e[-+]?\d+)? ?(?:s|ms)\b")


def examples(text: str) -> list[tuple[str, str, int, str]]:
    """(kind, code, line, output) in document order: kind 'console' (one command, with the
    output shown under it) or 'python' (output '')."""
    out: list[tuple[str, str, int, str]] = []
    for m in FENCE.finditer(text):
        line = text.count("\n", 0, m.start("body")) + 1
        indent = len(m.group("indent"))
        body = "\n".join(s[indent:] for s in m.group("body").splitlines())
        if m.group("lang") == "console":
            shown: list[str] | None = None
            going_on = False  # the command's last line ended with a backslash
            for k, s in enumerate(body.splitlines()):
                if going_on:
                    kind, code, at, said = out[-1]
                    out[-1] = (kind, code + "\n" + s, at, said)
                    going_on = s.endswith("\\")
                elif s.startswith("$ "):
                    shown = []
                    out.append(("console", s[2:], line + k, ""))
                    going_on = s.endswith("\\")
                elif shown is not None:
                    kind, code, at, said = out[-1]
                    out[-1] = (kind, code, at, said + s + "\n")
        elif m.group("lang") == "python":
            out.append(("python", body, line, ""))
    return out


def _lines(text: str) -> list[str]:
    lines = [DURATION.sub(rf"\1 {ELLIPSIS}", s.rstrip()) for s in text.splitlines()]
    while lines and not lines[-1]:
        lines.pop()
    return lines


def _line_pattern(shown: str) -> re.Pattern[str]:
    return re.compile(".*?".join(re.escape(p) for p in shown.split(ELLIPSIS)) + r"\Z", re.S)


def output_matches(shown: str, real: str) -> bool:
    """Whether `real` output is what the docs show (`shown`), under the module's rules."""
    want, got = _lines(shown), _lines(real)

    def match(i: int, j: int) -> bool:
        if i == len(want):
            return j == len(got)
        if want[i] == ELLIPSIS:  # any number of lines
            return any(match(i + 1, k) for k in range(j, len(got) + 1))
        return j < len(got) and bool(_line_pattern(want[i]).match(got[j])) and match(i + 1, j + 1)

    return match(0, 0)


def test_examples_parser_finds_commands_blocks_outputs_and_exit_codes():
    text = ("x\n```console\n$ echo hi\nhi\n$ false  # exits 1\n```\n"
            "- item\n\n  ```python\n  a = 1\n  ```\n```sh\n$ not run\n```\n")
    assert examples(text) == [("console", "echo hi", 3, "hi\n"),
                              ("console", "false  # exits 1", 5, ""),
                              ("python", "a = 1", 10, "")]
    assert int(EXITS.search("false  # exits 1").group(1)) == 1
    assert examples("```console\n$ echo a \\\n  b\na b\n```\n") == [
        ("console", "echo a \\\n  b", 2, "a b\n")]


def test_output_comparison_is_exact_but_for_marked_gaps():
    assert output_matches("a\nb\n", "a  \nb\n\n")
    assert not output_matches("a\nb\n", "a\nb\nc\n")  # a line more
    assert not output_matches("a\nb\n", "a\n")
    assert not output_matches("2 problems in the model:\n", "1 problem in the model:\n")
    assert output_matches("wrote out/x.html (… MB)\n", "wrote out/x.html (0.9 MB)\n")
    assert not output_matches("wrote out/x.html (… MB)\n", "wrote out/y.html (0.9 MB)\n")
    assert output_matches("first\n…\nlast\n", "first\n1\n2\nlast\n")
    assert output_matches("first\n…\nlast\n", "first\nlast\n")
    assert not output_matches("first\n…\nlast\n", "first\n1\n")
    assert output_matches("done in 0.31 s\n", "done in 1.5 s\n")  # a wall-clock time
    assert not output_matches("t_end 0.31 s\n", "t_end 1.5 s\n")  # a simulated one
    assert output_matches("", "") and not output_matches("", "something\n")


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


def test_no_shell_example_escapes_the_console_blocks():
    """A `$ ` command outside a ```console block would be neither run nor compared."""
    for page in _pages():
        text = (DOCS / page).read_text(encoding="utf-8")
        for m in FENCE.finditer(text):
            assert m.group("lang") == "console" or not re.search(
                r"^\s*\$ ", m.group("body"), re.M), (page, m.group("body")[:80])
        assert not re.search(r"^\s*\$ mbody", FENCE.sub("", text), re.M), page


@pytest.fixture
def docs_env(monkeypatch):
    bindir = str(Path(sys.executable).parent)
    monkeypatch.setenv("PATH", bindir + os.pathsep + os.environ.get("PATH", ""))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("PYTHONUNBUFFERED", "1")
    monkeypatch.setenv("COLUMNS", "80")  # argparse wraps help at the terminal's width
    monkeypatch.chdir(ROOT)
    (ROOT / "out").mkdir(exist_ok=True)
    return dict(os.environ)


@pytest.mark.parametrize("page", _pages())
def test_every_example_in_the_page_runs(page, docs_env):
    text = (DOCS / page).read_text(encoding="utf-8")
    namespace: dict = {"__name__": f"docs_{Path(page).stem}"}
    ran = 0
    for kind, code, line, shown in examples(text):
        where = f"docs/{page}:{line}"
        if kind == "console":
            m = EXITS.search(code)
            want = int(m.group(1)) if m else 0
            # one pipe for both streams, unbuffered: the order a terminal shows
            r = subprocess.run(["bash", "-c", code], cwd=ROOT, env=docs_env,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               timeout=300)
            assert r.returncode == want, (
                f"{where}: `{code}` exited {r.returncode}, expected {want}\n"
                f"output:\n{r.stdout[-3000:]}")
            assert "Traceback" not in r.stdout, f"{where}: {r.stdout[-3000:]}"
            assert output_matches(shown, r.stdout), (
                f"{where}: `{code}` printed what the page does not show\n"
                + "".join(difflib.unified_diff(_lines(shown), _lines(r.stdout), "docs",
                                               "real", lineterm="\n", n=2)))
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


def test_help_texts_name_what_the_commands_do():
    """`plot --help` names the reaction panels and their cap, as the figure draws them."""
    from mbody.present.plot import MAX_REACTIONS

    r = subprocess.run([sys.executable, "-m", "mbody.cli", "plot", "--help"],
                       capture_output=True, text=True, timeout=60, cwd=ROOT)
    text = " ".join(r.stdout.split())
    assert "joint reactions" in text and "reaction force components (N)" in text
    assert f"(the first {MAX_REACTIONS} of each kind;" in text
    assert "a kind the joints do not have, such as the moments of a planar revolute joint, " \
           "gets no panel)" in text
