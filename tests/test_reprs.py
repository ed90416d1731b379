"""Short reprs (issue 14, first part): a notebook or a REPL shows what an object is, its
sizes and what to call next, not kilobytes of arrays."""

from __future__ import annotations

from pathlib import Path

import pytest

import mbody
from mbody.equations.topology import topology
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


NEXT = {  # what each repr suggests calling next
    "Solution": "sol[label]", "State": ".replace(", "Body": ".inertia",
    "Joint": "reactions ", "BodyEquations": "print() it", "FreeBodyDiagram": "draw_fbd(it)",
    "ForceOnBody": ".W_vector", "ConstraintJacobian": ".row(label)",
    "ReactionTable": ".labels", "JointTable": ".first", "ForceTable": ".vector_at(t)",
    "SpringTable": ".stiffness", "ReactionColumns": ".W_e", "AppliedLoads": ".W_F",
    "Topology": ".parts",
}


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.stem)
def test_every_public_object_has_a_short_repr(path):
    """Under 300 characters on every shipped model, with its name and what to call next
    (a dataclass's own repr printed every array: 1-6 KB for a body's equations)."""
    model = mbody.load(path)
    asm = mbody.assemble(model)
    sol = asm.solve()
    first = model.body_names[0]
    eq = asm.bodies[first]
    objs = [(sol, "Solution"), (model.initial, "State"), (model.bodies[first], "Body"),
            (eq, "BodyEquations"), (eq.fbd, "FreeBodyDiagram")]
    objs += [(f, "ForceOnBody") for f in eq.fbd.forces]
    objs += [(j, "Joint") for j in model.joints] + [(ld, "Load") for ld in model.loads]
    objs += [(e, "Equation") for e in eq.equations]
    objs += [(asm.jacobian(), "ConstraintJacobian")]
    objs += [(model.reaction_table, "ReactionTable"), (model.joint_table, "JointTable"),
             (model.forces, "ForceTable"), (model.springs, "SpringTable"),
             (asm.columns, "ReactionColumns"), (asm.loads, "AppliedLoads"),
             (topology(model, columns=asm.columns), "Topology")]
    for obj, kind in objs:
        text = repr(obj)
        assert text.startswith(f"<{kind} ") or text.startswith(f"<{kind}:"), text
        assert len(text) < 300, (len(text), text)
        assert NEXT.get(kind, "") in text
    assert f"'{first}'" in repr(eq) and f"'{first}'" in repr(eq.fbd)
    assert str(eq.equations[0]) in repr(eq.equations[0])
    assert len(repr(sol.reactions)) < 300
    assert repr(asm.bodies).startswith(f"<bodies of {model.name!r}: '{first}'")
    assert len(repr(asm.bodies)) < 300


def test_short_reprs_say_the_values():
    model = mbody.load(MODELS[0].parent / "pendulum.yaml")
    asm = mbody.assemble(model)
    assert repr(model.bodies["rod"]) == ("<Body 'rod' (#0): m 2 kg, I (0.08354, 0.08354, "
                                         "0.1671) kg m^2; .inertia, .shape>")
    assert repr(model.joints[0]) == ("<Joint 'O': revolute, ground -> rod at (0, 0, 0) m; "
                                     "reactions O.Fx, O.Fy>")
    assert repr(asm.bodies["rod"].newton[1]) == "<Equation rod.y: 2 a_y = -19.62 + O.Fy>"
    assert repr(asm.solve()) == ("<Solution: 3 accelerations, 2 reaction components "
                                 "(2 solved); sol[label], .as_dict(), .reactions, .warnings>")
    assert repr(asm.solve().reactions).startswith("{'O.Fx': -6.3678")
    big = mbody.assemble(mbody.load(MODELS[0].parent / "fourbar_spatial.yaml")).solve()
    assert repr(big.reactions).startswith("<ReactionValues: 20 components (N; N m), O2.Fx")
    spring = mbody.load(MODELS[0].parent / "spring_mass_damper.yaml").loads[0]
    assert repr(spring).startswith(f"<Load {spring.name!r}: spring on ")


def test_a_drawing_scene_has_a_short_repr():
    """`fbd_scene` and `graph_scene` return a Scene (public in mbody.present.draw): its
    dataclass repr printed every item of every panel (12 KB for the double pendulum)."""
    from mbody.present.draw import fbd_scene, graph_scene

    m = mbody.load(MODELS[0].parent / "double_pendulum.yaml")
    asm = mbody.assemble(m)
    for sc in (fbd_scene(asm.bodies["upper"].fbd), graph_scene(m)):
        text = repr(sc)
        assert len(text) < 300, text
        assert text.startswith("<Scene ") and " panel" in text and "figure_svg" in text
        assert all(len(repr(p)) < 300 for p in (sc.root, *sc.panels))
    assert "Free-body diagram of upper" in repr(fbd_scene(asm.bodies["upper"].fbd))


def test_the_fast_solution_is_a_solution_as_the_dataclass_makes_it():
    """`solution()` (the solve's hot path) fills every field of `Solution`, no more, and
    equals the dataclass's own construction; the result stays frozen."""
    import dataclasses

    import numpy as np

    from mbody.equations.solution import Solution, solution

    names = [f.name for f in dataclasses.fields(Solution)]
    args = [["a"], np.zeros(1), {"A.Fx": 1.0}, ("A.Fx",), ("A.Fx",), 1e-16, 2.0, "m",
            ("B",), 1, "world"]
    fast = solution(*args)
    assert list(vars(fast)) == names
    assert fast == Solution(*args)
    assert solution(*args[:3]) == Solution(*args[:3])
    with pytest.raises(dataclasses.FrozenInstanceError):
        fast.redundant = 2  # type: ignore[misc]


def test_the_plain_solution_is_a_solution_as_the_dataclass_makes_it():
    """`plain_solution` (a full-rank solve's hot path: the plan's constant fields and the
    four that change) equals the dataclass's construction, field for field and in order,
    stays frozen, and leaves the plan's fields as they were."""
    import dataclasses

    import numpy as np

    from mbody.equations.solution import METHODS, Solution, plain_solution, solution_fields

    names = [f.name for f in dataclasses.fields(Solution)]
    fields = solution_fields(["a"], ("A.Fx",))
    before = dict(fields)
    acc, lam = np.ones(1), {"A.Fx": 1.0}
    fast = plain_solution(fields, acc, lam, 1e-16, METHODS[2])
    assert list(vars(fast)) == names
    assert fast == Solution(["a"], acc, lam, ("A.Fx",), residual=1e-16, method=METHODS[2])
    assert fields == before
    with pytest.raises(dataclasses.FrozenInstanceError):
        fast.residual = 0.0  # type: ignore[misc]


def test_reaction_values_array_is_read_only_and_the_values():
    """`ReactionValues.array` is the values given, as a read-only view (made on first
    use), the same object on every read."""
    import numpy as np

    from mbody.equations.solution import ReactionValues

    values = np.array([1.0, -2.0])
    rv = ReactionValues(["A.Fx", "A.Fy"], {"A.Fx": 0, "A.Fy": 1}, values)
    assert rv["A.Fy"] == -2.0 and dict(rv) == {"A.Fx": 1.0, "A.Fy": -2.0}
    arr = rv.array
    assert arr is rv.array and np.shares_memory(arr, values)
    assert not arr.flags.writeable
    with pytest.raises(ValueError):
        arr[0] = 3.0
    sol = mbody.assemble(mbody.load(MODELS[0].parent / "double_pendulum.yaml")).solve()
    assert not sol.reactions.array.flags.writeable  # type: ignore[attr-defined]


def test_a_verification_and_symbolic_equations_repr_in_a_line():
    """verify's and symbolic()'s results were dataclass dumps of 2-3 kB (every check's
    explanation, every term): one line each now, the report on print() as before."""
    root = MODELS[0].parent
    v = mbody.verify(root / "pendulum.yaml", root / "answers" / "pendulum.yaml")
    text = repr(v)
    assert text.startswith("<Verification of 'physical-pendulum'") and len(text) <= 300
    assert f"{v.correct} of {len(v.checks)} equations correct" in text
    assert all(c.diagnosis in text for c in v.checks if not c.correct)
    assert str(v) == v.text() and "\n" in str(v)
    assert all(repr(c).startswith(f"<Check [{c.index}] {c.body}: ") for c in v.checks)
    sym = mbody.assemble(mbody.load(root / "double_pendulum.yaml")).symbolic()
    shown = [repr(sym), repr(sym["upper"]), *map(repr, sym.rows)]
    assert all(len(t) <= 300 and t.endswith(">") for t in shown), shown
    assert shown[0] == ("<SymbolicEquations of 'double-pendulum' at t = 0 s: 2 bodies, 6 rows; "
                        "print() it, .text(), .latex(), [body]>")
    assert shown[2] == f"<SymbolicRow upper.x: {sym.rows[0].text()}>"


def test_a_linearization_repr_says_when_it_lists_only_some_frequencies():
    chain = mbody.loads("model: chain\ndimension: 2\ngravity: [0, -9.81]\nbodies:\n"
                        + "".join(f"  - {{name: b{i}, mass: 1, inertia: 0.1, position: "
                                  f"[0, {-i - 0.5}]}}\n" for i in range(6))
                        + "joints:\n" + "".join(
                            f"  - {{name: J{i}, type: revolute, parent: "
                            f"{'ground' if i == 0 else f'b{i - 1}'}, child: b{i}, "
                            f"at: [0, {-i}]}}\n" for i in range(6)))
    lin = mbody.linearize(chain)
    assert len(lin.frequencies) == 6
    assert "…" in repr(lin) and repr(lin).count(",") >= 4
    two = mbody.linearize(mbody.load(MODELS[0].parent / "double_pendulum.yaml"))
    assert "…" not in repr(two)
