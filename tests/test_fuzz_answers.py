"""The answers-file fuzzer (tools/fuzz_answers.py) in the suite: 2500 seeded cases, shipped
and generated answers files mutated in their equations and their YAML, through
``mbody verify`` and ``--json`` in this process. Every command ends with verdicts (exit 0
or 1, strict JSON) or one clean, located message (exit 2): no crash, no hang. The long
run is ``python tools/fuzz_answers.py`` (10 000 cases, several processes)."""

from __future__ import annotations

import importlib.util
import sys
from collections import Counter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CASES = 2500
SEED = 5


@pytest.fixture(scope="module")
def fa():
    spec = importlib.util.spec_from_file_location("mbody_fuzz_answers",
                                                  ROOT / "tools" / "fuzz_answers.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["mbody_fuzz_answers"] = module
    spec.loader.exec_module(module)
    return module


def test_mutated_answers_give_verdicts_or_clean_errors_only(fa, tmp_path):
    bases = fa._bases()
    verdicts: Counter = Counter()
    commands: Counter = Counter()
    changes: Counter = Counter()
    for i in range(CASES):
        case = fa.make_case(SEED, i, bases)
        outcomes = fa.run_case(case, tmp_path, hang=30.0)
        v = fa.fuzz.verdict(outcomes)
        verdicts[v] += 1
        commands.update(o.command for o in outcomes)
        changes.update(d.split(" ")[0] for d in case.did[1:])
        if v in (fa.CRASH, fa.HANG):
            bad = [o for o in outcomes if o.kind == v]
            pytest.fail(f"case {i} ({case.base}: {'; '.join(case.did)}): {v} in "
                        f"{bad[0].command}\n{bad[0].detail}\nanswers:\n{case.content!s:.3000}"
                        f"\n(python tools/fuzz_answers.py --seed {SEED} --only {i})")
    # neither all refused nor all harmless, and --json run on every judged file
    assert verdicts[fa.JUDGED] > CASES // 5 and verdicts[fa.CLEAN] > CASES // 3
    assert commands["verify --json"] >= verdicts[fa.JUDGED]
    # every kind of change was made
    for kind in ("number", "name", "unicode", "nesting", "long", "both", "function",
                 "nonlinear", "body", "eq", "duplicated", "odd", "top", "tab", "cut"):
        assert changes[kind] > 0, kind


def test_the_counts_report(fa):
    result = fa.run(10, seed=3, jobs=2, heavy_every=3, hang=60.0, log=lambda s: None)
    text = fa.report(result)
    assert text.startswith("mbody fuzz_answers: 10 answers files (seed 3), ")
    for label in ("judged", "clean errors", "crashes", "hangs"):
        assert f"  {label} " in text
    assert sum(result["verdicts"].values()) == 10
    assert result["verdicts"][fa.CRASH] == result["verdicts"][fa.HANG] == 0


def test_what_counts_as_a_crash(fa):
    """The classification can fail: each defect an answers file could bring out."""
    a = "a.yaml"
    summary = "\n1 of 2 equations correct; 1 of 3 rows covered.\n"
    judged = fa.classify(["verify", "m", a], 1, "[1] ..." + summary, "", "", a)
    assert judged.kind == fa.JUDGED
    # exit 0 with a wrong equation, and exit 70
    assert fa.classify(["verify", "m", a], 0, summary, "", "", a).kind == fa.CRASH
    assert fa.classify(["verify", "m", a], 70, "", "mbody: internal error: x", "",
                       a).kind == fa.CRASH
    # --json: NaN or Infinity, or a summary that disagrees with the exit code
    doc = '{"equations": [{}], "summary": {"equations": 1, "correct": 1}, "x": %s}'
    assert fa.classify(["verify", "m", a, "--json"], 0, doc % "1.5", "", "",
                       a).kind == fa.JUDGED
    assert fa.classify(["verify", "m", a, "--json"], 0, doc % "Infinity", "", "",
                       a).kind == fa.CRASH
    assert fa.classify(["verify", "m", a, "--json"], 1, doc % "1", "", "", a).kind == fa.CRASH
    # a problem in the answers without its line and column
    located = "mbody: error: 2 problems in the answers:\na.yaml:2:5: e: x\na.yaml:3:1: f: y\n"
    assert fa.classify(["verify", "m", a], 2, "", located, "", a).kind == fa.CLEAN
    unlocated = "mbody: error: a.yaml: equations[0].eq: x\n"
    assert fa.classify(["verify", "m", a], 2, "", unlocated, "", a).kind == fa.CRASH
