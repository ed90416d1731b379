"""Render the pictures shown in docs/diagrams.md from shipped models (never by hand).

    python tools/make_doc_images.py            # writes docs/images/*.png

Planar: the slider-crank's piston (gas force 4000 N beside 4.9 N of weight: the log
length scale at work; two reactions at one pin drawn side by side) and the upper link
of the double pendulum (the parent of joint A: its reactions are labelled −A.Fx, −A.Fy).
Spatial: the heavy top on its pivot, isometric view. And the slider-crank's body/joint
graph. The driven slider-crank's revolution (docs/driven.md).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import mbody
from mbody.model.graph import topology
from mbody.present.draw import draw_graph, save_figure
from mbody.present.plot import save_plot

ROOT = Path(__file__).resolve().parent.parent
PICTURES = (  # (model file, body, view, output name)
    ("slider_crank.yaml", "piston", "iso", "fbd_planar_piston.png"),
    ("double_pendulum.yaml", "upper", "iso", "fbd_planar_parent_side.png"),
    ("heavy_top.yaml", "top", "iso", "fbd_spatial_heavy_top.png"),
)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", default=str(ROOT / "docs" / "images"),
                   help="folder for the pictures (default: docs/images)")
    p.add_argument("--dpi", type=int, default=80)
    a = p.parse_args(argv)
    out = Path(a.output)
    for file, body, view, name in PICTURES:
        model = mbody.load(ROOT / "models" / file)
        fig = mbody.assemble(model).bodies[body].fbd.draw(view=view)
        print("wrote", save_figure(fig, out / name, dpi=a.dpi))
    run = mbody.kinematic_run(mbody.load(ROOT / "models" / "slider_crank_driven.yaml"),
                              0.1, 3600, axes="world")
    print("wrote", save_plot(run, out / "driven_slider_crank.png", dpi=a.dpi))
    model = mbody.load(ROOT / "models" / "slider_crank.yaml")
    fig = draw_graph(model, topology(model, mbody.assemble(model).G))
    print("wrote", save_figure(fig, out / "graph_slider_crank.png", dpi=a.dpi))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
