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
  compares as `…`, and trailing spaces and blank lines at the end are ignored;
- a number printed in full (13 significant digits or more: a float's repr, as JSON, CSV
  and MJCF output print them) compares as a number, not as text: its last digits are the
  rounding of the machine's BLAS kernel and maths library (OpenBLAS picks its kernels by
  CPU: the slider-crank's `crank.y` is 129.67690442594736 with AVX2 kernels,
  129.6769044259477 with AVX-512 ones). See `rounding_tolerance` for the bound.

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


NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
ANY_NUMBER = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
FULL_DIGITS = 13
"""A number shown with at least this many significant digits is a float printed in full
(repr gives 15 to 17; a display rounded for reading gives 6 or fewer)."""
CONDITION = re.compile(r"(?:\"condition\": |condition estimate )(\d[\d.]*(?:e[-+]?\d+)?)")
UNIT_ROUNDOFF = 2.0 ** -53
MAX_UNKNOWNS = 64
"""More unknowns than any model a page computes with has (the error bound's n)."""


def _printed_in_full(token: str) -> bool:
    mantissa = re.split(r"[eE]", token.lstrip("+-"))[0].replace(".", "").lstrip("0")
    return len(mantissa) >= FULL_DIGITS


def rounding_tolerance(shown: str, real: str) -> float:
    """How far a number printed in full may be from the page's, in absolute terms.

    Two backward-stable computations of the same x (the page's machine and this one,
    differing in the BLAS kernel's order of operations) each lie within κ·n·u·‖x‖∞ of the
    exact answer (u = 2⁻⁵³ the unit roundoff, n the number of unknowns, κ the problem's
    condition number), so they differ by at most 2·κ·n·u·‖x‖∞. Here n = `MAX_UNKNOWNS`,
    κ the condition estimate the command itself prints (`"condition": 3485`, `condition
    estimate 5.16e+00`; 1 for outputs that solve nothing: an evaluation's error is a few
    roundings of its largest term), and ‖x‖∞ the largest number the page shows for that
    output: a component's rounding is relative to the vector it was computed with (the
    slider-crank's piston.y is 1.7e-13 on one machine and -5.5e-14 on another, beside
    accelerations of 3.2e4)."""
    kappa = max([float(k) for k in CONDITION.findall(real)] + [1.0])
    scale = max([abs(float(m)) for m in NUMBER.findall(shown)] + [0.0])
    return 2.0 * kappa * MAX_UNKNOWNS * UNIT_ROUNDOFF * scale


def _line_pattern(shown: str) -> tuple[re.Pattern[str], list[float]]:
    """The line as a pattern (`…` any text, each number printed in full any number) and
    the numbers printed in full, in order."""
    parts: list[str] = []
    full: list[float] = []
    for k, piece in enumerate(shown.split(ELLIPSIS)):
        if k:
            parts.append(".*?")
        at = 0
        for m in NUMBER.finditer(piece):
            if _printed_in_full(m.group()):
                parts.append(re.escape(piece[at:m.start()]) + ANY_NUMBER)
                full.append(float(m.group()))
                at = m.end()
        parts.append(re.escape(piece[at:]))
    return re.compile("".join(parts) + r"\Z", re.S), full


def _line_matches(shown: str, real: str, tol: float) -> bool:
    pattern, full = _line_pattern(shown)
    m = pattern.match(real)
    return m is not None and all(abs(float(got) - want) <= tol
                                 for got, want in zip(m.groups(), full, strict=True))


def output_matches(shown: str, real: str) -> bool:
    """Whether `real` output is what the docs show (`shown`), under the module's rules."""
    want, got = _lines(shown), _lines(real)
    tol = rounding_tolerance(shown, real)

    def match(i: int, j: int) -> bool:
        if i == len(want):
            return j == len(got)
        if want[i] == ELLIPSIS:  # any number of lines
            return any(match(i + 1, k) for k in range(j, len(got) + 1))
        return j < len(got) and _line_matches(want[i], got[j], tol) and match(i + 1, j + 1)

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


def test_numbers_printed_in_full_compare_within_their_rounding():
    # the slider-crank's JSON on AVX2 (the page) and AVX-512 (another machine) kernels
    page = ('"crank.y": 129.67690442594736,\n"theta": 32009.64448135288,\n'
            '"y": 1.723066134218243e-13\n')
    other = ('"crank.y": 129.6769044259477,\n"theta": 32009.644481352996,\n'
             '"y": -5.5067062021407764e-14\n')
    assert output_matches(page, other + '"condition": 3485.0030456706745\n') is False  # a line more
    assert output_matches(page + "…\n", other + '"condition": 3485.0030456706745\n')
    assert output_matches(page, other)  # κ = 1: 2·64·u·32009 = 4.5e-10 > 1.2e-10 apart
    # a change of the physics (the 11th digit) is not rounding
    assert not output_matches('"crank.y": 129.67690442594736\n', '"crank.y": 129.67690442694736\n')
    # rounding is relative to the largest number of the output, not to each number
    assert rounding_tolerance("x 129.67690442594736 y 1.0\n", "") == pytest.approx(
        2 * 64 * 2.0 ** -53 * 129.67690442594736)
    assert rounding_tolerance("a 2.0\n", '"condition": 1e3') == pytest.approx(
        2 * 64 * 2.0 ** -53 * 2e3)
    # the text around the numbers still compares exactly; short numbers as text
    assert not output_matches('"crank.y": 129.67690442594736\n', '"crank.x": 129.67690442594736\n')
    assert not output_matches("a_x = -3.1839 m/s^2\n", "a_x = -3.18391 m/s^2\n")
    assert output_matches('pos="0.0176776695296637 0.0176776695296637 0"\n',
                          'pos="0.017677669529663688 0.0176776695296637 0"\n')
    assert not output_matches('pos="0.0176776695296637 0"\n', 'pos="0.0176776695296637 1"\n')


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
