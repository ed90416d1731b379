"""Free-body pictures: what the drawing contains (arrows, directions, styles, labels),
the projection, the log length scale, the graph picture and the fbd/graph commands."""

from __future__ import annotations

import io
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.colors import to_hex
from matplotlib.figure import Figure

import mbody
from mbody.cli import main
from mbody.equations.topology import topology
from mbody.errors import MbodyError
from mbody.present.draw import (
    COLORS,
    arrow_lengths,
    draw_fbd,
    draw_graph,
    fbd_scene,
    figure_bytes,
    figure_svg,
    graph_scene,
    parse_view,
    projection,
    save_figure,
    scene_figure,
)
from mbody.present.draw.scene import Line, Text

ROOT = Path(__file__).resolve().parent.parent
MODELS = sorted((ROOT / "models").glob("*.yaml"))
S3 = 1 / np.sqrt(3)


def drawing(fig: Figure):
    return next(a for a in fig.axes if a.get_gid() == "drawing")


def arrows(fig: Figure, prefix: str) -> dict:
    """gid -> Line2D of the arrow shafts whose gid starts with `prefix`."""
    return {ln.get_gid(): ln for ln in drawing(fig).lines
            if (ln.get_gid() or "").startswith(prefix)}


def direction(line) -> np.ndarray:
    xy = line.get_xydata()
    d = xy[-1] - xy[0]
    return d / np.linalg.norm(d)


def labels(fig: Figure) -> dict[str, str]:
    return {t.get_gid(): t.get_text() for t in drawing(fig).texts
            if (t.get_gid() or "").startswith("label:")}


def body(model_file: str, name: str, **kw):
    m = mbody.load(ROOT / "models" / model_file) if not isinstance(model_file, dict) \
        else mbody.load(model_file)
    return mbody.assemble(m).bodies[name]


def planar_model(loads, joints=(), reactions=None, gravity=True):
    spec = {"model": "t", "dimension": 2,
            "bodies": [{"name": "plate", "mass": 2.0, "inertia": 0.1, "position": [1, 2],
                        "shape": {"box": [0.6, 0.4]}}],
            "loads": list(loads), "joints": list(joints)}
    if gravity:
        spec["gravity"] = [0, -9.81]
    if reactions:
        spec["reactions"] = reactions
    return mbody.load(spec)


# -- projection and scale ---------------------------------------------------------------
def test_named_views_project_world_axes_as_drawn_on_paper():
    iso = projection("iso")
    np.testing.assert_allclose(iso @ [1, 0, 0], [-np.sqrt(0.5), -np.sqrt(1 / 6)], atol=1e-12)
    np.testing.assert_allclose(iso @ [0, 1, 0], [np.sqrt(0.5), -np.sqrt(1 / 6)], atol=1e-12)
    np.testing.assert_allclose(iso @ [0, 0, 1], [0, np.sqrt(2 / 3)], atol=1e-12)
    # the isometric eye looks along (1, 1, 1): that direction projects to a point
    np.testing.assert_allclose(iso @ [S3, S3, S3], [0, 0], atol=1e-12)
    np.testing.assert_allclose(projection("front"), [[1, 0, 0], [0, 0, 1]], atol=1e-12)
    np.testing.assert_allclose(projection("top"), [[1, 0, 0], [0, 1, 0]], atol=1e-12)
    np.testing.assert_allclose(projection("side"), [[0, 1, 0], [0, 0, 1]], atol=1e-12)
    for v in ("iso", (20, -70), "30,-60"):
        P = projection(v)
        np.testing.assert_allclose(P @ P.T, np.eye(2), atol=1e-12)  # orthonormal rows


def test_bad_view_is_a_clear_error():
    with pytest.raises(MbodyError, match="did you mean 'iso'"):
        parse_view("isso")
    with pytest.raises(MbodyError, match="ELEV,AZIM"):
        parse_view("30;40")
    assert parse_view("30, -60") == (30.0, -60.0)


def test_log_lengths_keep_a_1000_to_1_ratio_readable():
    ell = arrow_lengths([1.0, 10.0, 1000.0, 0.0], 2.0)
    # 1 + log10(F/F_min): steps 1, 2, 4, scaled so the longest is 2
    np.testing.assert_allclose(ell, [0.5, 1.0, 2.0, 0.0])
    np.testing.assert_allclose(arrow_lengths([3.0, 3.0], 1.0), [1.0, 1.0])
    assert arrow_lengths([], 1.0).shape == (0,)


# -- planar diagrams -----------------------------------------------------------------------
def test_seed_example_1_one_applied_arrow_along_x_at_its_point():
    eq = body("seed_example_1.yaml", "plate")
    fig = draw_fbd(eq.fbd)
    assert isinstance(fig, Figure)
    shafts = arrows(fig, "arrow:")
    assert list(shafts) == ["arrow:applied:push"]  # no gravity in this model, no joints
    push = shafts["arrow:applied:push"]
    np.testing.assert_allclose(direction(push), [1, 0], atol=1e-12)
    # it acts at [0, -0.4], on the plate's lower edge and along it: drawn just below the
    # edge, not on it, with a dotted leader from the point where it acts to its tail
    lead = next(ln for ln in drawing(fig).lines if ln.get_gid() == "leader:applied:push")
    np.testing.assert_allclose(lead.get_xydata()[0], [0, -0.4], atol=1e-12)
    np.testing.assert_allclose(lead.get_xydata()[1], push.get_xydata()[0], atol=1e-12)
    assert push.get_xydata()[0, 0] == pytest.approx(0, abs=1e-12)
    assert -0.45 < push.get_xydata()[0, 1] < -0.4  # a few points below the edge
    assert push.get_linestyle() == "-"
    assert to_hex(push.get_color()) == COLORS["applied"]
    assert labels(fig)["label:applied:push"] == "push 50 N"
    eqs = next(t for t in fig.texts if t.get_gid() == "equations").get_text()
    for e in eq.equations:
        assert str(e) in eqs
    assert "10 a_x = 50" in eqs and "0.5 alpha = 20" in eqs  # the course's answer


def test_pendulum_gravity_and_dashed_reactions_at_the_pin():
    fig = draw_fbd(body("pendulum.yaml", "rod").fbd)
    grav = arrows(fig, "arrow:gravity:")
    reac = arrows(fig, "arrow:reaction:")
    assert list(grav) == ["arrow:gravity:gravity"]
    np.testing.assert_allclose(direction(grav["arrow:gravity:gravity"]), [0, -1], atol=1e-12)
    np.testing.assert_allclose(grav["arrow:gravity:gravity"].get_xydata()[0],
                               [0.25, -0.4330127018922193], atol=1e-12)  # at G
    assert sorted(reac) == ["arrow:reaction:O.Fx", "arrow:reaction:O.Fy"]
    np.testing.assert_allclose(direction(reac["arrow:reaction:O.Fx"]), [1, 0], atol=1e-9)
    np.testing.assert_allclose(direction(reac["arrow:reaction:O.Fy"]), [0, 1], atol=1e-9)
    for ln in reac.values():
        np.testing.assert_allclose(ln.get_xydata()[0], [0, 0], atol=1e-9)  # the pin O
        assert ln.get_linestyle() != "-"  # dashed
        assert to_hex(ln.get_color()) == COLORS["reaction"]
        assert to_hex(ln.get_color()) != COLORS["applied"]
    lab = labels(fig)
    assert lab["label:reaction:O.Fx"] == "O.Fx" and lab["label:reaction:O.Fy"] == "O.Fy"
    assert lab["label:gravity:gravity"] == "m g = 19.62 N"
    legend = " ".join(t.get_text() for t in fig.texts
                      if (t.get_gid() or "").startswith("legend"))
    assert "log10" in legend and "reaction" in legend and "gravity" in legend


def test_lengths_within_one_picture_follow_the_log_rule():
    m = planar_model([{"name": "small", "type": "force", "body": "plate", "force": [1, 0]},
                      {"name": "big", "type": "force", "body": "plate", "force": [0, 1000],
                       "at": [0.1, 0]}], gravity=False)
    fig = draw_fbd(mbody.assemble(m).bodies["plate"].fbd)
    sh = arrows(fig, "arrow:applied:")
    length = {k: np.linalg.norm(np.ptp(v.get_xydata(), axis=0)) for k, v in sh.items()}
    assert length["arrow:applied:big"] / length["arrow:applied:small"] == pytest.approx(4.0)
    np.testing.assert_allclose(direction(sh["arrow:applied:big"]), [0, 1], atol=1e-12)
    assert labels(fig)["label:applied:big"] == "big 1000 N"


def test_planar_couples_are_curved_with_the_sense_of_rotation():
    m = planar_model([{"name": "ccw", "type": "torque", "body": "plate", "torque": 5},
                      {"name": "cw", "type": "torque", "body": "plate", "torque": -2}])
    fig = draw_fbd(mbody.assemble(m).bodies["plate"].fbd)
    cps = arrows(fig, "couple:applied:")
    assert sorted(cps) == ["couple:applied:ccw", "couple:applied:cw"]
    G = np.array([1.0, 2.0])
    for gid, sense in (("couple:applied:ccw", 1), ("couple:applied:cw", -1)):
        xy = cps[gid].get_xydata() - G
        turn = np.sum(xy[:-1, 0] * xy[1:, 1] - xy[:-1, 1] * xy[1:, 0])  # signed area x 2
        assert np.sign(turn) == sense
        radius = np.linalg.norm(xy, axis=1)
        np.testing.assert_allclose(radius, radius[0], rtol=1e-9)  # an arc about G
    assert labels(fig)["label:applied:cw"] == "cw 2 N m"


def test_known_reactions_show_values_and_zeros_are_listed_not_drawn():
    m = planar_model([], joints=[{"name": "A", "type": "revolute", "parent": "ground",
                                  "child": "plate", "at": [1.3, 2]}],
                     reactions={"A.Fx": 0, "A.Fy": -4})
    fig = draw_fbd(mbody.assemble(m).bodies["plate"].fbd)
    reac = arrows(fig, "arrow:reaction:")
    assert list(reac) == ["arrow:reaction:A.Fy"]
    # drawn in the component's positive direction; the value carries the sign
    np.testing.assert_allclose(direction(reac["arrow:reaction:A.Fy"]), [0, 1], atol=1e-12)
    assert labels(fig)["label:reaction:A.Fy"] == "A.Fy = −4 N"
    note = next(t for t in fig.texts if t.get_gid() == "zero-note").get_text()
    assert "A.Fx" in note


# -- spatial diagrams ------------------------------------------------------------------------
@pytest.mark.parametrize(("view", "end_on"), [("iso", 0), ("front", 5), ("top", 2),
                                              ((25.0, -130.0), 0)])
def test_spatial_arrows_point_along_their_projected_vectors(view, end_on):
    eq = body("fourbar_spatial.yaml", "coupler")
    fbd = eq.fbd
    fig = draw_fbd(fbd, view=view)
    P = projection(view)
    forces = arrows(fig, "arrow:reaction:")
    moments = arrows(fig, "couple:reaction:")
    assert len(forces) == 6 and len(moments) == 4  # two revolutes: Fx Fy Fz Mx My each
    checked = 0
    for fo in fbd.forces:
        gid = ("couple:" if fo.couple else "arrow:") + f"{fo.kind}:{fo.label or fo.name}"
        line = arrows(fig, gid)[gid]
        page = P @ (fo.side * fo.W_vector)  # along the joint axis, −R on the parent
        if np.linalg.norm(page) < 1e-6:  # seen end-on in this view
            continue
        np.testing.assert_allclose(direction(line), page / np.linalg.norm(page), atol=1e-9)
        checked += 1
    # the front view sees gravity and the y components end-on, the top view the z ones
    assert checked == len(fbd.forces) - end_on
    gids = [p.get_gid() or "" for p in drawing(fig).patches]
    # every moment has a double head, or two rings when seen end-on
    double = {g.split(":")[2] for g in gids if g.endswith((":head2", ":ring2"))}
    assert double == {"A.Mx", "A.My", "B.Mx", "B.My"}
    assert sum(g.endswith(":end-on") for g in gids) == end_on
    lab = labels(fig)
    # the coupler is A's child (+R) and B's parent (−R)
    assert {lab[f"label:reaction:{c}"] for c in ("A.Fx", "B.Mx")} == {"A.Fx", "−B.Mx"}


@pytest.mark.parametrize("model_file", ["double_pendulum.yaml", "slider_crank.yaml",
                                        "fourbar_planar.yaml", "triple_pendulum.yaml"])
def test_parent_side_reactions_are_labelled_minus_and_agree_with_the_equations(model_file):
    m = mbody.load(ROOT / "models" / model_file)
    asm = mbody.assemble(m)
    parents = {j.name for j in m.joints}
    seen = 0
    for name in m.body_names:
        eq = asm.bodies[name]
        fig = draw_fbd(eq.fbd)
        lab = labels(fig)
        for fo in eq.fbd.reactions:
            if fo.value == 0:
                continue
            joint = fo.label.split(".")[0]
            on_parent = next(j for j in m.joints if j.name == joint).parent == name
            gid = ("couple:" if fo.couple else "arrow:") + f"reaction:{fo.label}"
            text = lab["label:" + gid.split(":", 1)[1]]
            assert text.startswith("−") == on_parent, (name, text)
            assert text.lstrip("−").split(" ")[0] == fo.label
            sign = -1.0 if text.startswith("−") else 1.0
            # label sign × drawn direction = the force per unit of the unknown, which is
            # the unknown's column of G in this body's rows
            line = arrows(fig, gid)[gid]
            if not fo.couple:
                np.testing.assert_allclose(sign * direction(line), fo.W_vector[:2] / np.linalg.norm(
                    fo.W_vector[:2]), atol=1e-9)
                rows = {e.row.split(".")[-1]: e.reactions.get(fo.label, 0.0) for e in eq.newton}
                np.testing.assert_allclose([rows["x"], rows["y"]], fo.W_vector[:2], atol=1e-9)
            seen += on_parent
        # the legend explains the minus exactly when the picture has one
        legend = " ".join(t.get_text() for t in fig.texts
                          if (t.get_gid() or "") == "legend-entry")
        assert ("on the joint's parent" in legend) == any(
            v.startswith("−") for k, v in lab.items() if k.startswith("label:reaction:"))
    assert seen > 0 and parents


def test_spatial_body_without_shape_is_its_equivalent_box():
    fbd = body("seed_example_2.yaml", "body").fbd  # inertia (2, 3, 4), no shape
    fig = draw_fbd(fbd, view="top")
    outline = next(p for p in drawing(fig).patches if p.get_gid() == "body-outline")
    xy = outline.get_xy()
    # box edges a² = 6 (I2 + I3 − I1)/m: 30, 18, 6 -> seen from the top: a × b
    a, b = np.sqrt(6 * 5), np.sqrt(6 * 3)
    np.testing.assert_allclose(np.ptp(xy, axis=0), [a, b], rtol=1e-6)
    world = next(a for a in fig.axes if a.get_gid() == "world-axes")
    assert {ln.get_gid() for ln in world.lines} >= {"world-axis:x", "world-axis:y"}
    assert {ln.get_gid() for ln in drawing(fig).lines} >= {
        "body-axis:x", "body-axis:y", "body-axis:z"}


def _own_overlaps(fig: Figure) -> list[str]:
    """Labels whose box is crossed by the arrow they name (display pixels)."""
    ax = drawing(fig)
    r = fig.canvas.get_renderer()
    shafts = {ln.get_gid().split(":", 1)[1]: ln for ln in ax.lines
              if (ln.get_gid() or "").split(":")[0] in ("arrow", "couple")}
    bad = []
    for t in ax.texts:
        gid = t.get_gid() or ""
        if not gid.startswith("label:") or gid[6:] not in shafts:
            continue
        bb = t.get_window_extent(r)
        pts = ax.transData.transform(shafts[gid[6:]].get_xydata())
        s = np.vstack([p + (q - p) * np.linspace(0, 1, 50)[:, None]
                       for p, q in zip(pts[:-1], pts[1:], strict=True)])
        if np.any((s[:, 0] > bb.x0) & (s[:, 0] < bb.x1) & (s[:, 1] > bb.y0)
                  & (s[:, 1] < bb.y1)):
            bad.append(t.get_text())
    return bad


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_labels_do_not_cross_their_arrows_on_shipped_models(path):
    m = mbody.load(path)
    asm = mbody.assemble(m)
    for name in m.body_names[:6]:
        fig = draw_fbd(asm.bodies[name].fbd)
        n_arrows = len(arrows(fig, "arrow:")) + len(arrows(fig, "couple:"))
        drawn = [f for f in asm.bodies[name].fbd.forces
                 if f.unknown or (f.value != 0 if f.kind == "reaction" else f.magnitude > 0)]
        assert n_arrows == len(drawn)
        assert _own_overlaps(fig) == [], (m.name, name)


# -- output and the API ---------------------------------------------------------------------
def test_outputs_svg_png_pdf_and_jupyter(tmp_path):
    fbd = body("pendulum.yaml", "rod").fbd
    svg = fbd._repr_svg_()
    assert svg.startswith("<svg") and svg.rstrip().endswith("</svg>")
    assert "<?xml" not in svg and "<metadata>" not in svg
    fig = draw_fbd(fbd)
    assert figure_svg(fig).startswith("<svg")
    assert figure_bytes(fig, "png")[:8] == b"\x89PNG\r\n\x1a\n"
    assert figure_bytes(fig, "pdf")[:5] == b"%PDF-"
    out = save_figure(fig, tmp_path / "rod.png")
    assert out.read_bytes()[:4] == b"\x89PNG"
    assert [p.name for p in tmp_path.iterdir()] == ["rod.png"]  # no temporary left behind
    with pytest.raises(MbodyError, match="format"):
        save_figure(fig, tmp_path / "rod.gif")


def test_drawing_never_imports_pyplot():
    code = ("import sys, mbody; a = mbody.assemble(mbody.load('models/pendulum.yaml')); "
            "mbody.draw_fbd(a.bodies['rod'].fbd); print('matplotlib.pyplot' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "False"


def test_graph_picture_has_every_body_and_joint():
    m = mbody.load(ROOT / "models" / "slider_crank.yaml")
    fig = draw_graph(m, topology(m))
    ax = next(a for a in fig.axes if a.get_gid() == "graph")
    nodes = {t.get_gid() for t in ax.texts if (t.get_gid() or "").startswith("node:")}
    nodes |= {p.get_gid() for p in ax.patches if (p.get_gid() or "").startswith("node:")}
    assert nodes == {"node:ground"} | {f"node:{b}" for b in m.body_names}
    edges = {ln.get_gid() for ln in ax.lines}
    assert edges == {f"joint:{j.name}" for j in m.joints}
    text = {t.get_gid(): t.get_text() for t in ax.texts}
    for j in m.joints:
        assert text[f"joint-label:{j.name}"] == (f"{j.name}: {j.type}\n"
                                                 f"{len(j.components)} reactions")
    title = next(t for t in fig.texts if t.get_gid() == "title").get_text()
    assert "1 closed loop" in title and "mobility 1" in title


# -- commands --------------------------------------------------------------------------------
def test_fbd_command_writes_one_picture_per_body(tmp_path, capsys):
    assert main(["fbd", "models/slider_crank.yaml", "-o", str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "fbd_crank.svg", "fbd_piston.svg", "fbd_rod.svg"]
    assert (tmp_path / "fbd_rod.svg").read_text().lstrip().startswith("<?xml")
    assert main(["fbd", "models/heavy_top.yaml", "-o", str(tmp_path), "--body", "top",
                 "--image-format", "png", "--view", "front"]) == 0
    assert (tmp_path / "fbd_top.png").read_bytes()[:4] == b"\x89PNG"
    assert "fbd_top.png" in capsys.readouterr().out


def test_fbd_no_equations_is_the_diagram_without_its_newton_euler_pair(tmp_path):
    """A handout: `--no-equations` (`equations=False`) drops the body's rows, and only
    them: the arrows, their labels and the legend are the same as with the rows."""
    rows = [str(e) for e in body("slider_crank.yaml", "rod").equations]
    files = {}
    for flag in ([], ["--no-equations"]):
        out = tmp_path / ("bare" if flag else "full")
        assert main(["fbd", "models/slider_crank.yaml", "-o", str(out), "--body", "rod",
                     *flag]) == 0
        files[bool(flag)] = (out / "fbd_rod.svg").read_text()
    ids = {k: set(re.findall(r'<(?:g|polyline|polygon|circle) id="([^"]+)"', v))
           for k, v in files.items()}  # drawn elements (not the glyphs' paths)
    assert "equations" in ids[False] and "equations" not in ids[True]
    assert ids[False] - ids[True] == {"equations"}  # nothing else is left out
    assert all(f"{r} -->" in files[False] and r not in files[True] for r in rows)
    height = {k: float(re.search(r'<svg[^>]* height="([0-9.]+)pt"', v).group(1))
              for k, v in files.items()}
    assert height[True] < height[False]  # no room kept for the rows

    fbd = body("slider_crank.yaml", "rod").fbd
    gids = {k: {t.get_gid() for t in mbody.draw_fbd(fbd, equations=k).texts}
            for k in (True, False)}
    assert "equations" in gids[True] and "equations" not in gids[False]


def test_fbd_command_bad_body_and_view_exit_2(tmp_path, capsys):
    assert main(["fbd", "models/slider_crank.yaml", "-o", str(tmp_path), "--body",
                 "pistn"]) == 2
    err = capsys.readouterr().err
    assert "no body named 'pistn'" in err and "did you mean 'piston'?" in err
    assert "Traceback" not in err
    assert main(["fbd", "models/slider_crank.yaml", "-o", str(tmp_path), "--view",
                 "sideways"]) == 2
    assert "unknown view 'sideways'" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(SystemExit) as exc:
        main(["fbd", "models/slider_crank.yaml", "--image-format", "gif"])
    assert exc.value.code == 2


def test_graph_command(tmp_path, capsys):
    out = tmp_path / "g.png"
    assert main(["graph", "models/fourbar_planar.yaml", "-o", str(out)]) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"
    assert main(["graph", "models/fourbar_planar.yaml", "-o", str(tmp_path / "g.gif")]) == 2
    assert ".svg, .png, .pdf" in capsys.readouterr().err


# -- the fast SVG path ------------------------------------------------------------------------
def test_scene_svg_holds_every_arrow_label_and_glyph_it_uses(tmp_path):
    fbd = body("fourbar_spatial.yaml", "coupler").fbd
    sc = fbd_scene(fbd)
    svg = figure_svg(sc, prefix="p1-")
    assert svg.startswith("<svg") and svg.endswith("</svg>") and "<?xml" not in svg
    for fo in fbd.forces:
        tail = f"{fo.kind}:{fo.label or fo.name}"
        assert f'id="{"couple" if fo.couple else "arrow"}:{tail}"' in svg
        assert f'id="label:{tail}"' in svg
    used = set(re.findall(r'xlink:href="#(p1-[^"]+)"', svg))
    defined = set(re.findall(r'<path id="(p1-[^"]+)"', svg))
    assert used and used == defined  # every glyph drawn is defined once, nothing more
    # the same picture as the matplotlib figure: same arrows, same label texts
    fig = draw_fbd(fbd)
    shafts = {it.gid for p in sc.panels for it in p.items
              if isinstance(it, Line) and (it.gid or "").startswith(("arrow:", "couple:"))}
    assert shafts == set(arrows(fig, "arrow:")) | set(arrows(fig, "couple:"))
    path = save_figure(sc, tmp_path / "c.svg")
    assert path.read_text().startswith("<?xml")


def test_scene_text_width_matches_matplotlib():
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import text_to_path

    from mbody.present.draw.fonts import layout

    for s in ("A.Fx = −3.463 N", "m g = 19.62 N", "Wave"):
        w, _, _ = text_to_path.get_text_width_height_descent(
            s, FontProperties(family=["DejaVu Sans"], size=9), False)
        assert layout(s, 9).width == pytest.approx(w, rel=0.01)


def test_scene_text_boxes_match_matplotlib_svg_layout():
    # multi-line pitch, line box heights, math, alignment: where matplotlib's own SVG
    # writer puts each text (its layout in matplotlib >= 3.10: line height from the
    # font's typo metrics, ink centred in each line)
    from matplotlib.backends.backend_svg import RendererSVG

    from mbody.present.draw.scene import Scene, Text
    from mbody.present.draw.svg import text_box

    sc = Scene(400, 400)
    texts = [Text("O.Fx", np.array([200.0, 200.0]), 9),
             Text("m g = 9.81 N", np.array([200.0, 200.0]), 9, ha="center", va="center"),
             Text("Newton (world axes):\n  upper.x:  a_x = O.Fx\n  y", np.array([20.0, 380]),
                  9, va="top", family="mono", linespacing=1.45),
             Text("A: revolute\n5 reactions", np.array([200.0, 200]), 8, ha="center",
                  va="center"),
             Text("$x_B$", np.array([200.0, 200]), 8, math=True, va="bottom"),
             Text("G", np.array([200.0, 200]), 9, ha="right", va="top", offset=(3, -4)),
             Text("two\nlines", np.array([200.0, 200]), 9, va="baseline", align="right")]
    sc.root.add(*texts)
    fig = scene_figure(sc)
    fig.dpi = 72
    renderer = RendererSVG(400, 400, io.StringIO())
    for t, a in zip(texts, fig.texts, strict=True):
        e = a.get_window_extent(renderer)
        x0, y0, w, h = text_box(t, t.xy)
        assert (x0, y0, w, h) == pytest.approx((e.x0, e.y0, e.width, e.height), abs=0.05), t.s


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_every_shipped_model_draws_as_svg(path):
    m = mbody.load(path)
    asm = mbody.assemble(m)
    for name in m.body_names:
        assert figure_svg(fbd_scene(asm.bodies[name].fbd)).count("<polyline") >= 1
    assert 'id="node:' in figure_svg(graph_scene(m))


@pytest.mark.parametrize(("model_file", "name"), [("slider_crank.yaml", "piston"),
                                                  ("slider_crank.yaml", "crank"),
                                                  ("fourbar_spatial.yaml", "coupler")])
def test_legend_symbols_are_drawn_as_in_the_picture(model_file, name):
    from mbody.present.draw.scene import Disc, Poly, Wedge

    sc = fbd_scene(body(model_file, name).fbd)
    drawing_items = next(p for p in sc.panels if p.gid == "drawing").items
    root = sc.root.items
    # the mass centre: a white disc with two black quarters, in the picture and legend
    for items, gid in ((drawing_items, "mass-centre"), (root, "legend-handle:G")):
        k = next(i for i, it in enumerate(items) if getattr(it, "gid", None) == gid)
        disc, w1, w2 = items[k:k + 3]
        assert isinstance(disc, Disc) and (disc.face, disc.edge) == ("white", "black")
        assert [(type(w), w.a0, w.a1, w.face) for w in (w1, w2)] == [
            (Wedge, 0, 90, "black"), (Wedge, 180, 270, "black")]
    # every kind of arrow: same colour, width and dash as drawn, with a head
    drawn = [it for it in drawing_items if isinstance(it, Line)
             and (it.gid or "").startswith("arrow:")]
    kinds = {it.gid.split(":")[1] for it in drawn}
    assert "reaction" in kinds
    for kind in kinds:
        pic = next(it for it in drawn if it.gid.split(":")[1] == kind)
        leg = next(it for it in root if getattr(it, "gid", None) == f"legend-handle:{kind}")
        assert (leg.color, leg.lw, leg.dash) == (pic.color, pic.lw, pic.dash)
        assert any(isinstance(it, Poly) and it.gid == f"legend-handle:{kind}:head"
                   and it.face == pic.color for it in root)
    couples = [it for it in drawing_items if isinstance(it, Line)
               and (it.gid or "").startswith("couple:")]
    leg = [it for it in root if getattr(it, "gid", None) == "legend-handle:couple"]
    assert len(leg) == (1 if couples else 0)
    if couples:  # drawn as the picture's first couple
        assert (leg[0].color, leg[0].dash) == (couples[0].color, couples[0].dash)
    parent = any(t.s.startswith("−") for t in drawing_items
                 if isinstance(t, Text) and (t.gid or "").startswith("label:reaction:"))
    assert any(getattr(it, "gid", None) == "legend-handle:parent" for it in root) == parent


# -- drivers' efforts -------------------------------------------------------------------------
def _driven_arm():
    """An arm on a pin with a hand driven about the elbow E (its effort on the hand, and
    as −elbow.M on the arm, E's parent), and a block pressed along a slide S (a force)."""
    return mbody.load({
        "model": "t", "dimension": 2, "gravity": [0, -9.81],
        "bodies": [{"name": "arm", "mass": 1.0, "inertia": 0.02, "position": [0.25, 0],
                    "shape": {"box": [0.5, 0.05]}},
                   {"name": "hand", "mass": 0.5, "inertia": 0.01, "position": [0.65, 0],
                    "shape": {"box": [0.3, 0.05]}},
                   {"name": "slide", "mass": 0.5, "inertia": 0.01, "position": [0, -0.5],
                    "shape": {"box": [0.1, 0.1]}}],
        "joints": [{"name": "O", "type": "revolute", "parent": "ground", "child": "arm",
                    "at": [0, 0]},
                   {"name": "E", "type": "revolute", "parent": "arm", "child": "hand",
                    "at": [0.5, 0]},
                   {"name": "S", "type": "prismatic", "parent": "ground", "child": "slide",
                    "at": [0, -0.5], "axis": [1, 0]}],
        "drivers": [{"name": "elbow", "joint": "E", "angle": "0.3*t"},
                    {"name": "press", "joint": "S", "displacement": "0.1*t"}]})


def _items(sc, gid):
    return [it for p in (sc.root, *sc.panels) for it in p.items
            if getattr(it, "gid", None) == gid]


@pytest.mark.parametrize(("model", "name", "gid", "text"), [
    ("slider_crank_driven.yaml", "crank", "couple:effort:motor.M", "motor.M"),
    ("arm", "hand", "couple:effort:elbow.M", "elbow.M"),
    ("arm", "arm", "couple:effort:elbow.M", "−elbow.M"),
    ("arm", "slide", "arrow:effort:press.F", "press.F")])
def test_driver_effort_is_drawn_as_an_actuators_effort_apart_from_reactions(
        model, name, gid, text):
    from mbody.present.draw.scene import Poly
    from mbody.present.draw.style import DASHES

    m = _driven_arm() if model == "arm" else mbody.load(ROOT / "models" / model)
    fbd = mbody.assemble(m).bodies[name].fbd
    sc = fbd_scene(fbd)
    # its own colour and dash: neither a reaction's nor a solid applied load's
    (shaft,) = _items(sc, gid)
    assert shaft.color == COLORS["effort"] and shaft.dash == DASHES["effort"]
    assert len({COLORS[k] for k in ("applied", "gravity", "reaction", "effort")}) == 4
    assert DASHES["effort"] != DASHES["reaction"] and shaft.dash is not None
    assert _items(sc, gid.replace("effort", "reaction")) == []
    (label,) = _items(sc, "label:" + gid.split(":", 1)[1])
    assert label.s == text and label.color == COLORS["effort"]
    # the joints' reactions keep theirs
    reactions = [it for it in next(p for p in sc.panels if p.gid == "drawing").items
                 if isinstance(it, Line) and (it.gid or "").startswith("arrow:reaction:")]
    assert reactions and all(r.color == COLORS["reaction"] and r.dash == DASHES["reaction"]
                             for r in reactions)
    # a legend entry for it, its handle drawn as the arrow is
    (handle,) = _items(sc, "legend-handle:effort")
    assert (handle.color, handle.lw, handle.dash) == (shaft.color, shaft.lw, shaft.dash)
    assert any(isinstance(it, Poly) and it.face == shaft.color
               for it in _items(sc, "legend-handle:effort:head"))
    entries = [t.s for t in _items(sc, "legend-entry")]
    assert any(s.startswith("driver effort") for s in entries)
    # −elbow.M acts on the joint's parent: the legend says what the minus means, for an
    # effort as for a reaction
    minus = [t.s for t in next(p for p in sc.panels if p.gid == "drawing").items
             if isinstance(t, Text) and t.s.startswith("−")]
    assert (text in minus) == text.startswith("−")
    assert any("on the joint's parent" in s for s in entries) == bool(minus)
    # the matplotlib figure draws it so too
    line = arrows(mbody.draw_fbd(fbd), gid)[gid]
    assert to_hex(line.get_color()) == COLORS["effort"] and line.get_linestyle() != "-"


def test_no_effort_in_the_legend_without_a_driver_and_a_spatial_effort_is_a_moment():
    sc = fbd_scene(body("slider_crank.yaml", "crank").fbd)
    assert _items(sc, "legend-handle:effort") == []
    assert not any(t.s.startswith("driver effort") for t in _items(sc, "legend-entry"))
    spindle = body("flyball_governor.yaml", "spindle").fbd
    # seen from the front the motor's torque about the vertical spindle is a double-headed
    # arrow up the page; from the top it points at the eye: two rings
    front = fbd_scene(spindle, view="front")
    (shaft,) = _items(front, "couple:effort:motor.M")
    d = shaft.xy[-1] - shaft.xy[0]
    np.testing.assert_allclose(d / np.linalg.norm(d), [0, 1], atol=1e-9)
    assert len(_items(front, "couple:effort:motor.M:head2")) == 1
    top = fbd_scene(spindle, view="top")
    assert len(_items(top, "couple:effort:motor.M:ring2")) == 1


# -- layout rules in general terms -------------------------------------------------------------
def test_symbols_stay_small_when_a_long_thin_body_is_seen_end_on():
    """Bricard's rod2 (1 m long, 0.1 m across) seen along its length from the front: its
    arrows are sized by its length, the body is a 0.1 m square on the page; arrowheads
    and G's marker are capped in points, not grown with the arrows."""
    from mbody.present.draw.arrows import HEAD
    from mbody.present.draw.diagram import SYMBOLS
    from mbody.present.draw.scene import Disc, Poly

    sc = fbd_scene(body("bricard.yaml", "rod2").fbd, view="front")
    panel = next(p for p in sc.panels if p.gid == "drawing")
    heads = [it for it in panel.items if isinstance(it, Poly)
             and (it.gid or "").endswith(":head") and it.gid.startswith(("arrow:", "couple:"))]
    assert len(heads) >= 4
    lengths = [np.linalg.norm(h.xy[0] - (h.xy[1] + h.xy[2]) / 2) * panel.scale for h in heads]
    assert max(lengths) <= HEAD * SYMBOLS * (1 + 1e-9)
    shafts = [np.linalg.norm(np.diff(it.xy, axis=0)) * panel.scale for it in panel.items
              if isinstance(it, Line) and (it.gid or "").startswith(("arrow:", "couple:"))]
    assert max(shafts) > 10 * max(lengths)  # where a head a fixed share of the arrow is big
    (marker,) = [it for it in panel.items if isinstance(it, Disc) and it.gid == "mass-centre"]
    assert marker.r * panel.scale <= 0.045 * SYMBOLS * (1 + 1e-9)


def test_an_arrow_along_an_outline_seen_almost_edge_on_is_moved_off_it():
    """A curved outline is many short segments: together they count as an edge (a
    cylinder's end seen almost edge-on, a thin ellipse, with a reaction along it)."""
    from mbody.present.draw.arrows import Arrow
    from mbody.present.draw.spacing import CLEAR, separate

    t = np.linspace(0, 2 * np.pi, 73)
    rim = np.column_stack((20 * np.cos(t), 0.6 * np.sin(t)))  # in points: scale 1
    a = Arrow("arrow:reaction:A.Fz", "reaction", "A.Fz", COLORS["reaction"], (4.0, 2.5),
              False, np.zeros(2), np.array([60.0, 0.0]), length3=60.0)
    (b,) = separate([a], [rim], 1.0, np.array([0.0, 40.0]))
    assert b.moved_from is not None and abs(b.tail[1]) >= CLEAR + 0.6
    np.testing.assert_allclose(b.vec, a.vec)  # moved parallel to itself, full length
    # a rim across the arrow is no edge along it
    (c,) = separate([a], [rim[:, ::-1]], 1.0, np.array([0.0, 40.0]))
    assert c.moved_from is None
