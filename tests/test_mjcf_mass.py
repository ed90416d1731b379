"""A body's mass, mass centre and inertia from its MJCF geoms, against MuJoCo's own
(``body_mass``, ``body_ipos``, ``body_iquat``, ``body_inertia``), for every geom type
mbody computes (sphere, capsule, cylinder, ellipsoid, box, height field) and every way a
size is given: one, two or three numbers, ``fromto``, a default class's size longer or
shorter than the geom's (MuJoCo keeps the class's trailing numbers), nested classes and
``childclass``, ``mass`` or ``density`` (given, from a class, or MuJoCo's 1000),
``shellinertia``, every orientation form, several geoms in one body, the geoms MuJoCo
leaves out, and the compiler's mass options. What MuJoCo refuses, mbody refuses too, with
a located message (exit 2 on the command line).

Tolerances, from how MuJoCo computes: masses and mass centres are sums and products of
the same doubles (1e-12 relative). A single geom's inertia is copied as computed (1e-12).
Several geoms' tensor is diagonalised by MuJoCo's Jacobi iteration (``mjuu_eig3``), which
stops when a rotation's cosine is within 1e-12 of 1, i.e. a last angle below 1.5e-6 rad:
the principal moments are then within ~1e-12 of the spread of moments (second order),
the off-diagonal terms of mbody's tensor in MuJoCo's principal axes within 1.5e-6 of
that spread (first order), plus MuJoCo's absolute stop of 1e-12.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import main
from mbody.errors import ModelError
from mbody.io.interop.mjcf import read_mjcf
from mbody.model.model import Model
from mbody.model.validate import validate

mujoco = pytest.importorskip("mujoco")

ARM = Path(__file__).resolve().parent.parent / "models" / "robots" / "two_link_arm.xml"

SIZES = {"sphere": "0.1", "capsule": "0.05 0.2", "cylinder": "0.05 0.2",
         "ellipsoid": "0.1 0.2 0.3", "box": "0.1 0.2 0.3"}
SOLIDS = tuple(SIZES)
FROMTO = ("capsule", "cylinder", "ellipsoid", "box")


@pytest.fixture(autouse=True)
def _elsewhere(tmp_path, monkeypatch):
    """MuJoCo writes its warnings (settotalmass is deprecated) to MUJOCO_LOG.TXT in the
    working folder: not the checkout's."""
    monkeypatch.chdir(tmp_path)


def _doc(geoms: str, *, defaults: str = "", compiler: str = "", asset: str = "",
         body: str = "", inertial: str = "") -> str:
    return (f"<mujoco>{compiler}{asset}<default>{defaults}</default><worldbody>"
            f'<body name="b" {body}><joint name="j" axis="0 1 0"/>{inertial}{geoms}</body>'
            "</worldbody></mujoco>")


def _theirs(xml: str) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """MuJoCo's (mass, mass centre, principal moments, principal axes as columns)."""
    m = mujoco.MjModel.from_xml_string(xml)
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, m.body_iquat[1])
    return float(m.body_mass[1]), m.body_ipos[1].copy(), m.body_inertia[1].copy(), \
        R.reshape(3, 3)


def _ours(xml: str) -> tuple[float, np.ndarray, np.ndarray]:
    """mbody's (mass, mass centre, inertia tensor about it), world axes (= the body's)."""
    model = Model.from_spec(validate(read_mjcf(xml)))
    (i,) = [k for k, n in enumerate(model.body_names) if n == "b"]
    R = model.initial.W_R_B[i]
    return float(model.mass[i]), model.initial.position[i], R @ model.J[i] @ R.T


def _agree(xml: str, several: bool = False) -> None:
    mass, com, moments, axes = _theirs(xml)
    m, c, J = _ours(xml)
    assert m == pytest.approx(mass, rel=1e-12), (m, mass)
    scale = max(1.0, float(np.abs(com).max()))
    np.testing.assert_allclose(c, com, rtol=0, atol=1e-12 * scale)
    in_axes = axes.T @ J @ axes  # mbody's tensor in MuJoCo's principal axes
    spread = float(moments.max() - moments.min())
    np.testing.assert_allclose(np.diag(in_axes), moments, rtol=1e-12,
                               atol=1e-12 * max(spread, float(moments.max())))
    off = in_axes - np.diag(np.diag(in_axes))
    bound = (1.5e-6 * spread + 1e-12) if several else 1e-12 * float(moments.max())
    assert np.abs(off).max() <= bound, (in_axes, moments)


def _refused(xml: str) -> str:
    with pytest.raises(ModelError) as info:
        read_mjcf(xml, file="m.xml")
    (issue,) = info.value.issues
    assert issue.file == "m.xml" and issue.line >= 1 and issue.column >= 1
    with pytest.raises(ValueError):  # MuJoCo refuses it too
        mujoco.MjModel.from_xml_string(xml)
    return issue.message + " (" + issue.hint + ")"


# ---- every type, every size form ------------------------------------------------------

@pytest.mark.parametrize("typ", SOLIDS)
@pytest.mark.parametrize("size", ["exact", "longer"])
def test_each_solid_with_its_own_size(typ, size):
    """As many numbers as the type uses, or three (the rest unused)."""
    given = SIZES[typ] if size == "exact" else " ".join((SIZES[typ] + " 0.7 0.9").split()[:3])
    _agree(_doc(f'<geom type="{typ}" size="{given}" pos="0.1 -0.2 0.3"/>'))


@pytest.mark.parametrize("typ", FROMTO)
@pytest.mark.parametrize("size", ["0.05", "0.05 0.3", "0.05 0.3 0.4"])
def test_fromto_with_one_two_or_three_numbers(typ, size):
    """MuJoCo: a capsule's or cylinder's half-length, a box's or an ellipsoid's third
    half-size, is half the fromto length; a box's and an ellipsoid's two cross
    half-sizes are both size[0] (mbody used size[1] for the second: 3.52 kg against
    MuJoCo's 5.52 kg for the issue's box)."""
    _agree(_doc(f'<geom type="{typ}" size="{size}" fromto="0.1 0 0 0.3 0.4 -0.2"/>'))


def test_the_issues_fromto_box():
    xml = _doc('<geom type="box" size="0.05 0.03" fromto="0 0 0 0 0 1.1" density="1000"/>')
    mass, *_ = _theirs(xml)
    assert _ours(xml)[0] == pytest.approx(mass, rel=1e-12)
    assert mass == pytest.approx(1000 * 0.1 * 0.1 * 1.1)  # both cross sizes 0.05


@pytest.mark.parametrize("typ", SOLIDS)
@pytest.mark.parametrize("mine", ["0.07", "0.07 0.15"])
def test_a_shorter_size_keeps_the_class_trailing_numbers(typ, mine):
    """The class says three numbers, the geom one or two: MuJoCo keeps the class's
    trailing numbers (mbody filled zeros: a capsule became a sphere, a box or an
    ellipsoid had 'no volume')."""
    defaults = f'<geom type="{typ}" size="0.1 0.2 0.3"/>'
    _agree(_doc(f'<geom size="{mine}"/>', defaults=defaults))


@pytest.mark.parametrize("typ", SOLIDS)
def test_a_longer_size_over_a_shorter_class(typ):
    _agree(_doc('<geom size="0.1 0.2 0.3"/>', defaults=f'<geom type="{typ}" size="0.05"/>'))


@pytest.mark.parametrize("typ", SOLIDS)
def test_nested_classes_and_childclass(typ):
    defaults = (f'<geom type="{typ}" size="0.1 0.2 0.3" density="700"/>'
                '<default class="thin"><geom size="0.03"/>'
                '<default class="thinner"><geom size="0.02 0.25" mass="2"/></default>'
                "</default>")
    _agree(_doc('<geom size="0.015"/><geom class="thin" pos="0 0 0.5"/>',
                defaults=defaults, body='childclass="thinner"'), several=True)


@pytest.mark.parametrize("typ", SOLIDS)
@pytest.mark.parametrize("how", ['mass="3"', 'density="250"', "", "class"])
@pytest.mark.parametrize("shell", [False, True])
def test_mass_density_and_shellinertia(typ, how, shell):
    """A solid, or a shell (``shellinertia``: the density is per area), of a given mass,
    density, MuJoCo's default density 1000, or a class's density."""
    attrs = (how if how != "class" else "") + (' shellinertia="true"' if shell else "")
    defaults = '<geom density="420"/>' if how == "class" else ""
    _agree(_doc(f'<geom type="{typ}" size="{SIZES[typ]}" {attrs} euler="10 20 30"/>',
                defaults=defaults))


@pytest.mark.parametrize("typ", FROMTO)
def test_shellinertia_with_fromto(typ):
    _agree(_doc(f'<geom type="{typ}" size="0.05" fromto="0 0 0 0.2 0.1 0.3" '
                'shellinertia="true"/>'))


def test_height_field_takes_its_asset_size():
    asset = '<asset><hfield name="h" size="0.5 0.3 0.2 0.1" nrow="2" ncol="2"/></asset>'
    _agree(_doc('<geom type="hfield" hfield="h" pos="0 0 0.1"/>', asset=asset))


@pytest.mark.parametrize("orientation", ['quat="0.9 0.1 0.3 0.2"', 'euler="10 -20 30"',
                                         'axisangle="1 2 3 40"',
                                         'xyaxes="1 1 0 -1 1 0.3"', 'zaxis="0.2 1 0.5"'])
def test_every_orientation_form(orientation):
    _agree(_doc(f'<geom type="box" size="0.1 0.2 0.3" {orientation} pos="0.1 0 0"/>'
                f'<geom type="capsule" size="0.05 0.2" {orientation} pos="0 0.3 0"/>'),
           several=True)


@pytest.mark.parametrize("mine", ['quat="0 1 0 0"', 'zaxis="0 1 1"', ""])
def test_a_geoms_orientation_replaces_its_class(mine):
    """A class's euler and the geom's quat are not 'given twice': the geom's replaces
    it, as in MuJoCo (a class's orientation holds when the geom gives none)."""
    _agree(_doc(f'<geom type="box" size="0.1 0.2 0.3" {mine}/>',
                defaults='<geom euler="0 0 90"/>'))


def test_several_geoms_of_every_type():
    asset = '<asset><hfield name="h" size="0.5 0.3 0.2 0.1" nrow="2" ncol="2"/></asset>'
    _agree(_doc('<geom type="sphere" size="0.1" pos="0.3 0 0"/>'
                '<geom type="capsule" size="0.05" fromto="0 0 0 0 0.4 0.1" density="300"/>'
                '<geom type="cylinder" size="0.04 0.1" pos="0 0 0.5" euler="30 0 0"/>'
                '<geom type="ellipsoid" size="0.1 0.05 0.02" pos="-0.2 0 0" mass="0.4"/>'
                '<geom type="box" size="0.1 0.2 0.05" pos="0 -0.3 0" '
                'shellinertia="true" mass="1.5"/>'
                '<geom type="hfield" hfield="h" pos="0 0 -0.4" density="10"/>', asset=asset),
           several=True)


def test_the_geoms_mujoco_leaves_out():
    """Out of inertiagrouprange; mass or density 0; a mass at or below mjEPS (1e-14);
    a given mass on a volume at or below mjEPS; a plane in a body that does not move."""
    xml = _doc('<geom type="sphere" size="0.1"/>'
               '<geom type="sphere" size="0.2" pos="1 0 0" group="4"/>'
               '<geom type="sphere" size="0.2" pos="0 1 0" density="0"/>'
               '<geom type="sphere" size="0.2" pos="0 0 1" mass="0"/>'
               '<geom type="sphere" size="0.2" pos="0 0 1" mass="1e-15"/>'
               '<geom type="sphere" size="1e-6" pos="0 0 2" mass="5"/>',
               compiler='<compiler inertiagrouprange="0 3"/>')
    _agree(xml)
    assert _theirs(xml)[0] == pytest.approx(1000 * 4 / 3 * np.pi * 0.1**3)


@pytest.mark.parametrize("compiler", [
    '<compiler boundmass="50"/>', '<compiler boundinertia="0.5"/>',
    '<compiler settotalmass="7"/>', '<compiler angle="radian" eulerseq="ZYX"/>',
    '<compiler inertiafromgeom="true"/>'])
def test_the_compilers_mass_options(compiler):
    inertial = '<inertial pos="0 0 1" mass="1" diaginertia="1 1 1"/>'
    _agree(_doc('<geom type="box" size="0.1 0.2 0.3" euler="0.3 0.2 0.1"/>'
                '<geom type="sphere" size="0.1" pos="0.2 0 0"/>', compiler=compiler,
                inertial=inertial if "inertiafromgeom" in compiler else ""), several=True)


# ---- what MuJoCo refuses, refused ----------------------------------------------------

@pytest.mark.parametrize("geom, said", [
    ('type="capsule" size="0.1"', "capsule geom needs its radius and half-length greater "
                                  "than zero; its size is 0.1 0"),
    ('type="box" size="0.1 -0.2 0.3"', "box geom needs its three half-sizes greater than "
                                       "zero"),
    ('type="ellipsoid" size="0.1 0.2"', "ellipsoid geom needs its three radii"),
    ('type="sphere" size="0.1" fromto="0 0 0 0 0 1"', "fromto places a capsule, cylinder, "
                                                      "ellipsoid or box, not a sphere"),
    ('type="capsule" size="0.1" fromto="0 0 0 0 0 1" pos="0 0 1"', "takes no pos"),
    ('type="capsule" size="0.1" fromto="0 0 1 0 0 1"', "the two ends coincide"),
    ('type="plane" size="1 1 1"', "plane geom is only allowed in a body that does not move"),
    ('type="sphere" size="0.1" density="-3"', "the geom's density is negative"),
    ('type="sphere" size="0.1" mass="-3"', "the geom's mass is negative"),
    ('type="hfield" hfield="nothing"', "names no <hfield> asset"),
])
def test_what_mujoco_refuses_is_refused(geom, said):
    assert said in _refused(_doc(f"<geom {geom}/>"))


def test_a_class_size_that_stays_too_short_says_so():
    msg = _refused(_doc('<geom size="0.07"/>', defaults='<geom type="box" size="0.1 0.2"/>'))
    assert "its size is 0.07 0.2 0" in msg and "default class's trailing numbers" in msg


def test_mesh_mass_and_a_mesh_fitted_size_are_refused():
    asset = '<asset><mesh name="m" vertex="0 0 0 1 0 0 0 1 0 0 0 1"/></asset>'
    for geom, said in (('type="mesh" mesh="m"', "takes its mass from a mesh geom"),
                       ('type="box" mesh="m"', "its size is fitted to mesh 'm'")):
        xml = _doc(f"<geom {geom}/>", asset=asset)
        mujoco.MjModel.from_xml_string(xml)  # MuJoCo reads meshes; mbody does not
        with pytest.raises(ModelError) as info:
            read_mjcf(xml)
        assert said in str(info.value) and "<inertial>" in str(info.value)


def test_a_refused_geom_exits_2_at_its_line(tmp_path, capsys):
    path = tmp_path / "m.xml"
    path.write_text("<mujoco>\n <worldbody>\n  <body>\n   <joint/>\n"
                    '   <geom type="capsule" size="0.1"/>\n  </body>\n </worldbody>\n'
                    "</mujoco>\n")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}:5:25: <geom size>: a capsule geom needs" in err
    assert "Traceback" not in err


def test_the_shipped_arms_masses_are_mujocos():
    m = mujoco.MjModel.from_xml_path(str(ARM))
    model = mbody.load(ARM)
    for i, name in enumerate(model.body_names):
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        assert model.mass[i] == pytest.approx(m.body_mass[b], rel=1e-12)


def test_inertiafromgeom_true_keeps_the_inertial_of_a_body_without_geoms():
    """Found by tools/fuzz_xml.py: with inertiafromgeom="true", a body whose geoms give
    no mass keeps its <inertial> in MuJoCo (mbody gave it no mass, then boundmass's)."""
    xml = ('<mujoco><compiler inertiafromgeom="true" boundmass="0.1"/><worldbody>'
           '<body name="b"><joint axis="0 1 0"/><inertial pos="0.1 0 0" mass="3.7" '
           'diaginertia="0.07 0.08 0.06"/></body></worldbody></mujoco>')
    _agree(xml)
    assert _ours(xml)[0] == pytest.approx(3.7)


def test_settotalmass_scales_as_mujoco_bounds_it():
    """Found by tools/fuzz_xml.py: MuJoCo's scale is at least mjMINVAL (1e-15), so
    settotalmass="1e-20" leaves a one-body model 1e-15 kg heavy, not 1e-20."""
    xml = _doc('<geom type="sphere" size="0.1" mass="1"/>',
               compiler='<compiler settotalmass="1e-20"/>')
    assert _theirs(xml)[0] == pytest.approx(1e-15)
    _agree(xml)
