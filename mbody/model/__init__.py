"""The model: YAML text in, a validated, immutable `Model` out.

The flow, one module a step: `loader` (text -> plain values with a line mark each),
`validate` (every rule of the model-file contract, every problem with its line), `model`
(`Model` and `State` as per-body arrays; `load`, `loads`), with `tables` (the loads and
joints as arrays), `records` (`Body`, `Load`, `Joint`, made on first use), `build` (a
validated specification -> those tables and records) and `reprs` (the reprs' text pieces);
`expressions` (the safe parser for loads that vary in time) and `graph` (the body/joint
graph and the topology it implies).
"""

from mbody._moved import submodule as _submodule
from mbody.model.model import (
    Body,
    ForceTable,
    Joint,
    JointTable,
    Load,
    Model,
    ReactionTable,
    SpringTable,
    State,
    count,
    load,
    loads,
)

__all__ = ["Body", "ForceTable", "Joint", "JointTable", "Load", "Model", "ReactionTable",
           "SpringTable", "State", "count", "load", "loads"]


def __getattr__(name: str):
    return _submodule(__name__, name)
