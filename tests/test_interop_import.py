"""MJCF and URDF import (mbody.io.interop): cross-checked against MuJoCo, real models from
installed packages, and bad XML reported like bad YAML.

MuJoCo is the reference, never used by the import itself: each model is loaded by both,
put in the same random state (MuJoCo's ``qpos``/``qvel`` written into a keyframe, or URDF
joint values), and compared body by body: the mass centre's acceleration (MuJoCo's
``mj_objectAcceleration`` plus gravity, after ``mj_rnePostConstraint``), the angular
acceleration (world axes), and on tree models the joint reactions against ``cfrc_int``
(what the parent exerts on the body: [moment about ``subtree_com[root]``, force], world).
Passive forces, armature, actuators and constraints (limits, contacts) are switched off in
MuJoCo: the import lists them as not imported.
"""

from __future__ import annotations

import importlib.metadata
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import main
from mbody.errors import ModelError
from mbody.io.interop.mjcf import read_mjcf, solid
from mbody.io.interop.tree import joint_name
from mbody.io.interop.urdf import read_urdf
from mbody.io.interop.xmlsource import parse_xml
from mbody.model.model import Model
from mbody.model.validate import validate

ROBOTS = Path(__file__).resolve().parent.parent / "models" / "robots"
RTOL = 1e-9

# ---- helpers ---------------------------------------------------------------------------


def _mujoco():
    return pytest.importorskip("mujoco")


def _quiet(m) -> None:
    """What the import does not model, switched off in MuJoCo."""
    mj = _mujoco()
    bits = mj.mjtDisableBit
    m.opt.disableflags |= (bits.mjDSBL_CONSTRAINT | bits.mjDSBL_SPRING | bits.mjDSBL_DAMPER
                           | bits.mjDSBL_ACTUATION)
    m.dof_armature[:] = 0


def _random_state(m, d, rng, speed=1.0) -> None:
    d.qpos[:] = m.qpos0
    for j in range(m.njnt):
        a, t = m.jnt_qposadr[j], m.jnt_type[j]
        if t == 0:  # free
            q = rng.normal(size=4)
            d.qpos[a:a + 3] = rng.normal(size=3)
            d.qpos[a + 3:a + 7] = q / np.linalg.norm(q)
        elif t == 1:  # ball
            q = rng.normal(size=4)
            d.qpos[a:a + 4] = q / np.linalg.norm(q)
        else:
            d.qpos[a] = rng.uniform(-1.5, 1.5)
    d.qvel[:] = rng.normal(size=m.nv) * speed


def _with_key(text: str, d) -> str:
    nums = lambda v: " ".join(repr(float(x)) for x in v)  # noqa: E731
    key = f'<keyframe><key name="xcheck" qpos="{nums(d.qpos)}" qvel="{nums(d.qvel)}"/></keyframe>'
    i = text.rindex("</mujoco>")
    return text[:i] + key + text[i:]


def _compare(m, d, model: Model, reactions: bool) -> float:
    """Largest relative difference between mbody and MuJoCo at the state; asserts it."""
    mj = _mujoco()
    mj.mj_forward(m, d)
    mj.mj_rnePostConstraint(m, d)
    sol = mbody.assemble(model).solve()
    # 6 rows per body, 3 per particle (no rotation): split at each body's first row
    rows = np.cumsum([0] + [3 if p else 6 for p in model.particle])
    assert rows[-1] == sol.accelerations.size
    # cacc holds -g only when gravity is on (dm_control's finger switches it off)
    g = (np.zeros(3) if m.opt.disableflags & mj.mjtDisableBit.mjDSBL_GRAVITY
         else m.opt.gravity)
    res = np.zeros(6)
    worst = 0.0
    R = model.initial.W_R_B
    for i, name in enumerate(model.body_names):
        b = mj.mj_name2id(m, mj.mjtObj.mjOBJ_BODY, name)
        assert b >= 0, name
        np.testing.assert_allclose(model.initial.position[i], d.xipos[b], atol=1e-12)
        mj.mj_objectAcceleration(m, d, mj.mjtObj.mjOBJ_BODY, b, res, 0)
        a = sol.accelerations[rows[i]:rows[i + 1]]
        if model.particle[i]:  # a point mass: its angular acceleration means nothing
            mine, ref = a, res[3:] + g
        else:
            mine = np.concatenate([a[:3], R[i] @ a[3:]])
            ref = np.concatenate([res[3:] + g, res[:3]])
        scale = max(1.0, float(np.abs(ref).max()))
        worst = max(worst, float(np.abs(mine - ref).max()) / scale)
    if reactions:
        parent_of = {jt.child: jt.parent for jt in model.joints}
        for jt in model.joints:
            b = mj.mj_name2id(m, mj.mjtObj.mjOBJ_BODY, jt.child)
            F, M = np.zeros(3), np.zeros(3)
            for label in jt.labels:
                comp, value = label.split(".")[-1], sol.reactions[label]
                if comp == "Mt":
                    M += value * np.cross(jt.axis, jt.axis2) / np.linalg.norm(
                        np.cross(jt.axis, jt.axis2))
                else:
                    col = jt.W_E0[:, "xyz".index(comp[1])]
                    (F if comp[0] == "F" else M)[:] += value * col
            c = d.subtree_com[m.body_rootid[b]]
            torque = M + np.cross(jt.at - c, F)
            ref = d.cfrc_int[b].copy()
            for k in np.flatnonzero(m.body_parentid == b):
                # cfrc_int carries the subtree; what mbody hangs elsewhere (the children
                # of a welded point mass hang from the body it is welded to) is taken out
                kid = mj.mj_id2name(m, mj.mjtObj.mjOBJ_BODY, int(k))
                if parent_of.get(kid, jt.child) != jt.child or (
                        kid not in parent_of and model.particle[model.body_names.index(
                            jt.child)]):
                    ref -= d.cfrc_int[k]
            scale = max(1.0, float(np.abs(ref).max()))
            worst = max(worst, float(np.abs(np.concatenate([torque, F]) - ref).max()) / scale)
    assert worst < RTOL, worst
    return worst


def _mjcf_check(path: Path, seeds=(0, 1, 2), reactions=True) -> float:
    mj = _mujoco()
    text = path.read_text()
    m = mj.MjModel.from_xml_path(str(path))
    _quiet(m)
    d = mj.MjData(m)
    worst = 0.0
    for seed in seeds:
        _random_state(m, d, np.random.default_rng(seed))
        doc = read_mjcf(_with_key(text, d), keyframe="xcheck", file=str(path))
        worst = max(worst, _compare(m, d, Model.from_spec(validate(doc)), reactions))
    return worst


def _urdf_mujoco(path: Path, floating: bool):
    """MuJoCo's own URDF reader, given the file without its meshes."""
    mj = _mujoco()
    text = path.read_text()
    text = re.sub(r"<(visual|collision)\b.*?</\1>", "", text, flags=re.S)
    text = re.sub(r"(<robot[^>]*>)", r'\1<mujoco><compiler fusestatic="false" '
                  r'discardvisual="true"/></mujoco>', text, count=1)
    if not floating:
        return mj.MjModel.from_xml_string(text)
    spec = mj.MjSpec.from_string(text)
    spec.worldbody.first_body().add_freejoint()
    return spec.compile()


def _urdf_check(path: Path, floating=False, seeds=(0, 1)) -> float:
    mj = _mujoco()
    m = _urdf_mujoco(path, floating)
    _quiet(m)
    d = mj.MjData(m)
    worst = 0.0
    for seed in seeds:
        rng = np.random.default_rng(seed)
        d.qpos[:] = m.qpos0
        d.qvel[:] = 0
        qp, qv = {}, {}
        for j in range(m.njnt):
            if m.jnt_type[j] == 0:
                continue  # the floating base: at the origin, at rest
            name = mj.mj_id2name(m, mj.mjtObj.mjOBJ_JOINT, j)
            qp[name], qv[name] = rng.uniform(-1.5, 1.5), rng.normal()
            d.qpos[m.jnt_qposadr[j]], d.qvel[m.jnt_dofadr[j]] = qp[name], qv[name]
        doc = read_urdf(path, joint_positions=qp, joint_velocities=qv, floating_base=floating)
        worst = max(worst, _compare(m, d, Model.from_spec(validate(doc)), reactions=True))
    return worst


def _robot(path: str) -> Path:
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (pip install example-robot-data)")
    p = Path(str(dist.locate_file(
        f"cmeel.prefix/share/example-robot-data/robots/{path}")))
    if not p.is_file():
        pytest.skip(f"example-robot-data has no {path}")
    return p


def _suite(name: str) -> Path:
    dm = pytest.importorskip("dm_control", reason="dm_control is not installed")
    return Path(dm.__file__).parent / "suite" / f"{name}.xml"


# ---- MJCF against MuJoCo -------------------------------------------------------------

def test_two_link_arm_mjcf_agrees_with_mujoco():
    assert _mjcf_check(ROBOTS / "two_link_arm.xml") < RTOL


def test_keyframe_and_reference_pose():
    model = mbody.load(ROBOTS / "two_link_arm.xml", keyframe="swing")
    assert model.initial.omega.any()
    rest = mbody.load(ROBOTS / "two_link_arm.xml")
    assert not rest.initial.velocity.any() and not rest.initial.omega.any()
    with pytest.raises(ModelError, match="did you mean 'swing'"):
        mbody.load(ROBOTS / "two_link_arm.xml", keyframe="swimg")
    names = [j.name for j in rest.joints]
    assert names == ["turntable", "shoulder", "elbow"]
    assert "shoulder.Fx" in mbody.assemble(rest).reactions


COMPOSED = """<mujoco model="composed">
  <compiler angle="radian" eulerseq="zyx"/>
  <option gravity="0.3 -0.2 -9.81"/>
  <worldbody>
    <body name="torso" pos="0 0 1" euler="0.1 0.2 0.3">
      <freejoint name="root"/>
      <inertial pos="0.01 0.02 0" mass="5" fullinertia="0.3 0.4 0.5 0.01 -0.02 0.03"/>
      <body name="upper" pos="0.1 0 0" quat="0.9 0.1 0.3 0.2">
        <joint name="hip_x" type="hinge" axis="1 0 0" pos="0 0 0.05"/>
        <joint name="hip_z" type="hinge" axis="0 0 1" pos="0 0 0.05"/>
        <joint name="hip_y" type="hinge" axis="0 1 0.3" pos="0 0 0.05"/>
        <geom type="capsule" fromto="0 0 0 0.05 0.01 -0.3" size="0.05"/>
        <body name="lower" pos="0 0 -0.35" axisangle="0 1 0 0.4">
          <joint name="knee_a" type="hinge" axis="2 1 1"/>
          <joint name="knee_b" type="hinge" axis="0 -1 1"/>
          <geom type="ellipsoid" size="0.05 0.06 0.15" pos="0 0 -0.15" density="800"/>
          <body name="foot" pos="0 0 -0.3" xyaxes="0 1 0 -1 0 0.2">
            <joint name="ankle" type="ball" pos="0 0 0.02"/>
            <geom type="box" size="0.1 0.04 0.02" mass="0.7"/>
            <geom type="sphere" size="0.03" pos="0.1 0 0"/>
          </body>
        </body>
      </body>
      <body name="slider" pos="0 0.3 0" zaxis="0 1 1">
        <joint name="rail" type="slide" axis="0 0 1"/>
        <joint name="spin" type="hinge" axis="0 0 1" pos="0.01 0 0"/>
        <geom type="cylinder" size="0.04 0.1"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_composed_joints_agree_with_mujoco(tmp_path):
    """Three hinges through one point -> spherical; two perpendicular -> universal; a
    hinge and a slide along one axis -> cylindrical; ball; free; every orientation form;
    geoms of every solid shape with mass and density."""
    path = tmp_path / "composed.xml"
    path.write_text(COMPOSED)
    assert _mjcf_check(path) < RTOL
    model = mbody.load(path)
    types = {j.name: j.type for j in model.joints}
    assert types == {"hip": "spherical", "knee": "universal", "ankle": "spherical",
                     "rail+spin": "cylindrical"}


def test_geom_mass_and_inertia_are_mujocos():
    mj = _mujoco()
    xml = COMPOSED
    m = mj.MjModel.from_xml_string(xml)
    model = Model.from_spec(validate(read_mjcf(xml)))
    for i, name in enumerate(model.body_names):
        b = mj.mj_name2id(m, mj.mjtObj.mjOBJ_BODY, name)
        assert model.mass[i] == pytest.approx(m.body_mass[b], rel=1e-12)
        principal = np.linalg.eigvalsh(model.J[i])
        assert principal == pytest.approx(np.sort(m.body_inertia[b]), rel=1e-9)
    vol, _ = solid("capsule", np.array([0.05, 0.1, 0]))
    assert vol == pytest.approx(np.pi * 0.05**2 * 0.2 + 4 / 3 * np.pi * 0.05**3)


CONNECT = """<mujoco>
  <worldbody>
    <body name="a" pos="0 0 1"><joint name="ja" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 1 0 0" size="0.05"/></body>
    <body name="b" pos="2 0 1"><joint name="jb" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 -1 0 0" size="0.05"/></body>
  </worldbody>
  <equality><connect name="tie" body1="a" body2="b" anchor="1 0 0"/></equality>
</mujoco>"""


def test_connect_becomes_a_spherical_joint_closing_the_loop():
    model = Model.from_spec(validate(read_mjcf(CONNECT)))
    tie = next(j for j in model.joints if j.name == "tie")
    assert (tie.type, tie.parent, tie.child) == ("spherical", "a", "b")
    assert tie.at == pytest.approx([1, 0, 1])


@pytest.mark.parametrize("name", ["acrobot", "cartpole", "pendulum", "reacher", "finger",
                                  "quadruped", "humanoid_CMU"])
def test_dm_control_suite_agrees_with_mujoco(name):
    """Every suite model that loads (the finger has gravity switched off)."""
    assert _mjcf_check(_suite(name), seeds=(0, 1)) < RTOL


def test_humanoid_says_which_body_cannot_be_expressed():
    """dm_control's humanoid composes everything except its ankles (two hinges at two
    points: a massless frame between them, which mbody has not)."""
    with pytest.raises(ModelError) as info:
        mbody.load(_suite("humanoid"))
    text = str(info.value)
    assert "body 'right_foot' has 2 joints" in text
    assert "anchors differ" in text and "humanoid.xml:" in text


def test_humanoid_with_ankles_through_one_point_agrees_with_mujoco(tmp_path):
    """The same model with each ankle's two hinges moved to one point loads and agrees
    (free root, universal abdomen and shoulders, spherical hips)."""
    src = _suite("humanoid")
    shutil.copytree(src.parent / "common", tmp_path / "common")
    text = src.read_text().replace('pos="0 0 .08" axis="0 1 0"', 'pos="0 0 .04" axis="0 1 0"')
    path = tmp_path / "humanoid.xml"
    path.write_text(text.replace('axis="1 0 .5"', 'axis="1 0 0"'))
    assert _mjcf_check(path, seeds=(0, 1)) < RTOL


# ---- URDF against MuJoCo -------------------------------------------------------------

def test_two_link_arm_urdf_agrees_with_mujoco():
    assert _urdf_check(ROBOTS / "two_link_arm.urdf") < RTOL
    model = mbody.load(ROBOTS / "two_link_arm.urdf")
    assert model.body_names == ("base", "upper_arm", "forearm")  # tool: a frame, no mass
    assert [j.name for j in model.joints] == ["mount", "shoulder", "elbow"]


@pytest.mark.parametrize("path, floating", [
    ("ur_description/urdf/ur5_robot.urdf", False),
    ("panda_description/urdf/panda.urdf", False),
    ("solo_description/robots/solo12.urdf", True),
    ("a1_description/urdf/a1.urdf", True),
    # point masses welded to a link (contact and sensor links: spherical joints; what is
    # fixed to them hangs from the link): quadruped, so101, Talos, Baxter
    ("quadruped_description/urdf/quadruped.urdf", True),
    ("so_arm_description/urdf/so101.urdf", False),
    ("talos_data/robots/talos_left_arm.urdf", False),
    ("baxter_description/urdf/baxter.urdf", False),
    # massless feet with an inertia: it adds to the lower leg's
    ("bolt_description/robots/bolt.urdf", True),
    ("go2_description/urdf/go2.urdf", True),
    ("g1_description/urdf/g1_29dof_rev_1_0.urdf", True),
    ("xarm_description/urdf/xarm7.urdf", False),
    # <collision_checking> in its links: an extension, noted
    ("simple_humanoid_description/urdf/simple_humanoid.urdf", True),
])
def test_example_robot_data_agrees_with_mujoco(path, floating):
    assert _urdf_check(_robot(path), floating) < RTOL


POINTS = """<robot name="points">
  <link name="arm"><inertial><origin xyz="0.2 0 0"/><mass value="2"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.05"/></inertial></link>
  <joint name="tip_fixed" type="fixed"><parent link="arm"/><child link="tip"/>
    <origin xyz="0.4 0.05 0" rpy="0.3 0.2 0.1"/></joint>
  <link name="tip"><inertial><mass value="0.3"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="finger_joint" type="revolute"><parent link="tip"/><child link="finger"/>
    <origin xyz="0.05 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="finger"><inertial><origin xyz="0.05 0 0"/><mass value="0.2"/>
    <inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0004" iyz="0" izz="0.0004"/></inertial>
  </link>
  <joint name="pad_fixed" type="fixed"><parent link="finger"/><child link="pad"/>
    <origin xyz="0.1 0 0" rpy="0 0.5 0"/></joint>
  <link name="pad"><inertial><mass value="0"/>
    <inertia ixx="0.0002" ixy="0.00001" ixz="0" iyy="0.0003" iyz="0" izz="0.0004"/>
  </inertial></link>
</robot>"""


def test_point_masses_and_massless_inertias_are_exact(tmp_path):
    """A link with a mass and no inertia welded to another (a contact or sensor link)
    is a particle on a spherical joint (a fixed joint has no orientation to hold), and
    what is fixed to it hangs from the link it is welded to; a link with an inertia and
    no mass adds its inertia to the body it is welded to. Both exact: MuJoCo agrees."""
    path = tmp_path / "points.urdf"
    path.write_text(POINTS)
    assert _urdf_check(path, floating=True) < RTOL
    model = mbody.load(path, floating_base=True)
    assert model.body_names == ("arm", "tip", "finger")
    joints = {j.name: (j.type, j.parent, j.child) for j in model.joints}
    assert joints == {"tip_fixed": ("spherical", "arm", "tip"),
                      "finger_joint": ("revolute", "arm", "finger")}
    assert model.particle[1] and not model.particle[2]
    assert np.linalg.eigvalsh(model.J[2]).sum() == pytest.approx(0.0009 + 0.0009)


def test_joint_values_by_name():
    model = mbody.load(ROBOTS / "two_link_arm.urdf", joint_positions={"shoulder": 0.5},
                       joint_velocities={"elbow": 2.0})
    assert model.initial.omega[2] @ model.initial.omega[2] == pytest.approx(4.0)
    with pytest.raises(ModelError, match="did you mean 'shoulder'"):
        mbody.load(ROBOTS / "two_link_arm.urdf", joint_positions={"shouldr": 1})
    with pytest.raises(mbody.MbodyError, match="this model is read as URDF"):
        mbody.load(ROBOTS / "two_link_arm.urdf", keyframe="swing")


def test_not_imported_is_one_warning():
    model = mbody.load(ROBOTS / "two_link_arm.xml")
    notes = [w for w in model.warnings if "not imported" in w.message]
    assert len(notes) == 1
    for word in ("contacts", "joint damping", "joint limits", "actuators (shoulder_motor)"):
        assert word in notes[0].message


def _contacts(geoms: str) -> str:
    """The contacts part of the warning for a model of one body with `geoms` (and a
    floor), '' when none is listed."""
    doc = read_mjcf(f"""<mujoco><worldbody><geom name="floor" type="plane" size="1 1 .1"/>
      <body name="b"><freejoint/>{geoms}</body></worldbody></mujoco>""")
    notes = " ".join(w.message for w in doc.warnings)
    found = re.search(r"contacts \(([^)]*)\)", notes)
    return found.group(1) if found else ""


def test_contacts_listed_only_for_geoms_that_can_touch():
    """MuJoCo tests a pair of geoms of different bodies when (contype1 & conaffinity2)
    or (contype2 & conaffinity1)."""
    off = 'contype="0" conaffinity="0"'
    assert _contacts(f'<geom size=".1" {off}/>') == ""
    assert _contacts('<geom size=".1"/>') == "world geom 'floor', 1 body geoms collide in MuJoCo"
    assert _contacts(f'<geom size=".1" {off}/><geom size=".2" pos="1 0 0"/>') == (
        "world geom 'floor', 1 body geoms collide in MuJoCo")
    # bits that never meet: type 2 against affinity 1 (the floor's), affinity 0 against
    # the floor's type 1
    assert _contacts('<geom size=".1" contype="2" conaffinity="0"/>') == ""
    # through a default class
    doc = read_mjcf(f"""<mujoco><default><default class="quiet"><geom {off}/></default>
      </default><worldbody><body name="b" childclass="quiet"><freejoint/>
      <geom size=".1"/></body></worldbody></mujoco>""")
    assert not doc.warnings


def test_exported_joint_parts_give_back_any_name():
    """The export names a universal joint's hinges J:1, J:2 and a cylindrical joint's
    parts J:slide, J:turn; the stem comes back whatever J is (one letter, a colon)."""
    assert joint_name(["A:1", "A:2"]) == "A"
    assert joint_name(["x:slide", "x:turn"]) == "x"
    assert joint_name(["a:b:1", "a:b:2"]) == "a:b"
    assert joint_name(["right_hip_x", "right_hip_z", "right_hip_y"]) == "right_hip"
    assert joint_name(["a", "b"]) == "a+b"
    assert joint_name(["A:1", "B:2"]) == "A:1+B:2"


def test_mbody_entries_that_are_wrong_are_located():
    base = '<mujoco><custom>{}</custom><worldbody><body name="b"><freejoint/>' \
           '<inertial mass="1" diaginertia="1 1 1"/></body></worldbody></mujoco>'
    issues = _issues(base.format('<numeric name="mbody:dimensoin" data="2"/>'))
    assert issues == ["bad.xml:1:26: <numeric name>: unknown mbody entry kind 'dimensoin' "
                      "(did you mean 'dimension'?)"]
    issues = _issues(base.format('<text name="mbody:body:b" data="{inertia: 0}"/>'))
    assert len(issues) == 1 and "the data is not JSON" in issues[0]
    issues = _issues(base.format('<text name="mbody:body:c" data=\'{"inertia": 0}\'/>'))
    assert len(issues) == 1 and "no body 'c'" in issues[0]
    issues = _issues(base.format('<numeric name="mbody:dimension" data="4"/>'))
    assert len(issues) == 1 and "must be 2 or 3" in issues[0]
    # other custom entries are MuJoCo's or another tool's: not read
    doc = read_mjcf(base.format('<numeric name="other:dimension" data="7"/>'))
    assert doc.data["dimension"] == 3


# ---- bad XML -------------------------------------------------------------------------

def _issues(text: str, reader=read_mjcf) -> list[str]:
    with pytest.raises(ModelError) as info:
        reader(text, file="bad.xml")
    return [str(i) for i in info.value.issues]


def test_syntax_error_has_line_and_column():
    (msg,) = _issues("<mujoco>\n  <worldbody>\n    <body name='a'>\n  </worldbody>\n</mujoco>")
    assert msg.startswith("bad.xml:4:5:") and "mismatched tag" in msg


def test_misspelt_element_and_attribute():
    msgs = _issues('<mujoco>\n <worldbody>\n  <bodi name="a"/>\n  <body nme="b"/>\n'
                   " </worldbody>\n</mujoco>")
    assert msgs[0].startswith("bad.xml:3:3:") and "did you mean 'body'" in msgs[0]
    assert msgs[1].startswith("bad.xml:4:9:") and "did you mean 'name'" in msgs[1]
    (msg,) = _issues('<robot name="r"><link name="a"><inertail/></link></robot>', read_urdf)
    assert "did you mean 'inertial'" in msg


ARM = ('<robot name="r"><link name="a"/><joint name="j" type="revolute">'
       '<parent link="a"/><child link="b"/>{joint}</joint>'
       '<link name="{child}">{link}<inertial><mass value="1"/>'
       '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>'
       '</robot>')


def test_urdf_extensions_are_noted_and_typos_refused():
    """ANYmal's ``<limit command_effort gear_velocity>`` and the simple humanoid's
    ``<collision_checking>`` are tools' extensions (noted in the warning, the robot
    loads); a name one edit or very little away from URDF's is a typo (refused)."""
    text = ARM.format(joint='<limit effort="1" command_effort="2" gear_velocity="3"/>',
                      child="b", link="<collision_checking/>")
    doc = read_urdf(text)
    (note,) = [w.message for w in doc.warnings]
    for name in ("limit command_effort", "limit gear_velocity",
                 "<collision_checking> in <link>"):
        assert name in note
    for joint, hint in (('<origin rpi="0 0 1"/>', "did you mean 'rpy'"),
                        ('<orgin xyz="0 0 1"/>', "did you mean 'origin'"),
                        ('<limit efort="1"/>', "did you mean 'effort'")):
        (msg,) = _issues(ARM.format(joint=joint, child="b", link=""), read_urdf)
        assert hint in msg


def test_urdf_ground_link_empty_robot_and_a_lone_fixed_link(tmp_path):
    """asr_twodof's link 'ground' is renamed (with a warning), ur3.urdf (xacro macros
    only) has no link, hector's quadrotor is one link fixed to the world."""
    doc = read_urdf(ARM.format(joint="", child="ground", link="").replace(
        '<child link="b"/>', '<child link="ground"/>'))
    model = Model.from_spec(validate(doc))
    assert model.body_names == ("ground_body",)
    assert "'ground' is named 'ground_body'" in doc.warnings[0].message
    (msg,) = _issues('<robot name="r"></robot>', read_urdf)
    assert "has no <link>" in msg and "xacro" in msg
    (msg,) = _issues('<robot name="r"><link name="a"><inertial><mass value="1"/>'
                     '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'
                     '</inertial></link></robot>', read_urdf)
    assert "only link with a mass" in msg and "floating_base=True lets it move" in msg
    path = tmp_path / "drone.urdf"
    path.write_text('<robot name="r"><link name="a"><inertial><mass value="1"/>'
                    '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'
                    '</inertial></link></robot>')
    assert mbody.load(path, floating_base=True).body_names == ("a",)


def test_an_included_files_problems_name_that_file(tmp_path, capsys):
    """What validation finds in an <include>d file is at that file's line, not the main
    file's (it named main.xml with parts.xml's line)."""
    (tmp_path / "main.xml").write_text('<mujoco model="m">\n  <include file="parts.xml"/>\n'
                                       "</mujoco>\n")
    (tmp_path / "parts.xml").write_text(
        '<mujoco>\n  <worldbody>\n    <body name="a">\n      <joint type="hinge"/>\n'
        '      <inertial pos="0 0 0" mass="1" diaginertia="1 1 5"/>\n    </body>\n'
        "  </worldbody>\n</mujoco>\n")
    with pytest.raises(ModelError) as info:
        mbody.load(tmp_path / "main.xml")
    (issue,) = info.value.issues
    assert (Path(issue.file).name, issue.line, issue.column) == ("parts.xml", 5, 7)
    assert main(["convert", str(tmp_path / "main.xml"), "-o", str(tmp_path / "m.yaml")]) == 2
    assert "parts.xml:5:7: body 'a' <inertial>" in capsys.readouterr().err


def test_planar_root_says_why_and_a_bad_size_is_said_once():
    """dm_control's walkers slide in two directions: the hint says it is a planar body
    (giving a frame a mass, the general hint, would change the motion). A geom size of
    the wrong length is one message (it also said the geom had no volume)."""
    (msg,) = _issues('<mujoco><worldbody><body name="torso">'
                     '<joint name="rootx" type="slide" axis="1 0 0"/>'
                     '<joint name="rootz" type="slide" axis="0 0 1"/>'
                     '<joint name="rooty" axis="0 1 0"/><geom size="0.1"/>'
                     "</body></worldbody></mujoco>")
    assert "move in a plane" in msg and "with a mass" not in msg
    (msg,) = _issues('<mujoco><worldbody><body name="a"><joint/>'
                     '<geom size="0.1 0.2 0.3 0.4"/></body></worldbody></mujoco>')
    assert "expected 1 to 3 numbers, got 4" in msg


def test_bad_numbers_angles_and_units():
    (msg,) = _issues('<mujoco><compiler angle="degrees"/></mujoco>')
    assert "did you mean 'degree'" in msg
    (msg,) = _issues('<mujoco><worldbody><body pos="0 0 1m"><geom size="1"/>'
                     "</body></worldbody></mujoco>")
    assert "'1m' is not a number" in msg and ":1:" in msg
    (msg,) = _issues('<mujoco><worldbody><body euler="0 0"><geom size="1"/>'
                     "</body></worldbody></mujoco>")
    assert "expected 3 numbers, got 2" in msg


def test_entities_and_doctype_are_refused():
    bomb = ('<?xml version="1.0"?>\n<!DOCTYPE lolz [<!ENTITY lol "lol">'
            + "".join(f'<!ENTITY lol{i} "{"&lol" + str(i - 1) + ";" if i > 1 else "&lol;"}'
                      f'{"&lol" + str(i - 1) + ";" if i > 1 else "&lol;"}">'
                      for i in range(1, 10))
            + ']>\n<mujoco model="&lol9;"/>')
    (msg,) = _issues(bomb)
    assert "document type declaration is not accepted" in msg
    ext = '<!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]><robot name="&x;"/>'
    (msg,) = _issues(ext, read_urdf)
    assert "not accepted" in msg
    assert parse_xml("<a/>").tag == "a"


def test_massless_moving_body_is_an_error():
    (msg,) = _issues("<mujoco><worldbody><body name='ghost'><joint name='j'/>"
                     "</body></worldbody></mujoco>")
    assert "body 'ghost' has no mass but moves on joint 'j'" in msg


def test_mesh_mass_is_an_error():
    (msg,) = _issues("<mujoco><asset><mesh name='m' file='m.stl'/></asset><worldbody>"
                     "<body name='b'><joint/><geom type='mesh' mesh='m'/></body>"
                     "</worldbody></mujoco>")
    assert "takes its mass from a mesh geom" in msg and "<inertial>" in msg


# ---- the command line ----------------------------------------------------------------

def test_cli_reads_mjcf_and_urdf(capsys):
    assert main(["check", str(ROBOTS / "two_link_arm.xml"), "--keyframe", "swing"]) == 0
    out = capsys.readouterr()
    assert "imported from two_link_arm.xml (MJCF)" in out.out
    assert main(["solve", str(ROBOTS / "two_link_arm.urdf"), "--q", "shoulder=30deg",
                 "--qd", "elbow=1"]) in (0, 1)
    assert re.search(r"shoulder\s+Fx\s", capsys.readouterr().out)


def test_cli_bad_xml_exits_2_without_traceback(tmp_path, capsys):
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco>\n  <worldbody>\n    <bodi/>\n  </worldbody>\n</mujoco>\n")
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:3:5:" in err and "did you mean 'body'" in err
    assert "Traceback" not in err
    assert main(["check", str(ROBOTS / "two_link_arm.urdf"), "--q", "shoulder"]) == 2
    assert "JOINT=VALUE" in capsys.readouterr().err


def test_format_flag_reads_any_extension(tmp_path, capsys):
    copy = tmp_path / "arm.model"
    copy.write_text((ROBOTS / "two_link_arm.urdf").read_text())
    assert main(["check", str(copy), "--format", "urdf"]) == 0
    capsys.readouterr()


# ---- every number and keyword read, checked (exit 2, never 70) -------------------------

BODY = ('<mujoco>{top}<worldbody><body {body}><joint {joint}/><geom size="0.1" {geom}/>'
        "</body></worldbody>{end}</mujoco>")


def _mjcf(top="", body="", joint="", geom="", end="") -> str:
    return BODY.format(top=top, body=body, joint=joint, geom=geom, end=end)


BAD_MJCF = [
    (_mjcf(top='<option density="0 0 0"/>'), "<option density>", "expected 1 number, got 3"),
    (_mjcf(top='<option wind="a b c"/>'), "<option wind>", "'a' is not a number"),
    (_mjcf(top='<option wind="1 2"/>'), "<option wind>", "expected 3 numbers, got 2"),
    (_mjcf(top='<option viscosity="1e400"/>'), "<option viscosity>", "'1e400' is too large"),
    (_mjcf(body='gravcomp="1 1"'), "<body gravcomp>", "expected 1 number, got 2"),
    (_mjcf(geom='group="nan"'), "<geom group>", "'nan' is not a whole number"),
    (_mjcf(geom='group="1e400"'), "<geom group>", "'1e400' is not a whole number"),
    (_mjcf(geom='group="3000000000"'), "<geom group>", "outside the integers MuJoCo reads"),
    (_mjcf(geom='contype="1.5"'), "<geom contype>", "'1.5' is not a whole number"),
    (_mjcf(top='<compiler inertiagrouprange="0 1.5"/>'), "<compiler inertiagrouprange>",
     "'1.5' is not a whole number"),
    (_mjcf(joint='damping="1e"'), "<joint damping>", "'1e' is not a number"),
    (_mjcf(joint='damping="1 2 3 4"'), "<joint damping>", "expected 1 to 3 numbers, got 4"),
    (_mjcf(joint='range="1"'), "<joint range>", "expected 2 numbers, got 1"),
    (_mjcf(geom='mass="1_000"'), "<geom mass>", "'1_000' is not a number"),
    (_mjcf(body='pos="0,0,1"'), "<body pos>", "separate numbers with spaces"),
    (_mjcf(end='<keyframe><key qvel="x"/></keyframe>'), "<key qvel>", "'x' is not a number"),
    (_mjcf(body='mocap="yes"'), "<body mocap>", "'yes' is not a value of 'mocap'"),
    (_mjcf(joint='limited="yes"'), "<joint limited>", "'yes' is not a value of 'limited'"),
    (_mjcf(geom='shellinertia="True"'), "<geom shellinertia>", "did you mean 'true'"),
    (_mjcf(top='<option><flag gravity="off"/></option>'), "<flag gravity>",
     "expected disable or enable"),
    (_mjcf(top='<compiler balanceinertia="1"/>'), "<compiler balanceinertia>",
     "'1' is not a value of 'balanceinertia'"),
]


@pytest.mark.parametrize("xml, key, said", BAD_MJCF)
def test_every_mjcf_number_and_keyword_is_checked(xml, key, said, tmp_path, capsys):
    """Bare float() and int(float()) reads ended in exit 70 (`<option density="0 0 0">`,
    `wind="a b c"`, `gravcomp="1 1"`, `group="nan"` or `"1e400"`): each is now one
    located message, exit 2, where MuJoCo refuses the value too."""
    path = tmp_path / "m.xml"
    path.write_text(xml)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert re.search(rf"^mbody: error: {re.escape(str(path))}:1:\d+: {re.escape(key)}: ", err)
    assert said in err and "Traceback" not in err and "internal error" not in err
    mj = _mujoco()
    with pytest.raises(ValueError):
        mj.MjModel.from_xml_string(xml)


@pytest.mark.parametrize("xml", [
    _mjcf(top='<option density="1.2" viscosity="0.1" wind="0 1 0"/>'),
    _mjcf(body='gravcomp="0.5"', joint='damping="1 0.5" stiffness="2 1 0.1"'),
    _mjcf(geom='group="3" contype="0" conaffinity="-1"'),
    _mjcf(body='pos="0x1p-1 0 +.5"', joint='axis=" 0\t1\n 0 "'),
    _mjcf(joint='range=""', geom='pos=""'),
])
def test_values_mujoco_reads_are_read(xml):
    """What MuJoCo 4 accepts loads: fluid options and gravity compensation (noted),
    damping and stiffness as polynomials (up to three coefficients), C's hexadecimal
    numbers, any blanks around numbers, an empty value (as if not given)."""
    mj = _mujoco()
    mj.MjModel.from_xml_string(xml)
    model = Model.from_spec(validate(read_mjcf(xml)))
    assert model.body_names == ("body1",)


def test_a_class_value_is_reported_at_the_class(tmp_path):
    (msg,) = _issues('<mujoco>\n<default>\n  <geom group="x"/>\n</default>\n<worldbody>\n'
                     '<body><joint/><geom size="0.1"/></body>\n</worldbody>\n</mujoco>')
    assert msg.startswith("bad.xml:3:9: <geom group>: 'x' is not a whole number")


@pytest.mark.parametrize("joint, link, key, said", [
    ('<dynamics damping="1e"/>', "", "<dynamics damping>", "'1e' is not a number"),
    ('<dynamics friction="inf"/>', "", "<dynamics friction>", "'inf' is not a finite number"),
    ('<origin xyz="1 2"/>', "", "<origin xyz>", "expected 3 numbers, got 2"),
    ('<axis xyz="0 0 1e999"/>', "", "<axis xyz>", "too large for a number"),
    ("", '<visual><geometry><sphere radius="x"/></geometry></visual>', "<sphere radius>",
     "'x' is not a number"),
    ("", '<visual><geometry><box size="1 1"/></geometry></visual>', "<box size>",
     "expected 3 numbers, got 2"),
])
def test_every_urdf_number_is_checked(joint, link, key, said, tmp_path, capsys):
    path = tmp_path / "r.urdf"
    path.write_text(ARM.format(joint=joint, child="b", link=link))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert re.search(rf"^mbody: error: {re.escape(str(path))}:1:\d+: {re.escape(key)}: ", err)
    assert said in err and "Traceback" not in err


def test_an_mbody_entry_number_is_checked():
    base = ('<mujoco><worldbody><body name="a"><joint/><geom size="0.1"/></body>'
            '</worldbody><custom>{}</custom></mujoco>')
    (msg,) = _issues(base.format('<numeric name="mbody:dimension" data="inf"/>'))
    assert "'inf' is not a finite number" in msg
    (msg,) = _issues(base.format('<numeric name="mbody:body:a" data="1"/>'))
    assert "a <numeric> entry holds mbody:dimension or mbody:reaction" in msg


# ---- reading: marks found in one pass; included files bounded together ----------------

def test_attribute_marks_with_angle_brackets_and_wide_characters():
    """Each attribute's line and column, found by reading each tag once (the search up
    to the first '>' stopped inside a value, and took time with the square of it)."""
    text = ("<root a='1>2' b=\"x\"\n"
            '  c="é>é"\tdd="4"><kid e="5"/>é<kid f="6"/></root>')
    root = parse_xml(text)
    first, second = text.split("\n")

    def at(line: str, what: str) -> int:  # 1-based column, in characters
        return line.index(what) + 1

    assert root.attr_marks == {"a": (1, at(first, "a=")), "b": (1, at(first, "b=")),
                               "c": (2, at(second, "c=")), "dd": (2, at(second, "dd="))}
    assert root.attr_marks["dd"] == (2, 11)
    kids = root.findall("kid")
    assert kids[0].attr_marks == {"e": (2, at(second, "e="))}
    assert kids[1].attr_marks == {"f": (2, at(second, "f="))} == {"f": (2, 36)}
    assert (kids[1].line, kids[1].column) == (2, at(second, "<kid f"))


def test_included_files_are_bounded_together(tmp_path, capsys, monkeypatch):
    """100 includes of one 30 MB file took 3.8 GB, then 'out of memory': the bytes read
    over all included files are bounded (MAX_INCLUDED_BYTES, 64 MiB; lowered here), and
    the include that passes the bound is named at its line."""
    from mbody.io.interop import mjcf_source

    part = tmp_path / "part.xml"
    part.write_text("<mujoco><custom>" + '<text name="t" data="x"/>' * 160
                    + "</custom></mujoco>")
    monkeypatch.setattr(mjcf_source, "MAX_INCLUDED_BYTES", 3 * part.stat().st_size)
    main_file = tmp_path / "main.xml"
    main_file.write_text('<mujoco model="m">\n' + '  <include file="part.xml"/>\n' * 4
                         + '  <worldbody><body><joint/><geom size="0.1"/></body></worldbody>'
                         "\n</mujoco>\n")
    assert main(["check", str(main_file)]) == 2
    err = capsys.readouterr().err
    size = part.stat().st_size
    assert re.search(rf"^mbody: error: {re.escape(str(main_file))}:5:12: <include file>: "
                     r"including 'part.xml' brings the included files to 15\.\d KiB "
                     rf"\({4 * size:,} bytes\) together \(include number 4\); at most "
                     rf"11\.\d KiB \({3 * size:,} bytes\) of included files is read for one "
                     "model", err), err
    main_file.write_text(main_file.read_text().replace('  <include file="part.xml"/>\n',
                                                       "", 1))
    assert main(["check", str(main_file)]) == 0


def test_a_value_with_line_breaks_stays_on_its_line(tmp_path, capsys):
    """Found by tools/fuzz_xml.py: a joint type written with &#10; split the message into
    lines that looked like problems without a place; the break is written as \\n."""
    path = tmp_path / "m.xml"
    path.write_text(_mjcf(joint='type="1&#9;2&#10;3"'))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown joint type '1\t2\\n3'" in err


@pytest.mark.parametrize("key", ["²", "9" * 5000])
def test_a_keyframe_index_that_is_no_number_is_a_name(key, capsys):
    """'²' is a digit to str.isdigit but not to int(); 5000 digits are past int()'s
    limit: both were exit 70."""
    assert main(["check", str(ROBOTS / "two_link_arm.xml"), "--keyframe", key]) == 2
    err = capsys.readouterr().err
    assert "no keyframe named" in err and "(the file has: swing)" in err and len(err) < 300


def test_a_planar_model_out_of_its_plane_is_refused(tmp_path, capsys):
    """Found by tools/fuzz_xml.py: an exported planar model (mbody:dimension 2) whose body
    was moved to z = -1e9 loaded with the z dropped; now each body and joint out of the
    x-y plane is named at its line."""
    from mbody.io.interop.mjcf_write import to_mjcf

    text = to_mjcf(mbody.load(ROBOTS.parent / "triple_pendulum.yaml"))
    path = tmp_path / "m.xml"
    path.write_text(text)
    assert main(["check", str(path)]) == 0
    capsys.readouterr()
    lines = text.split("\n")
    (k,) = [i for i, line in enumerate(lines) if '<body name="lower"' in line]
    lines[k] = re.sub(r'pos="([^ ]+) ([^ ]+) ([^"]+)"', r'pos="\1 \2 -1e9"', lines[k])
    path.write_text("\n".join(lines))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}:{k + 1}:" in err and "says the model moves in the world x-y plane, " \
        "but body 'lower' is at z = -1e+09" in err and "joint 'B' is at z" in err


def test_an_include_whose_name_is_too_long_is_located(tmp_path, capsys):
    path = tmp_path / "m.xml"
    path.write_text('<mujoco>\n  <include file="' + "x" * 5000 + '"/>\n</mujoco>\n')
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"mbody: error: {path}:2:12: <include file>: cannot read the "
                          "included file 'xxx") and "File name too long" in err


def test_a_planar_mjcf_body_with_zero_inertia_reads_as_a_point_mass(tmp_path):
    """mbody's planar export of a point pendulum with its <inertial> given diaginertia
    0 0 0 (the XML fuzzer's case): read back as the particle it is (it raised a KeyError
    on the orientation such a body does not have)."""
    path = tmp_path / "pp.xml"
    path.write_text(
        '<mujoco model="point-pendulum"><option gravity="0 -9.81 0" /><worldbody>'
        '<body name="bob" pos="0.5 -0.8660254037844386 0" quat="1 0 0 0">'
        '<joint name="O" type="hinge" pos="-0.5 0.8660254037844386 0" axis="0 0 1" />'
        '<inertial pos="0 0 0" mass="1" diaginertia="0 0 0" /></body></worldbody>'
        '<custom><numeric name="mbody:dimension" data="2" />'
        '<text name="mbody:body:bob" data="{&quot;inertia&quot;: 0}" /></custom></mujoco>')
    model = mbody.load(path)
    assert model.dimension == 2 and bool(model.particle[0])
    np.testing.assert_allclose(model.initial.position[0, :2], [0.5, -0.8660254037844386])
    # the point pendulum at 30 deg from the vertical: g sin(30 deg) / L along the path
    a = mbody.assemble(model).solve().accelerations
    np.testing.assert_allclose(np.hypot(a[0], a[1]), 9.81 * 0.5, rtol=1e-12)
