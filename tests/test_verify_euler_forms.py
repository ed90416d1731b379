"""Two slips with Euler's equations, each a diagnosis of its own: the gyroscopic term moved
across the '=' without its sign (`gyroscopic_term_sign`), and the principal-axes form
I_k α_k + (I_j − I_i) ω_i ω_j = M_k written for a body whose axes are not principal
(`missing_products_of_inertia`); and neither is ever given to a correct equation."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.answers import DIAGNOSES
from mbody.answers.compare import CONST
from mbody.answers.rows import body_rows
from mbody.answers.verify import verify
from mbody.cli.app import main

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
NEW = {"gyroscopic_term_sign", "missing_products_of_inertia"}
SPATIAL = [p for p in sorted(MODELS.glob("*.yaml")) if mbody.load(p).dimension == 3]


def one(name: str, body: str, eq: str):
    v = verify(MODELS / f"{name}.yaml", [{"body": body, "eq": eq}])
    return v.checks[0]


def test_both_are_in_the_vocabulary_of_diagnoses():
    assert set(DIAGNOSES) >= NEW
    assert "cyclic order" in DIAGNOSES["gyroscopic_term_sign"]
    assert "products of inertia" in DIAGNOSES["missing_products_of_inertia"]


def test_a_flipped_gyroscopic_sign_is_named_on_the_command_line(capsys, tmp_path):
    # worked example 2: I = (2, 3, 4), w = (1, 2, 3): (ω × Iω)_1 = (4 − 3)·2·3 = 6 N m
    path = tmp_path / "a.yaml"
    path.write_text('equations:\n  - {body: body, eq: "I_1*alpha_1 = (I_3 - I_2)*w_2*w_3"}\n',
                    encoding="utf-8")
    assert main(["verify", str(MODELS / "seed_example_2.yaml"), str(path)]) == 1
    out = " ".join(capsys.readouterr().out.split())
    assert ("gyroscopic_term_sign: an Euler row with ω × Iω of the wrong sign (mind the "
            "cyclic order 1 → 2 → 3) expected (body.w1): 2 alpha_1 + 6 = 0") in out
    assert ("(ω × Iω)_1 = (I_3 − I_2) w_2 w_3 = (4 − 3)·2·3 = 6 N m, which belongs on the "
            "left beside I α (on the right side it is −(ω × Iω)); mind the cyclic order") in out
    assert main(["verify", str(MODELS / "seed_example_2.yaml"), str(path), "--json"]) == 1
    d = json.loads(capsys.readouterr().out)["equations"][0]
    assert d["diagnosis"] == "gyroscopic_term_sign" and d["details"]["value"] == 6.0


@pytest.mark.parametrize("name, body, eq, row", [
    ("seed_example_2", "body", "alpha_1 = 3", "body.w1"),
    ("practice_3_euler", "block", "I_2*alpha_2 = (I_1 - I_3)*w_3*w_1", "block.w2"),
    ("heavy_top", "top", "I_1*alpha_1 = (I_3 - I_2)*w_2*w_3 + 0.0469846*pivot.Fy "
     "+ 0.017101*pivot.Fz", "top.w1"),
    ("rotor_offset_load", "rotor", "I_2*alpha_2 = (I_1 - I_3)*w_3*w_1", "rotor.w2"),
    ("rotated_full_inertia", "bracket",
     "I_21*alpha_1 + I_22*alpha_2 + I_23*alpha_3 = -1.28552 + 0.104", "bracket.w2"),
])
def test_a_flipped_gyroscopic_sign_on_shipped_models(name, body, eq, row):
    c = one(name, body, eq)
    assert (c.diagnosis, c.row) == ("gyroscopic_term_sign", row), c.explanation
    assert "of the wrong sign" in c.explanation


# the bracket: J = [[0.08, -0.012, 0.004], [-0.012, 0.11, -0.006], [0.004, -0.006, 0.07]],
# w = (2, -1, 3) rad/s, M = (1.24302, -1.28552, 0.301279) N m about G in body axes;
# principal moments 0.068494, 0.076217, 0.115289 kg m² (the model file's comment)
ROWS = {"bracket.w1": "0.08 alpha_1 - 0.012 alpha_2 + 0.004 alpha_3 + 0.232 = 1.24302",
        "bracket.w2": "-0.012 alpha_1 + 0.11 alpha_2 - 0.006 alpha_3 + 0.104 = -1.28552",
        "bracket.w3": "0.004 alpha_1 - 0.006 alpha_2 + 0.07 alpha_3 - 0.12 = 0.301279"}
"""The bracket's true Euler rows (`mbody assemble models/rotated_full_inertia.yaml`)."""
PRINCIPAL = [
    # with the diagonal entries as I_1, I_2, I_3
    ("I_11*alpha_1 - (I_22 - I_33)*w_2*w_3 = 1.24302", "bracket.w1", "diagonal entries"),
    ("I_22*alpha_2 - (I_33 - I_11)*w_3*w_1 = -1.28552", "bracket.w2", "diagonal entries"),
    ("I_33*alpha_3 - (I_11 - I_22)*w_1*w_2 = 0.301279", "bracket.w3", "diagonal entries"),
    # with the principal moments as listed, ascending
    ("0.068494*alpha_1 - (0.076217 - 0.115289)*w_2*w_3 = 1.24302", "bracket.w1",
     "principal moments"),
    ("0.076217*alpha_2 - (0.115289 - 0.068494)*w_3*w_1 = -1.28552", "bracket.w2",
     "principal moments"),
    # with the principal moments of the nearest principal axes (0.076, 0.115, 0.068)
    ("0.068494*alpha_3 - (0.076217 - 0.115289)*w_1*w_2 = 0.301279", "bracket.w3",
     "principal moments"),
]


@pytest.mark.parametrize("eq, row, used", PRINCIPAL)
def test_the_principal_axes_form_off_principal_axes_is_named(eq, row, used):
    c = one("rotated_full_inertia", "bracket", eq)
    assert (c.diagnosis, c.row) == ("missing_products_of_inertia", row), c.explanation
    assert f"with its {used}" in c.explanation
    assert ("its tensor has products of inertia (I_12 = -0.012, I_13 = 0.004, I_23 = -0.006 "
            "kg m²)") in c.explanation
    assert c.details["products"] == {"I_12": -0.012, "I_13": 0.004, "I_23": -0.006}
    assert c.expected == ROWS[row]
    assert f"(I α)_{row[-1]} = {ROWS[row].partition(' + 0.')[0].partition(' - 0.12')[0]}" \
        in c.explanation


def test_the_principal_axes_form_on_the_command_line(capsys):
    answers = MODELS / "answers" / "rotated_full_inertia.yaml"
    assert main(["verify", str(MODELS / "rotated_full_inertia.yaml"), str(answers)]) == 1
    out = capsys.readouterr().out
    assert "[3] bracket: 0.068494*alpha_1 - (0.076217 - 0.115289)*w_2*w_3 = 1.24302  " \
           "(line 10)\n    missing_products_of_inertia: " in out
    assert "    gyroscopic_term_sign: " in out
    assert out.rstrip().endswith("2 of 4 equations correct; 2 of 6 rows covered.")


def test_the_satellite_with_products_of_inertia_too():
    """satellite_thrusters' spacecraft has a full tensor: each Euler row in principal form
    with its diagonal entries is named (a body, numbers and moments of its own)."""
    m = mbody.load(MODELS / "satellite_thrusters.yaml")
    asm = mbody.assemble(m)
    br = body_rows(asm, "spacecraft")
    named = 0
    for e in br.euler:
        k = e.axis
        i, j = (k + 1) % 3, (k + 2) % 3
        rest = e.row.get(CONST) - e.gyro  # −M_k: the applied moments' share
        eq = (f"I_{k + 1}{k + 1}*alpha_{k + 1} + (I_{j + 1}{j + 1} - I_{i + 1}{i + 1})"
              f"*w_{i + 1}*w_{j + 1} = {-rest!r}")
        c = verify(m, [("spacecraft", eq)], asm=asm).checks[0]
        principal_gyro = (br.J[j, j] - br.J[i, i]) * br.omega[i] * br.omega[j]
        alphas = [a for a in e.row.unknowns if a.startswith("alpha") and a != e.acc]
        if abs(principal_gyro - e.gyro) > 1e-6 or alphas:
            assert c.diagnosis == "missing_products_of_inertia", (eq, c.explanation)
            named += 1
    assert named == 3


def _principal(e, br, flip: bool = False) -> str:
    """Euler row e of a body with a diagonal tensor, in the principal form with the
    vocabulary's names, every other term (reactions, the moments' numbers) as in the
    row; flip: ω × Iω moved to the right side without its sign."""
    k = e.axis
    i, j = (k + 1) % 3, (k + 2) % 3
    gyro = f"(I_{j + 1} - I_{i + 1})*w_{i + 1}*w_{j + 1}"
    rest = [f"({v!r})*{key}" for key, v in e.row.coef.items()
            if key not in (CONST, e.acc) and v != 0.0]
    rest.append(repr(e.row.get(CONST) - e.gyro))
    left = f"I_{k + 1}*alpha_{k + 1}" + ("" if flip else f" + {gyro}")
    right = f"{gyro}" if flip else "0"
    return f"{left} + {' + '.join(rest)} = {right}"


@pytest.mark.parametrize("path", SPATIAL, ids=lambda p: p.stem)
def test_never_given_to_a_correct_equation(path):
    """Every row of every spatial shipped model written right, in several ways (the
    numbers of the row; on a body with principal axes, the principal form with I_1, I_2,
    I_3 and w_1, w_2, w_3), is correct; the gyroscopic sign flipped, it is named so."""
    m = mbody.load(path)
    asm = mbody.assemble(m)
    answers, expect = [], []
    for b in m.body_names:
        br = body_rows(asm, b)
        diagonal = np.count_nonzero(br.J - np.diag(np.diag(br.J))) == 0
        for r in br.rows:
            if not r.row.unknowns:
                continue
            for k in (1.0, -2.5, 1e-3):
                terms = " + ".join(f"({k * v!r})" + ("" if key == CONST else f"*{key}")
                                   for key, v in r.row.coef.items() if v != 0.0)
                answers.append((b, f"{terms} = 0"))
                expect.append("correct")
            if r.euler and diagonal and br.J[r.axis, r.axis] != 0.0:
                answers.append((b, _principal(r, br)))
                expect.append("correct")
                if abs(r.gyro) > 1e-9:
                    answers.append((b, _principal(r, br, flip=True)))
                    expect.append("gyroscopic_term_sign")
    if not answers:
        pytest.skip("no rows with unknowns")
    v = verify(m, answers, asm=asm)
    for c, want in zip(v.checks, expect, strict=True):
        assert c.diagnosis not in NEW or c.diagnosis == want, (c.eq, c.explanation)
        assert c.diagnosis == want, (c.eq, c.diagnosis, c.explanation)
