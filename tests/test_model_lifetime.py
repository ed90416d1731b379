"""A model's workspace (its compiled form and what its runs made once: `Workspace.memo`)
is kept while the model lives, and no longer: nothing kept there may refer back to the
model, or every model a program simulated would stay in memory for good (a sweep or a
class's grading loads hundreds)."""

from __future__ import annotations

import gc
import importlib
import weakref
from pathlib import Path

import pytest

import mbody

MODELS = Path(__file__).resolve().parent.parent / "models"
workspaces = importlib.import_module("mbody.equations.workspace")._WORKSPACES


def _runs(model: mbody.Model) -> None:
    mbody.simulate(model, 0.2, 10)
    mbody.simulate(model, 0.2, 10, rtol=1e-6, atol=1e-8)  # the prepared run, again
    mbody.simulate(model, 0.2, 10, method="RK45", rtol=1e-6, atol=1e-8)
    mbody.assemble(model, model.initial).solve()
    mbody.solve_many(model, [model.initial, model.initial])
    if model.drivers is not None and len(model.drivers.names):
        mbody.kinematic_at(model, [0.0, 0.01])
    else:
        mbody.linearize(model, model.initial)


@pytest.mark.parametrize("name", ["pendulum", "slider_crank", "heavy_top",
                                  "slider_crank_driven", "spring_mass_damper"])
def test_a_model_is_freed_once_dropped_whatever_it_ran(name):
    model = mbody.load(MODELS / f"{name}.yaml")
    _runs(model)
    if model.reactions and name != "slider_crank_driven":  # a value given as `known`
        label = model.reactions[0]
        mbody.simulate(model, 0.2, 10, known={label: 0.0})
    alive = weakref.ref(model)
    key = id(model)
    assert key in workspaces
    del model
    gc.collect()
    assert alive() is None, "something kept in the model's workspace refers to the model"
    assert key not in workspaces
