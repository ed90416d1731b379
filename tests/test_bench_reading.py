"""tools/bench_reading.py, kept honest without timing anything: each case makes the input
it says it makes (one line, many attributes, a '>' in a value...), of about the size
asked, that mbody reads to the end it should (a model, or a located refusal); and the
table has a row per size for every case."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

import mbody
from mbody.errors import ModelError

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_reading",
                                                  ROOT / "tools" / "bench_reading.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["bench_reading"] = module
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("index", range(7))
def test_each_case_makes_what_it_says(bench, index, tmp_path):
    name, make = bench.CASES[index]
    item = make(20_000)
    assert 15_000 < len(item.text.encode()) < 25_000, name
    path = tmp_path / f"input{item.suffix}"
    path.write_text(item.text)
    if "one long line" in name:
        assert "\n" not in item.text
    if "'>'" in name:
        assert " -> y" in item.text
    if "many attributes" in name and "MJCF" in name:
        with pytest.raises(ModelError, match="unknown attribute of <mujoco> 'a0'"):
            mbody.load(path)
    else:
        model = mbody.load(path)
        assert model.body_names
        if "screws" in name:  # each body's slide and hinge, tied: a helical joint
            assert {j.type for j in model.joints} == {"helical"}


def test_the_table(bench, capsys):
    assert len(bench.CASES) == 7
    assert bench.main(["--sizes", "0.005,0.01", "--repeat", "1", "--only", "URDF"]) == 0
    out = capsys.readouterr().out
    # per case: its name, the header, a row per size; then the note on growth
    assert out.count("size (MB)") == 2 and len(out.splitlines()) == 2 * (2 + 2) + 1
