"""Bad MJCF and URDF input (review R1: B5, P7, P8): nothing in the file is dropped in
silence, nothing written twice is half read, and every message is located and speaks the
file's own terms (its links, bodies and elements; the options the user typed).

Each test runs the command line or `mbody.load` on a small file and asserts exit 2 (or
the `ModelError`), the file, line and column, and the names the message gives; never
another library's wording.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import mbody
from mbody.cli.app import main
from mbody.errors import ModelError

ROBOTS = Path(__file__).resolve().parent.parent / "models" / "robots"
ARM_URDF = (ROBOTS / "two_link_arm.urdf").read_text()

INERTIAL = ('<inertial><mass value="{m}"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" '
            'iyz="0"/></inertial>')


def _line_of(text: str, needle: str) -> int:
    """1-based line of the first line of `text` holding `needle`."""
    return next(k for k, line in enumerate(text.splitlines(), 1) if needle in line)


def _refused(argv: list[str], capsys) -> str:
    """The one-paragraph message of a command that must exit 2."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "internal error" not in err
    return err


# ---- B5: every link of the file is a body of the model or named in an error -----------

def _cycle_urdf() -> str:
    return "\n".join([
        '<robot name="r">', '  <link name="world"/>',
        '  <joint name="j1" type="continuous"><parent link="world"/><child link="a"/>'
        '<axis xyz="0 1 0"/></joint>',
        f'  <link name="a">{INERTIAL.format(m=1)}</link>',
        f'  <link name="b">{INERTIAL.format(m=5)}</link>',
        f'  <link name="c">{INERTIAL.format(m=5)}</link>',
        '  <joint name="j2" type="continuous"><parent link="b"/><child link="c"/>'
        '<axis xyz="0 1 0"/></joint>',
        '  <joint name="j3" type="continuous"><parent link="c"/><child link="b"/>'
        '<axis xyz="0 1 0"/></joint>', "</robot>"])


def test_a_urdf_cycle_apart_from_the_root_is_refused_at_its_first_joint(tmp_path, capsys):
    """Links b and c (10 kg) hang from each other, not from the root: they and their
    joints were dropped and `check` said OK; `convert` wrote the truncated model."""
    path = tmp_path / "cycle.urdf"
    path.write_text(_cycle_urdf())
    err = _refused(["check", str(path)], capsys)
    assert err.startswith(f"mbody: error: {path}:7:3: <joint>: joints 'j2', 'j3' form a "
                          "cycle")
    assert "links 'b', 'c' are not connected to the root link 'world'" in err
    out = tmp_path / "out.yaml"
    _refused(["convert", str(path), "-o", str(out)], capsys)
    assert not out.exists()


def test_the_shipped_arm_with_its_elbow_on_itself_is_refused(tmp_path, capsys):
    """A one-word slip: the elbow's parent written as its own child lost the 1.2 kg
    forearm and the tool frame, and `check` said OK."""
    text = ARM_URDF.replace('<parent link="upper_arm"/>', '<parent link="forearm"/>')
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    with pytest.raises(ModelError) as info:
        mbody.load(path)
    (issue,) = info.value.issues
    assert (issue.line, issue.column) == (_line_of(text, 'joint name="elbow"'), 3)
    assert "joint 'elbow' has link 'forearm' as its parent and its child" in issue.message
    assert "links 'forearm', 'tool' are not connected to the root link 'world'" in issue.hint


def test_an_mjcf_equality_on_one_body_is_refused_or_said(tmp_path, capsys):
    """MJCF is nested, so no body can be cut off from the tree; what else joins bodies
    (an equality) either joins two (a loop), is refused (a body joined to itself, as
    MuJoCo refuses it) or is said to be left out (both ends welded into one body)."""
    text = ('<mujoco model="m">\n<worldbody>\n'
            '<body name="a"><joint name="h"/><geom size="0.1"/><body name="tip"/></body>\n'
            '</worldbody>\n<equality>\n'
            '  <connect name="self" body1="a" body2="a" anchor="0 0 0"/>\n'
            '  <connect name="inside" body1="tip" body2="a" anchor="0 0 0"/>\n'
            "</equality>\n</mujoco>\n")
    path = tmp_path / "m.xml"
    path.write_text(text)
    err = _refused(["check", str(path)], capsys)
    assert err.startswith(f"mbody: error: {path}:6:34: <connect body2>: the connect joins "
                          "body 'a' to itself")
    path.write_text(text.replace('body2="a" anchor="0 0 0"/>\n  <connect name="inside"',
                                 'body2="world" anchor="0 0 0"/>\n  <connect name="inside"'))
    model = mbody.load(path)
    (said,) = [w for w in model.warnings if "'inside'" in w.message]
    assert (said.line, said.column) == (7, 3)
    assert "one rigid body ('a')" in said.message and "left out" in said.message


def test_a_massless_free_body_is_refused_not_dropped(tmp_path, capsys):
    """A body with a free joint and no mass (nor any body with a mass welded to it) was
    left out with its joint, and the rest of the model said OK."""
    path = tmp_path / "m.xml"
    path.write_text('<mujoco model="m">\n<worldbody>\n'
                    '<body name="a"><joint name="h"/><geom size="0.1"/></body>\n'
                    '<body name="ghost">\n  <freejoint name="fly"/>\n</body>\n'
                    "</worldbody>\n</mujoco>\n")
    err = _refused(["check", str(path)], capsys)
    assert err.startswith(f"mbody: error: {path}:5:3: <freejoint>: body 'ghost' has no mass "
                          "but moves on joint 'fly'")


# ---- P7: what a format gives once, given twice, is refused, not read in part -----------

def test_a_second_mass_in_a_urdf_inertial_is_refused_at_it(tmp_path, capsys):
    """The first <mass> (2 kg) silently won; the 3 kg written after it was ignored."""
    text = ARM_URDF.replace('<mass value="2.0"/>', '<mass value="2.0"/><mass value="3.0"/>')
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    line = _line_of(text, '<mass value="3.0"/>')
    err = _refused(["check", str(path)], capsys)
    assert err.startswith(f"mbody: error: {path}:{line}:26: <mass>: a second <mass> in "
                          f"<inertial> (the first is at line {line}, column 7)")


@pytest.mark.parametrize(("old", "new", "said"), [
    ('<axis xyz="0 1 0"/>\n    <limit', '<axis xyz="0 1 0"/><axis xyz="1 0 0"/>\n    <limit',
     "a second <axis> in <joint>"),
    ('<origin xyz="0 0 0.1" rpy="0 0 0"/>', '<origin xyz="0 0 0.1"/><origin xyz="0 0 1"/>',
     "a second <origin> in <joint>"),
    ('<geometry><cylinder radius="0.12" length="0.1"/>',
     '<geometry><cylinder radius="0.12" length="0.1"/><box size="1 1 1"/>',
     "a second shape <box> in <geometry> (the first, <cylinder>"),
    ('<joint name="tool_mount"', '<joint name="mount"', "duplicate joint name 'mount'"),
], ids=["axis", "origin", "shape", "joint name"])
def test_a_urdf_element_given_twice_is_refused(old, new, said, tmp_path, capsys):
    text = ARM_URDF.replace(old, new, 1)
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    line = next(k for k, (a, b) in enumerate(zip(text.splitlines(), ARM_URDF.splitlines(),
                                                 strict=True), 1) if a != b)
    err = _refused(["check", str(path)], capsys)
    assert err.startswith(f"mbody: error: {path}:{line}:") and said in err


def test_a_second_inertial_in_an_mjcf_body_is_refused_as_mujoco_refuses_it(tmp_path,
                                                                           capsys):
    path = tmp_path / "m.xml"
    path.write_text('<mujoco>\n  <option><flag gravity="disable"/><flag contact="disable"/>'
                    '</option>\n  <worldbody><body name="a"><joint/>\n'
                    '    <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>\n'
                    '    <inertial pos="0 0 0" mass="2" diaginertia="1 1 1"/>\n'
                    "  </body></worldbody>\n</mujoco>\n")
    err = _refused(["check", str(path)], capsys)
    assert f"{path}:2:36: <flag>: a second <flag> in <option> (the first is at line 2, " \
        "column 11)" in err
    assert f"{path}:5:5: <inertial>: a second <inertial> in <body> (the first is at line " \
        "4, column 5)" in err


def test_the_elements_mjcf_allows_once_are_mujocos():
    """`UNIQUE` against MuJoCo's own schema: the elements it marks (?) or (!), at the
    paths `SCHEMA` names them by."""
    mujoco = pytest.importorskip("mujoco")
    import re

    from mbody.io.interop.mjcf_schema import SCHEMA, UNIQUE

    stack: list[str] = []
    once = set()
    for line in mujoco.mj_printSchema(False, True).splitlines():
        m = re.match(r"^( *)(\S+) \((.)\)", line)
        if m is None:
            continue
        depth = len(m.group(1)) // 3
        stack = [*stack[:depth], m.group(2)]
        if m.group(3) in "?!" and depth > 0:
            once.add("/".join(stack).replace("(world)body", "body"))
    assert once == UNIQUE
    assert UNIQUE.issubset(SCHEMA)


# ---- P7: the model checks' findings in the file's own terms ---------------------------

def test_a_urdf_inertia_problem_names_the_link_and_element_not_a_yaml_path(tmp_path,
                                                                            capsys):
    """It said "bodies[1].inertia: ... ('inertia: 0' makes a particle)": a YAML path and
    YAML advice for a file that has neither."""
    text = ARM_URDF.replace('ixx="0.042" iyy="0.042" izz="0.0016" ixy="0"',
                            'ixx="0.042" iyy="0.042" izz="0.0016" ixy="0.5"')
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    line = _line_of(text, 'ixy="0.5"')
    err = _refused(["check", str(path)], capsys)
    assert err.startswith(f"mbody: error: {path}:{line}:7: link 'upper_arm' <inertia>: the "
                          "inertia tensor is not positive definite")
    assert "an <inertia> whose six entries are 0 makes a point mass" in err
    assert "bodies[" not in err and "inertia: 0" not in err


def test_an_mjcf_problem_names_the_body_and_a_name_clash_names_both_links(tmp_path,
                                                                          capsys):
    path = tmp_path / "m.xml"
    path.write_text('<mujoco>\n  <worldbody>\n    <body name="a"><joint name="h"/>\n'
                    '      <inertial pos="0 0 0" mass="1" fullinertia="1 1 1 2 0 0"/>\n'
                    "    </body>\n  </worldbody>\n</mujoco>\n")
    err = _refused(["check", str(path)], capsys)
    assert err.startswith(f"mbody: error: {path}:4:7: body 'a' <inertial>: the inertia "
                          "tensor is not positive definite")
    assert 'an <inertial> with diaginertia="0 0 0" makes a point mass' in err
    # 'upper.arm' is read as upper_arm (a '.' would break reaction labels): the clash
    # with the link named so names both links, not "first used by bodies[1]"
    text = (ARM_URDF.replace("upper_arm", "upper.arm")
            .replace('<link name="forearm">', '<link name="upper_arm">')
            .replace('link="forearm"', 'link="upper_arm"'))
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    err = _refused(["check", str(path)], capsys)
    line = _line_of(text, '<link name="upper_arm">')
    assert (f"{path}:{line}:9: link 'upper_arm' name: duplicate body name 'upper_arm' (first "
            "used by link 'upper.arm')") in err


# ---- P7: an option is named as it was typed -------------------------------------------

@pytest.mark.parametrize(("argv", "said"), [
    (["check", "models/pendulum.yaml", "--q", "O=1"],
     "--q sets a URDF model's state; this model is read as YAML"),
    (["check", "models/pendulum.yaml", "--qd", "O=1"],
     "--qd sets a URDF model's state; this model is read as YAML"),
    (["check", "models/pendulum.yaml", "--floating-base"],
     "--floating-base sets a URDF model's state; this model is read as YAML"),
    (["check", "models/robots/two_link_arm.urdf", "--keyframe", "swing"],
     "--keyframe sets an MJCF model's state; this model is read as URDF"),
    (["convert", "models/robots/two_link_arm.urdf", "--keyframe", "swing", "-o", "OUT"],
     "--keyframe sets an MJCF model's state; this model is read as URDF"),
    (["check", "models/robots/two_link_arm.urdf", "--q", "sholder=1"],
     "models/robots/two_link_arm.urdf: --q: no joint named 'sholder' moves in this model "
     "(did you mean 'shoulder'?)"),
    (["check", "models/robots/two_link_arm.xml", "--keyframe", "swng"],
     "models/robots/two_link_arm.xml: --keyframe: no keyframe named 'swng' (did you mean "
     "'swing'?)"),
], ids=["q", "qd", "floating-base", "keyframe", "convert --keyframe", "q joint",
        "keyframe name"])
def test_the_command_line_names_the_option_typed_not_the_keyword(argv, said, tmp_path,
                                                                 capsys, monkeypatch):
    """It said "'joint_positions' sets a URDF model's state" for --q, "keyframe" for
    --keyframe: the names of `mbody.load`'s keywords, which a command-line user never
    typed. `mbody.load` itself still names its keywords."""
    monkeypatch.chdir(ROBOTS.parent.parent)
    argv = [str(tmp_path / "out.yaml") if a == "OUT" else a for a in argv]
    err = _refused(argv, capsys)
    assert err == f"mbody: error: {said}\n"
    for keyword in ("joint_positions", "joint_velocities", "floating_base", "'keyframe'"):
        assert keyword not in err


def test_the_floating_base_advice_names_the_flag_or_the_keyword(tmp_path, capsys):
    path = tmp_path / "drone.urdf"
    path.write_text(f'<robot name="r"><link name="a">{INERTIAL.format(m=1)}</link></robot>')
    err = _refused(["check", str(path)], capsys)
    assert "(--floating-base lets it move freely)" in err
    assert "floating_base" not in err.replace(str(path), "")
    with pytest.raises(ModelError) as info:
        mbody.load(path)
    assert "(floating_base=True lets it move freely)" in str(info.value)
    with pytest.raises(mbody.MbodyError, match="^joint_positions sets a URDF model's "
                       "state; this model is read as YAML$"):
        mbody.load(ROBOTS.parent / "pendulum.yaml", joint_positions={"O": 1})


# ---- P7: a file read as the wrong format says which format it is ----------------------

@pytest.mark.parametrize(("model", "fmt", "said", "hint"), [
    ("robots/two_link_arm.urdf", "yaml", ":4:1: expected an mbody YAML model, got XML "
     "(<robot>)", "(this is a URDF file: read it as URDF (a .urdf name, or --format urdf))"),
    ("robots/two_link_arm.xml", "yaml", ":3:1: expected an mbody YAML model, got XML "
     "(<mujoco>)", "(this is an MJCF file: read it as MJCF (a .xml name, or --format "
     "mjcf))"),
    ("pendulum.yaml", "urdf", ":1:1: expected a URDF model file, which is XML (it starts "
     "with <robot>), got text that does not start with '<'", "(this is an mbody YAML "
     "file: read it as mbody YAML (a .yaml name, or --format yaml))"),
    ("pendulum.yaml", "mjcf", ":1:1: expected an MJCF model file, which is XML (it starts "
     "with <mujoco>), got text that does not start with '<'", "(this is an mbody YAML "
     "file: read it as mbody YAML (a .yaml name, or --format yaml))"),
], ids=["urdf as yaml", "mjcf as yaml", "yaml as urdf", "yaml as mjcf"])
def test_a_model_read_as_another_format_is_told_which_it_is(model, fmt, said, hint, capsys):
    """--format yaml on a URDF file said "YAML syntax error: mapping values are not
    allowed in this context"; --format urdf on a YAML file "XML syntax error: not
    well-formed": only MJCF read as URDF (and the reverse) said what the file was."""
    path = ROBOTS.parent / model
    err = _refused(["check", str(path), "--format", fmt], capsys)
    assert err == f"mbody: error: {path}{said} {hint}\n"


# ---- P8: a file that is no file says what it is ---------------------------------------

@pytest.mark.parametrize(("target", "kind"), [
    ("/dev/zero", "a character device"), (".", "a directory"), ("pipe", "a named pipe")])
def test_an_include_of_a_folder_device_or_pipe_says_what_it_is(target, kind, tmp_path,
                                                               capsys):
    """It said "the included file '/dev/zero' does not exist"."""
    if target == "pipe":
        if not hasattr(os, "mkfifo"):
            pytest.skip("no named pipes on this system")
        os.mkfifo(tmp_path / "pipe")
    elif not Path(target).exists():
        pytest.skip(f"{target} is not on this system")
    path = tmp_path / "m.xml"
    path.write_text(f'<mujoco model="m">\n  <include file="{target}"/>\n  <worldbody/>\n'
                    "</mujoco>\n")
    err = _refused(["check", str(path)], capsys)
    assert err.startswith(f"mbody: error: {path}:2:12: <include file>: the included file "
                          f"'{target}' is {kind}")
    assert "does not exist" not in err


@pytest.mark.parametrize(("fmt", "expected"), [
    ("mjcf", "an MJCF model file"), ("urdf", "a URDF model file")])
def test_a_device_or_folder_read_as_mjcf_or_urdf_names_that_format(fmt, expected, tmp_path,
                                                                   capsys):
    """`check /dev/urandom --format mjcf` said "expected a YAML model file"."""
    err = _refused(["check", "/dev/urandom", "--format", fmt], capsys)
    assert err.startswith("mbody: error: /dev/urandom: this is a character device") and \
        f"expected {expected} " in err and "YAML" not in err
    assert f"--format {fmt} <" in err  # the pipe it could be read from, in that format
    err = _refused(["check", str(tmp_path), "--format", fmt], capsys)
    assert err == f"mbody: error: {tmp_path}: this is a directory; expected {expected}\n"
