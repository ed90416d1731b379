"""Structure-aware fuzzer of mbody's MJCF and URDF import, cross-checked against MuJoCo.

    python tools/fuzz_xml.py [-n 10000] [--seed 0] [--jobs 2] [--hang 30] [--only I]

Each case (number i of the run, reproducible from --seed and i alone) takes a robot
model (the shipped models/robots/*.xml and *.urdf, every shipped YAML model exported to
MJCF, dm_control's suite when it is installed, or a small MJCF or URDF generated for the
case: random body trees with every joint, geom type and size form, default classes,
compiler options, keyframes), changes its element tree one to four times in ways that
know the formats (an attribute given an awkward number or text, scaled, lengthened,
shortened, dropped, misspelt or added; an element dropped, duplicated, misspelt or
grafted elsewhere; a geom of any type and size form added; a default class added and
used; part of the model moved into an ``<include>``d file, or an include that is
missing, cyclic or not MJCF; a joint type changed; compiler, option and keyframe
entries), writes it out, and sometimes damages the text as well (cut short, a stray
``<`` or ``&``, a byte that is not UTF-8, a DOCTYPE, an entity, a ``>`` in a value).

It then runs ``mbody check`` and, on what check accepts, ``mbody solve`` through
``mbody.cli.main`` in this process, classified as tools/fuzz.py classifies the YAML
fuzzer's commands (accepted, clean error, crash, hang; its `run_command` and `classify`).
Every accepted MJCF that MuJoCo also loads is compared with MuJoCo: every body's mass,
mass centre and inertia at the state mbody reads by default, and where the model is a
tree mbody maps exactly (no equality constraints, no mbody entries, no particles; what
mbody lists as not imported switched off in MuJoCo, as tests/test_interop_import.py
does) the mass-centre and angular accelerations there. That state is the key 'initial'
when the file has one, else qpos0 at rest (`mbody.io.interop.mjcf_state.chosen`); MuJoCo
is reset to the same (`_reset`). A difference is a mismatch,
counted with the crashes.

Tolerances: masses and mass centres 1e-9 relative (the same sums of the same doubles:
~1e-15). Inertias in MuJoCo's principal axes: the moments to 1e-9 of the largest, the
off-diagonal terms within 1.5e-6 of the spread of the moments (MuJoCo's Jacobi iteration
stops at a last rotation below 1.5e-6 rad). Accelerations, with MuJoCo given mbody's
exact principal axes (so that they compare the dynamics, not MuJoCo's diagonalisation):
1e-9 of the largest acceleration (at least 1), plus the error bound of mbody's solve,
1e-15 times the condition number of its Schur complement (about 4.5 eps cond); a model
whose Schur complement has a condition number over 1e10, or MuJoCo's mass matrix over
1e6, is counted as not compared.

The counts are printed at the end, with the first few failures in full (``--only I``
reproduces one, printing its files).
"""

from __future__ import annotations

import contextlib
import copy
import io
import math
import multiprocessing as mp
import os
import random
import re
import shutil
import sys
import tempfile
import time
import traceback
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

TOOLS = Path(__file__).resolve().parent
ROOT = TOOLS.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))
if str(TOOLS) not in sys.path:
    sys.path.insert(0, str(TOOLS))

from fuzz import (  # noqa: E402  (the YAML fuzzer: its commands and their classes)
    ACCEPTED,
    CLEAN,
    CRASH,
    HANG,
    Outcome,
    _misspell,
    _unlocated_problems,
    classify,
    count_lines,
    failure_lines,
    fuzz_arguments,
    run_command,
    verdict,
)

MISMATCH = "mismatch with MuJoCo"
KINDS = (CLEAN, ACCEPTED, CRASH, HANG, MISMATCH)
MASS_RTOL = 1e-9
ACC_RTOL = 1e-9
COND_LIMIT = 1e6
SCHUR_LIMIT = 1e10


# -- the inputs --------------------------------------------------------------------------

@dataclass
class Base:
    name: str
    kind: str  # "mjcf" or "urdf"
    text: str
    files: dict[str, str] = field(default_factory=dict)  # other files next to it


def _dm_control() -> list[Base]:
    try:
        import dm_control  # noqa: PLC0415 - optional, heavy
    except ImportError:
        return []
    suite = Path(dm_control.__file__).parent / "suite"
    common = {f"common/{p.name}": p.read_text() for p in (suite / "common").glob("*.xml")}
    names = ("acrobot", "cartpole", "pendulum", "reacher", "finger", "point_mass",
             "hopper", "walker", "cheetah", "swimmer", "ball_in_cup", "manipulator")
    return [Base(f"dm_control/{n}.xml", "mjcf", (suite / f"{n}.xml").read_text(), common)
            for n in names if (suite / f"{n}.xml").is_file()]


def _exported() -> list[Base]:
    """Every shipped YAML model written as MJCF (with its mbody entries)."""
    import mbody  # noqa: PLC0415 - loaded with the package
    from mbody.io.interop.mjcf_write import to_mjcf  # noqa: PLC0415

    out = []
    for p in sorted((ROOT / "models").glob("*.yaml")):
        with contextlib.suppress(Exception):
            out.append(Base(f"{p.stem}.yaml->mjcf", "mjcf", to_mjcf(mbody.load(p))))
    return out


def bases() -> list[Base]:
    robots = ROOT / "models" / "robots"
    found = [Base(p.name, "mjcf" if p.suffix == ".xml" else "urdf", p.read_text())
             for p in sorted(robots.glob("*")) if p.suffix in (".xml", ".urdf")]
    return found + _exported() + _dm_control()


GEOMS = ("sphere", "capsule", "cylinder", "ellipsoid", "box")


def _num(rng: random.Random, lo: float = 0.02, hi: float = 0.5) -> str:
    return f"{rng.uniform(lo, hi):.4g}"


def _vec(rng: random.Random, n: int, lo: float = -0.5, hi: float = 0.5) -> str:
    return " ".join(_num(rng, lo, hi) for _ in range(n))


def random_geom(rng: random.Random, cls: str | None = None) -> str:
    """A geom of any type and size form: one to three numbers, fromto or a position and
    orientation, a mass, a density or neither, sometimes a shell, a class, a group."""
    typ = rng.choice(GEOMS + ("sphere", "box", "capsule"))
    attrs = [f'type="{typ}"']
    fromto = typ != "sphere" and rng.random() < 0.4
    n = 1 if fromto else {"sphere": 1, "capsule": 2, "cylinder": 2}.get(typ, 3)
    if rng.random() < 0.25:  # fewer or more numbers: the rest from a class, or unused
        n = rng.choice([1, 2, 3])
    if rng.random() < 0.92 or cls:
        attrs.append(f'size="{_vec(rng, n, 0.02, 0.3)}"')
    if fromto:
        a = _vec(rng, 3)
        b = _vec(rng, 3)
        attrs.append(f'fromto="{a} {b}"')
    else:
        attrs.append(f'pos="{_vec(rng, 3)}"')
        form = rng.choice(["", "quat", "euler", "axisangle", "xyaxes", "zaxis"])
        if form:
            count = {"quat": 4, "euler": 3, "axisangle": 4, "xyaxes": 6, "zaxis": 3}[form]
            attrs.append(f'{form}="{_vec(rng, count, -1, 1)}"')
    r = rng.random()
    if r < 0.25:
        attrs.append(f'mass="{_num(rng, 0.1, 5)}"')
    elif r < 0.5:
        attrs.append(f'density="{_num(rng, 100, 3000)}"')
    if rng.random() < 0.15:
        attrs.append('shellinertia="true"')
    if cls:
        attrs.append(f'class="{cls}"')
    if rng.random() < 0.1:
        attrs.append(f'group="{rng.choice([0, 1, 3, 4, 5])}"')
    return f"<geom {' '.join(attrs)}/>"


def _joint(rng: random.Random, root: bool) -> str:
    kind = rng.choice(["hinge"] * 5 + ["slide"] * 2 + ["ball"] + (["free"] if root else []))
    if kind == "free":
        return "<freejoint/>" if rng.random() < 0.5 else '<joint type="free"/>'
    axis = f' axis="{_vec(rng, 3, -1, 1)}"' if kind != "ball" and rng.random() < 0.7 else ""
    pos = f' pos="{_vec(rng, 3, -0.2, 0.2)}"' if rng.random() < 0.5 else ""
    return f'<joint type="{kind}"{axis}{pos}/>'


def generated_mjcf(rng: random.Random) -> Base:
    """A small MJCF: a random tree of bodies with joints and geoms of every kind."""
    classes = []
    defaults = ""
    if rng.random() < 0.5:
        typ = rng.choice(GEOMS)
        defaults = (f'<default><geom type="{typ}" size="{_vec(rng, 3, 0.05, 0.3)}"/>'
                    f'<default class="c1"><geom size="{_vec(rng, rng.choice([1, 2]), 0.05, 0.2)}"'
                    f' density="{_num(rng, 200, 2000)}"/>'
                    f'<default class="c2"><geom type="{rng.choice(GEOMS)}"/></default>'
                    "</default></default>")
        classes = ["c1", "c2"]
    compiler = rng.choice(["", '<compiler angle="radian"/>', '<compiler eulerseq="ZYX"/>',
                           '<compiler inertiafromgeom="true"/>', '<compiler boundmass="0.5"/>',
                           '<compiler inertiagrouprange="0 3"/>'])
    counter = [0]

    def body(depth: int) -> str:
        counter[0] += 1
        name = f' name="b{counter[0]}"' if rng.random() < 0.9 else ""
        joints = "".join(_joint(rng, depth == 0)
                         for _ in range(rng.choice([1] * 10 + [0, 2])))
        if rng.random() < 0.2:
            a, b, c = (rng.uniform(0.01, 0.1) for _ in range(3))  # principal moments
            mass = (f'<inertial pos="{_vec(rng, 3)}" mass="{_num(rng, 0.1, 5)}" '
                    f'diaginertia="{b + c:.4g} {a + c:.4g} {a + b:.4g}"/>')
        else:
            mass = "".join(random_geom(rng, rng.choice(classes + [None, None]))
                           for _ in range(rng.choice([1, 1, 2, 3])))
        kids = "".join(body(depth + 1) for _ in range(rng.choice([0, 1, 1, 2]))
                       if depth < 3 and counter[0] < 6)
        frame = rng.choice(["", f' euler="{_vec(rng, 3, -90, 90)}"',
                            f' quat="{_vec(rng, 4, -1, 1)}"'])
        childclass = f' childclass="{rng.choice(classes)}"' if classes and \
            rng.random() < 0.2 else ""
        return (f'<body{name} pos="{_vec(rng, 3)}"{frame}{childclass}>{joints}{mass}'
                f"{kids}</body>")

    bodies = "".join(body(0) for _ in range(rng.choice([1, 1, 2])))
    gravity = rng.choice(["", f'<option gravity="{_vec(rng, 3, -10, 10)}"/>'])
    return Base("generated.xml", "mjcf", f'<mujoco model="generated">{compiler}{gravity}'
                f"{defaults}<worldbody>{bodies}</worldbody></mujoco>")


def generated_urdf(rng: random.Random) -> Base:
    """A small URDF: a chain (with a branch) of links on every joint type."""
    links = ['<link name="base"/>']
    joints = []
    for k in range(1, rng.choice([2, 3, 4, 5])):
        parent = "base" if k == 1 else f"l{rng.randrange(1, k)}"
        a, b, c = (rng.uniform(0.01, 0.1) for _ in range(3))
        inertia = (f'<inertia ixx="{b + c:.4g}" ixy="0" ixz="0" iyy="{a + c:.4g}" '
                   f'iyz="0" izz="{a + b:.4g}"/>')
        shape = rng.choice([f'<box size="{_vec(rng, 3, 0.05, 0.3)}"/>',
                            f'<cylinder radius="{_num(rng)}" length="{_num(rng)}"/>',
                            f'<sphere radius="{_num(rng)}"/>'])
        links.append(f'<link name="l{k}"><inertial><origin xyz="{_vec(rng, 3)}" '
                     f'rpy="{_vec(rng, 3, -1, 1)}"/><mass value="{_num(rng, 0.1, 3)}"/>'
                     f"{inertia}</inertial><visual><geometry>{shape}</geometry></visual>"
                     "</link>")
        typ = rng.choice(["revolute", "continuous", "prismatic", "fixed"])
        joints.append(f'<joint name="j{k}" type="{typ}"><parent link="{parent}"/>'
                      f'<child link="l{k}"/><origin xyz="{_vec(rng, 3)}" '
                      f'rpy="{_vec(rng, 3, -1, 1)}"/><axis xyz="{_vec(rng, 3, -1, 1)}"/>'
                      '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
    return Base("generated.urdf", "urdf",
                f'<robot name="generated">{"".join(links)}{"".join(joints)}</robot>')


XML_NUMBERS = ["", " ", "0", "-0", "1", "-1", "0.5", "1e3", "1e9", "-1e9", "1e100",
               "1e101", "-1e200", "1e308", "1.8e308", "1e400", "-1e400", "1e-400", "5e-324",
               "nan", "NaN", "inf", "-inf", "infinity", "0x1p3", "0x10", "1_000", "1,5",
               "1e", "+.5", ".", "-", "1.", "2147483648", "-2147483649", "1.5", "١",
               "1 2", "1 2 3 4 5 6 7", "a b c", "0 0 0", "0 0 0 0", "1e9 1e9 1e9",
               "1e-12", "1e-15", "1e-20", "123456789012345678901234567890", "2m", "30deg",
               "1 nan 1", "1\t2\n3", " 1 ", "1\u00a02", "9" * 400, "1e" + "9" * 50]
XML_TEXTS = ["", "x", "true", "false", "True", "yes", "auto", "disable", "enable", "world",
             "main", "hinge", "slide", "ball", "free", "sphere", "box", "mesh", "plane",
             "hfield", "degree", "radian", "ZYX", "xyzz", "local", "global", "a>b", "é",
             "<", "&amp;", "x" * 5000]
ATTRS = {
    "geom": ["type", "size", "fromto", "pos", "quat", "euler", "mass", "density",
             "shellinertia", "group", "contype", "conaffinity", "class", "mesh", "hfield"],
    "body": ["pos", "quat", "euler", "axisangle", "xyaxes", "zaxis", "childclass", "mocap",
             "gravcomp", "name"],
    "joint": ["type", "axis", "pos", "ref", "damping", "stiffness", "range", "limited",
              "armature", "class"],
    "inertial": ["pos", "mass", "diaginertia", "fullinertia", "quat", "euler"],
    "compiler": ["angle", "eulerseq", "inertiafromgeom", "inertiagrouprange", "boundmass",
                 "boundinertia", "settotalmass", "coordinate", "balanceinertia"],
    "option": ["gravity", "density", "viscosity", "wind", "timestep"],
    "key": ["qpos", "qvel", "time", "name"],
    "link": ["name"], "joint_urdf": ["name", "type"], "origin": ["xyz", "rpy"],
    "mass": ["value"], "inertia": ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"],
    "axis": ["xyz"], "dynamics": ["damping", "friction"], "box": ["size"],
    "sphere": ["radius"], "cylinder": ["radius", "length"],
}


def awkward(rng: random.Random) -> str:
    k = rng.random()
    if k < 0.6:
        return rng.choice(XML_NUMBERS)
    if k < 0.9:
        return rng.choice(XML_TEXTS)
    return " ".join(rng.choice(XML_NUMBERS[:20]) for _ in range(rng.choice([2, 3, 4, 6])))


def _numbers(text: str) -> list[float] | None:
    try:
        return [float(t) for t in text.split()] if text.split() else None
    except ValueError:
        return None


def _elements(root: ET.Element) -> list[tuple[ET.Element, ET.Element | None]]:
    """Every (element, parent) below the root."""
    out: list[tuple[ET.Element, ET.Element | None]] = [(root, None)]
    for parent in root.iter():
        out.extend((c, parent) for c in parent)
    return out


def mutate_tree(rng: random.Random, root: ET.Element, kind: str, files: dict[str, str]
                ) -> str:
    """Change the tree in place once; return what was done."""
    elements = _elements(root)
    e, parent = rng.choice(elements)
    with_attrs = [(x, p) for x, p in elements if x.attrib]
    op = rng.choices(range(16), weights=[4, 3, 2, 1.5, 1, 2, 1.5, 1.5, 1.5, 0.5, 4, 2, 1.5,
                                         1.5, 1.5, 1])[0]
    if op <= 5 and with_attrs:
        e, parent = rng.choice(with_attrs)
        name = rng.choice(list(e.attrib))
        value = e.attrib[name]
        if op == 0:
            e.set(name, awkward(rng))
            return f"<{e.tag} {name}> = {e.get(name)!r:.40}"
        nums = _numbers(value)
        if op == 1 and nums is not None:
            k = rng.choice([rng.randint(-150, 150), rng.randint(-8, 8), 0])
            i = rng.randrange(len(nums))
            nums[i] = -nums[i] if k == 0 else nums[i] * 10.0 ** k
            e.set(name, " ".join(repr(x) for x in nums))
            return f"<{e.tag} {name}> scaled 1e{k} at {i}"
        if op == 2 and nums is not None:
            if rng.random() < 0.5 and len(nums) > 1:
                nums.pop(rng.randrange(len(nums)))
            else:
                nums.append(rng.choice(nums))
            e.set(name, " ".join(repr(x) for x in nums))
            return f"<{e.tag} {name}> length {len(nums)}"
        if op == 3:
            del e.attrib[name]
            return f"del <{e.tag} {name}>"
        if op == 4:
            new = _misspell(rng, name)
            e.attrib[new] = e.attrib.pop(name)
            return f"<{e.tag} {name}> -> {new}"
        known = ATTRS.get("joint_urdf" if kind == "urdf" and e.tag == "joint" else e.tag)
        if known:
            new = rng.choice(known)
            e.set(new, awkward(rng) if rng.random() < 0.5 else value)
            return f"<{e.tag}> add {new}"
    if op == 6 and parent is not None:
        parent.remove(e)
        return f"drop <{e.tag}>"
    if op == 7 and parent is not None:
        parent.insert(list(parent).index(e), copy.deepcopy(e))
        return f"dup <{e.tag}>"
    if op == 8 and parent is not None:
        target, _ = rng.choice(elements)
        if target is not e and e not in list(target.iter()):
            moved = rng.random() < 0.5  # moved, or copied
            if moved:
                parent.remove(e)
            target.append(copy.deepcopy(e))
            return f"{'move' if moved else 'copy'} <{e.tag}> into <{target.tag}>"
    if op == 9:
        e.tag = _misspell(rng, e.tag)
        return f"tag -> <{e.tag}>"
    if kind == "mjcf":
        return _mutate_mjcf(rng, root, op, files)
    return _mutate_urdf(rng, root, op)


def _bodies(root: ET.Element) -> list[ET.Element]:
    return list(root.iter("body"))


def _mutate_mjcf(rng: random.Random, root: ET.Element, op: int, files: dict[str, str]
                 ) -> str:
    bodies = _bodies(root)
    if op == 10 and bodies:  # a geom of any type and size form
        b = rng.choice(bodies)
        b.append(ET.fromstring(random_geom(rng, rng.choice([None, None, "fz"]))))
        _ensure_class(root, rng, "fz")
        return f"geom into <body {b.get('name', '?')}>"
    if op == 11:  # a default class, used
        _ensure_class(root, rng, "fz")
        geoms = [g for b in bodies for g in b.findall("geom")]
        for g in rng.sample(geoms, min(2, len(geoms))):
            g.set("class", "fz")
        if bodies and rng.random() < 0.3:
            rng.choice(bodies).set("childclass", "fz")
        return "default class 'fz'"
    if op == 12:  # an include
        how = rng.choice(["move", "move", "missing", "self", "other root", "nested"])
        name = f"part{len(files)}.xml"
        inc = ET.Element("include", {"file": name})
        if how == "move":
            sections = [c for c in root if c.tag in ("default", "asset", "worldbody",
                                                     "keyframe", "equality", "custom")]
            if sections:
                s = rng.choice(sections)
                root.remove(s)
                files[name] = ET.tostring(ET.Element("mujoco"), encoding="unicode").replace(
                    "<mujoco />", f"<mujoco>{ET.tostring(s, encoding='unicode')}</mujoco>")
                root.insert(0, inc)
                return f"<{s.tag}> into {name}"
        if how == "missing":
            inc.set("file", "nothing.xml")
        elif how == "self":
            files[name] = f'<mujoco><include file="{name}"/></mujoco>'
        elif how == "other root":
            files[name] = '<robot name="r"/>'
        else:
            files[name] = f'<mujoco><include file="inner{len(files)}.xml"/></mujoco>'
            files[f"inner{len(files)}.xml"] = "<mujoco><option gravity='0 0 -1'/></mujoco>"
        root.insert(rng.randrange(len(root) + 1), inc)
        return f"include ({how})"
    if op == 13:  # a joint type changed, or a joint added
        joints = list(root.iter("joint"))
        if joints and rng.random() < 0.6:
            j = rng.choice(joints)
            j.set("type", rng.choice(["hinge", "slide", "ball", "free", "hinge"]))
            return f"joint type {j.get('type')}"
        if bodies:
            b = rng.choice(bodies)
            b.insert(0, ET.fromstring(_joint(rng, True)))
            return "joint added"
    if op == 14:  # compiler and option entries
        tag = rng.choice(["compiler", "option"])
        e = root.find(tag)
        if e is None:
            e = ET.Element(tag)
            root.insert(0, e)
        name = rng.choice(ATTRS[tag])
        good = {"angle": ["radian", "degree"], "eulerseq": ["xyz", "ZYX", "zxy"],
                "inertiafromgeom": ["true", "false", "auto"], "inertiagrouprange": ["0 3"],
                "boundmass": ["0.1", "2"], "boundinertia": ["0.01"], "settotalmass": ["5"],
                "gravity": ["0 0 -1", "1 2 3"], "density": ["1.2"], "wind": ["0 1 0"]}
        e.set(name, rng.choice(good.get(name, ["0"])) if rng.random() < 0.6 else awkward(rng))
        if tag == "option" and rng.random() < 0.3:
            flag = ET.SubElement(e, "flag")
            flag.set(rng.choice(["gravity", "contact", "constraint"]),
                     rng.choice(["disable", "enable", "off"]))
        return f"<{tag} {name}>"
    # a keyframe
    kf = root.find("keyframe")
    if kf is None:
        kf = ET.SubElement(root, "keyframe")
    key = ET.SubElement(kf, "key", {"name": f"k{len(kf)}"})
    for a in ("qpos", "qvel"):
        if rng.random() < 0.6:
            key.set(a, " ".join(_num(rng, -1, 1) for _ in range(rng.randrange(0, 15))))
    return "keyframe"


def _ensure_class(root: ET.Element, rng: random.Random, name: str) -> None:
    if any(d.get("class") == name for d in root.iter("default")):
        return
    top = root.find("default")
    if top is None:
        top = ET.Element("default")
        root.insert(0, top)
    cls = ET.SubElement(top, "default", {"class": name})
    attrs = {"size": _vec(rng, rng.choice([1, 2, 3]), 0.03, 0.3)}
    if rng.random() < 0.6:
        attrs["type"] = rng.choice(GEOMS)
    if rng.random() < 0.3:
        attrs["density"] = _num(rng, 100, 2000)
    if rng.random() < 0.2:
        attrs["euler"] = _vec(rng, 3, -90, 90)
    ET.SubElement(cls, "geom", attrs)


def _mutate_urdf(rng: random.Random, root: ET.Element, op: int) -> str:
    joints = root.findall("joint")
    if op in (10, 11) and joints:
        j = rng.choice(joints)
        j.set("type", rng.choice(["revolute", "continuous", "prismatic", "fixed", "floating",
                                  "planar", "hinge"]))
        return f"urdf joint type {j.get('type')}"
    links = root.findall("link")
    if op in (12, 13) and links:
        ln = rng.choice(links)
        i = ln.find("inertial")
        if i is None:
            i = ET.SubElement(ln, "inertial")
        m = i.find("mass")
        if m is not None and rng.random() < 0.3:
            i.remove(m)  # (else a second <mass>)
        ET.SubElement(i, "mass", {"value": rng.choice(["1", "0", "-1", "1e-20", awkward(rng)])})
        return f"urdf mass of {ln.get('name')}"
    if op == 14 and joints:
        j = rng.choice(joints)
        d = ET.SubElement(j, rng.choice(["dynamics", "limit", "mimic", "calibration"]))
        d.set(rng.choice(["damping", "friction", "lower", "joint"]), awkward(rng))
        return "urdf joint extra"
    if links:
        ln = rng.choice(links)
        v = ET.SubElement(ln, rng.choice(["visual", "collision"]))
        g = ET.SubElement(v, "geometry")
        shape = rng.choice(["box", "sphere", "cylinder", "capsule", "mesh"])
        s = ET.SubElement(g, shape)
        for a in ATTRS.get(shape, ["filename"]):
            s.set(a, rng.choice(["0.1", "0.1 0.2 0.3", awkward(rng)]))
        return f"urdf {shape}"
    return "none"


def mutate_text(rng: random.Random, text: str) -> tuple[str | bytes, str]:
    """Damage the written text once; bytes when it is no longer UTF-8."""
    op = rng.randrange(9)
    i = rng.randrange(len(text) + 1)
    if op == 0:
        return text[:i], "cut"
    if op == 1:
        return text[:i] + rng.choice(["<", "&", "</x>", "<!-- ", "]]>", '"']) + text[i:], \
            "stray"
    if op == 2:
        raw = text.encode("utf-8")
        return raw[:i] + b"\xff\xfe" + raw[i:], "not utf-8"
    if op == 3:
        return ('<?xml version="1.0"?><!DOCTYPE m [<!ENTITY a "aaaa">]>' + text,
                "doctype")
    if op == 4:
        return text.replace('name="', 'name="&amp;&lt;', 1), "escaped name"
    if op == 5:
        return text.replace('="', '=">', 3), "'>' in values"
    if op == 6:
        many = "".join(f' x{k}="1"' for k in range(rng.choice([10, 1000, 20000])))
        return text.replace(">", many + ">", 1), "many attributes"
    if op == 7:
        return "\ufeff" + text.replace("\n", "\r\n"), "BOM, CRLF"
    return text.replace("><", ">\n<"), "one element a line"


@dataclass
class Case:
    index: int
    base: str
    kind: str
    did: list[str]
    files: dict[str, str | bytes]  # relative path -> content; "main.xml"/"main.urdf" first

    @property
    def main(self) -> str:
        return next(iter(self.files))


def make_case(seed: int, index: int, found: list[Base]) -> Case:
    rng = random.Random(f"xml:{seed}:{index}")
    r = rng.random()
    if r < 0.3:
        base = generated_mjcf(rng)
    elif r < 0.4:
        base = generated_urdf(rng)
    else:
        base = rng.choice(found)
    root = ET.fromstring(base.text)
    extra: dict[str, str] = dict(base.files)
    did = [mutate_tree(rng, root, base.kind, extra) for _ in range(rng.choice([0, 1, 1, 2,
                                                                                 3, 4]))]
    text: str | bytes = ET.tostring(root, encoding="unicode")
    if rng.random() < 0.12:
        text, what = mutate_text(rng, str(text))
        did.append(what)
    main = "main.xml" if base.kind == "mjcf" else "main.urdf"
    return Case(index, base.name, base.kind, did or ["unchanged"], {main: text, **extra})


# -- running one case ----------------------------------------------------------------------

def run_case(case: Case, workdir: Path, hang: float, compare: bool = True,
             solve_every: int = 1) -> list[Outcome]:
    """``check`` the case, ``solve`` it when check accepts it (every `solve_every`'th
    case), and compare it with MuJoCo (`compare`); the outcome of each."""
    folder = Path(tempfile.mkdtemp(prefix=f"case{case.index}.", dir=workdir))
    try:
        for rel, content in case.files.items():
            p = folder / rel
            p.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, bytes):
                p.write_bytes(content)
            else:
                p.write_text(content, encoding="utf-8", newline="")
        path = str(folder / case.main)
        outcomes = []
        commands = [["check", path]] + ([["solve", path]]
                                        if case.index % solve_every == 0 else [])
        for command in commands:
            code, out, err, esc = run_command(command, hang)
            outcomes.append(classify_xml(command[0], code, out, err, esc, folder, case))
            if code != 0:
                break
        if compare and case.kind == "mjcf" and outcomes[0].kind == ACCEPTED:
            try:
                outcomes.append(compare_with_mujoco(Path(path)))
            except Exception as exc:  # noqa: BLE001 - mbody.load or solve escaping: a crash
                outcomes.append(Outcome("mujoco", CRASH, 70, "".join(
                    traceback.format_exception(exc))[-3000:]))
        return outcomes
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def classify_xml(command: str, code: int | None, out: str, err: str, escaped: str,
                 folder: Path, case: Case) -> Outcome:
    """tools/fuzz.py's classes, a problem located in any file of the case (an included
    file names itself) counting as located."""
    path = str(folder / case.main)
    o = classify(command, code, out, err, escaped, path)
    if o.kind != CRASH or not o.detail.startswith("model error without"):
        return o
    text = err[err.index("mbody: error: "):]
    unlocated = set(_unlocated_problems(text, path))
    for rel in case.files:
        unlocated &= set(_unlocated_problems(text, str(folder / rel)))
    if unlocated:
        return Outcome(command, CRASH, code, "model error without file:line:column: "
                       + "\n".join(sorted(unlocated))[:2000])
    return Outcome(command, CLEAN, code, err[:300])


def _quiet_mujoco() -> object | None:
    try:
        import mujoco  # noqa: PLC0415 - optional, heavy
    except ImportError:
        return None
    mujoco.set_mju_user_warning(lambda message: None)  # no MUJOCO_LOG.TXT, no stderr
    return mujoco


def _mj_names(mj, m) -> list[str]:
    """Each MuJoCo body's name as mbody names it (unnamed: body<id>; '.' and blanks
    become '_'; 'ground' is 'ground_body')."""
    out = []
    for b in range(m.nbody):
        n = mj.mj_id2name(m, mj.mjtObj.mjOBJ_BODY, b) or f"body{b}"
        n = "".join("_" if ch == "." or ch.isspace() else ch for ch in n)
        out.append("ground_body" if n == "ground" else n)
    return out


def compare_with_mujoco(path: Path) -> Outcome:
    """mbody's masses (and accelerations, where the model is a tree mbody maps exactly)
    against MuJoCo's; ACCEPTED with what was compared, or MISMATCH with the numbers."""
    import mbody  # noqa: PLC0415

    mj = _quiet_mujoco()
    if mj is None:
        return Outcome("mujoco", ACCEPTED, 0, "not compared: no MuJoCo")
    try:
        m = mj.MjModel.from_xml_path(str(path))
    except Exception:  # noqa: BLE001 - MuJoCo refuses what mbody accepts: not compared
        return Outcome("mujoco", ACCEPTED, 0, "not compared: MuJoCo refuses it")
    text = "\n".join(p.read_text(encoding="utf-8", errors="replace")
                     for p in sorted(path.parent.rglob("*.xml")))  # included files too
    if re.search(r"fusestatic\s*=\s*[\"']true", text):
        return Outcome("mujoco", ACCEPTED, 0, "not compared: fusestatic")
    with warnings_as_errors():
        model = mbody.load(path)
    names = _mj_names(mj, m)
    index = {n: k for k, n in enumerate(names) if names.count(n) == 1}
    d = mj.MjData(m)
    _reset(mj, m, d)
    mj.mj_kinematics(m, d)
    compared = 0
    for i, name in enumerate(model.body_names):
        b = index.get(name)
        if b is None:
            continue
        wrong = _body_differs(model, i, m, d, b, pose=model.file_state is None)
        if wrong:
            return Outcome("mujoco", MISMATCH, 0, f"body '{name}': {wrong}")
        compared += 1
    detail = f"masses {compared}"
    if compared and _exact_tree(mj, text, model, m):
        found = _accelerations(mj, m, model, index)
        if found is None:
            detail += "; accelerations not compared (conditioning or solve)"
        elif found[0] > found[1]:
            return Outcome("mujoco", MISMATCH, 0, f"accelerations differ by {found[0]:.3g} "
                           f"of the largest (tolerance {found[1]:.3g})")
        else:
            detail += "; accelerations"
    return Outcome("mujoco", ACCEPTED, 0, detail)


def _reset(mj, m, d) -> None:
    """MuJoCo's `d` at the state mbody reads an MJCF file in when no keyframe is named:
    the key 'initial' when the file has one, else qpos0 at rest (as MjData starts)."""
    key = mj.mj_name2id(m, mj.mjtObj.mjOBJ_KEY, "initial")
    if key >= 0:
        mj.mj_resetDataKeyframe(m, d, key)


def _body_differs(model, i: int, m, d, b: int, pose: bool = True) -> str:
    """What differs between mbody's body `i` and MuJoCo's body `b` at the state (mass, mass
    centre, inertia), or ''. The inertia is compared in MuJoCo's principal axes: MuJoCo
    finds them by a Jacobi iteration that stops at a last rotation below 1.5e-6 rad, or
    off-diagonal terms below 1e-12 (``mjuu_eig3``), so the moments agree to second order
    and the off-diagonal terms within 1.5e-6 of the spread of the moments.

    Without `pose` (a model mbody assembles at load: its bodies moved onto their joints
    and drivers from the file's pose its ``<custom>`` entries keep, while MuJoCo's qpos0
    is the tree's pose, which a mutation may have moved), the mass and the principal
    moments only."""
    ours, theirs = float(model.mass[i]), float(m.body_mass[b])
    if not math.isclose(ours, theirs, rel_tol=MASS_RTOL, abs_tol=1e-300):
        return f"mass {ours!r} in mbody, {theirs!r} in MuJoCo"
    if not pose:
        if model.particle[i]:
            return ""
        moments = np.sort(m.body_inertia[b])
        ours_m = np.sort(np.linalg.eigvalsh(model.J[i]))
        if model.dimension == 2:  # the moment about z: the one about the plane's normal
            return "" if np.isclose(ours_m, moments, rtol=1e-6, atol=1e-12).any() else (
                f"moments {ours_m.tolist()} in mbody, {moments.tolist()} in MuJoCo")
        if np.abs(ours_m - moments).max() > 1e-6 * float(moments.max()) + 1e-12:
            return f"moments {ours_m.tolist()} in mbody, {moments.tolist()} in MuJoCo"
        return ""
    x, ref = model.initial.position[i], d.xipos[b]
    if np.abs(x - ref).max() > MASS_RTOL * max(1.0, float(np.abs(ref).max())):
        return f"mass centre {x.tolist()} in mbody, {ref.tolist()} in MuJoCo"
    if model.particle[i]:
        return ""
    R = model.initial.W_R_B[i]
    axes = d.ximat[b].reshape(3, 3)
    moments = m.body_inertia[b]
    top, spread = float(moments.max()), float(moments.max() - moments.min())
    if model.dimension == 2:  # a planar body has a moment about z only
        ours = float((R @ model.J[i] @ R.T)[2, 2])
        theirs = float((axes @ np.diag(moments) @ axes.T)[2, 2])
        if abs(ours - theirs) > 1.5e-6 * spread + MASS_RTOL * top + 1e-12:
            return f"moment about z {ours!r} in mbody, {theirs!r} in MuJoCo"
        return ""
    A = axes.T @ (R @ model.J[i] @ R.T) @ axes  # mbody's tensor in MuJoCo's axes
    off = A - np.diag(np.diag(A))
    if (np.abs(np.diag(A) - moments).max() > MASS_RTOL * top + 1e-12
            or np.abs(off).max() > 1.5e-6 * spread + MASS_RTOL * top + 1e-12):
        return (f"inertia in MuJoCo's principal axes {A.round(12).tolist()} in mbody, "
                f"moments {moments.tolist()} in MuJoCo")
    return ""


def _exact_inertia(mj, m, d, model, index: dict[str, int]) -> None:
    """MuJoCo's principal moments and axes replaced by those of mbody's tensor (exact
    to rounding; MuJoCo's own are within 1.5e-6 rad, see `_body_differs`), so that the
    accelerations compare the dynamics, not MuJoCo's diagonalisation."""
    for i, name in enumerate(model.body_names):
        b = index[name]
        if model.particle[i]:
            continue
        R = model.initial.W_R_B[i]
        w, V = np.linalg.eigh(R @ model.J[i] @ R.T)
        if np.linalg.det(V) < 0:
            V[:, 0] = -V[:, 0]
        local = d.xmat[b].reshape(3, 3).T @ V  # the principal axes in the body frame
        q = np.zeros(4)
        mj.mju_mat2Quat(q, local.ravel())
        m.body_inertia[b] = w
        m.body_iquat[b] = q
        m.body_sameframe[b] = mj.mjtSameFrame.mjSAMEFRAME_NONE  # (no shortcut: the axes
        # are no longer the body's)


@contextlib.contextmanager
def warnings_as_errors():
    import warnings  # noqa: PLC0415

    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        yield


def _exact_tree(mj, text: str, model, m) -> bool:
    """A tree mbody maps exactly: no equality constraint, no mbody entry, no particle,
    every MuJoCo body that moves is an mbody body."""
    if "<equality" in text or "mbody:" in text or any(model.particle):
        return False
    moving = {n for k, n in enumerate(_mj_names(mj, m))
              if k and m.body_weldid[k] != 0}
    return moving <= set(model.body_names)


def _accelerations(mj, m, model, index: dict[str, int]) -> tuple[float, float] | None:
    """(largest difference of the bodies' accelerations at the state, relative to
    the largest acceleration; its tolerance), what mbody does not model switched off in
    MuJoCo; None when not comparable. The tolerance is ACC_RTOL plus the error bound of
    mbody's solve, 1e-15 times the condition number of its Schur complement (about
    4.5 eps cond(S)); worse than SCHUR_LIMIT, or MuJoCo's mass matrix worse than
    COND_LIMIT, is not compared."""
    import mbody  # noqa: PLC0415
    from mbody.errors import MbodyError  # noqa: PLC0415

    if any(name not in index for name in model.body_names):
        return None
    bits = mj.mjtDisableBit
    m.opt.disableflags |= (bits.mjDSBL_CONSTRAINT | bits.mjDSBL_SPRING | bits.mjDSBL_DAMPER
                           | bits.mjDSBL_ACTUATION)
    m.dof_armature[:] = 0
    m.body_gravcomp[:] = 0
    m.opt.density = m.opt.viscosity = 0
    m.opt.wind[:] = 0
    d = mj.MjData(m)
    _reset(mj, m, d)
    mj.mj_kinematics(m, d)
    _exact_inertia(mj, m, d, model, index)
    mj.mj_forward(m, d)
    mj.mj_rnePostConstraint(m, d)
    if m.nv:
        M = np.zeros((m.nv, m.nv))
        mj.mj_fullM(m, d, M)
        if not np.all(np.isfinite(M)) or np.linalg.cond(M) > COND_LIMIT:
            return None
    try:
        with warnings_as_errors():
            sol = mbody.assemble(model).solve(condition=True)
    except (MbodyError, np.linalg.LinAlgError, FloatingPointError, RuntimeWarning):
        return None
    condition = sol.condition if sol.condition is not None else 1.0
    if not condition < SCHUR_LIMIT:
        return None
    rows = np.cumsum([0] + [3 if p else 6 for p in model.particle])
    g = np.zeros(3) if m.opt.disableflags & bits.mjDSBL_GRAVITY else m.opt.gravity
    res = np.zeros(6)
    diff, scale = 0.0, 1.0
    for i, name in enumerate(model.body_names):
        mj.mj_objectAcceleration(m, d, mj.mjtObj.mjOBJ_BODY, index[name], res, 0)
        a = sol.accelerations[rows[i]:rows[i + 1]]
        mine = np.concatenate([a[:3], model.initial.W_R_B[i] @ a[3:]])
        ref = np.concatenate([res[3:] + g, res[:3]])
        if not np.all(np.isfinite(ref)):
            return None
        diff = max(diff, float(np.abs(mine - ref).max()))
        scale = max(scale, float(np.abs(ref).max()))
    return diff / scale, ACC_RTOL + 1e-15 * condition


def classify_case(outcomes: list[Outcome]) -> str:
    """The case's verdict: a crash or hang first (tools/fuzz.py's), then a mismatch."""
    v = verdict(outcomes)
    if v in (CRASH, HANG):
        return v
    return MISMATCH if any(o.kind == MISMATCH for o in outcomes) else v


# -- the run ---------------------------------------------------------------------------

def run_chunk(seed: int, indices: list[int], hang: float, log=None, solve_every: int = 1
              ) -> dict:
    """Run the cases `indices` here, one after another; the counts and failures."""
    found = bases()
    _quiet_mujoco()
    verdicts: Counter = Counter()
    compared: Counter = Counter()
    failures = []
    workdir = Path(tempfile.mkdtemp(prefix="mbody-fuzz-xml."))
    t0 = time.perf_counter()
    try:
        with contextlib.chdir(workdir):  # what any library writes lands here
            for n, i in enumerate(indices, 1):
                case = make_case(seed, i, found)
                outcomes = run_case(case, workdir, hang, solve_every=solve_every)
                v = classify_case(outcomes)
                verdicts[v] += 1
                for o in outcomes:
                    if o.command == "mujoco" and o.kind == ACCEPTED:
                        compared["masses" if o.detail.startswith("masses") else
                                 "not compared"] += 1
                        compared["accelerations"] += o.detail.endswith("; accelerations")
                if v in (CRASH, HANG, MISMATCH):
                    failures.append((i, case, outcomes))
                if log and n % 500 == 0:
                    log(f"  {n} / {len(indices)} cases, {time.perf_counter() - t0:.0f} s: "
                        + ", ".join(f"{k} {verdicts[k]}" for k in KINDS))
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    return {"verdicts": verdicts, "compared": compared, "failures": failures}


def _chunk(args):
    seed, indices, hang = args
    with contextlib.redirect_stdout(io.StringIO()):
        return run_chunk(seed, indices, hang)


def run(n: int, seed: int = 0, jobs: int = 1, hang: float = 30.0, first: int = 0,
        log=print) -> dict:
    """Cases first .. first + n - 1, in `jobs` processes; the merged counts."""
    todo = list(range(first, first + n))
    t0 = time.perf_counter()
    if jobs <= 1:
        parts = [run_chunk(seed, todo, hang, log)]
    else:
        ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
        with ctx.Pool(jobs) as pool:
            parts = pool.map(_chunk, [(seed, todo[k::jobs], hang) for k in range(jobs)])
    verdicts, compared, failures = Counter(), Counter(), []
    for p in parts:
        verdicts.update(p["verdicts"])
        compared.update(p["compared"])
        failures.extend(p["failures"])
    return {"n": n, "seed": seed, "verdicts": verdicts, "compared": compared,
            "failures": sorted(failures, key=lambda f: f[0]),
            "seconds": time.perf_counter() - t0}


def report(result: dict, show: int = 5) -> str:
    v, c = result["verdicts"], result["compared"]
    lines = [f"mbody fuzz_xml: {result['n']} mutated MJCF and URDF models (seed "
             f"{result['seed']}), {result['seconds']:.0f} s",
             *count_lines(v, [("clean errors", CLEAN, "check refused the file, naming "
                                    "what and where"),
                                   ("accepted", ACCEPTED, "check passed; solve ran on it"),
                                   ("crashes", CRASH, ""), ("hangs", HANG, ""),
                                   ("mismatches", MISMATCH, "with MuJoCo")]),
             f"  against MuJoCo: masses compared on {c['masses']} accepted MJCF files, "
             f"accelerations on {c['accelerations']}; {c['not compared']} not compared "
             "(MuJoCo refuses them, or no body to match)"]
    for i, case, outcomes in result["failures"][:show]:
        lines.append(f"\n#{i} {case.base}: {'; '.join(case.did)}")
        lines += failure_lines(outcomes, case.files, (CRASH, HANG, MISMATCH))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    a = fuzz_arguments(__doc__, "cases", jobs=min(2, os.cpu_count() or 1),
                            hang=30.0).parse_args(argv)
    if a.only is not None:
        case = make_case(a.seed, a.only, bases())
        print(f"#{a.only} {case.base}: {'; '.join(case.did)}")
        for rel, content in case.files.items():
            print(f"--- {rel}\n{content!s:.3000}")
        _quiet_mujoco()
        workdir = Path(tempfile.mkdtemp(prefix="mbody-fuzz-xml."))
        for o in run_case(case, workdir, a.hang):
            print(f"{o.command}: {o.kind} (exit {o.code}) {o.detail}")
        shutil.rmtree(workdir, ignore_errors=True)
        return 0
    result = run(a.n, a.seed, max(1, a.jobs), a.hang,
                 log=lambda s: print(s, file=sys.stderr, flush=True))
    print(report(result, a.show))
    bad = sum(result["verdicts"][k] for k in (CRASH, HANG, MISMATCH))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
