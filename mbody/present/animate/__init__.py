"""Animate a `Trajectory` in meshcat: a self-contained HTML page, or the live viewer.

    mbody.animate(traj, "run.html", model=model)        # the page; see docs/animation.md

The parts, in the order the data flows:

- `scene`: `build_scene` lowers the bodies' shapes, the grid, the camera, load arrows
  and the keyframe tracks to meshcat commands (a `Scene`);
- `wire`: `pack` turns a command into the msgpack bytes meshcat's viewer reads, with
  keyframes as Float32Arrays; it is where meshcat (0.3.2) is imported, on demand;
- `page`: `page_html` and `write_page`, the offline page;
- `live`: `LiveViewer`, meshcat's server on 127.0.0.1;
- `source`: `resolve`, a (trajectory, model) pair from whatever `animate` was given.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from mbody.errors import MbodyError
from mbody.model.model import Model
from mbody.present.animate.live import HOST, LiveViewer
from mbody.present.animate.page import page_html, write_page
from mbody.present.animate.scene import (
    CAMERA,
    COUPLE_COLOR,
    FILL,
    FORCE_COLOR,
    PALETTE,
    REACTION_COLOR,
    REACTION_COUPLE_COLOR,
    ROOT,
    SCENE_SIZE,
    CameraFit,
    Scene,
    build_scene,
    camera_fit,
)
from mbody.present.animate.source import Source, resolve
from mbody.present.animate.wire import pack, unpack
from mbody.util.atomic import write_atomic

__all__ = [
    "CAMERA", "FILL", "COUPLE_COLOR", "FORCE_COLOR", "HOST", "PALETTE", "REACTION_COLOR",
    "REACTION_COUPLE_COLOR", "ROOT", "SCENE_SIZE", "CameraFit", "LiveViewer", "Scene",
    "Source", "animate", "build_scene", "camera_fit", "pack", "page_html", "resolve",
    "unpack", "write_page",
]


def animate(source: Source, out: str | os.PathLike[str] | None = "run.html", *,
            model: Model | str | os.PathLike[str] | None = None, forces: bool = False,
            live: bool = False, t_end: float | None = None, fps: float | None = None,
            bodies: Iterable[str] | None = None, reactions: bool = False
            ) -> Path | LiveViewer:
    """Animate a motion: write a self-contained page, or (live=True) open the live viewer.

    Parameters
    ----------
    source : Trajectory, Model or path
        A `Trajectory` (then give `model`), a `Model` (simulated first, `t_end`/`fps`
        passed to `mbody.simulate`), or a path to a model (.yaml) or run (.npz) file.
    out : path, optional
        The page to write (atomically); not used with live=True.
    model : Model or path, optional
        The model of a trajectory (default: the one a run file carries or names).
    forces : bool
        Draw applied forces (yellow) and couples (magenta) as arrows.
    live : bool
        Open meshcat's live viewer on 127.0.0.1 instead of writing a page.
    t_end, fps : float, optional
        Simulated time and frame rate when `source` is a model.
    bodies : iterable of str, optional
        Draw only these bodies.
    reactions : bool
        Draw each joint's reaction force and couple on its child.

    Returns
    -------
    Path or LiveViewer
        The page's path; with live=True, a running `LiveViewer` (no page is written;
        show its `url` in a browser and `close()` it when done).
    """
    traj, mdl = resolve(source, model, t_end=t_end, fps=fps)
    scene = build_scene(traj, mdl, forces=forces, bodies=bodies, reactions=reactions)
    if not live:
        if out is None:
            raise MbodyError("give out= (the page to write) or live=True")
        return write_atomic(out, page_html(scene))
    viewer = LiveViewer()
    try:
        viewer.show(scene)
    except BaseException:
        viewer.close()
        raise
    return viewer
