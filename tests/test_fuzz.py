"""The structure-aware fuzzer (tools/fuzz.py) in the suite: a few thousand mutations of the
shipped models through check, assemble and solve (and, for some, simulate, export,
jacobian and fbd), in this process, seeded, in four chunks that run in parallel under
pytest-xdist. Every command ends accepted or with one clean, located message: no crash,
no hang. The long run is ``python tools/fuzz.py`` (10 000 mutations, several processes).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
MUTATIONS = 3000
CHUNKS = 4
SEED = 11


@pytest.fixture(scope="module")
def fuzz():
    spec = importlib.util.spec_from_file_location("mbody_fuzz", ROOT / "tools" / "fuzz.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["mbody_fuzz"] = module
    spec.loader.exec_module(module)
    module.warm_up()
    return module


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_mutated_models_give_clean_errors_only(fuzz, chunk, tmp_path):
    bases = fuzz._bases()
    size = MUTATIONS // CHUNKS
    verdicts = []
    for i in range(chunk * size, (chunk + 1) * size):
        case = fuzz.make_case(SEED, i, bases, heavy_every=12)
        outcomes = fuzz.run_case(case, tmp_path, hang=30.0)
        v = fuzz.verdict(outcomes)
        verdicts.append(v)
        if v in (fuzz.CRASH, fuzz.HANG):
            bad = [o for o in outcomes if o.kind == v]
            pytest.fail(f"mutation {i} ({case.base}: {'; '.join(case.did)}): {v} in "
                        f"{bad[0].command}\n{bad[0].detail}\nmodel:\n{case.content!s:.3000}"
                        f"\n(python tools/fuzz.py --seed {SEED} --only {i} --heavy-every 12)")
    # the mutants are neither all refused nor all harmless
    assert verdicts.count(fuzz.CLEAN) > size // 2
    assert verdicts.count(fuzz.ACCEPTED) > size // 20


def test_the_counts_report(fuzz):
    result = fuzz.run(12, seed=3, jobs=2, heavy_every=4, hang=60.0, log=lambda s: None)
    text = fuzz.report(result)
    assert text.startswith("mbody fuzz: 12 mutations of the shipped models (seed 3), ")
    for label in ("clean errors", "accepted", "crashes", "hangs"):
        assert f"  {label} " in text
    assert sum(result["verdicts"].values()) == 12
    assert result["verdicts"][fuzz.CRASH] == result["verdicts"][fuzz.HANG] == 0


def test_a_located_model_error_and_an_unlocated_one(fuzz):
    ok = "mbody: error: 2 problems in the model:\nm.yaml:3:5: a: x\nm.yaml:4:1: b: y\n"
    assert fuzz._unlocated_problems(ok, "m.yaml") == []
    bad = "mbody: error: m.yaml: YAML error: unacceptable character\n"
    assert fuzz._unlocated_problems(bad, "m.yaml") == [bad.removeprefix("mbody: error: ")
                                                      .rstrip()]
    assert fuzz.classify("check", 2, "", bad, "", "m.yaml").kind == fuzz.CRASH
    assert fuzz.classify("check", 70, "", "mbody: internal error: x", "", "m").kind == fuzz.CRASH
    assert fuzz.classify("solve", None, "", "", "", "m").kind == fuzz.HANG
