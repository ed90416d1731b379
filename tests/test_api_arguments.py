"""What the public functions take, checked where it comes in (`mbody.model.arguments`, and
`State` itself): a state of another model, a dict where a state goes, values that are not
finite, known reaction values of the wrong kind, numbers given as text or bools, a path
where a model goes. Each refusal names the argument and what it takes, in mbody's words
(an `MbodyError`; an `MbodyTypeError`, also a `TypeError`, for a wrong type), before
any work; and what is right still gives the numbers it did."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.errors import MbodyTypeError
from mbody.solve.configure import configure

MODELS = Path(__file__).resolve().parent.parent / "models"


@pytest.fixture(scope="module")
def pendulum() -> mbody.Model:
    return mbody.load(MODELS / "pendulum.yaml")


@pytest.fixture(scope="module")
def double() -> mbody.Model:
    return mbody.load(MODELS / "double_pendulum.yaml")


def _one_body(position=(0.0, 0.0, 0.0), quaternion=(1.0, 0.0, 0.0, 0.0)) -> mbody.State:
    return mbody.State([list(position)], [list(quaternion)], [[0.0] * 3], [[0.0] * 3])


# -- a state: its model's bodies, finite values ------------------------------------------

WRONG_STATE = {
    "assemble": lambda m, s: mbody.assemble(m, s),
    "linearize": lambda m, s: mbody.linearize(m, s),
    "simulate": lambda m, s: mbody.simulate(m, 0.1, 10, initial=s),
    "equilibrium": lambda m, s: mbody.equilibrium(m, start=s),
    "kinematics": lambda m, s: mbody.kinematics(m, 0.0, start=s),
    "configure": lambda m, s: configure(m, {}, start=s),
    "generalized": lambda m, s: mbody.equations.generalized.generalized(m, s),
    "solve_many": lambda m, s: mbody.solve_many(m, [m.initial, s]),
}
ARGUMENT = {"assemble": "state", "linearize": "state", "simulate": "initial",
            "equilibrium": "start", "kinematics": "start", "configure": "start",
            "generalized": "state", "solve_many": r"states\[1\]"}


@pytest.mark.parametrize("call", WRONG_STATE)
def test_a_state_of_another_model_is_refused_naming_the_argument_and_the_bodies(
        call, pendulum, double):
    """The pendulum's one-body state given for the double pendulum: refused where it comes
    in (it used to fail in the compiled core: 'y: expected 28 values'), with the model's
    bodies named and the grammar of one body."""
    with pytest.raises(mbody.MbodyError,
                       match=rf"^{ARGUMENT[call]} has 1 body, model 'double-pendulum' has 2 "
                             r"\(upper, lower\): a state of another model\?$"):
        WRONG_STATE[call](double, pendulum.initial)


@pytest.mark.parametrize("call", WRONG_STATE)
def test_a_dict_where_a_state_goes_is_a_type_error_that_points_to_configure(call, pendulum):
    with pytest.raises(MbodyTypeError) as err:
        WRONG_STATE[call](pendulum, {"O.angle": 0.1})
    text = str(err.value)
    assert isinstance(err.value, TypeError)
    assert text.startswith(f"{ARGUMENT[call].replace(chr(92), '')} must be a State (")
    assert "got dict; for the state at given joint coordinates ({'O.angle': 0.1}) use " \
        "mbody.solve.configure.configure(model, {...})" in text
    # the function it points to exists and does that
    turned = mbody.solve.configure.configure(pendulum, {"O.angle": 0.1})
    assert 2 * math.atan2(turned.quaternion[0, 3], turned.quaternion[0, 0]) == \
        pytest.approx(0.1, abs=1e-12)


@pytest.mark.parametrize("call", WRONG_STATE)
def test_values_that_are_not_finite_and_a_zero_quaternion_are_refused(call, pendulum):
    for state, match in (
            (_one_body((0.0, math.nan, 0.0)),
             r"position of body 'rod' is \[0.0, nan, 0.0\]: not finite$"),
            (_one_body((0.0, -math.inf, 0.0)), r"position of body 'rod' is .*: not finite$"),
            (pendulum.initial.replace(omega=np.array([[0.0, 0.0, math.nan]])),
             r"omega of body 'rod' is \[0.0, 0.0, nan\]: not finite$"),
            (_one_body(quaternion=(0.0, 0.0, 0.0, 0.0)),
             r"quaternion of body 'rod' is 0, not a rotation")):
        with pytest.raises(mbody.MbodyError, match=rf"^{ARGUMENT[call]}\.{match}"):
            WRONG_STATE[call](pendulum, state)


def test_a_checked_state_gives_the_numbers_it_did(double):
    """A state written as lists is converted (it used to be kept as lists and fail in
    `.solve()`); with large finite values the quick sum overflows and the state still
    passes (the arrays are then looked at one by one)."""
    lists = mbody.State([[0.0, -0.25, 0.0], [0.0, -0.75, 0.0]], [[1, 0, 0, 0]] * 2,
                        [[0, 0, 0]] * 2, [[0, 0, 0]] * 2)
    assert lists.position.dtype == float and lists.quaternion.shape == (2, 4)
    arrays = mbody.State(np.array([[0.0, -0.25, 0.0], [0.0, -0.75, 0.0]]),
                         np.array([[1.0, 0, 0, 0]] * 2), np.zeros((2, 3)), np.zeros((2, 3)))
    np.testing.assert_array_equal(mbody.assemble(double, lists).solve().accelerations,
                                  mbody.assemble(double, arrays).solve().accelerations)
    far = arrays.replace(position=np.array([[1e200, 0.0, 0.0], [1e200, 0.0, 0.0]]))
    assert mbody.assemble(double, far).state is far
    many = mbody.load(MODELS / "triple_pendulum.yaml")  # and the vectorised path (n > 8)
    from mbody.model.arguments import SMALL, checked_state
    n = SMALL + 1
    big = mbody.State(np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)), np.zeros((n, 3)),
                      np.zeros((n, 3)))
    with pytest.raises(mbody.MbodyError, match=f"^s has {n} bodies, model "):
        checked_state(many, big, "s")
    big.position[SMALL, 1] = math.nan
    from mbody.model.arguments import _problem
    assert _problem(big) == ("position", SMALL, "[0.0, nan, 0.0]: not finite")
    big.position[SMALL, 1] = 0.0
    big.quaternion[3] = 0.0
    assert _problem(big)[:2] == ("quaternion", 3)


def test_solve_many_says_one_body(pendulum, double):
    with pytest.raises(mbody.MbodyError, match=r"^states\[0\] has 1 body, model "):
        mbody.solve_many(double, pendulum.initial)
    with pytest.raises(MbodyTypeError, match="^values must be a list of mappings, one "
                                             "per case"):
        mbody.solve_many(pendulum, values={"bodies.rod.mass": 2.0})
    with pytest.raises(MbodyTypeError, match=r"^values\[1\] must be a mapping path -> value"):
        mbody.solve_many(pendulum, values=[{"bodies.rod.mass": 2.0}, 3.0])


# -- State and State.planar themselves ----------------------------------------------------

def test_state_refuses_shapes_and_times_it_cannot_use():
    one = ([[0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0, 0.0]], [[0.0] * 3], [[0.0] * 3])
    with pytest.raises(MbodyTypeError, match=r"^State: t must be a number of seconds, got "
                                             r"str '0'$"):
        mbody.State(*one, "0")  # it used to be kept, and repr() then failed
    with pytest.raises(MbodyTypeError, match="got bool True"):
        mbody.State(*one, True)
    with pytest.raises(mbody.MbodyError, match="^State: t must be a finite number"):
        mbody.State(*one, math.nan)
    s = mbody.State(*one, np.float32(0.5))
    assert type(s.t) is float and s.t == 0.5 and "t = 0.5 s" in repr(s)
    with pytest.raises(mbody.MbodyError, match=r"^State: position must be an \(n, 3\) array, "
                                               r"one row per body, got shape \(3,\) \(one "
                                               r"body: \[\[\.\.\., \.\.\., \.\.\.\]\]\)$"):
        mbody.State(np.zeros(3), *one[1:])
    with pytest.raises(mbody.MbodyError, match=r"^State: position has 2 rows \(bodies\), "
                                               r"quaternion 1: one row per body in each$"):
        mbody.State(np.zeros((2, 3)), one[1], np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(MbodyTypeError, match=r"^State: velocity must be an \(n, 3\) array of "
                                             r"numbers, got list"):
        mbody.State(one[0], one[1], [[0.0, "fast", 0.0]], one[3])
    kept = np.zeros((1, 3))
    assert mbody.State(kept, *one[1:]).position is kept  # a float array is not copied


def test_state_planar_takes_one_body_as_scalars_and_names_a_mismatch():
    row = mbody.State.planar([[0.0, -0.5]], [0.3], [[1.0, 0.0]], [2.0], t=1.5)
    for scalars in (mbody.State.planar([0.0, -0.5], 0.3, [1.0, 0.0], 2.0, t=1.5),
                    mbody.State.planar([0.0, -0.5], [0.3], [1.0, 0.0], [2.0], t=1.5)):
        for name in ("position", "quaternion", "velocity", "omega"):
            np.testing.assert_array_equal(getattr(scalars, name), getattr(row, name))
    assert row.quaternion[0, 3] == pytest.approx(math.sin(0.15), abs=1e-15)
    rest = mbody.State.planar(np.zeros((2, 2)), [0.0, 1.0], 0, 0)  # 0: every body at rest
    assert rest.velocity.shape == (2, 3) and not rest.omega.any()
    with pytest.raises(mbody.MbodyError, match=r"^State.planar: position has 3 rows, angle 2: "
                                               "one per body in each$"):
        mbody.State.planar(np.zeros((3, 2)), np.zeros(2), np.zeros((2, 2)), np.zeros(2))
    with pytest.raises(mbody.MbodyError, match=r"^State.planar: velocity must be a \(2, 2\) "
                                               r"array \(one row per body; angle gives 2\), "
                                               r"got shape \(2,\)$"):
        mbody.State.planar(np.zeros((2, 2)), np.zeros(2), np.zeros(2), np.zeros(2))
    with pytest.raises(MbodyTypeError, match="^State.planar: angle must be an"):
        mbody.State.planar([0.0, 0.0], "30 deg", [0.0, 0.0], 0.0)


# -- simulate's numbers ---------------------------------------------------------------------

@pytest.mark.parametrize("value", [0, -1.0, math.nan])
@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_max_step_is_checked_up_front(pendulum, value, method):
    """0 used to end in 'the integration stopped at t = 4.9e-323 s', -1 with RK45 in
    scipy's own wording, NaN was accepted."""
    with pytest.raises(mbody.MbodyError, match=r"^max_step must be a positive number of "
                                               r"seconds \(inf: no bound\), got "
                                               f"{value:g}$"):
        mbody.simulate(pendulum, 0.1, 10, max_step=value, method=method)
    with pytest.raises(MbodyTypeError, match="^max_step must be .*, got str '0.01'; write it "
                                             "as a number: 0.01$"):
        mbody.simulate(pendulum, 0.1, 10, max_step="0.01", method=method)
    bounded = mbody.simulate(pendulum, 0.1, 10, max_step=0.001, method=method)
    free = mbody.simulate(pendulum, 0.1, 10, max_step=math.inf, method=method)
    assert bounded.info["steps"] >= 100 > free.info["steps"] >= 1


@pytest.mark.parametrize("kwargs, match", [
    ({"t_end": True}, "^t_end must be a positive number of seconds, got bool True$"),
    ({"fps": True}, "^fps must be a positive number of samples per second, got bool True$"),
    ({"t_end": "1"}, "^t_end must be a positive number of seconds, got str '1'; write it as "
                     "a number: 1.0$"),
    ({"t_end": [1.0]}, "^t_end must be a positive number of seconds, got list$"),
    ({"rtol": "1e-6"}, r"^rtol must be a number between 0 and 1 \(relative tolerance\), got "
                       "str '1e-6'; write it as a number: 1e-06$"),
    ({"atol": "1e-9"}, r"^atol must be a positive number \(absolute tolerance\), got str"),
])
def test_numbers_given_as_text_or_bools_are_type_errors(pendulum, kwargs, match):
    with pytest.raises(MbodyTypeError, match=match):
        mbody.simulate(pendulum, **{"t_end": 0.1, "fps": 10, **kwargs})


def test_a_last_sample_short_of_t_end_is_warned_with_the_fps_that_samples_it(pendulum):
    """fps < 1/t_end gave one sample at t = 0 for a one-second run, without a word."""
    run = mbody.simulate(pendulum, 1.0, 0.5)
    assert run.t.tolist() == [0.0]
    assert run.info["warnings"][0] == (
        "the last sample is at t = 0 s, short of t_end = 1 s: samples are every 1/fps = 2 s, "
        "and t_end * fps = 0.5 is not a whole number; for a sample at t_end, use fps = 1 (or "
        "a multiple of it) or t_end = 2")
    run = mbody.simulate(pendulum, 1.0, 7.5)
    assert run.t[-1] == pytest.approx(7 / 7.5, rel=1e-15)
    assert run.info["warnings"][0].startswith("the last sample is at t = 0.933333 s, short of "
                                              "t_end = 1 s")
    assert "use fps = 8 (or a multiple of it) or t_end = 1.06667" in run.info["warnings"][0]
    # quiet where t_end * fps is whole to within rounding (0.1 * 30 = 3.0000000000000004,
    # 0.3 * 60 = 17.999999999999996)
    for t_end, fps in ((0.1, 30), (0.3, 60), (1.0, 60)):
        run = mbody.simulate(pendulum, t_end, fps)
        assert run.t[-1] == pytest.approx(t_end, rel=1e-12)
        assert not any(w.startswith("the last sample") for w in run.info["warnings"])


def test_a_kinematic_run_short_of_t_end_is_warned_too():
    """A fully driven mechanism (simulate hands it to kinematic_run) says the same."""
    model = mbody.load(MODELS / "slider_crank_driven.yaml")
    for run in (mbody.kinematic_run(model, 0.1, 25), mbody.simulate(model, 0.1, 25)):
        assert run.t[-1] == pytest.approx(0.08, rel=1e-12)
        assert run.info["warnings"][0].startswith(
            "the last sample is at t = 0.08 s, short of t_end = 0.1 s")
    assert not any(w.startswith("the last sample") for w in
                   mbody.kinematic_run(model, 0.1, 30).info["warnings"])
    with pytest.raises(MbodyTypeError, match="^fps must be a positive number of samples per "
                                             "second, got str '30'; write it as a number: 30.0$"):
        mbody.kinematic_run(model, 0.1, "30")
    for bad in (math.nan, math.inf):  # the argument at fault is named (review R3, B9)
        with pytest.raises(mbody.MbodyError, match="^t_start must be a finite number of "
                                                   "seconds, got (nan|inf)$"):
            mbody.kinematic_run(model, 1.0, 10, t_start=bad)


# -- known reaction values --------------------------------------------------------------------

def test_known_must_be_a_mapping_of_finite_numbers(pendulum):
    asm = mbody.assemble(pendulum)
    calls = {"solve": lambda k: asm.solve(known=k),
             "generalized": lambda k: asm.generalized(known=k),
             "simulate": lambda k: mbody.simulate(pendulum, 0.1, 10, known=k)}
    for call in calls.values():
        with pytest.raises(MbodyTypeError, match=r"^known must be a mapping of reaction label "
                                                 r"-> number or expression of t \(\{'O.Fx': "
                                                 r"1.0\}\), got list$"):
            call([("O.Fx", 1.0)])
        for bad in (math.nan, math.inf, -math.inf):
            with pytest.raises(mbody.MbodyError, match=rf"^known\['O.Fx'\] must be a finite "
                                                       rf"number \(N or N m\), got {bad}$"):
                call({"O.Fx": bad})
        for bad, got in ((np.array([1.0]), r"ndarray of shape \(1,\)"), (True, "bool True"),
                         (None, "NoneType")):
            with pytest.raises(MbodyTypeError, match=rf"^known\['O.Fx'\] must be a number \(N "
                                                     rf"or N m\) or an expression of t as text "
                                                     rf"\('2\*t'\), got {got}$"):
                call({"O.Fx": bad})
        with pytest.raises(mbody.MbodyError, match=r"^known\['O.Fx'\]: the expression ends "
                                                   "too early at character 3 of '2\\*'$"):
            call({"O.Fx": "2*"})
        with pytest.raises(mbody.MbodyError, match="^no reaction component 'O.fx' in this "
                                                   "model; did you mean 'O.Fx'\\?$"):
            call({"O.fx": 1.0})


def test_solve_takes_an_expression_of_t_at_the_state_time(pendulum):
    """As the file's known reactions: `known={"O.Fx": "2*t"}` at t = 0.5 s is O.Fx = 1 N
    (it used to be 'could not convert string to float')."""
    asm = mbody.assemble(pendulum, pendulum.initial.replace(t=0.5))
    by_text = asm.solve(known={"O.Fx": "2*t"})
    by_number = asm.solve(known={"O.Fx": 1.0})
    assert by_text.reactions["O.Fx"] == 1.0
    np.testing.assert_array_equal(by_text.accelerations, by_number.accelerations)
    assert by_text.reactions["O.Fy"] == by_number.reactions["O.Fy"]
    g = asm.generalized(known={"O.Fx": "2*t"})
    np.testing.assert_array_equal(g.f, asm.generalized(known={"O.Fx": 1.0}).f)
    with pytest.raises(mbody.MbodyError, match=r"^known\['O.Fx'\] = '1/\(t - 0.5\)' is not "
                                               r"finite at the state's t = 0.5 s \(inf\)$"):
        asm.solve(known={"O.Fx": "1/(t - 0.5)"})


def test_a_model_without_reactions_says_so():
    model = mbody.load(MODELS / "seed_example_1.yaml")
    with pytest.raises(mbody.MbodyError, match=r"^no reaction component 'A.Fx' in this model "
                                               r"\(it has none\)$"):
        mbody.assemble(model).solve(known={"A.Fx": 0})


# -- a model where a model goes ----------------------------------------------------------------

@pytest.mark.parametrize("call", [
    lambda m: mbody.assemble(m), lambda m: mbody.simulate(m, 0.1, 10),
    lambda m: mbody.linearize(m), lambda m: mbody.equilibrium(m),
    lambda m: mbody.kinematics(m), lambda m: mbody.kinematic_run(m, 0.1, 10),
    lambda m: mbody.solve_many(m)])
def test_a_path_where_a_model_goes_says_to_load_it(call):
    path = str(MODELS / "pendulum.yaml")
    with pytest.raises(MbodyTypeError, match=rf"^model must be a Model \(from mbody.load\), "
                                             rf"got str '{path}'; read the file first: "
                                             rf"mbody.load\('{path}'\)$"):
        call(path)
    with pytest.raises(MbodyTypeError, match=r"^model must be a Model \(from mbody.load\), "
                                             r"got PosixPath; read the file first"):
        call(Path(path))


def test_equilibrium_time_must_be_a_number(pendulum):
    with pytest.raises(MbodyTypeError, match="^t must be a number of seconds, got str '1'; "
                                             "write it as a number: 1.0$"):
        mbody.equilibrium(pendulum, t="1")


# -- URDF floating_base --------------------------------------------------------------------------

def test_floating_base_must_be_a_bool():
    path = MODELS / "robots" / "two_link_arm.urdf"
    for value, got in (("false", "str 'false'"), (1, "int 1"), ("True", "str 'True'")):
        with pytest.raises(MbodyTypeError, match=f"^floating_base must be True or False, got "
                                                 f"{got}$"):
            mbody.load(path, floating_base=value)
    fixed, floating = mbody.load(path, floating_base=False), mbody.load(path, floating_base=True)
    assert (len(fixed.joints), len(fixed.reactions)) == (3, 16)  # the root welded
    assert (len(floating.joints), len(floating.reactions)) == (2, 10)
