"""Short reprs (issue 14, first part): a notebook or a REPL shows what an object is, its
sizes and what to call next, not kilobytes of arrays."""

from __future__ import annotations

from pathlib import Path

import pytest

import mbody
from mbody.io.export import exported

MODELS = sorted((Path(__file__).resolve().parents[1] / "models").glob("*.yaml"))


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.stem)
def test_model_assembly_and_export_reprs_are_short_and_say_what_they_are(path):
    model = mbody.load(path)
    asm = mbody.assemble(model)
    for obj, kind in ((model, "Model"), (asm, "Assembly"), (exported(asm), "ExportedAssembly")):
        text = repr(obj)
        assert text.startswith(f"<{kind} ") and text.endswith(">"), text
        assert repr(model.name) in text
        assert len(text) <= 300, (len(text), text)
    assert f"{model.n} bod" in repr(model)
    assert f"{len(model.reactions)} reaction component" in repr(asm)


def test_trajectory_repr_is_short():
    traj = mbody.simulate(mbody.load(MODELS[0].parent / "double_pendulum.yaml"), 0.5, 20)
    text = repr(traj)
    assert text == ("<Trajectory of 'double-pendulum': 2 bodies, 11 samples, t = 0 .. 0.5 s, "
                    "4 reaction series; .state(k), .kinetic_energy(), .save(path)>"), text
