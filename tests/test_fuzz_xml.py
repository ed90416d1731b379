"""The MJCF/URDF fuzzer (tools/fuzz_xml.py) in the suite: mutated robot models and small
generated MJCF and URDF documents through ``mbody check`` (and ``solve`` for some), in
this process, seeded. Every command ends accepted or with one clean, located message: no
crash, no hang; and every accepted MJCF that MuJoCo also loads has MuJoCo's body masses,
and, where it is a tree mbody maps exactly, MuJoCo's accelerations. The long run is
``python tools/fuzz_xml.py`` (10 000 cases, two processes).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
CASES = 1500
SEED = 7

pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def fx():
    spec = importlib.util.spec_from_file_location("mbody_fuzz_xml",
                                                  ROOT / "tools" / "fuzz_xml.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["mbody_fuzz_xml"] = module
    spec.loader.exec_module(module)
    return module


def test_mutated_robot_models_give_clean_errors_or_mujocos_answers(fx):
    result = fx.run_chunk(SEED, list(range(CASES)), hang=30.0, solve_every=4)
    v, compared = result["verdicts"], result["compared"]
    for i, case, outcomes in result["failures"][:1]:
        bad = [o for o in outcomes if o.kind in (fx.CRASH, fx.HANG, fx.MISMATCH)]
        files = "\n".join(f"--- {rel}\n{content!s:.2000}" for rel, content in
                          case.files.items())
        pytest.fail(f"case {i} ({case.base}: {'; '.join(case.did)}): {bad[0].kind} in "
                    f"{bad[0].command}\n{bad[0].detail}\n{files}\n"
                    f"(python tools/fuzz_xml.py --seed {SEED} --only {i})")
    assert v[fx.CRASH] == v[fx.HANG] == v[fx.MISMATCH] == 0
    # the cases are neither all refused nor all harmless, and many reach MuJoCo
    assert v[fx.CLEAN] > CASES // 2
    assert v[fx.ACCEPTED] > CASES // 5
    assert compared["masses"] > CASES // 6
    assert compared["accelerations"] > CASES // 20


ONE_BODY = ('<mujoco><worldbody><body name="arm" pos="0 0 1"><joint axis="0 1 0"/>'
            '<geom type="box" size="0.2 0.05 0.1" pos="0.3 0 0"/>'
            "</body></worldbody></mujoco>")  # a horizontal arm: gravity turns it


def test_a_wrong_mass_inertia_or_joint_is_a_mismatch(fx, tmp_path, monkeypatch):
    """The comparison can fail: mbody given a doubled volume (the mass), a doubled
    inertia, or a hinge axis tilted by 0.1 rad (the accelerations) differs from MuJoCo,
    and says where."""
    from mbody.io.interop import mjcf, mjcf_geoms, tree

    path = tmp_path / "m.xml"
    path.write_text(ONE_BODY)
    ok = fx.compare_with_mujoco(path)
    assert (ok.kind, ok.detail) == (fx.ACCEPTED, "masses 1; accelerations")
    solid = mjcf_geoms.solid
    with monkeypatch.context() as patch:
        patch.setattr(mjcf_geoms, "solid", lambda *a, **k: (2 * solid(*a, **k)[0],
                                                           solid(*a, **k)[1]))
        wrong = fx.compare_with_mujoco(path)
    assert wrong.kind == fx.MISMATCH and wrong.detail.startswith("body 'arm': mass ")
    with monkeypatch.context() as patch:
        patch.setattr(mjcf_geoms, "solid", lambda *a, **k: (solid(*a, **k)[0],
                                                           2 * solid(*a, **k)[1]))
        wrong = fx.compare_with_mujoco(path)
    assert wrong.kind == fx.MISMATCH and "body 'arm': inertia" in wrong.detail
    with monkeypatch.context() as patch:
        patch.setattr(mjcf, "unit", lambda v: tree.unit(v + np.array([0.1, 0, 0])))
        wrong = fx.compare_with_mujoco(path)
    assert wrong.kind == fx.MISMATCH and "accelerations differ by" in wrong.detail


def test_an_included_files_location_counts_as_located(fx, tmp_path):
    case = fx.Case(0, "x", "mjcf", ["x"], {"main.xml": "", "part.xml": ""})
    err = f"mbody: error: {tmp_path / 'part.xml'}:3:5: <geom size>: wrong\n"
    assert fx.classify_xml("check", 2, "", err, "", tmp_path, case).kind == fx.CLEAN
    err = "mbody: error: somewhere else: wrong\n"
    assert fx.classify_xml("check", 2, "", err, "", tmp_path, case).kind == fx.CRASH


def test_the_counts_report(fx):
    result = fx.run(8, seed=3, jobs=2, hang=60.0, log=lambda s: None)
    text = fx.report(result)
    assert text.startswith("mbody fuzz_xml: 8 mutated MJCF and URDF models (seed 3), ")
    for label in ("clean errors", "accepted", "crashes", "hangs", "mismatches"):
        assert f"  {label} " in text
    assert sum(result["verdicts"].values()) == 8
