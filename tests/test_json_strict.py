"""Every JSON output parses under a strict reader: ``mbody solve|jacobian|verify --json`` on
every shipped model and answers file, and the JSON export (``mbody export -o x.json``).

Strict means what JavaScript's ``JSON.parse`` accepts: no ``NaN``, ``Infinity`` or
``-Infinity`` (Python's ``json`` writes them by default and reads them back). Python's
reader is made strict by refusing those constants; where Node.js is installed, the same
texts are also given to ``JSON.parse`` itself.
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from mbody.cli.app import main
from mbody.util import jsontext

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
SHIPPED = sorted([*MODELS.glob("*.yaml"), *(MODELS / "robots").glob("*.xml"),
                  *(MODELS / "robots").glob("*.urdf")])
ANSWERS = sorted((MODELS / "answers").glob("*.yaml"))


def strict_loads(text: str):
    """json.loads that refuses NaN, Infinity and -Infinity, as JSON.parse does."""
    def refuse(name: str):
        raise ValueError(f"{name} is not JSON")
    return json.loads(text, parse_constant=refuse)


def run(capsys, *argv: str | Path) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_plain_writes_non_finite_numbers_as_null():
    data = {"a": math.inf, "b": [1.5, -math.inf, math.nan], "c": np.array([1.0, np.nan]),
            "d": np.float64(np.inf), "e": np.int64(3), "f": (np.float32(2.5), "x"),
            "g": np.array([[1, 2]]), 4: None, "h": True}
    text = jsontext.dumps(data)
    assert "Infinity" not in text and "NaN" not in text
    assert strict_loads(text) == {"a": None, "b": [1.5, None, None], "c": [1.0, None],
                                  "d": None, "e": 3, "f": [2.5, "x"], "g": [[1, 2]],
                                  "4": None, "h": True}
    with pytest.raises(TypeError, match="set is not a JSON value"):
        jsontext.dumps({"s": {1}})


def test_the_strict_reader_refuses_what_python_writes_by_default():
    """The check below can fail: Python's own json writes Infinity, and it is refused."""
    with pytest.raises(ValueError, match="Infinity is not JSON"):
        strict_loads(json.dumps({"condition": math.inf}))


def test_a_singular_solve_writes_its_condition_as_null(capsys):
    """fourbar_spatial has redundant constraints: the condition estimate is infinite, which
    was printed as ``Infinity``; it is null, and the warning says why."""
    code, out, err = run(capsys, "solve", MODELS / "fourbar_spatial.yaml", "--json")
    assert code == 0, err
    doc = strict_loads(out)
    assert doc["condition"] is None
    assert any("redundant constraint" in w for w in doc["warnings"])
    assert doc["backward_error"] < 1e-12


def _outputs(capsys, tmp_path) -> dict[str, str]:
    texts: dict[str, str] = {}
    for model in SHIPPED:
        for command in ("solve", "jacobian"):
            code, out, err = run(capsys, command, model, "--json")
            assert code == 0, (command, model.name, err)
            texts[f"{command} {model.relative_to(MODELS)}"] = out
        target = tmp_path / f"{model.stem}.json"
        code, out, err = run(capsys, "export", model, "-o", target)
        assert code == 0, (model.name, err)
        texts[f"export {model.relative_to(MODELS)}"] = target.read_text(encoding="utf-8")
    for answers in ANSWERS:
        code, out, err = run(capsys, "verify", MODELS / answers.name, answers, "--json")
        assert code in (0, 1), (answers.name, err)
        texts[f"verify {answers.name}"] = out
    return texts


def test_every_json_output_of_every_shipped_model_is_strict_json(capsys, tmp_path):
    texts = _outputs(capsys, tmp_path)
    assert len(texts) == 3 * len(SHIPPED) + len(ANSWERS)
    for what, text in texts.items():
        try:
            strict_loads(text)
        except ValueError as exc:
            pytest.fail(f"{what}: {exc}")
    node = shutil.which("node")
    if node is None:
        return
    # the same texts through JavaScript's JSON.parse, in one process
    (tmp_path / "texts.json").write_text(json.dumps(texts), encoding="utf-8")
    script = ("const t = JSON.parse(require('fs').readFileSync(process.argv[1], 'utf8'));"
              "let bad = 0; for (const [k, v] of Object.entries(t)) {"
              "try { JSON.parse(v); } catch (e) { bad++; console.log(k + ': ' + e.message); } }"
              "console.log('parsed ' + Object.keys(t).length + ', refused ' + bad);")
    p = subprocess.run([node, "-e", script, str(tmp_path / "texts.json")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip().endswith(f"parsed {len(texts)}, refused 0"), p.stdout


# -- the nesting bound of text read back (review R3, S2) ----------------------------------


def depth(value) -> int:
    """How deep a parsed value nests (objects read as lists of their values, so that a
    key given twice still counts)."""
    if isinstance(value, list):
        return 1 + max(map(depth, value), default=0)
    return 0


def parsed_depth(text: str) -> int:
    return depth(json.loads(text, object_pairs_hook=lambda pairs: [v for _, v in pairs]))


@pytest.mark.parametrize("text", [
    "1", '"[{"', "[]", "[[]]", '{"a": {"b": [1, {}]}}',
    r'["a\\", ["]"], {"k\"[": [1]}]',  # an escaped backslash: the quote ends it
    r'["\\\"[", "\\\\", [["\\"]]]',  # three, then four backslashes
    r'{"\\": "]]]", "x": [["\"{\"", {"\\\\\"": []}]]}',
    '["\\u005c", ["\\u0022["]]',  # escapes by number: other characters here
    '[' * 70 + ']' * 70, '{"a":' * 30 + "1" + "}" * 30,
])
def test_nesting_counts_the_brackets_outside_strings_as_the_parser_reads_them(text):
    assert jsontext.nesting(text) == parsed_depth(text)


def test_many_escaped_quotes_are_scanned_once():
    """Review R3, S2: a string of escaped quotes that never ends made the string pattern
    run from each quote to the end of the text (64 kB took 21 s; these 400 kB some 14
    minutes). Not timed: read once, the answers come in milliseconds."""
    text = '"' + '\\"' * 200_000
    assert jsontext.nesting(text) == 0
    with pytest.raises(json.JSONDecodeError) as exc:  # the string that never ends
        jsontext.loads(text)
    assert exc.value.pos == 0
    closed = text + '"' + "[" * 100 + "]" * 100  # the last quote ends it: 100 deep after
    assert jsontext.nesting(closed) == 100
    with pytest.raises(ValueError, match="JSON nested 100 deep; at most 64 levels"):
        jsontext.loads(closed)
