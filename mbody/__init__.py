"""mbody: per-body Newton-Euler equations for multibody models.

    model = mbody.load("models/seed_example_1.yaml")
    asm = mbody.assemble(model)          # M v̇ + b = Q + G λ at the model's state
    sol = asm.solve(known={"A.Fx": 0})   # accelerations, aligned with asm.coordinates
"""

from .animate import animate
from .assemble import Assembly, Solution, assemble
from .errors import Issue, MbodyError, ModelError, UnknownReactionsError
from .export import ExportedAssembly, load_export
from .fbd import BodyEquations, Equation, ForceOnBody, FreeBodyDiagram
from .model import Body, Joint, Load, Model, State, load, loads
from .simulate import simulate
from .trajectory import Trajectory

__version__ = "0.1.0"

__all__ = [
    "Assembly", "Body", "BodyEquations", "Equation", "ExportedAssembly", "ForceOnBody",
    "FreeBodyDiagram", "load_export",
    "Issue", "Joint", "Load", "MbodyError", "Model", "ModelError", "Solution", "State",
    "Trajectory", "simulate",
    "UnknownReactionsError", "animate", "assemble", "load", "loads",
]
