"""The state an MJCF file is read in, the same on every path: `mbody.load`, every command
and `mbody convert` read the key ``initial`` when the file has one (the state mbody's
export writes there), else the reference pose (``qpos0``) at rest; a keyframe named
explicitly wins. So a model written by ``mbody convert`` to MJCF reads back in the state
of the YAML file it came from, and gives the same numbers.

Tolerances. The MJCF writer prints every number with ``repr`` (17 significant digits:
the same double back), except what it writes as 0 because it is below 1e-14 of the
model's length (``_snap``: rounding noise of a frame change). On the way, each body's
pose is turned into its parent's frame and back, a few roundings of a unit each. So the
file's data differ from the YAML model's by at most ``WRITTEN`` = 1e-14 + 64 eps
relative (3e-14): the state is compared to that. The accelerations solve
[M −G; Gᵀ 0] [v̇; λ] = [Q − b; γ], whose relative change is at most its condition number
κ times the relative change of its data (a linear system's perturbation bound), so they
are compared to ``WRITTEN · κ`` of the largest (κ from numpy, ≤ 1e4 for the models
here). The bug this guards against (the spin of heavy_top dropped) changed them by
half of the largest.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.cli.app import main

MODELS = Path(__file__).resolve().parent.parent / "models"
WRITTEN = 3e-14
"""Relative difference of the data of an exported MJCF file from its YAML model: the
writer's 1e-14 of the length below which it writes 0, and 64 roundings of a frame
change."""
SHIPPED = ["heavy_top", "spring_mass_damper", "double_pendulum", "triple_pendulum",
           "spherical_pendulum", "rotor_gyroscopic_bearings", "gyroscope_gimbals",
           "torque_free_asymmetric", "slider_crank", "scotch_yoke", "helical_chain",
           "practice_2_flywheel"]
"""Models that move at their initial state (a spin, velocities, drivers), planar and
spatial, trees and closed loops without redundant constraints (their κ is finite)."""


def _dense(x) -> np.ndarray:
    return x.toarray() if hasattr(x, "toarray") else np.asarray(x, dtype=float)


def _exported(name: str, tmp_path: Path) -> Path:
    """models/<name>.yaml written to MJCF by ``mbody convert``."""
    xml = tmp_path / f"{name}.xml"
    assert main(["convert", str(MODELS / f"{name}.yaml"), "-o", str(xml)]) == 0
    return xml


def _same_state(a: mbody.Model, b: mbody.Model) -> None:
    """Both models' initial states agree body by body (matched by name) to `WRITTEN`."""
    assert sorted(a.body_names) == sorted(b.body_names)
    order = [b.index[n] for n in a.body_names]
    sa, sb = a.initial, b.initial
    for what, x, y in (("position", sa.position, sb.position[order]),
                       ("rotation", sa.W_R_B, sb.W_R_B[order]),
                       ("velocity", sa.velocity, sb.velocity[order]),
                       ("omega", sa.omega, sb.omega[order])):
        scale = max(1.0, float(np.abs(x).max(initial=0.0)))
        assert np.abs(x - y).max(initial=0.0) <= WRITTEN * scale, what


def _accelerations(capsys, path: Path) -> dict[str, float]:
    """``mbody solve --json`` of `path`: its accelerations by coordinate label."""
    capsys.readouterr()
    assert main(["solve", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    return dict(zip(out["coordinates"], out["accelerations"], strict=True))


@pytest.mark.parametrize("name", SHIPPED)
def test_an_exported_model_reads_back_in_its_state(name, tmp_path, capsys):
    """YAML → ``mbody convert`` → MJCF → ``mbody.load`` and ``mbody solve``: the same
    initial state and the same accelerations as the YAML file."""
    yaml_model = mbody.load(MODELS / f"{name}.yaml")
    xml = _exported(name, tmp_path)
    back = mbody.load(xml)
    _same_state(yaml_model, back)
    ours, theirs = _accelerations(capsys, MODELS / f"{name}.yaml"), _accelerations(capsys, xml)
    assert sorted(ours) == sorted(theirs)
    asm = mbody.assemble(yaml_model)
    M, G = _dense(asm.M), _dense(asm.G)
    r = G.shape[1]
    kappa = float(np.linalg.cond(np.block([[M, -G], [G.T, np.zeros((r, r))]])))
    assert kappa < 1e6  # no redundant constraint: the bound means something
    scale = max(1.0, max(abs(v) for v in ours.values()))
    worst = max(abs(ours[k] - theirs[k]) for k in ours)
    assert worst <= WRITTEN * kappa * scale, (worst, kappa)


def test_every_path_reads_the_same_state(tmp_path):
    """`mbody.load`, ``mbody convert`` back to YAML and an explicit ``keyframe='initial'``
    give one state: the spinning top's spin (150 rad/s about its axis) is kept."""
    xml = _exported("heavy_top", tmp_path)
    default = mbody.load(xml)
    named = mbody.load(xml, keyframe="initial")
    yml = tmp_path / "heavy_top.yaml"
    assert main(["convert", str(xml), "-o", str(yml)]) == 0
    converted = mbody.load(yml)
    for other in (named, converted):
        _same_state(default, other)
    spin = float(default.initial.omega[0, 2])  # body axes: z is the top's axis
    assert abs(spin - 150.0) <= WRITTEN * 150.0


def test_the_state_read_is_said(tmp_path, capsys):
    """`mbody check` (the model's description) says which state the numbers are at."""
    xml = _exported("spring_mass_damper", tmp_path)
    capsys.readouterr()
    assert main(["check", str(xml)]) == 0
    assert "imported from spring_mass_damper.xml (MJCF) at the keyframe 'initial'" in \
        capsys.readouterr().out
    assert main(["check", str(MODELS / "robots" / "two_link_arm.xml")]) == 0
    assert "(MJCF) at the reference pose, at rest" in capsys.readouterr().out


ARM = """<mujoco model="arm">
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="hinge" axis="0 1 0"/>
      <geom type="box" size="0.2 0.05 0.1" pos="0.3 0 0"/>
    </body>
  </worldbody>
  {keys}
</mujoco>
"""


@pytest.mark.parametrize("keys", [
    "",
    '<keyframe><key name="swing" qpos="0.5" qvel="2"/></keyframe>',
    '<keyframe><key qpos="0.5" qvel="2"/></keyframe>',
])
def test_without_an_initial_key_the_file_starts_at_rest(keys, tmp_path, capsys):
    """No key named ``initial`` (no keyframe, another name, no name): the reference pose
    at rest, on `mbody.load` and on the command line, as MuJoCo's ``mj_resetData``."""
    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(keys=keys))
    model = mbody.load(path)
    assert not model.initial.velocity.any() and not model.initial.omega.any()
    np.testing.assert_allclose(model.initial.W_R_B[0], np.eye(3), rtol=0, atol=0)
    assert main(["check", str(path)]) == 0
    assert "at the reference pose, at rest" in capsys.readouterr().out


def test_a_named_keyframe_wins_over_initial(tmp_path, capsys):
    """A file with the keys ``swing`` and ``initial``: ``initial`` unless another is
    named (by name or by index), in Python and on the command line."""
    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(keys='<keyframe><key name="swing" qpos="0.5" qvel="2"/>'
                               '<key name="initial" qpos="-0.25" qvel="-1"/></keyframe>'))
    rate = {None: -1.0, "initial": -1.0, "swing": 2.0, "0": 2.0, "1": -1.0}
    for key, qvel in rate.items():
        model = mbody.load(path, **({"keyframe": key} if key is not None else {}))
        # a hinge about y: the body's angular velocity is qvel about y (body axes too)
        assert model.initial.omega[0].tolist() == [0.0, qvel, 0.0], key
    capsys.readouterr()
    assert main(["solve", str(path), "--json", "--keyframe", "swing"]) == 0
    swing = json.loads(capsys.readouterr().out)
    assert main(["solve", str(path), "--json"]) == 0
    initial = json.loads(capsys.readouterr().out)
    assert swing["accelerations"] != initial["accelerations"]  # other states, other a
    for key in ("swing", "0"):  # a key given by its index is named by its name
        assert main(["check", str(path), "--keyframe", key]) == 0
        assert "at the keyframe 'swing'" in capsys.readouterr().out
