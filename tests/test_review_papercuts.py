"""Messages and refusals a hostile review found missing (review R1's papercuts P3, P4,
P5, P9-P13 and P15): every one is exit 2 (or a located warning) naming the file, the
key or option, and what was expected, before any output is written.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from mbody.cli import main

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
PENDULUM = MODELS / "pendulum.yaml"


def run(capsys, *args) -> tuple[int, str, str]:
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


def line_of(path: Path, text: str) -> int:
    """The 1-based line of the first line of `path` holding `text`."""
    return next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if text in ln)


# == P3: a body's colour is checked when the model is read ======================================

@pytest.mark.parametrize(("colour", "hint"), [
    ("#zzzzzz", "'#rrggbb' with six hex digits"),
    ("oragne", "did you mean 'orange'?"),
])
def test_a_bad_colour_is_refused_by_check_at_its_line(tmp_path, capsys, colour, hint):
    text = (MODELS / "heavy_top.yaml").read_text()
    assert '    color: "#d35400"' in text
    bad = tmp_path / "badcolor.yaml"
    bad.write_text(text.replace('    color: "#d35400"', f'    color: "{colour}"'))
    code, _, err = run(capsys, "check", bad)
    line = line_of(bad, colour)
    assert code == 2
    assert f"{bad}:{line}:12: bodies[0].color: '{colour}' is not a colour" in err
    assert hint in err


def test_colour_names_and_forms_that_draw_are_accepted(tmp_path, capsys):
    text = (MODELS / "heavy_top.yaml").read_text()
    for colour in ("SteelBlue", "#D35400", "tab:blue"):
        good = tmp_path / "color.yaml"
        good.write_text(text.replace('    color: "#d35400"', f'    color: "{colour}"'))
        code, out, err = run(capsys, "check", good)
        assert (code, err) == (0, ""), colour
