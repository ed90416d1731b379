"""Which values a student's ``set:`` may change (`--allow-set`, review R5-3): a ``set:``
can change anything the model file holds, so a file that leaves gravity out of every row
and sets gravity to zero would otherwise grade all correct."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import mbody
from mbody.answers.load import AnswersError
from mbody.answers.summary import grade
from mbody.answers.variant import allow_list
from mbody.errors import MbodyError

MODEL = Path(__file__).resolve().parents[1] / "models" / "double_pendulum.yaml"

# the lower rod's rows with gravity left out: right only in a world without gravity
NO_GRAVITY = ('student: Ben\nset: {gravity: [0, 0]}\nequations:\n'
              '  - {body: lower, eq: "m*a_x = A.Fx"}\n  - {body: lower, eq: "m*a_y = A.Fy"}\n')
# Eve's own mass and inertia (I_G = m L^2 / 12 = 1.5 * 0.5^2 / 12)
EVE = ('student: Eve\nset: {bodies.lower.mass: 1.5, bodies.lower.inertia: 0.03125}\n'
       'equations:\n  - {body: lower, eq: "1.5*a_x = A.Fx"}\n'
       '  - {body: lower, eq: "m*a_y = A.Fy - 14.715"}\n')


@pytest.fixture
def files(tmp_path):
    out = {}
    for name, text in (("ben", NO_GRAVITY), ("eve", EVE)):
        out[name] = tmp_path / f"{name}.yaml"
        out[name].write_text(text)
    return out


def test_without_an_allow_list_a_set_changes_the_physics_and_the_summary_says_so(files):
    model = mbody.load(MODEL)
    v = mbody.verify(model, files["ben"])
    assert v.correct == 2  # the rows of a world without gravity: why the list is needed
    summary = grade(model, [files["ben"], files["eve"]], require="lower.x")
    assert "2 files set their own values" in summary.text()
    assert "any path was allowed" in summary.text()


def test_a_path_the_list_does_not_allow_is_that_files_error(files):
    model = mbody.load(MODEL)
    allow = "bodies.lower.mass,bodies.lower.inertia"
    with pytest.raises(AnswersError) as e:
        mbody.verify(model, files["ben"], allow_set=allow)
    (issue,) = e.value.issues
    assert (issue.line, issue.column, issue.key) == (2, 7, "set.gravity")
    assert "bodies.lower.mass, bodies.lower.inertia" in issue.message
    assert mbody.verify(model, files["eve"], allow_set=allow).all_correct is False  # rows
    assert mbody.verify(model, files["eve"], allow_set=allow).correct == 2
    summary = grade(model, [files["ben"], files["eve"]], require="lower.x", allow_set=allow)
    ben, eve = summary.graded
    assert ben.verification is None and "set.gravity" in ben.error
    assert ben.student == "Ben"  # the file's student line, read before its set: failed
    assert eve.all_correct
    assert "a file may set bodies.lower.mass, bodies.lower.inertia" in summary.text()


@pytest.mark.parametrize("allow", ["bodies.*.mass,bodies.*.inertia", "bodies.lower",
                                   ["bodies.lower.mass", "bodies.lower.inertia"]])
def test_wildcards_whole_entries_and_lists_allow(files, allow):
    assert mbody.verify(mbody.load(MODEL), files["eve"], allow_set=allow).correct == 2


@pytest.mark.parametrize("allow", ["*", "bodies.*", "bodies.lower.*", "bodies.*.inertia",
                                   "gravity.?", "joints.*.at.0", "bodies.*.color"])
def test_a_pattern_matching_some_path_of_the_model_is_accepted(allow):
    """Matched against every path the model file could take, the keys it leaves out
    (a colour) and the components of those it gives (a joint point's x) included."""
    assert allow_list(mbody.load(MODEL), allow) == (allow,)


def test_a_component_is_allowed_by_its_path(tmp_path):
    f = tmp_path / "g.yaml"
    f.write_text('set: {gravity.1: -9.81}\nequations:\n  - {body: lower, eq: "m*a_x = A.Fx"}\n')
    assert mbody.verify(mbody.load(MODEL), f, allow_set="gravity").correct == 1
    with pytest.raises(AnswersError):
        mbody.verify(mbody.load(MODEL), f, allow_set="bodies.lower.mass")


@pytest.mark.parametrize("allow, said", [
    ("bodies.lower.mas", "did you mean 'mass'"),
    ("bodies.lower.mass,", "an empty path"),
    ("gravty", "gravity"),
    # a pattern matching no path (review R6-6): would refuse every file that sets a value
    ("bodies.*.mas", "matches no path of the model.*did you mean 'bodies.upper.mass'"),
    ("gravity[1]", "matches no path.*did you mean 'gravity.1'"),
    ("joints.*.speed", "matches no path"),
])
def test_a_pattern_naming_nothing_is_refused_before_any_file(files, allow, said):
    with pytest.raises(MbodyError, match=said):
        mbody.verify(mbody.load(MODEL), files["eve"], allow_set=allow)
    with pytest.raises(MbodyError, match=said):
        grade(mbody.load(MODEL), [files["eve"]], allow_set=allow)


def test_the_command_line(files, tmp_path):
    def run(*args):
        return subprocess.run([sys.executable, "-m", "mbody", "verify", str(MODEL), *args],
                              capture_output=True, text=True)

    r = run(str(files["ben"]), "--allow-set", "bodies.lower.mass")
    assert r.returncode == 2 and "--allow-set" in r.stderr and "Traceback" not in r.stderr
    r = run(str(files["ben"]), "--allow-set", "bodies.lower.mas")
    assert r.returncode == 2 and "--allow-set bodies.lower.mas" in r.stderr
    r = run(str(files["ben"]), str(files["eve"]), "--summary", str(tmp_path / "s.csv"),
            "--allow-set", "bodies.lower.mass", "--allow-set", "bodies.lower.inertia")
    assert r.returncode == 1
    assert "a file may set bodies.lower.mass, bodies.lower.inertia" in r.stdout


@pytest.mark.parametrize("given", [5, [1], ["bodies.lower.mass", 2.5]])
def test_require_and_allow_set_take_text_or_a_sequence_of_text(files, given):
    """Both read their words the same way (`errors.comma_words`): anything else is an
    MbodyTypeError naming the argument (a bare int was a raw TypeError from list())."""
    from mbody.errors import MbodyTypeError

    model = mbody.load(MODEL)
    with pytest.raises(MbodyTypeError, match="^allow_set: expected paths"):
        mbody.verify(model, files["eve"], allow_set=given)
    with pytest.raises(MbodyTypeError, match="^require: expected words"):
        mbody.verify(model, files["eve"], require=given)
