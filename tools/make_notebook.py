"""Write docs/notebooks/tutorial.ipynb from the cells below (the notebook's source).

    python tools/make_notebook.py           # write it
    python tools/make_notebook.py --check   # exit 1 when the stored notebook differs
    python tools/make_notebook.py --docs    # docs/notebook.md's displays, from this code

``--docs`` puts the pendulum's Solution display (its HTML) between the markers in
docs/notebook.md and a screenshot of its body display (headless Chromium) in
docs/images/notebook_body.png.

The notebook is stored without outputs: its diff is the cells' text, it holds no stale
numbers and no megabyte animation, and `tests/test_notebook.py` runs it top to bottom.
Cell ids are fixed (``cell-00``...) so that writing it twice gives the same file.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import nbformat
from nbformat import v4

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK = ROOT / "docs" / "notebooks" / "tutorial.ipynb"
PAGE = ROOT / "docs" / "notebook.md"
PICTURE = ROOT / "docs" / "images" / "notebook_body.png"
BEGIN, END = "<!-- solution display (tools/make_notebook.py --docs) -->", "<!-- end -->"
CHROMIUM = "/usr/bin/chromium"

CELLS: list[tuple[str, str]] = [
    ("md", """\
# Newton-Euler equations with mbody

This notebook follows the course module *Newton-Euler equations of motion* on the models
shipped in `models/`: draw the free body, write Newton's and Euler's equations (planar,
then spatial with the gyroscopic term), keep applied and constraint forces apart, then
solve, simulate, animate and export. Every mbody object shows itself: a model as tables
and its body/joint graph, a body as its free-body diagram and equations, a solution as
accelerations and reactions with units, a run as plots."""),
    ("code", """\
import tempfile
from pathlib import Path

import numpy as np
from IPython.display import Math, display

import mbody
from mbody.io.export import write_export
from mbody.present.latex import stacked_latex
from mbody.present.rich import animation

# the shipped models, found from the repository root or any folder below it
MODELS = next(p / "models" for p in (Path.cwd(), *Path.cwd().parents)
              if (p / "models" / "pendulum.yaml").is_file())
OUT = Path(tempfile.mkdtemp(prefix="mbody-notebook-"))  # the files this notebook writes"""),
    ("md", """\
## 1. A model and the free body of each body (skill 6.5)

Worked example 1 of the module: a 10 kg plate (I_G = 0.5 kg m²) pushed by 50 N along a
line 0.4 m below its mass centre. Loading the file checks it; the model shows what it
holds."""),
    ("code", """\
plate_model = mbody.load(MODELS / "seed_example_1.yaml")
plate_model"""),
    ("md", """\
`mbody.assemble` writes the equations at the model's state. `asm.bodies[name]` is one
body: its free-body diagram (every force, where it acts, its moment about G) and its
Newton-Euler pair."""),
    ("code", """\
asm = mbody.assemble(plate_model)
plate = asm.bodies["plate"]
plate"""),
    ("md", "`print` gives the same block as the command `mbody assemble`:"),
    ("code", "print(plate)"),
    ("md", """\
## 2. Newton: ΣF = m a_G (skill 6.1)

Newton's rows are in world axes. Summing the forces of the free body and dividing by
the mass is the whole of it; `asm.solve()` does the same for every body at once."""),
    ("code", """\
F = sum(f.W_vector for f in plate.fbd.forces)  # every force on the plate, world axes (N)
print("ΣF =", F[:2], "N;  a_G = ΣF / m =", F[:2] / plate.fbd.mass, "m/s²")
plate.newton[0]"""),
    ("code", """\
sol = asm.solve()
sol"""),
    ("md", """\
## 3. Planar Euler: ΣM_G = I_G α (skill 6.2)

Moments are taken about the mass centre. The push acts 0.4 m below G, so it turns the
plate as well as moving it."""),
    ("code", """\
M_G = sum(f.B_moment[2] for f in plate.fbd.forces)  # moments about G (N m)
I_G = plate.fbd.inertia[2, 2]
print(f"ΣM_G = {M_G:g} N m, I_G = {I_G:g} kg m², α = ΣM_G / I_G = {M_G / I_G:g} rad/s²")
assert np.isclose(M_G / I_G, sol["plate.theta"])
plate.euler[0]"""),
    ("md", """\
## 4. Euler's equations in space: the gyroscopic term (skill 6.3)

Worked example 2: principal inertias (2, 3, 4) kg m², ω = (1, 2, 3) rad/s, no torque.
In space the Euler rows read J ω̇ + ω × (J ω) = M; the term ω × (J ω) couples the axes,
so the spin rates change although nothing acts on the body."""),
    ("code", """\
spin = mbody.assemble(mbody.load(MODELS / "seed_example_2.yaml"))
body = spin.bodies["body"]
body"""),
    ("code", """\
J = body.fbd.inertia
w = spin.state.omega[0]
gyro = np.cross(w, J @ w)  # ω × (J ω), body axes (N m)
print("ω × Jω =", gyro, "N m;  ω̇ = J⁻¹(M − ω × Jω) =", np.linalg.solve(J, -gyro), "rad/s²")
print("mbody:", spin.solve().accelerations[3:], "rad/s²  (without the term: 0)")
body.euler[0]"""),
    ("md", """\
The heavy top leans 20° and spins at 150 rad/s: gravity's moment about the pivot is
balanced by the gyroscopic term, so the top precesses instead of falling, and the pivot
carries its weight."""),
    ("code", """\
top = mbody.assemble(mbody.load(MODELS / "heavy_top.yaml"))
top.solve()"""),
    ("md", """\
## 5. Applied forces and constraint forces (skill 6.4)

A physical pendulum: gravity is applied (known); the pin's components `O.Fx`, `O.Fy`
are constraint forces, unknowns of the solve. Each reaction acts as +R on the joint's
child and −R on its parent."""),
    ("code", """\
pendulum = mbody.assemble(mbody.load(MODELS / "pendulum.yaml"))
rod = pendulum.bodies["rod"]
print("applied (known):", [f.name for f in rod.fbd.applied])
print("constraint (unknown):", [f.label for f in rod.fbd.reactions if f.unknown])
rod"""),
    ("md", """\
## 6. Solve: accelerations and reactions together

The stacked system M v̇ + b = Q + G λ, with the joint's constraint, gives both the
accelerations and the pin force."""),
    ("code", """\
display(Math(stacked_latex(pendulum)))
pendulum_sol = pendulum.solve()
pendulum_sol"""),
    ("md", """\
Two bodies: every body's free body and pair, one after the other, then the solve. The
reaction at `A` acts on `lower` as +R and on `upper` as −R."""),
    ("code", """\
double = mbody.load(MODELS / "double_pendulum.yaml")
double_asm = mbody.assemble(double)
double_asm"""),
    ("code", "double_asm.solve()"),
    ("md", """\
## 7. Simulate

`mbody.simulate(model, t_end, fps)` integrates the motion with the reactions solved at
every step, in mbody's compiled core (built when mbody was installed: nothing compiles
when a run starts). A run shows its facts, its plots and the motion in 3-D."""),
    ("code", """\
run = mbody.simulate(double, 1.0, 30)
run"""),
    ("md", """\
## 8. Animate

`animation(run, reactions=True)` plays the run with the joint reactions drawn as arrows,
in a frame holding the offline page (about 1 MB: the 3-D viewer comes with it).
`mbody.animate` writes the same page to a file."""),
    ("code", "animation(run, reactions=True)"),
    ("code", """\
page = mbody.animate(run, OUT / "double_pendulum.html", model=double)
print(page.name, f"{page.stat().st_size / 1e6:.1f} MB")"""),
    ("md", """\
## 9. Export

The equations go to MATLAB, numpy or JSON with their labels; the export solves as the
assembly does. A run saves to `.npz` and loads back."""),
    ("code", """\
exported = mbody.load_export(write_export(pendulum, OUT / "pendulum.mat"))
print(exported)
print("α from the export:", exported.solve()["rod.theta"], " from mbody:",
      pendulum_sol["rod.theta"])
print(mbody.Trajectory.load(run.save(OUT / "double_pendulum.npz")))"""),
]
"""The notebook: (kind, source) in order, kind 'md' or 'code'."""


def build() -> nbformat.NotebookNode:
    """The notebook from `CELLS`, without outputs.

    Returns
    -------
    nbformat.NotebookNode
    """
    nb = v4.new_notebook()
    nb.metadata = {"kernelspec": {"display_name": "Python 3", "language": "python",
                                  "name": "python3"},
                   "language_info": {"name": "python"}}
    for k, (kind, source) in enumerate(CELLS):
        cell = v4.new_markdown_cell(source) if kind == "md" else v4.new_code_cell(source)
        cell.id = f"cell-{k:02d}"
        nb.cells.append(cell)
    nbformat.validate(nb)
    return nb


def text() -> str:
    """The notebook file's text (nbformat's JSON, one space indent, final newline).

    Returns
    -------
    str
    """
    return nbformat.writes(build()) + "\n"


def solution_display() -> str:
    """The pendulum's Solution display, as docs/notebook.md shows it.

    Returns
    -------
    str
    """
    import mbody
    from mbody.present.rich import solution_html

    return solution_html(mbody.assemble(mbody.load(ROOT / "models" / "pendulum.yaml")).solve())


def write_docs() -> None:
    """Refresh the Solution display in docs/notebook.md and the body display's picture."""
    from PIL import Image, ImageChops

    import mbody
    from mbody.present.rich import body_html

    page = PAGE.read_text(encoding="utf-8")
    head, rest = page.split(BEGIN, 1)
    PAGE.write_text(head + BEGIN + "\n" + solution_display() + "\n" + END
                    + rest.split(END, 1)[1], encoding="utf-8")
    asm = mbody.assemble(mbody.load(ROOT / "models" / "pendulum.yaml"))
    with tempfile.TemporaryDirectory() as tmp:
        html, png = Path(tmp) / "body.html", Path(tmp) / "body.png"
        html.write_text('<html><head><meta charset="utf-8"/></head><body style="margin:8px">'
                        + body_html(asm.bodies["rod"]) + "</body></html>", encoding="utf-8")
        subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
                        "--hide-scrollbars", "--force-device-scale-factor=1",
                        "--window-size=760,1500", f"--screenshot={png}", html.as_uri()],
                       check=True, capture_output=True, timeout=120)
        img = Image.open(png).convert("RGB")
        box = ImageChops.difference(img, Image.new("RGB", img.size, "white")).getbbox()
        assert box is not None, "the screenshot is blank"
        img = img.crop((0, 0, min(img.width, box[2] + 12), min(img.height, box[3] + 12)))
        img.save(PICTURE, optimize=True)
    print(f"wrote {PAGE.relative_to(ROOT)} (Solution display) and {PICTURE.relative_to(ROOT)}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--check", action="store_true",
                   help="exit 1 when the stored notebook is not what this script writes")
    p.add_argument("--docs", action="store_true",
                   help="refresh the displays docs/notebook.md shows")
    a = p.parse_args(argv)
    if a.docs:
        write_docs()
        return 0
    want = text()
    if a.check:
        same = NOTEBOOK.is_file() and NOTEBOOK.read_text(encoding="utf-8") == want
        print(f"{NOTEBOOK.relative_to(ROOT)}: " + ("up to date" if same else
              "differs from tools/make_notebook.py; run it"))
        return 0 if same else 1
    NOTEBOOK.parent.mkdir(parents=True, exist_ok=True)
    NOTEBOOK.write_text(want, encoding="utf-8")
    print(f"wrote {NOTEBOOK.relative_to(ROOT)} ({len(CELLS)} cells)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
