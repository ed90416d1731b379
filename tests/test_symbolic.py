"""Symbolic Newton-Euler pairs: the model's numbers substituted into every body's rows give
back the numeric assembly's M, b, Q and G rows (every shipped model, at its initial state
and at a random one); the course's example 2 reads as the course writes it; text, LaTeX
(compiled by pdflatex where installed) and the command line."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sympy = pytest.importorskip("sympy")

import mbody  # noqa: E402
from mbody.equations.symbolic import (  # noqa: E402
    GRAVITY,
    GYROSCOPIC,
    SymbolicBody,
    SymbolicEquations,
    latex_symbol,
    load_symbols,
)
from mbody.model.model import State  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
ALL = sorted(MODELS.glob("*.yaml"))
TOL = 1e-12
"""Relative to the size of the row's terms (their absolute values summed)."""

I1, I2, I3, w1, w2, w3 = sympy.symbols("I_1 I_2 I_3 w_1 w_2 w_3")
a1, a2, a3 = sympy.symbols("alpha_1 alpha_2 alpha_3")


def _load(name: str) -> mbody.Model:
    return mbody.load(MODELS / name)


def random_state(model: mbody.Model, seed: int) -> State:
    """Any state at all (the joints need not hold: M, b, Q, G are defined everywhere)."""
    rng = np.random.default_rng(seed)
    n = model.n
    t = float(rng.uniform(0.1, 3.0))
    if model.dimension == 2:
        return State.planar(rng.normal(size=(n, 2)), rng.uniform(-np.pi, np.pi, n),
                            rng.normal(size=(n, 2)), rng.normal(size=n) * 3, t)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    omega = np.where(model.particle[:, None], 0.0, rng.normal(size=(n, 3)) * 3)
    return State(rng.normal(size=(n, 3)), q, rng.normal(size=(n, 3)), omega, t)


def _scale(expr, sub) -> float:
    """Σ |term| of the expanded expression at `sub`: what rounding is relative to."""
    return sum(abs(float(a.xreplace(sub))) for a in sympy.Add.make_args(sympy.expand(expr)))


def check_reproduces(asm: mbody.Assembly) -> int:
    """Every body's symbolic rows, with the model's values, against M, b, Q, G; returns
    the number of rows checked."""
    sym = asm.symbolic()
    assert isinstance(sym, SymbolicEquations)
    M, G = asm.M.toarray(), asm.G.toarray()
    coords = asm.coordinates
    index = {c: k for k, c in enumerate(coords)}
    suffix = {"a_x": "x", "a_y": "y", "a_z": "z", "alpha": "theta", "alpha_1": "w1",
              "alpha_2": "w2", "alpha_3": "w3"}
    assert [r.label for r in sym.rows] == coords  # stacking order, every row
    checked = 0
    for body in sym.bodies:
        sub = {sympy.Symbol(k): sympy.Float(v) for k, v in body.values.items()}
        body_euler = {x.label for x in body.euler}
        for row, val in zip(body.rows, body.evaluate(), strict=True):
            r = index[row.label]
            # M: this row's entries, by coordinate
            got = {f"{body.body}.{suffix[k]}": v for k, v in val.inertia.items()}
            want = {coords[c]: M[r, c] for c in np.flatnonzero(M[r])}
            assert got.keys() == want.keys(), row.label
            for k, v in want.items():
                assert got[k] == pytest.approx(v, rel=TOL, abs=0), (row.label, k)
            # b and Q: relative to the size of their terms
            for name, value, expr, numeric in (
                    ("b", val.gyroscopic, row.gyroscopic, asm.b[r]),
                    ("Q", val.applied, row.applied, asm.Q[r])):
                scale = max(_scale(expr, sub), abs(numeric))
                assert abs(value - numeric) <= TOL * scale, (row.label, name, value, numeric)
            # G: every column, the coefficients of the reaction labels
            g = G[r]
            gmax = float(np.max(np.abs(g), initial=0.0))
            # the body's rows of the same kind (force or moment) as this one
            kind = [index[x.label] for x in body.rows
                    if (x.label in body_euler) == (row.label in body_euler)]
            unit = row_units(asm, body.body, r, row.label in body_euler)
            for c, label in enumerate(asm.reactions):
                if label not in val.reactions and g[c] != 0.0:
                    # left out as rounding noise: tiny beside the reaction's largest
                    # coefficient on the body's rows of this kind (a 1e-17 m lever arm),
                    # or beside the largest coefficient of its unit in this row (1.9e-18 m
                    # next to 0.25 m), or below 1e-12 (as `mbody assemble` prints 0)
                    column = float(np.max(np.abs(G[kind, c])))
                    ref = max(column, unit[label.rpartition(".")[2].startswith("M")])
                    assert abs(g[c]) < 1e-12 or abs(g[c]) <= 1e-14 * ref, (
                        row.label, label, g[c], column, ref)
                    continue
                assert abs(val.reactions.get(label, 0.0) - g[c]) <= TOL * gmax, (row.label,
                                                                                   label)
            assert set(val.reactions) <= set(asm.reactions)
            checked += 1
    return checked


def row_units(asm: mbody.Assembly, body: str, r: int, euler: bool) -> dict[bool, float]:
    """The largest coefficient of each unit in row `r` of the assembly (key: whether the
    symbol is a moment): the reactions' entries of G and the loads' and gravity's unit
    wrenches, in an Euler row lever arms (m) for forces, direction cosines for moments."""
    model = asm.model
    unit = {False: 0.0, True: 0.0}
    for c, label in enumerate(asm.reactions):
        moment = label.rpartition(".")[2].startswith("M")
        unit[moment] = max(unit[moment], abs(float(asm.G[r, c])))
    first = min(j for j, c in enumerate(asm.coordinates) if c.startswith(body + "."))
    six = (np.array([0, 1, 5]) if model.dimension == 2 else np.arange(6))[r - first]
    for sym in load_symbols(model, asm.state, body):
        moment = not np.any(sym.wrench[:3])
        unit[moment] = max(unit[moment], abs(float(sym.wrench[six])))
    if not euler and np.any(model.gravity):
        unit[False] = max(unit[False], float(np.max(np.abs(model.gravity)))
                          / float(np.linalg.norm(model.gravity)))
    return unit


@pytest.mark.parametrize("path", ALL, ids=[p.stem for p in ALL])
def test_numbers_substituted_reproduce_the_assembly(path):
    model = mbody.load(path)
    assert check_reproduces(mbody.assemble(model)) == len(model.coordinates)
    assert check_reproduces(mbody.assemble(model, random_state(model, 12))) == len(
        model.coordinates)


def test_shipped_models_cover_both_dimensions_and_every_inertia_form():
    forms = {(m.dimension, b.inertia_form) for m in (_load(p.name) for p in ALL)
             for b in mbody.assemble(m).symbolic().bodies}
    assert forms >= {(2, "planar"), (2, "particle"), (3, "principal"), (3, "tensor")}


def test_a_wrong_value_is_noticed():
    """The check above can fail: a changed inertia no longer reproduces b."""
    asm = mbody.assemble(_load("seed_example_2.yaml"))
    body = asm.symbolic()["body"]
    rows = body.evaluate({"I_2": 3.5})
    assert rows[3].gyroscopic != pytest.approx(asm.b[3])
    assert body.evaluate()[3].gyroscopic == pytest.approx(asm.b[3])


# -- the course's example 2 ----------------------------------------------------------------
def test_example_2_euler_rows_are_the_course_forms():
    body = mbody.assemble(_load("seed_example_2.yaml")).bodies["body"].symbolic()
    assert isinstance(body, SymbolicBody) and body.inertia_form == "principal"
    course = [(I1 * a1, (I2 - I3) * w2 * w3), (I2 * a2, (I3 - I1) * w3 * w1),
              (I3 * a3, (I1 - I2) * w1 * w2)]
    for row, (lhs, rhs) in zip(body.euler, course, strict=True):
        assert row.lhs == lhs
        assert sympy.expand(row.rhs - rhs) == 0
        # solved for the angular acceleration: the course's ω̇₁ = (I₂ − I₃)ω₂ω₃/I₁
        acc = lhs.as_ordered_factors()[1]
        assert sympy.simplify(sympy.solve(row.equation, acc)[0] - rhs / (lhs / acc)) == 0
    assert [r.text() for r in body.euler] == [
        "I_1*alpha_1 = (I_2 - I_3)*w_2*w_3",
        "I_2*alpha_2 = (I_3 - I_1)*w_3*w_1",
        "I_3*alpha_3 = (I_1 - I_2)*w_1*w_2"]
    # the gyroscopic term is b = ω × Jω, and its value is the course's: ω̇ = (-3, 2, -0.5)
    assert [sympy.expand(r.gyroscopic) for r in body.euler] == [
        sympy.expand(e) for e in ((I3 - I2) * w2 * w3, (I1 - I3) * w3 * w1,
                                  (I2 - I1) * w1 * w2)]
    values = body.evaluate()
    assert [-v.gyroscopic / v.inertia[f"alpha_{k + 1}"]
            for k, v in enumerate(values[3:])] == [-3.0, 2.0, -0.5]
    assert "  b = ((I_3 - I_2)*w_2*w_3, (I_1 - I_3)*w_3*w_1, (I_2 - I_1)*w_1*w_2)" in (
        body.text())


def test_full_tensor_writes_the_cross_product_of_w_and_jw():
    body = mbody.assemble(_load("rotated_full_inertia.yaml")).symbolic()["bracket"]
    assert body.inertia_form == "tensor"
    I = sympy.Matrix(3, 3, lambda j, k: sympy.Symbol(f"I_{min(j, k) + 1}{max(j, k) + 1}"))
    w = sympy.Matrix([w1, w2, w3])
    b = w.cross(I * w)
    for k, row in enumerate(body.euler):
        assert sympy.expand(row.gyroscopic - b[k]) == 0
        assert sympy.expand(row.lhs - (I * sympy.Matrix([a1, a2, a3]))[k]) == 0
    assert "b_1 = w_2*(I_13*w_1 + I_23*w_2 + I_33*w_3) - w_3*(I_12*w_1 + I_22*w_2 + " \
           "I_23*w_3)" in body.text()
    # entries are the tensor's (negative products of inertia stay negative)
    assert body.values["I_12"] == -0.012 and body.values["I_23"] == -0.006


def test_planar_rows_name_loads_gravity_and_reactions():
    rod = mbody.assemble(_load("pendulum.yaml")).symbolic()["rod"]
    assert [r.text() for r in rod.rows] == [
        "m*a_x = O.Fx", "m*a_y = -m*g + O.Fy", "I_G*alpha = -0.433013*O.Fx - 0.25*O.Fy"]
    assert rod.unknowns == ["O.Fx", "O.Fy"] and rod.values["g"] == 9.81
    assert [t.part for t in rod.rows[1].right] == [GRAVITY, "reaction"]
    plate = mbody.assemble(_load("planar_time_varying_force.yaml")).symbolic()["plate"]
    assert [r.text() for r in plate.rows] == ["m*a_x = F_push_x", "m*a_y = -m*g",
                                              "I_G*alpha = M_twist"]
    assert plate.definitions == {"F_push_x": "50*sin(2*t)", "M_twist": "0.5*cos(3*t)"}
    later = mbody.assemble(plate_model := _load("planar_time_varying_force.yaml"),
                           plate_model.initial.replace(t=1.0)).symbolic()["plate"]
    assert later.values["F_push_x"] == pytest.approx(50 * np.sin(2.0), rel=1e-15)
    assert "  F_push_x = 50*sin(2*t) = 45.4649 N at t = 1 s" in later.text().splitlines()


def test_spring_tension_is_one_symbol_with_its_law():
    block = mbody.assemble(_load("spring_mass_damper.yaml")).symbolic()["block"]
    assert block.rows[1].text() == "m*a_y = T_suspension - m*g"
    assert block.values["T_suspension"] == pytest.approx(38.4, rel=1e-14)
    assert ("  T_suspension = k (L - L0) + c dL/dt = 800*(0.55 - 0.5) + 8*(-0.2) = 38.4 N"
            in block.text().splitlines())


def test_body_frame_loads_are_numbered_world_loads_lettered():
    sc = mbody.assemble(_load("satellite_thrusters.yaml")).symbolic()["spacecraft"]
    names = {t.key for r in sc.rows for t in r.right if t.part == "applied"}
    assert names == {"F_main_engine_3", "F_rcs_1_1", "F_rcs_2_1"}
    # the couple of the roll pair: r × F about body axis 3 from each thruster
    assert sc.euler[2].text().endswith("- 0.75*F_rcs_1_1 + 0.75*F_rcs_2_1")
    br = mbody.assemble(_load("rotated_full_inertia.yaml")).symbolic()["bracket"]
    assert br.rows[2].text() == "m*a_z = F_lift_z - m*g"
    assert {"M_motor_1", "M_motor_3"} <= set(br.values)  # the 0 component is no symbol
    assert "M_motor_2" not in br.values


def test_gyroscopic_terms_are_only_on_euler_rows():
    for body in mbody.assemble(_load("heavy_top.yaml")).symbolic().bodies:
        for row in body.newton:
            assert all(t.part != GYROSCOPIC for t in row.terms)
            assert row.gyroscopic == 0


# -- text and LaTeX ---------------------------------------------------------------------
def test_text_rows_parse_back_to_the_same_equations():
    """A row printed with 17 digits, read by sympy, is the row itself (what a student
    copies is the equation)."""
    for name in ("pendulum.yaml", "rotated_full_inertia.yaml", "fourbar_spatial.yaml"):
        for row in mbody.assemble(_load(name)).symbolic().rows:
            text = row.text(digits=17)
            labels = sorted(set(re.findall(r"\b[A-Za-z_]\w*\.\w+", text)), key=len,
                            reverse=True)
            local = {f"R{k}": sympy.Symbol(lab) for k, lab in enumerate(labels)}
            for k, lab in enumerate(labels):
                text = re.sub(rf"\b{re.escape(lab)}\b", f"R{k}", text)
            lhs, rhs = (sympy.parse_expr(side, local_dict=local) for side in text.split(" = "))
            sym = {s.name: s for s in lhs.free_symbols | rhs.free_symbols}
            assert sympy.expand(lhs - row.lhs.xreplace(sym)) == 0
            diff = sympy.expand(rhs - row.rhs)
            assert all(abs(float(c)) < 1e-15 for c in diff.as_coefficients_dict().values())


def test_latex_symbols():
    assert [latex_symbol(s) for s in ("alpha_1", "w_2", "I_12", "I_G", "alpha", "O.Fx",
                                      "F_push_x", "M_motor_1", "M_twist", "T_k1", "U.Mt")] == [
        r"\dot{\omega}_{1}", r"\omega_{2}", "I_{12}", "I_G", r"\alpha", r"F^{\text{O}}_{x}",
        r"F^{\text{push}}_{x}", r"M^{\text{motor}}_{1}", r"M^{\text{twist}}",
        r"T^{\text{k1}}", r"M^{\text{U}}_{t}"]
    assert latex_symbol("F_my_load_x") == r"F^{\text{my\_load}}_{x}"


def test_latex_of_example_2():
    tex = mbody.assemble(_load("seed_example_2.yaml")).symbolic()["body"].latex()
    assert (r"I_{1} \dot{\omega}_{1} &= \left(I_{2} - I_{3}\right) \omega_{2} \omega_{3}"
            in tex)
    assert tex.startswith(r"\begin{aligned}") and tex.endswith(r"\end{aligned}")
    sym = mbody.assemble(_load("pendulum.yaml")).symbolic()
    assert sym._repr_latex_().startswith("$$\\begin{aligned}")
    assert r"I_G \alpha &= - 0.433013\,F^{\text{O}}_{x}" in sym.latex().replace(
        r"-0.433013", r"- 0.433013")


DOCS = ["seed_example_2.yaml", "rotated_full_inertia.yaml", "spring_mass_damper.yaml",
        "slider_crank.yaml", "point_pendulum.yaml"]


@pytest.mark.skipif(shutil.which("pdflatex") is None,
                    reason="pdflatex not installed (Debian: texlive-latex-base)")
def test_document_compiles_with_pdflatex(tmp_path):
    # the pages' models first, then every other shipped model
    for name in DOCS + [p.name for p in ALL if p.name not in DOCS]:
        (tmp_path / "sym.tex").write_text(
            mbody.assemble(_load(name)).symbolic().document(), encoding="utf-8")
        r = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error",
                            "-no-shell-escape", "sym.tex"], cwd=tmp_path, capture_output=True,
                           text=True, timeout=120)
        assert r.returncode == 0, r.stdout[-3000:]
        assert not re.search(r"^! |Undefined control sequence|Missing character", r.stdout,
                             re.M)


# -- the command line -----------------------------------------------------------------------
def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mbody", *args], capture_output=True,
                          text=True, timeout=120, cwd=ROOT)


def test_cli_prints_the_api_text(tmp_path):
    path = str(MODELS / "seed_example_2.yaml")
    r = _cli("assemble", path, "--symbolic")
    assert r.returncode == 0, r.stderr
    want = mbody.assemble(mbody.load(path)).symbolic()
    assert r.stdout == want.text() + "\n"
    assert "  body.w1  I_1*alpha_1 = (I_2 - I_3)*w_2*w_3\n" in r.stdout
    r = _cli("assemble", str(MODELS / "pendulum.yaml"), "--symbolic", "--body", "rod")
    assert r.returncode == 0 and r.stdout.startswith("== rod ==")
    r = _cli("assemble", str(MODELS / "pendulum.yaml"), "--symbolic", "--body", "rood")
    assert r.returncode == 2 and "did you mean 'rod'" in r.stderr
    out = tmp_path / "sym.tex"
    r = _cli("assemble", path, "--symbolic", "--latex", str(out))
    assert r.returncode == 0, r.stderr
    assert out.read_text(encoding="utf-8") == want.document()


def test_load_symbols_need_no_sympy_and_match_the_rows():
    """`load_symbols` (numpy only, for `mbody verify`) gives the symbols and values the
    rows use."""
    model = _load("satellite_thrusters.yaml")
    state = random_state(model, 3)
    loads = load_symbols(model, state, "spacecraft")
    body = mbody.assemble(model, state).symbolic()["spacecraft"]
    assert [s.name for s in loads] == ["F_main_engine_3", "F_rcs_1_1", "F_rcs_2_1"]
    assert {s.name: s.value for s in loads} == {k: v for k, v in body.values.items()
                                                if k.startswith("F_")}


def test_import_and_numeric_assemble_do_not_load_sympy():
    code = ("import sys, mbody; a = mbody.assemble(mbody.load('models/pendulum.yaml')); "
            "str(a.bodies['rod']); a.solve(); print('sympy' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "False"


# -- the same vocabulary as `mbody verify` --------------------------------------------
@pytest.mark.parametrize("path", ALL, ids=[p.stem for p in ALL])
def test_every_symbolic_row_copied_into_an_answers_file_is_correct(path):
    """What `mbody assemble --symbolic` prints is what `mbody verify` reads: every row of
    every shipped model, copied as printed (6 figures) and exactly (17), is `correct`
    and is that row; no printed coefficient is rounding noise (a 2e-17 lever arm would
    be a term the student cannot write and the checker refuses)."""
    from mbody.answers import verify

    model = mbody.load(path)
    asm = mbody.assemble(model)
    sym = asm.symbolic()
    answers, labels = [], []
    for body in sym.bodies:
        for row in body.rows:
            for digits in (6, 17):
                answers.append({"body": body.body, "eq": row.text(digits=digits)})
                labels.append(row.label)
            assert not re.search(r"\de-1\d", row.text()), row.text()
    v = verify(model, answers, asm=asm)
    for check, label in zip(v.checks, labels, strict=True):
        assert check.correct and check.row == label, (label, check.eq, check.explanation)


# -- rounding noise beside the row's own terms -----------------------------------------
DP_SPRING = (Path(__file__).parent / "dp_spring.yaml").read_text()


def copied_rows_are_correct(model: mbody.Model, asm: mbody.Assembly) -> None:
    from mbody.answers import verify

    answers, labels = [], []
    for body in asm.symbolic().bodies:
        for row in body.rows:
            for digits in (6, 17):
                answers.append({"body": body.body, "eq": row.text(digits=digits)})
                labels.append(row.label)
    v = verify(model, answers, asm=asm)
    for check, label in zip(v.checks, labels, strict=True):
        assert check.correct and check.row == label, (label, check.eq, check.explanation)


def test_a_lever_arm_of_1e_18_beside_one_of_a_quarter_metre_is_noise(tmp_path):
    """A.Fy's only moment on the lower rod is a 1.86e-18 m lever arm (the rod hangs
    straight down from A): the largest of its kind, so only the row's other lever arms
    (0.25 m for A.Fx) show it is noise; it was printed as 1.85927e-18*A.Fy."""
    path = tmp_path / "dp_spring.yaml"
    path.write_text(DP_SPRING)
    model = mbody.load(path)
    asm = mbody.assemble(model)
    lower = asm.symbolic()["lower"]
    assert lower.rows[2].text() == "I_G*alpha = 0.249902*T_k1 - 0.25*A.Fx"
    # the lever arm is rounding (1.86e-18 m with the numpy path that wrote this test, 0
    # with the compiled core's order of operations): never more than noise beside 0.25 m
    arm = asm.G[asm.coordinates.index("lower.theta"), asm.reactions.index("A.Fy")]
    assert abs(arm) <= 1e-15 * 0.25
    assert not re.search(r"\de-1\d", lower.text())
    assert "10^{-" not in lower.latex()
    assert check_reproduces(asm) == len(model.coordinates)
    copied_rows_are_correct(model, asm)


@pytest.mark.parametrize("q", [{}, {"shoulder_lift_joint": -1.2, "elbow_joint": 1.0}],
                         ids=["zero", "posed"])
def test_ur5_rows_print_no_term_the_numeric_rows_print_as_0(q):
    """example-robot-data's UR5 (docs/robots.md): at q = 0 the upper arm's Euler rows had
    three reaction terms of 5.9e-13 to 7.1e-13 m (a 4.9e-12 rad misalignment in the file
    times the elbow's lever arms) that `mbody assemble` prints as 0 and `mbody verify`'s
    rows do not have; posed, the shoulder's row had a 1.4e-17 m arm."""
    import importlib.metadata

    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots/"
                                     "ur_description/urdf/ur5_robot.urdf")))
    if not path.is_file():
        pytest.skip("example-robot-data has no ur5_robot.urdf")
    model = mbody.load(path, joint_positions=q)
    asm = mbody.assemble(model)
    sym = asm.symbolic()
    for body in sym.bodies:
        for row in body.rows:
            assert all(abs(c) >= 1e-12 for c in row.reactions.values()), row.text()
    arm = sym["upper_arm_link"]
    if not q:
        assert "elbow_joint.Fy" not in arm.rows[3].text()  # w1
        assert "elbow_joint.Fx" not in arm.rows[4].text() + arm.rows[5].text()
    else:
        assert not re.search(r"\de-1\d", sym.text()), sym.text()
    assert check_reproduces(asm) == len(model.coordinates)
    copied_rows_are_correct(model, asm)
