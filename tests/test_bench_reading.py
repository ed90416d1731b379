"""tools/bench_reading.py, kept honest without timing anything: each case makes the input
it says it makes (one line, many attributes, a '>' in a value...), of about the size
asked, that mbody reads to the end it should (a model, or a located refusal); the table
has a row per size and a verdict for every case; each of the refusals is refused; the
growth exponent is the slope it should be."""

from __future__ import annotations

import importlib.util
import os
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
    # per case: its name, the header, a row per size, the fit's verdict; then the note on
    # growth (no refusal is named like URDF)
    assert out.count("size (MB)") == 2 and len(out.splitlines()) == 2 * (2 + 2 + 1) + 1
    assert out.count("  fit: t ~ n^") == 2 and "Refusals" not in out


@pytest.mark.parametrize("index", range(5))
def test_each_refusal_is_refused_with_a_reference(bench, index, monkeypatch, tmp_path):
    """Each hostile file is refused (`refused` raises AssertionError if it is read), and
    set against a reference that took time."""
    from mbody.model import loader

    monkeypatch.setattr(loader, "FIFO_WAIT", 0.05)
    refusal = bench.REFUSALS[index]
    if "pipe" in refusal.name and not hasattr(os, "mkfifo"):
        pytest.skip("no named pipes")
    seconds, reference, of = refusal.run(tmp_path, 1)
    assert seconds > 0 and reference > 0 and of and refusal.bound >= 1


def test_refused_says_when_a_file_was_read(bench):
    with pytest.raises(AssertionError, match="was read, not refused"):
        bench.refused(ROOT / "models" / "pendulum.yaml")


def test_growth_and_its_verdict():
    sys.path.insert(0, str(ROOT / "tools"))
    from timing import growth, linear_verdict

    n = [1.0, 2.0, 4.0, 8.0]
    assert growth(n, [3 * x for x in n]) == pytest.approx(1.0)
    assert growth(n, [x * x for x in n]) == pytest.approx(2.0)
    assert growth(n, [5.0] * 4) == pytest.approx(0.0)
    assert linear_verdict(n, [x ** 1.2 for x in n]).endswith(
        "PASS (linear: exponent at most 1.3)")
    assert "FAIL" in linear_verdict(n, [x ** 1.5 for x in n])
    assert linear_verdict(n[:2], [1.0, 4.0], stopped=True).startswith("fit: t ~ n^2.00")
    assert linear_verdict(n[:2], [1.0, 2.0], stopped=True).endswith(
        "PASS (linear: exponent at most 1.3) (stopped at the time limit)")
    assert linear_verdict(n[:1], [40.0], stopped=True).endswith("time limit: FAIL")
    assert linear_verdict([1.0], [1.0]) == "fit: too few sizes for a fit"
