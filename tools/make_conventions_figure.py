"""Draw docs/figures/conventions.png: frames and reaction signs on a planar two-body example.

    python tools/make_conventions_figure.py [-o docs/figures/conventions.png]

Left: a crank pinned to the ground at O and a rod pinned to the crank at A, with the
world frame, each body's frame at its mass centre, and the joint frames (fixed to the
parent). Middle: the same bodies drawn apart, with each joint's reaction components
acting as +R on the child and -R on the parent. Right: a prismatic joint whose slide
axis is tilted 30 degrees, with its joint frame (x along the axis, y turned +90 degrees)
and its two components, Fy and Mz.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import FancyArrowPatch, Polygon  # noqa: E402

from mbody.util.atomic import atomic_path  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
WORLD, BODY, JOINT, REACT, GRAV = "#555555", "#1f77b4", "#2ca02c", "#d62728", "#7f7f7f"


def rot(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def arrow(ax, start, vec, color, label="", lw=1.6, offset=(0.0, 0.0), style="-|>",
          fontsize=9, ls="-"):
    start = np.asarray(start, float)
    end = start + np.asarray(vec, float)
    ax.add_patch(FancyArrowPatch(start, end, arrowstyle=style, mutation_scale=11, lw=lw,
                                 color=color, ls=ls, shrinkA=0, shrinkB=0))
    if label:
        ax.annotate(label, end + np.asarray(offset), color=color, fontsize=fontsize,
                    ha="center", va="center")


def frame(ax, origin, R, color, names, length=0.25, fontsize=9):
    for k in range(2):
        arrow(ax, origin, length * R[:, k], color, names[k],
              offset=0.09 * R[:, k] / np.linalg.norm(R[:, k]), fontsize=fontsize)


def link(ax, p, q, color="#c7d7ea", width=0.07):
    d = (q - p) / np.linalg.norm(q - p)
    n = np.array([-d[1], d[0]]) * width / 2
    ax.add_patch(Polygon([p + n, q + n, q - n, p - n], closed=True, fc=color,
                         ec="#4a6b8a", lw=1.0, zorder=0))


def pin(ax, p):
    ax.plot(*p, "o", ms=6, mfc="white", mec="black", zorder=5)


def ground(ax, p, size=0.14):
    x, y = p
    ax.add_patch(Polygon([(x, y), (x - size, y - 1.3 * size), (x + size, y - 1.3 * size)],
                         closed=True, fc="#dddddd", ec="black", lw=0.8, zorder=1))
    for k in range(5):
        xx = x - size + k * size / 2
        ax.plot([xx, xx - 0.06], [y - 1.3 * size, y - 1.3 * size - 0.06], color="black", lw=0.6)


def geometry():
    """A crank O-A at 40 deg and a rod A-B at -15 deg (body x along each link)."""
    O = np.array([0.0, 0.0])
    th1, th2 = np.radians(40), np.radians(-15)
    A = O + 0.9 * np.array([np.cos(th1), np.sin(th1)])
    B = A + 1.3 * np.array([np.cos(th2), np.sin(th2)])
    return O, A, B, th1, th2


def assembled(ax):
    O, A, B, th1, th2 = geometry()
    G1, G2 = (O + A) / 2, (A + B) / 2
    link(ax, O, A)
    link(ax, A, B)
    ground(ax, O)
    pin(ax, O)
    pin(ax, A)
    frame(ax, np.array([-0.55, -0.45]), np.eye(2), WORLD, ("$x_W$", "$y_W$"), 0.3)
    ax.annotate("world", (-0.55, -0.58), color=WORLD, fontsize=8, ha="center")
    frame(ax, G1, rot(th1), BODY, ("$x_1$", "$y_1$"))
    frame(ax, G2, rot(th2), BODY, ("$x_2$", "$y_2$"))
    ax.plot(*G1, "o", color=BODY, ms=4)
    ax.plot(*G2, "o", color=BODY, ms=4)
    ax.annotate("$G_1$ (crank)", G1 + [0.12, -0.12], color=BODY, fontsize=9)
    ax.annotate("$G_2$ (rod)", G2 + [-0.05, -0.2], color=BODY, fontsize=9)
    # Joint frames: no axis given, so world-aligned at the initial pose; fixed to the parent.
    frame(ax, A, np.eye(2), JOINT, ("$x_A$", "$y_A$"), 0.3)
    frame(ax, O, np.eye(2), JOINT, ("$x_O$", "$y_O$"), 0.3)
    ax.annotate("A", A + [-0.12, 0.05], fontsize=10, weight="bold")
    ax.annotate("O", O + [-0.13, 0.06], fontsize=10, weight="bold")
    arrow(ax, G2, A - G2, "#9467bd", "", lw=1.0, style="->", ls="--")
    ax.annotate(r"$r_{A}$ from $G_2$", (G2 + A) / 2 + [-0.1, -0.22], color="#9467bd",
                fontsize=8)
    ax.set_title("frames: world, body (at G), joint (at the joint point)", fontsize=10)


def exploded(ax):
    O, A, B, th1, th2 = geometry()
    gap = np.array([0.55, 0.35])  # the rod drawn apart from the crank
    A2, B2 = A + gap, B + gap
    link(ax, O, A)
    link(ax, A2, B2)
    ground(ax, O)
    pin(ax, O)
    pin(ax, A)
    pin(ax, A2)
    R = np.array([0.3, 0.35])  # a reaction of A, components along the joint frame
    arrow(ax, A2, [R[0], 0], REACT, "+A.Fx", offset=(0.2, 0.0))
    arrow(ax, A2, [0, R[1]], REACT, "+A.Fy", offset=(0.0, 0.08))
    arrow(ax, A, [-R[0], 0], REACT, "−A.Fx", offset=(0.0, 0.08))
    arrow(ax, A, [0, -R[1]], REACT, "−A.Fy", offset=(0.2, -0.02))
    Ro = np.array([0.3, 0.4])
    arrow(ax, O, [Ro[0], 0], REACT, "+O.Fx", offset=(0.08, -0.1))
    arrow(ax, O, [0, Ro[1]], REACT, "+O.Fy", offset=(-0.2, 0.0))
    for G in ((O + A) / 2, (A2 + B2) / 2):
        ax.plot(*G, "o", color=BODY, ms=4)
        arrow(ax, G, [0, -0.25], GRAV, "$m g$", offset=(0.12, 0.0), lw=1.2)
    ax.annotate("rod: child of A, so +R at A", A2 + [0.45, 0.2], color=REACT, fontsize=9)
    ax.annotate("crank: parent of A, so −R at A;\nchild of O, so +R at O", (0.35, -0.75),
                color=REACT, fontsize=9)
    ax.set_title("reactions: +R on the child, −R on the parent", fontsize=10)


def prismatic(ax):
    a = np.radians(30)
    e = np.array([np.cos(a), np.sin(a)])
    n = np.array([-e[1], e[0]])
    P = np.array([0.0, 0.0])
    # The guide (ground) and the slider block on it.
    ax.plot(*np.column_stack((P - 1.0 * e, P + 1.0 * e)), color="black", lw=2)
    for s in np.linspace(-0.9, 0.9, 10):
        q = P + s * e
        ax.plot(*np.column_stack((q, q - 0.06 * n - 0.05 * e)), color="black", lw=0.6)
    corners = [P + u * 0.25 * e + v * 0.15 * n for u, v in ((-1, 0), (1, 0), (1, 2), (-1, 2))]
    ax.add_patch(Polygon(corners, closed=True, fc="#c7d7ea", ec="#4a6b8a", lw=1.0, zorder=0))
    frame(ax, P, np.column_stack((e, n)), JOINT, ("$x_P$ (axis)", "$y_P$"), 0.5)
    C = P + 0.15 * n
    arrow(ax, C + 0.45 * e + 0.15 * n, 0.45 * n, REACT, "+P.Fy", offset=(0.12, 0.08))
    theta = a + np.radians(np.linspace(110, 250, 40))
    arc = C + 0.42 * np.column_stack((np.cos(theta), np.sin(theta)))
    ax.plot(arc[:, 0], arc[:, 1], color=REACT, lw=1.4)
    arrow(ax, arc[-2], arc[-1] - arc[-2], REACT, "", lw=1.4)
    ax.annotate("+P.Mz", arc[-1] + [0.12, -0.1], color=REACT, fontsize=9)
    ax.annotate("axis: [cos 30°, sin 30°]\nno force along $x_P$: it slides", (-0.2, -0.8),
                fontsize=8)
    ax.set_title("prismatic joint, tilted axis: Fy and Mz", fontsize=10)


def draw(out: Path) -> Path:
    xlims = ((-0.8, 2.3), (-0.6, 2.8), (-1.1, 1.2))
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6),
                             gridspec_kw={"width_ratios": [b - a for a, b in xlims]})
    assembled(axes[0])
    exploded(axes[1])
    prismatic(axes[2])
    for ax, xl in zip(axes, xlims, strict=True):
        ax.set_xlim(*xl)
        ax.set_ylim(-1.0, 1.55)
        ax.set_aspect("equal")
        ax.axis("off")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", type=Path, default=ROOT / "docs/figures/conventions.png")
    print(draw(p.parse_args().output))


if __name__ == "__main__":
    main()
