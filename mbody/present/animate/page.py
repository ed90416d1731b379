"""The offline page: one self-contained HTML file that plays a `Scene`.

meshcat's viewer script is inlined and the commands are replayed in order, synchronously,
from base64 strings of their msgpack bytes (`wire.pack`), so the page needs no server
and fetches nothing; it is complete as soon as it loads (`window.mbody_ready`).
"""

from __future__ import annotations

import base64
import html
import os
from collections.abc import Iterable
from pathlib import Path

from mbody.errors import MbodyError
from mbody.model.model import Model
from mbody.present.animate.scene import Scene, build_scene
from mbody.present.animate.wire import load_meshcat, pack
from mbody.simulate.trajectory import Trajectory
from mbody.util.atomic import write_atomic

_PAGE = """<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ margin: 0; overflow: hidden; font: 14px sans-serif; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
#mbody-bar {{ position: absolute; left: 0; right: 0; bottom: 0; display: flex; gap: 8px;
  align-items: center; padding: 6px 10px; background: rgba(0, 0, 0, 0.55); color: #fff; }}
#mbody-bar button {{ min-width: 4.5em; }}
#mbody-time {{ flex: 1; }}
#mbody-clock {{ min-width: 11em; font-variant-numeric: tabular-nums; }}
</style></head>
<body><div id="meshcat-pane"></div>
<div id="mbody-bar"><button id="mbody-play" type="button">pause</button>
<input id="mbody-time" type="range" min="0" max="{duration}" step="any" value="0">
<span id="mbody-clock"></span><span>{caption}</span></div>
<script>{js}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
[{blobs}].forEach(function (s) {{
  var b = atob(s), a = new Uint8Array(b.length);
  for (var i = 0; i < b.length; i++) a[i] = b.charCodeAt(i);
  viewer.handle_command_bytearray(a);
}});
{fit}(function () {{
  var anim = viewer.animator, t0 = {t0}, duration = {duration};
  var play = document.getElementById("mbody-play");
  var slider = document.getElementById("mbody-time");
  var clock = document.getElementById("mbody-clock");
  function toggle() {{ if (anim.playing) anim.pause(); else anim.play(); }}
  play.onclick = toggle;
  document.addEventListener("keydown", function (e) {{
    if (e.code === "Space") {{ e.preventDefault(); toggle(); }} }});
  slider.oninput = function () {{
    var t = +slider.value; anim.pause(); anim.seek(t); anim.display_progress(t); }};
  function show() {{
    var t = anim.time;
    if (document.activeElement !== slider) slider.value = t;
    clock.textContent = "t = " + (t0 + t).toFixed(3) + " s of " + (t0 + duration).toFixed(3);
    play.textContent = anim.playing ? "pause" : "play";
    requestAnimationFrame(show);
  }}
  show();
}})();
window.mbody_ready = true;
</script>
{extra}</body></html>
"""



def page_html(scene: Scene, *, extra_js: str = "", typed_arrays: bool = True) -> str:
    """A self-contained page: meshcat's viewer inlined, the commands replayed in order.

    Nothing is fetched: no server, no external links.

    Parameters
    ----------
    scene : Scene
        What `build_scene` returns.
    extra_js : str
        Appended as a last <script> (tests use it to probe the page).
    typed_arrays : bool
        Keyframes as Float32Arrays (default); False packs them one number at a time as
        meshcat does (slower, larger; kept to compare against).

    Returns
    -------
    str
        The page's HTML text.
    """
    js = (Path(load_meshcat().viewer_assets_path()) / "dist" / "main.min.js").read_text(
        encoding="utf-8")
    if "</script" in js.lower():  # would end the inline <script> early
        raise MbodyError("meshcat's viewer script cannot be inlined (it contains </script>)")
    blobs = ",".join(
        f'"{base64.b64encode(pack(c, typed_arrays=typed_arrays)).decode("ascii")}"'
        for c in scene.commands)
    extra = f"<script>\n{extra_js}\n</script>\n" if extra_js else ""
    fit = ""
    if scene.camera is not None:  # the window's own aspect, now and after every resize
        fit = (scene.camera.js() + "viewer.set_3d_pane_size(); fit(viewer);\n"
               'window.addEventListener("resize", function () { fit(viewer); });\n')
    caption = html.escape(f"{scene.title.removeprefix('mbody: ')} · {scene.frames} frames")
    return _PAGE.format(title=html.escape(scene.title), duration=repr(scene.duration),
                        t0=repr(scene.t0), caption=caption, js=js, fit=fit, blobs=blobs,
                        extra=extra)


def write_page(traj: Trajectory, out: str | os.PathLike[str], *, model: Model,
               forces: bool = False, bodies: Iterable[str] | None = None,
               extra_js: str = "", reactions: bool = False) -> Path:
    """Write the offline animation page for `traj` to `out` atomically.

    Parameters
    ----------
    traj : Trajectory
        The motion.
    out : path
        The page to write (a temporary file renamed into place).
    model : Model
        The model `traj` was computed from.
    forces, bodies, reactions
        As in `build_scene`.
    extra_js : str
        As in `page_html`.

    Returns
    -------
    Path
        The page written.
    """
    scene = build_scene(traj, model, forces=forces, bodies=bodies, reactions=reactions)
    return write_atomic(out, page_html(scene, extra_js=extra_js))
