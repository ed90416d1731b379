"""One test per rule of the model-file contract (docs: model-format sections 1 to 4).

Each test writes a small model to `tmp_path`, loads it, and asserts the `Issue`: the
file, the line and column (found in the text itself, so a test cannot drift from its
model), the dotted key path, a message that says what is wrong and what was expected,
and a did-you-mean hint for misspelt names.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.errors import Issue, ModelError

PLANAR = """\
model: t
dimension: 2
bodies:
  - name: plate
    mass: 10
    inertia: 0.5
"""

SPATIAL = """\
model: t
dimension: 3
bodies:
  - name: rotor
    mass: 2
    inertia: [2, 3, 4]
"""


def mark_of(text: str, needle: str, nth: int = 1) -> tuple[int, int]:
    """1-based (line, column) of the `nth` occurrence of `needle` in `text`.

    A '»' in `needle` marks the spot within it: ``"inertia: »0"`` is the 0 after
    ``inertia: ``.
    """
    before, _, after = needle.rpartition("»")
    at = -1
    for _ in range(nth):
        at = text.index(before + after, at + 1)
    at += len(before)
    return text.count("\n", 0, at) + 1, at - (text.rfind("\n", 0, at) + 1) + 1


@pytest.fixture
def model_file(tmp_path) -> Path:
    return tmp_path / "model.yaml"


def problems(path: Path, text: str) -> list[Issue]:
    path.write_text(text)
    with pytest.raises(ModelError) as err:
        mbody.load(path)
    found = err.value.issues
    assert all(i.file == str(path) for i in found)
    # The exception's text is what a user sees: every issue with file:line:column.
    for i in found[:ModelError.SHOWN]:
        assert f"{path}:{i.line}:{i.column}: " in str(err.value)
    return found


def problem(path: Path, text: str, needle: str, key: str, *words: str, nth: int = 1,
            hint: str | None = None) -> Issue:
    """Exactly one issue, at `needle`, about `key`, whose message contains `words`."""
    found = problems(path, text)
    assert len(found) == 1, "\n".join(map(str, found))
    i = found[0]
    assert (i.line, i.column) == mark_of(text, needle, nth), str(i)
    assert i.key == key
    for w in words:
        assert w in i.message, (w, str(i))
    if hint is not None:
        assert hint in i.hint, (hint, str(i))
    return i


def ok(path: Path, text: str) -> mbody.Model:
    path.write_text(text)
    return mbody.load(path)


# == 1. The file ======================================================================

def test_unknown_top_level_key_with_did_you_mean(model_file):
    text = PLANAR + "gravty: [0, -9.81]\n"
    problem(model_file, text, "gravty", "gravty", "unknown key 'gravty'",
            hint="did you mean 'gravity'?")


def test_unknown_key_far_from_any_lists_the_keys(model_file):
    text = PLANAR + "colour_scheme: dark\n"
    i = problem(model_file, text, "colour_scheme", "colour_scheme", "unknown key")
    assert i.hint.startswith("expected one of: model, dimension, gravity, bodies")


def test_missing_dimension(model_file):
    text = "model: t\nbodies: []\n"
    i = problem(model_file, text, "model", "", "missing required key 'dimension'")
    assert "2 for a planar model, 3 for a spatial one" in i.hint


@pytest.mark.parametrize("value", ["4", "'2'", "true", "2.5", "[2]"])
def test_dimension_must_be_2_or_3(model_file, value):
    text = PLANAR.replace("dimension: 2", f"dimension: {value}")
    # Only this problem: with no dimension, vector lengths cannot be judged.
    problem(model_file, text, value, "dimension", "expected 2 (planar) or 3 (spatial)")


def test_missing_bodies(model_file):
    problem(model_file, "dimension: 2\n", "dimension", "", "missing required key 'bodies'")


def test_empty_body_list(model_file):
    problem(model_file, "dimension: 2\nbodies: []\n", "[]", "bodies",
            "the model needs at least one of the bodies")


def test_bodies_must_be_a_list(model_file):
    problem(model_file, "dimension: 2\nbodies: {name: a}\n", "{name", "bodies",
            "expected a list of bodies, got a mapping")


def test_model_name_must_be_text(model_file):
    text = PLANAR.replace("model: t", "model: [t]")
    problem(model_file, text, "[t]", "model", "expected the model's name as text")


@pytest.mark.parametrize(("base", "gravity", "words", "hint"), [
    (PLANAR, "[0, 0, -9.81]", "expected 2 components, got 3", "planar models use 2-D"),
    (SPATIAL, "[0, -9.81]", "expected 3 components, got 2", "spatial models use 3-D"),
])
def test_vector_length_follows_the_dimension(model_file, base, gravity, words, hint):
    text = base + f"gravity: {gravity}\n"
    problem(model_file, text, gravity, "gravity", words, hint=hint)


@pytest.mark.parametrize("bad", [".nan", ".inf", "-.inf", ".NaN"])
def test_non_finite_numbers(model_file, bad):
    text = PLANAR + f"gravity: [0, {bad}]\n"
    problem(model_file, text, bad, "gravity[1]", "expected a finite number")


@pytest.mark.parametrize(("bad", "shown"), [("1e999", "1e999"), ("-1e999", "-1e999"),
                                            ("1" + "0" * 400, "an integer of 401 digits")])
def test_numbers_beyond_double_precision_are_out_of_range(model_file, bad, shown):
    text = PLANAR.replace("mass: 10", f"mass: {bad}")
    problem(model_file, text, bad, "bodies[0].mass",
            f"expected a number of magnitude at most 1e+100, got {shown}")


def test_booleans_are_not_numbers(model_file):
    text = PLANAR.replace("mass: 10", "mass: true")
    problem(model_file, text, "true", "bodies[0].mass", "expected a number, got a boolean")


@pytest.mark.parametrize("word", ["yes", "off", "on", "no"])
def test_yaml_1_1_booleans_are_text(model_file, word):
    text = PLANAR.replace("mass: 10", f"mass: {word}")
    problem(model_file, text, f"mass: »{word}", "bodies[0].mass",
            f"expected a number, got the text '{word}'")


def test_text_is_not_a_number(model_file):
    text = PLANAR.replace("mass: 10", "mass: ten")
    problem(model_file, text, "ten", "bodies[0].mass", "expected a number, got the text 'ten'")


def test_several_problems_are_reported_together_in_file_order(model_file):
    text = """\
dimension: 2
bodies:
  - {name: a, mass: -1, inertia: 0.5}
  - {name: a, mass: 1, inertia: 0.5, positon: [0, 0]}
loads:
  - {type: force, body: b, force: [1, 2, 3]}
joints:
  - {name: J, type: hinge, parent: ground, child: a, at: [0, 0]}
"""
    found = problems(model_file, text)
    got = [(i.line, i.key) for i in found]
    assert got == [
        (3, "bodies[0].mass"),
        (4, "bodies[1].positon"),
        (4, "bodies[1].name"),
        (6, "loads[0].body"),
        (6, "loads[0].force"),
        (8, "joints[0].type"),
    ]
    assert [i.hint for i in found][1] == "did you mean 'position'?"
    model_file.write_text(text)
    with pytest.raises(ModelError) as err:
        mbody.load(model_file)
    assert str(err.value).startswith("6 problems in the model:\n")


def test_load_from_a_dict_reports_keys_without_lines():
    with pytest.raises(ModelError) as err:
        mbody.load({"dimension": 2, "bodies": [{"name": "a", "mass": 0, "inertia": 1}]})
    (i,) = err.value.issues
    assert (i.file, i.line, i.key) == ("<dict>", 0, "bodies[0].mass")
    assert str(i) == "<dict>: bodies[0].mass: expected a number > 0, got 0"


# == 2. Bodies ========================================================================

def test_unknown_body_key_with_did_you_mean(model_file):
    text = PLANAR + "    intertia: 3\n"
    problem(model_file, text, "intertia", "bodies[0].intertia", "unknown key 'intertia'",
            hint="did you mean 'inertia'?")


def test_duplicate_body_names(model_file):
    text = PLANAR + "  - {name: plate, mass: 1, inertia: 1}\n"
    problem(model_file, text, "plate", "bodies[1].name", "duplicate body name 'plate'", nth=2,
            hint="first used by bodies[0]")


def test_ground_is_a_reserved_body_name(model_file):
    text = PLANAR + "  - {name: ground, mass: 1, inertia: 1}\n"
    problem(model_file, text, "ground", "bodies[1].name", "'ground' is reserved")


@pytest.mark.parametrize("name", ["'my plate'", "plate.1"])
def test_body_names_without_dots_or_spaces(model_file, name):
    text = PLANAR.replace("name: plate", f"name: {name}")
    problem(model_file, text, name, "bodies[0].name", "may not contain '.' or spaces")


def test_body_name_must_be_text(model_file):
    text = PLANAR.replace("name: plate", "name: 12")
    problem(model_file, text, "12", "bodies[0].name", "expected a body name (text), got the "
            "number 12")


def test_missing_mass(model_file):
    text = PLANAR.replace("    mass: 10\n", "")
    i = problem(model_file, text, "name: plate", "bodies[0]", "missing required key 'mass'")
    assert i.hint == "the mass in kg, a number > 0"


@pytest.mark.parametrize("mass", ["0", "-2", "0.0"])
def test_mass_must_be_positive(model_file, mass):
    text = PLANAR.replace("mass: 10", f"mass: {mass}")
    problem(model_file, text, mass, "bodies[0].mass", "expected a number > 0")


def test_missing_inertia_without_shape(model_file):
    text = PLANAR.replace("    inertia: 0.5\n", "")
    i = problem(model_file, text, "name: plate", "bodies[0]", "missing required key 'inertia'")
    assert "shape" in i.hint


def test_shape_gives_the_inertia_of_a_uniform_solid(model_file):
    m = ok(model_file, PLANAR.replace("inertia: 0.5", "shape: {box: [0.6, 0.8]}"))
    assert m.bodies["plate"].inertia[2, 2] == pytest.approx(10 * (0.36 + 0.64) / 12)
    m = ok(model_file, SPATIAL.replace("inertia: [2, 3, 4]",
                                       "shape: {cylinder: {radius: 0.5, length: 2}}"))
    J = m.bodies["rotor"].inertia
    axial, transverse = 2 * 0.25 / 2, 2 * (3 * 0.25 + 4) / 12  # m r^2/2, m(3r^2 + L^2)/12
    assert sorted(np.diag(J)) == pytest.approx(sorted([transverse, transverse, axial]))


def test_unknown_shape_with_did_you_mean(model_file):
    text = PLANAR.replace("inertia: 0.5", "shape: {bx: [1, 2]}")
    problem(model_file, text, "bx", "bodies[0].shape.bx", "unknown key 'bx'",
            hint="did you mean 'box'?")


def test_shape_sizes_must_be_positive(model_file):
    text = PLANAR + "    shape: {box: [1, 0]}\n"
    problem(model_file, text, "[1, 0]", "bodies[0].shape.box", "every size must be > 0")


def test_planar_inertia_is_a_scalar(model_file):
    text = PLANAR.replace("inertia: 0.5", "inertia: [1, 2, 3]")
    problem(model_file, text, "[1, 2, 3]", "bodies[0].inertia",
            "a planar body's inertia is the scalar I_G")


def test_planar_inertia_must_be_positive(model_file):
    # (inertia: 0 is a particle, see tests/test_particles.py)
    text = PLANAR.replace("inertia: 0.5", "inertia: -0.5")
    i = problem(model_file, text, "inertia: »-0.5", "bodies[0].inertia",
                "expected a number > 0")
    assert "'inertia: 0' makes a particle" in i.hint  # 0 is allowed: the hint says so


def test_spatial_inertia_is_not_a_scalar(model_file):
    text = SPATIAL.replace("inertia: [2, 3, 4]", "inertia: 3")
    problem(model_file, text, "inertia: »3", "bodies[0].inertia",
            "expected principal moments [I1, I2, I3] or a 3x3 inertia tensor")


def test_principal_moments_need_three(model_file):
    text = SPATIAL.replace("[2, 3, 4]", "[2, 3]")
    problem(model_file, text, "[2, 3]", "bodies[0].inertia", "expected 3 components, got 2")


def test_inertia_triangle_inequality(model_file):
    text = SPATIAL.replace("[2, 3, 4]", "[1, 2, 4]")
    i = problem(model_file, text, "[1, 2, 4]", "bodies[0].inertia", "not physically realisable",
                "triangle inequality (1 + 2 < 4)")
    assert "sum of the other two" in i.hint


def test_inertia_on_the_triangle_boundary_is_accepted(model_file):
    # A thin flat plate: I3 = I1 + I2 exactly.
    m = ok(model_file, SPATIAL.replace("[2, 3, 4]", "[1, 3, 4]"))
    assert np.diag(m.bodies["rotor"].inertia).tolist() == [1, 3, 4]


def test_inertia_tensor_must_be_symmetric(model_file):
    text = SPATIAL.replace("[2, 3, 4]", "[[2, 0.1, 0], [0, 3, 0], [0, 0, 4]]")
    i = problem(model_file, text, "[[2", "bodies[0].inertia", "not symmetric: row 1, column 2 "
                "is 0.1 but row 2, column 1 is 0")
    assert "(i, j) must equal entry (j, i)" in i.hint


def test_inertia_tensor_must_be_positive_definite(model_file):
    text = SPATIAL.replace("[2, 3, 4]", "[[2, 3, 0], [3, 2, 0], [0, 0, 4]]")
    i = problem(model_file, text, "[[2", "bodies[0].inertia", "not positive definite",
                "principal moments (-1, 4, 5)")
    assert "every principal moment must be > 0" in i.hint
    assert "'inertia: 0' makes a particle" in i.hint


def test_zero_principal_moment_is_not_positive_definite(model_file):
    text = SPATIAL.replace("[2, 3, 4]", "[0, 3, 3]")
    problem(model_file, text, "[0, 3, 3]", "bodies[0].inertia", "not positive definite")


def test_full_tensor_triangle_inequality_uses_principal_moments(model_file):
    # Diagonal (2, 2, 1) looks fine; the off-diagonal entries make the principal moments
    # (0.1, 1, 3.9): positive, but 0.1 + 1 < 3.9 -- no rigid body has this tensor.
    R = np.linalg.qr(np.array([[1.0, 2, 0], [0, 1, 3], [1, 0, 1]]))[0]
    J = R @ np.diag([0.1, 1.0, 3.9]) @ R.T
    rows = ", ".join("[" + ", ".join(repr(float(x)) for x in r) + "]" for r in J)
    text = SPATIAL.replace("[2, 3, 4]", f"[{rows}]")
    problem(model_file, text, "[[", "bodies[0].inertia", "triangle inequality")


def test_inertia_matrix_must_be_3x3(model_file):
    text = SPATIAL.replace("[2, 3, 4]", "[[2, 0, 0], [0, 3, 0]]")
    problem(model_file, text, "[[2", "bodies[0].inertia", "expected a 3x3 matrix")


def test_full_inertia_tensor_is_kept(model_file):
    m = ok(model_file, SPATIAL.replace("[2, 3, 4]", "[[2, -0.5, 0], [-0.5, 3, 0.2], "
                                                    "[0, 0.2, 4]]"))
    assert m.bodies["rotor"].inertia[0, 1] == -0.5 and m.bodies["rotor"].inertia[2, 1] == 0.2


@pytest.mark.parametrize(("base", "key", "value", "words"), [
    (PLANAR, "position", "[0, 0, 0]", "expected 2 components, got 3"),
    (PLANAR, "velocity", "[1]", "expected 2 components, got 1"),
    (SPATIAL, "position", "[0, 0]", "expected 3 components, got 2"),
    (SPATIAL, "velocity", "3", "expected a list of 3 numbers, got the number 3"),
    (SPATIAL, "angular_velocity", "[1, 2]", "expected 3 components, got 2"),
    (PLANAR, "angular_velocity", "[1, 2]", "expected a number"),
])
def test_body_vectors(model_file, base, key, value, words):
    text = base + f"    {key}: {value}\n"
    problem(model_file, text, f"{key}: »{value}", f"bodies[0].{key}", words)


def test_non_finite_component_names_its_index(model_file):
    text = SPATIAL + "    velocity: [0, .nan, 0]\n"
    problem(model_file, text, ".nan", "bodies[0].velocity[1]", "expected a finite number")


# -- angles and orientations ----------------------------------------------------------

@pytest.mark.parametrize(("angle", "radians"), [
    ("30 deg", math.pi / 6), ("'-90 deg'", -math.pi / 2), ("0.5", 0.5), ("1.5e1 deg",
                                                                         math.pi / 12),
    ("0.25 rad", 0.25),
])
def test_planar_angle_in_radians_or_degrees(model_file, angle, radians):
    m = ok(model_file, PLANAR + f"    angle: {angle}\n")
    w, x, y, z = m.initial.quaternion[0]
    assert 2 * math.atan2(z, w) == pytest.approx(radians)


@pytest.mark.parametrize("angle", ["30 degrees", "30deg!", "thirty deg", "30 grad"])
def test_bad_angle_text(model_file, angle):
    text = PLANAR + f"    angle: {angle}\n"
    problem(model_file, text, angle, "bodies[0].angle",
            f"expected a number (radians) or a string like '30 deg', got '{angle}'")


def test_angular_rate_in_degrees_per_second(model_file):
    m = ok(model_file, PLANAR + "    angular_velocity: 180 deg/s\n")
    assert m.initial.omega[0, 2] == pytest.approx(math.pi)


def test_angle_is_planar_only(model_file):
    text = SPATIAL + "    angle: 0.3\n"
    i = problem(model_file, text, "angle", "bodies[0].angle", "spatial bodies give their "
                "attitude with 'orientation'")
    assert "orientation:" in i.hint


def test_orientation_is_spatial_only(model_file):
    text = PLANAR + "    orientation: {quaternion: [1, 0, 0, 0]}\n"
    i = problem(model_file, text, "orientation", "bodies[0].orientation",
                "planar bodies give their angle with 'angle'")
    assert "angle: '30 deg'" in i.hint


def test_quaternion_is_w_first(model_file):
    s = math.sqrt(0.5)
    m = ok(model_file, SPATIAL + f"    orientation: {{quaternion: [{s}, 0, 0, {s}]}}\n")
    # 90 degrees about z: body x lies along world y.
    assert m.initial.W_R_B[0] @ [1, 0, 0] == pytest.approx([0, 1, 0])


def test_zero_quaternion(model_file):
    text = SPATIAL + "    orientation: {quaternion: [0, 0, 0, 0]}\n"
    problem(model_file, text, "[0, 0, 0, 0]", "bodies[0].orientation.quaternion",
            "the quaternion is zero", hint="identity is [1, 0, 0, 0]")


def test_quaternion_needs_four(model_file):
    text = SPATIAL + "    orientation: {quaternion: [0, 0, 1]}\n"
    problem(model_file, text, "[0, 0, 1]", "bodies[0].orientation.quaternion",
            "expected 4 components, got 3")


def test_non_unit_quaternion_is_normalised_with_a_warning(model_file):
    m = ok(model_file, SPATIAL + "    orientation: {quaternion: [2, 0, 0, 0]}\n")
    assert m.initial.quaternion[0].tolist() == [1, 0, 0, 0]
    (w,) = m.warnings
    assert w.key == "bodies[0].orientation.quaternion" and "norm 2" in w.message
    assert w.line == 7


def test_euler_angles_with_sequence(model_file):
    text = SPATIAL + "    orientation: {euler: [90 deg, 0, 0], sequence: ZYX}\n"
    m = ok(model_file, text)
    assert m.initial.W_R_B[0] @ [1, 0, 0] == pytest.approx([0, 1, 0])
    # Intrinsic Z-Y'-X'' (the default): yaw then pitch about the new y axis.
    m = ok(model_file, SPATIAL + "    orientation: {euler: [90 deg, 90 deg, 0]}\n")
    assert m.initial.W_R_B[0] @ [1, 0, 0] == pytest.approx([0, 0, -1])


@pytest.mark.parametrize("seq", ["ZZX", "XYW", "ZYx", "ZY", "123"])
def test_bad_euler_sequence(model_file, seq):
    text = SPATIAL + f"    orientation: {{euler: [0, 0, 0], sequence: '{seq}'}}\n"
    i = problem(model_file, text, f"'{seq}'", "bodies[0].orientation.sequence",
                f"invalid Euler sequence '{seq}'")
    assert "ZYX (intrinsic, upper case)" in i.hint


def test_euler_needs_three_angles(model_file):
    text = SPATIAL + "    orientation: {euler: [0, 0]}\n"
    problem(model_file, text, "[0, 0]", "bodies[0].orientation.euler",
            "expected 3 components, got 2")


def test_euler_angle_text_is_checked(model_file):
    text = SPATIAL + "    orientation: {euler: [0, 30 degs, 0]}\n"
    problem(model_file, text, "30 degs", "bodies[0].orientation.euler[1]", "'30 deg'")


def test_rotation_matrix(model_file):
    text = SPATIAL + "    orientation: {matrix: [[0, -1, 0], [1, 0, 0], [0, 0, 1]]}\n"
    m = ok(model_file, text)
    assert m.initial.W_R_B[0] == pytest.approx(np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]]))


@pytest.mark.parametrize(("matrix", "words"), [
    ("[[1, 0, 0], [0, 1, 0], [0, 0, 2]]", "R^T R differs from I by up to 3"),
    ("[[1, 0, 0], [0, 1, 0], [0, 0, -1]]", "determinant -1 (a reflection)"),
    ("[[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]", "R^T R differs from I by up to 0.1"),
])
def test_matrix_must_be_a_rotation(model_file, matrix, words):
    text = SPATIAL + f"    orientation: {{matrix: {matrix}}}\n"
    i = problem(model_file, text, matrix, "bodies[0].orientation.matrix",
                "not a rotation matrix: " + words)
    assert "orthonormal" in i.hint and "determinant +1" in i.hint


def test_exactly_one_orientation_form(model_file):
    text = SPATIAL + "    orientation: {quaternion: [1, 0, 0, 0], euler: [0, 0, 0]}\n"
    problem(model_file, text, "{quaternion", "bodies[0].orientation",
            "give exactly one of 'quaternion', 'euler' or 'matrix'", "(got quaternion, euler)")


def test_sequence_goes_with_euler(model_file):
    text = SPATIAL + "    orientation: {quaternion: [1, 0, 0, 0], sequence: ZYX}\n"
    problem(model_file, text, "sequence", "bodies[0].orientation.sequence",
            "'sequence' goes with 'euler'", hint="remove it, or give the angles as euler")


def test_misspelt_orientation_form(model_file):
    text = SPATIAL + "    orientation: {quaternoin: [1, 0, 0, 0]}\n"
    found = problems(model_file, text)
    assert found[0].key == "bodies[0].orientation.quaternoin"
    assert found[0].hint == "did you mean 'quaternion'?"
    assert (found[0].line, found[0].column) == mark_of(text, "quaternoin")


# == 3. Loads =========================================================================

def test_load_type_missing(model_file):
    text = PLANAR + "loads:\n  - {body: plate, force: [1, 0]}\n"
    i = problem(model_file, text, "{body", "loads[0]", "missing required key 'type'")
    assert "force, torque, spring" in i.hint


def test_load_type_misspelt(model_file):
    text = PLANAR + "loads:\n  - {type: forse, body: plate, force: [1, 0]}\n"
    problem(model_file, text, "forse", "loads[0].type", "unknown load type 'forse'",
            hint="did you mean 'force'?")


def test_load_key_misspelt(model_file):
    text = PLANAR + "loads:\n  - {type: force, body: plate, force: [1, 0], frme: body}\n"
    problem(model_file, text, "frme", "loads[0].frme", "unknown key 'frme'",
            hint="did you mean 'frame'?")


def test_load_body_misspelt(model_file):
    text = PLANAR + "loads:\n  - {type: force, body: plat, force: [1, 0]}\n"
    problem(model_file, text, "plat,", "loads[0].body", "no body named 'plat'",
            hint="did you mean 'plate'?")


def test_load_body_far_from_any_lists_the_bodies(model_file):
    text = PLANAR + "loads:\n  - {type: force, body: zz, force: [1, 0]}\n"
    i = problem(model_file, text, "zz", "loads[0].body", "no body named 'zz'")
    assert i.hint == "bodies are: plate"


def test_force_on_ground_is_refused(model_file):
    text = PLANAR + "loads:\n  - {type: force, body: ground, force: [1, 0]}\n"
    problem(model_file, text, "ground", "loads[0].body", "'ground' is not allowed here")


def test_load_frame_misspelt(model_file):
    text = PLANAR + "loads:\n  - {type: force, body: plate, force: [1, 0], frame: wrld}\n"
    problem(model_file, text, "wrld", "loads[0].frame", "unknown frame 'wrld'",
            hint="did you mean 'world'?")


def test_force_needs_its_vector(model_file):
    text = PLANAR + "loads:\n  - {type: force, body: plate}\n"
    problem(model_file, text, "{type", "loads[0]", "missing required key 'force'")


@pytest.mark.parametrize(("base", "load", "needle", "key", "words"), [
    (PLANAR, "{type: force, body: plate, force: [1, 0, 0]}", "[1, 0, 0]", "loads[0].force",
     "expected 2 components, got 3"),
    (PLANAR, "{type: force, body: plate, force: [1, 0], at: [0, 0, 1]}", "[0, 0, 1]",
     "loads[0].at", "expected 2 components, got 3"),
    (SPATIAL, "{type: force, body: rotor, force: [1, 0]}", "[1, 0]", "loads[0].force",
     "expected 3 components, got 2"),
    (PLANAR, "{type: torque, body: plate, torque: [0, 0, 2]}", "[0, 0, 2]", "loads[0].torque",
     "a planar torque is a scalar"),
    (SPATIAL, "{type: torque, body: rotor, torque: 2}", "2}", "loads[0].torque",
     "expected a list of 3 numbers"),
    (SPATIAL, "{type: force, body: rotor, force: [1, 0, .inf]}", ".inf", "loads[0].force[2]",
     "expected a finite number"),
])
def test_load_vectors(model_file, base, load, needle, key, words):
    text = base + f"loads:\n  - {load}\n"
    problem(model_file, text, needle, key, words)


def test_torque_has_no_point(model_file):
    text = PLANAR + "loads:\n  - {type: torque, body: plate, torque: 2, at: [0, 1]}\n"
    problem(model_file, text, "at:", "loads[0].at", "unknown key 'at'")


def test_duplicate_load_names(model_file):
    text = PLANAR + ("loads:\n  - {name: push, type: force, body: plate, force: [1, 0]}\n"
                     "  - {name: push, type: torque, body: plate, torque: 1}\n")
    problem(model_file, text, "push", "loads[1].name", "duplicate load name 'push'", nth=2,
            hint="first used by loads[0]")


def test_generated_load_names(model_file):
    m = ok(model_file, PLANAR + "loads:\n  - {type: force, body: plate, force: [1, 0]}\n"
           "  - {type: torque, body: plate, torque: 1}\n"
           "  - {type: force, body: plate, force: [0, 1]}\n")
    assert [ld.name for ld in m.loads] == ["force1", "torque1", "force2"]


def test_generated_names_avoid_names_given_in_the_file(model_file):
    # The unnamed force would be force1, but a later load is called that.
    m = ok(model_file, PLANAR + "loads:\n  - {type: force, body: plate, force: [1, 0]}\n"
           "  - {name: force1, type: force, body: plate, force: [0, 1]}\n")
    assert [ld.name for ld in m.loads] == ["force2", "force1"]


SPRING = "loads:\n  - {type: spring, bodies: [ground, plate], at: [[0, 1], [0, 0]], " \
         "stiffness: 100, rest_length: 0.5, damping: 2}\n"


def test_valid_spring(model_file):
    (s,) = ok(model_file, PLANAR + SPRING).loads
    assert (s.stiffness, s.rest_length, s.damping, s.bodies) == (100, 0.5, 2,
                                                                 ("ground", "plate"))


@pytest.mark.parametrize(("old", "new", "needle", "key", "words"), [
    ("stiffness: 100", "stiffness: -1", "-1", "loads[0].stiffness", "expected a number >= 0"),
    ("damping: 2", "damping: -2", "-2", "loads[0].damping", "expected a number >= 0"),
    ("rest_length: 0.5", "rest_length: .nan", ".nan", "loads[0].rest_length",
     "expected a finite number"),
    ("[ground, plate]", "[plate]", "[plate]", "loads[0].bodies",
     "expected two body names (or ground), got a list of 1"),
    ("[ground, plate]", "[plate, plate]", "[plate, plate]", "loads[0].bodies",
     "a spring needs two different ends"),
    ("[ground, plate]", "[groud, plate]", "groud", "loads[0].bodies[0]",
     "no body named 'groud'"),
    ("[[0, 1], [0, 0]]", "[[0, 1]]", "[[0, 1]]", "loads[0].at", "expected two attachment"),
    ("[[0, 1], [0, 0]]", "[[0, 1], [0, 0, 0]]", "[0, 0, 0]", "loads[0].at[1]",
     "expected 2 components, got 3"),
    ("stiffness: 100, ", "", "{type", "loads[0]", "missing required key 'stiffness'"),
    ("damping: 2", "damp: 2", "damp", "loads[0].damp", "unknown key 'damp'"),
])
def test_spring_rules(model_file, old, new, needle, key, words):
    text = PLANAR + SPRING.replace(old, new)
    i = problem(model_file, text, needle, key, words)
    if "groud" in new:
        assert i.hint == "did you mean 'ground'?"
    if "damp:" in new:
        assert i.hint == "did you mean 'damping'?"


# == 4. Joints ========================================================================

PIN = "joints:\n  - {name: A, type: revolute, parent: ground, child: plate, at: [0, 0]}\n"
HINGE = ("joints:\n  - {name: A, type: revolute, parent: ground, child: rotor, "
         "at: [0, 0, 0], axis: [0, 0, 1]}\n")


def test_valid_joints(model_file):
    m = ok(model_file, PLANAR + PIN)
    assert m.reactions == ["A.Fx", "A.Fy"]
    m = ok(model_file, SPATIAL + HINGE)
    assert m.reactions == ["A.Fx", "A.Fy", "A.Fz", "A.Mx", "A.My"]


def test_joint_type_misspelt(model_file):
    text = PLANAR + PIN.replace("revolute", "revolut")
    problem(model_file, text, "revolut", "joints[0].type", "unknown planar joint type "
            "'revolut'", hint="did you mean 'revolute'?")


@pytest.mark.parametrize("typ", ["spherical", "universal", "cylindrical"])
def test_spatial_joint_types_are_not_planar(model_file, typ):
    text = PLANAR + PIN.replace("revolute", typ)
    problem(model_file, text, typ, "joints[0].type", f"'{typ}' is a spatial joint type",
            "a planar model (dimension: 2) has: revolute, prismatic, fixed")


def test_unknown_spatial_joint_type_lists_them(model_file):
    text = SPATIAL + HINGE.replace("revolute", "bearing")  # weld: test_hardening's synonyms
    i = problem(model_file, text, "bearing", "joints[0].type",
                "unknown spatial joint type 'bearing'")
    assert i.hint == ("expected one of: revolute, prismatic, cylindrical, universal, "
                      "spherical, fixed, helical")


@pytest.mark.parametrize("typ", ["revolute", "prismatic", "cylindrical", "universal"])
def test_spatial_axis_required(model_file, typ):
    text = SPATIAL + HINGE.replace("revolute", typ).replace(", axis: [0, 0, 1]", "")
    found = problems(model_file, text)
    axis = [i for i in found if "needs an 'axis'" in i.message]
    assert len(axis) == 1 and axis[0].key == "joints[0]"
    assert (axis[0].line, axis[0].column) == mark_of(text, "{name: A")


def test_planar_prismatic_without_an_axis_slides_along_world_x(model_file):
    """docs/model-format.md: a planar `axis` defaults to world x. A 10 kg plate on such a
    slider, pushed by (3, 4) N at its mass centre with 2 N m: it slides along x at
    3/10 m/s², the joint holds the y force (Fy = -4 N) and the couple (Mz = -2 N m), as
    with `axis: [1, 0]` written out."""
    push = ("loads:\n  - {type: force, body: plate, force: [3, 4]}\n"
            "  - {type: torque, body: plate, torque: 2}\n")
    slider = PIN.replace("revolute", "prismatic")
    m = ok(model_file, PLANAR + push + slider)
    assert m.reactions == ["A.Fy", "A.Mz"]
    assert m.joints[0].axis is None
    np.testing.assert_array_equal(m.joints[0].W_E0, np.eye(3))
    sol = mbody.assemble(m).solve()
    np.testing.assert_allclose(sol.accelerations, [0.3, 0.0, 0.0], atol=1e-15)
    assert sol.reactions["A.Fy"] == pytest.approx(-4.0, rel=1e-14)
    assert sol.reactions["A.Mz"] == pytest.approx(-2.0, rel=1e-14)
    written = ok(model_file, PLANAR + push + slider.replace("at: [0, 0]",
                                                            "at: [0, 0], axis: [1, 0]"))
    np.testing.assert_array_equal(mbody.assemble(written).solve().accelerations,
                                  sol.accelerations)
    # the slide direction in turn: along world y when written
    up = ok(model_file, PLANAR + push + slider.replace("at: [0, 0]", "at: [0, 0], axis: [0, 1]"))
    np.testing.assert_allclose(mbody.assemble(up).solve().accelerations, [0.0, 0.4, 0.0],
                               atol=1e-15)


def test_planar_prismatic_without_an_axis_on_the_command_line(model_file, capsys):
    from mbody.cli import main

    model_file.write_text(PLANAR + PIN.replace("revolute", "prismatic"))
    assert main(["check", str(model_file)]) == 0
    out = capsys.readouterr().out
    assert "prismatic ground -> plate at (0, 0): A.Fy, A.Mz" in out


@pytest.mark.parametrize("typ", ["spherical", "fixed"])
def test_axis_optional_where_the_type_needs_none(model_file, typ):
    m = ok(model_file, SPATIAL + HINGE.replace("revolute", typ).replace(", axis: [0, 0, 1]",
                                                                         ""))
    assert len(m.reactions) == {"spherical": 3, "fixed": 6}[typ]


def test_zero_axis(model_file):
    text = SPATIAL + HINGE.replace("axis: [0, 0, 1]", "axis: [0, 0, 0]")
    problem(model_file, text, "[0, 0, 0]}", "joints[0].axis", "the axis is the zero vector",
            hint="give a direction")


def test_axis_length_follows_the_dimension(model_file):
    text = SPATIAL + HINGE.replace("axis: [0, 0, 1]", "axis: [0, 1]")
    problem(model_file, text, "[0, 1]", "joints[0].axis", "expected 3 components, got 2")


UJOINT = ("joints:\n  - {name: U, type: universal, parent: ground, child: rotor, "
          "at: [0, 0, 0], axis: [1, 0, 0], axis2: [0, 1, 0]}\n")


def test_universal_joint(model_file):
    assert ok(model_file, SPATIAL + UJOINT).reactions == ["U.Fx", "U.Fy", "U.Fz", "U.Mt"]


def test_universal_axes_must_be_perpendicular(model_file):
    text = SPATIAL + UJOINT.replace("axis2: [0, 1, 0]", "axis2: [1, 1, 0]")
    i = problem(model_file, text, "[1, 1, 0]", "joints[0].axis2",
                "a universal joint's axes must be perpendicular")
    assert i.hint == "axis . axis2 = 0.707"


def test_universal_needs_axis2(model_file):
    text = SPATIAL + UJOINT.replace(", axis2: [0, 1, 0]", "")
    problem(model_file, text, "{name: U", "joints[0]", "a universal joint needs 'axis2'")


def test_axis2_belongs_to_universal_joints(model_file):
    text = SPATIAL + HINGE.replace("axis: [0, 0, 1]", "axis: [0, 0, 1], axis2: [1, 0, 0]")
    problem(model_file, text, "axis2", "joints[0].axis2", "'axis2' belongs to universal joints",
            hint="use type: universal")


def test_joint_parent_misspelt(model_file):
    text = PLANAR + PIN.replace("parent: ground", "parent: grund")
    problem(model_file, text, "grund", "joints[0].parent", "no body named 'grund'",
            hint="did you mean 'ground'?")


def test_joint_child_misspelt(model_file):
    text = PLANAR + PIN.replace("child: plate", "child: plaet")
    problem(model_file, text, "plaet", "joints[0].child", "no body named 'plaet'",
            hint="did you mean 'plate'?")


def test_joint_child_must_not_be_its_parent(model_file):
    text = PLANAR + PIN.replace("parent: ground", "parent: plate")
    problem(model_file, text, "plate, at", "joints[0].child",
            "the joint connects 'plate' to itself", hint="must be different bodies")


def test_joint_child_must_not_be_ground(model_file):
    text = PLANAR + PIN.replace("parent: ground, child: plate", "parent: plate, child: ground")
    i = problem(model_file, text, "ground, at", "joints[0].child",
                "the child of a joint must be a body")
    assert i.hint == "put ground as the parent"


def test_joint_needs_a_point(model_file):
    text = PLANAR + PIN.replace(", at: [0, 0]", "")
    i = problem(model_file, text, "{name: A", "joints[0]", "missing required key 'at'")
    assert "world coordinates" in i.hint


def test_joint_point_length(model_file):
    text = PLANAR + PIN.replace("at: [0, 0]", "at: [0, 0, 0]")
    problem(model_file, text, "[0, 0, 0]", "joints[0].at", "expected 2 components, got 3")


def test_duplicate_joint_names(model_file):
    text = PLANAR + PIN + "  - {name: A, type: fixed, parent: ground, child: plate, at: [1, 0]}\n"
    problem(model_file, text, "A", "joints[1].name", "duplicate joint name 'A'", nth=2,
            hint="first used by joints[0]")


def test_joint_name_without_dot(model_file):
    text = PLANAR + PIN.replace("name: A", "name: A.1")
    i = problem(model_file, text, "A.1", "joints[0].name", "may not contain '.'")
    assert "<joint>.<component>" in i.hint


def test_unknown_joint_key(model_file):
    text = PLANAR + PIN.replace("at: [0, 0]", "at: [0, 0], axsi: [1, 0]")
    problem(model_file, text, "axsi", "joints[0].axsi", "unknown key 'axsi'",
            hint="did you mean 'axis'?")


# -- known reactions ------------------------------------------------------------------

def test_known_reactions(model_file):
    m = ok(model_file, PLANAR + PIN + "reactions: {A.Fx: 0, A.Fy: 98.1}\n")
    assert m.known_reactions == {"A.Fx": 0.0, "A.Fy": 98.1}


def test_reaction_label_misspelt(model_file):
    text = PLANAR + PIN + "reactions: {A.fx: 1}\n"
    problem(model_file, text, "A.fx", "reactions.A.fx", "no reaction component 'A.fx'",
            hint="did you mean 'A.Fx'?")


def test_reaction_component_the_joint_does_not_have(model_file):
    # A planar pin transmits no moment: there is no A.Mz to know.
    text = PLANAR + PIN + "reactions: {A.Fx: 1, Q.Mz: 2}\n"
    i = problem(model_file, text, "Q.Mz", "reactions.Q.Mz", "no reaction component 'Q.Mz'")
    assert i.hint == "the model's reaction components are: A.Fx, A.Fy"


def test_reactions_without_joints(model_file):
    text = PLANAR + "reactions: {A.Fx: 1}\n"
    i = problem(model_file, text, "A.Fx", "reactions.A.Fx", "no reaction component")
    assert i.hint == "the model has no joints"


def test_reaction_value_must_be_a_number(model_file):
    text = PLANAR + PIN + "reactions: {A.Fx: true}\n"
    problem(model_file, text, "true", "reactions.A.Fx", "expected a number, got a boolean")


def test_reactions_must_be_a_mapping(model_file):
    text = PLANAR + PIN + "reactions: [A.Fx]\n"
    problem(model_file, text, "[A.Fx]", "reactions", "expected a mapping of reaction labels")


# == No cascades: one mistake, one message ============================================

def test_a_body_with_a_bad_field_can_still_be_referenced(model_file):
    text = PLANAR.replace("mass: 10", "mass: -10") + PIN + SPRING
    problem(model_file, text, "-10", "bodies[0].mass", "expected a number > 0")


def test_a_joint_with_a_bad_point_keeps_its_reaction_labels(model_file):
    text = PLANAR + PIN.replace("at: [0, 0]", "at: [0, x]") + "reactions: {A.Fx: 1}\n"
    problem(model_file, text, "x]", "joints[0].at[1]", "expected a number, got the text 'x'")


def test_an_invalid_dimension_stops_before_vector_checks(model_file):
    text = PLANAR.replace("dimension: 2", "dimension: 5") + "gravity: [0, -9.81]\n"
    problem(model_file, text, "5", "dimension", "expected 2 (planar) or 3 (spatial), got the "
            "number 5")


@pytest.mark.parametrize("value", ["[revolute]", "{a: 1}", "3"])
def test_joint_type_that_is_not_text(model_file, value):
    text = PLANAR + PIN.replace("type: revolute", f"type: {value}")
    problem(model_file, text, value, "joints[0].type", "unknown planar joint type")


def test_numbers_too_large_to_multiply(model_file):
    text = PLANAR + "    position: [1e200, 0]\n"
    i = problem(model_file, text, "1e200", "bodies[0].position[0]",
                "expected a number of magnitude at most 1e+100, got 1e+200")
    assert "overflow" in i.hint


# == Any damage to a shipped model: a ModelError, never another exception ==============

MODELS = Path(__file__).resolve().parent.parent / "models"
_JUNK = [None, True, "x", -1, 0, [], {}, [1, 2], [1, 2, 3], [0, 0, 0, 0], {"a": 1},
         math.nan, "30 deg", 1e300, "ground", [[1, 0], [0, 1]], "revolute", "DELETE"]


def _paths(x, p=()):
    yield p
    items = x.items() if isinstance(x, dict) else enumerate(x) if isinstance(x, list) else ()
    for k, v in items:
        yield from _paths(v, (*p, k))


def test_damaged_models_raise_model_error_only():
    import copy
    import random

    import yaml

    rng = random.Random(20240)
    cases = []
    for f in sorted(MODELS.glob("*.yaml")):
        base = yaml.safe_load(f.read_text())
        cases += [(f.name, base, p, v) for p in _paths(base) if p for v in _JUNK]
    refused = 0
    for name, base, p, v in rng.sample(cases, min(len(cases), 3000)):
        d = copy.deepcopy(base)
        parent = d
        for k in p[:-1]:
            parent = parent[k]
        if v == "DELETE":
            del parent[p[-1]]
        else:
            parent[p[-1]] = copy.deepcopy(v)
        try:
            model = mbody.load(d)
        except ModelError as exc:
            refused += 1
            assert exc.issues and all(i.message for i in exc.issues)
            continue
        except Exception as exc:  # pragma: no cover - the failure message is the point
            pytest.fail(f"{name}: setting {p} to {v!r} raised {type(exc).__name__}: {exc}")
        mbody.assemble(model)  # a model that loads must assemble
    assert refused > 1000  # most damage is caught: the sample is not all harmless


@pytest.mark.parametrize(("section", "text", "needle", "key", "hint"), [
    ("spring", PLANAR + SPRING.replace("at: [[0, 1], [0, 0]], ", ""), "{type", "at",
     "the two attachment points: body axes, or world for ground"),
    ("spring", PLANAR + SPRING.replace("bodies: [ground, plate], ", ""), "{type", "bodies",
     "the two ends: [body, body] or [ground, body]"),
    ("joint", PLANAR + PIN.replace("child: plate, ", ""), "{name: A", "child", "a body name"),
    ("force", PLANAR + "loads:\n  - {type: force, force: [1, 0]}\n", "{type", "body",
     "the name of the body it acts on"),
])
def test_missing_key_hints_fit_their_section(model_file, section, text, needle, key, hint):
    i = problem(model_file, text, needle, f"{'joints' if section == 'joint' else 'loads'}[0]",
                f"missing required key '{key}'")
    assert i.hint == hint


def test_thousands_of_problems_are_all_kept_but_the_message_stays_readable(model_file):
    text = "dimension: 2\nbodies:\n" + "".join(
        f"  - {{name: b{i}, mass: -1, inertia: 1}}\n" for i in range(2000))
    found = problems(model_file, text)
    assert len(found) == 2000 and found[-1].line == 2002
    with pytest.raises(ModelError) as err:
        mbody.load(model_file)
    msg = str(err.value)
    assert msg.startswith("2000 problems in the model:\n")
    assert msg.count("\n") == 1 + ModelError.SHOWN
    assert msg.endswith(f"... and {2000 - ModelError.SHOWN} more (fix these first; often they "
                        "repeat)")


def test_a_misspelt_required_key_is_one_problem_not_two(tmp_path):
    """`mas:` for `mass:` is reported once, as an unknown key pointing at 'mass'; the
    'missing required key' that follows from it would only repeat the same mistake."""
    path = tmp_path / "typo.yaml"
    path.write_text("dimension: 2\nbodies:\n  - name: plate\n    mas: 10\n    inertia: 0.5\n")
    with pytest.raises(mbody.ModelError) as info:
        mbody.load(path)
    issues = info.value.issues
    assert len(issues) == 1
    assert (issues[0].line, issues[0].column) == (4, 5)
    assert "unknown key 'mas'" in issues[0].message and "'mass'" in issues[0].hint


@pytest.mark.parametrize(("written", "rad_per_s"), [
    ("100 rpm", 100 * 2 * math.pi / 60), ("30 rev/min", math.pi), ("1 rev/s", 2 * math.pi),
    ("2 Hz", 4 * math.pi), ("90 deg/s", math.pi / 2), ("1.5 rad/s", 1.5)])
def test_a_bodys_angular_velocity_takes_a_drivers_rate_units(written, rad_per_s):
    """Review R7-13: a driver's speed took rpm, rev/s and Hz, a body's angular velocity
    refused them; one table now serves both (the same conversion, to the last bit)."""
    root = Path(__file__).resolve().parents[1] / "models"
    planar = mbody.load(root / "pendulum.yaml").with_values(
        {"bodies.rod.angular_velocity": written})
    assert planar.initial.omega[0, 2] == pytest.approx(rad_per_s, rel=4e-16, abs=0)
    spatial = mbody.load(root / "heavy_top.yaml")
    name = spatial.body_names[0]
    w = spatial.with_values({f"bodies.{name}.angular_velocity": [written, 0, 0]}).initial
    assert w.omega[0, 0] == planar.initial.omega[0, 2]
    driven = mbody.load(root / "slider_crank_driven.yaml").with_values(
        {"drivers.motor.speed": written})
    assert driven.drivers.laws[0][1](0.0) == planar.initial.omega[0, 2]


def test_a_prefixed_rate_unit_is_refused_with_its_conversion():
    root = Path(__file__).resolve().parents[1] / "models"
    with pytest.raises(ModelError, match="0.1 krpm is 100 rpm"):
        mbody.load(root / "pendulum.yaml").with_values(
            {"bodies.rod.angular_velocity": "0.1 krpm"})
