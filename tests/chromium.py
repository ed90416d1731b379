"""Headless Chromium for tests: probe an offline page, or open a URL and keep it open.

A probe is JavaScript run inside the page once `window.mbody_ready` is set; it returns a
JSON-able value, which comes back through the page title (`--dump-dom` prints the DOM
after the virtual-time budget). WebGL renders on SwiftShader (CPU), so pixels can be read.

    if not chromium.AVAILABLE: pytest.skip(...)
    r = chromium.probe(page_path, "return {t: viewer.animator.duration};")
"""

from __future__ import annotations

import contextlib
import html
import json
import os
import re
import signal
import subprocess
import tempfile
from pathlib import Path
from typing import Any

CHROMIUM = "/usr/bin/chromium"
AVAILABLE = os.path.exists(CHROMIUM)
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
         "--disable-quic", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--disable-extensions",
         "--window-size=800,600")

_PROBE = """<script>
(function () {
  function finish(r) { document.title = "PROBE" + JSON.stringify(r); }
  function run() {
    if (!window.mbody_ready) { setTimeout(run, 50); return; }
    try { finish((function () { %s })()); }
    catch (e) { finish({error: String(e && e.stack || e)}); }
  }
  setTimeout(run, %d);
})();
</script>
"""

HELPERS = """
function node(path) { return viewer.scene_tree.find(path.split("/").filter(Boolean)).object; }
function at(t) { viewer.animator.pause(); viewer.animator.seek(t); viewer.render(); }
function local(path) {
  var o = node(path);
  return {p: o.position.toArray(), q: o.quaternion.toArray(), s: o.scale.toArray()};
}
function world(path) { var o = node(path), v = o.position.clone(); o.getWorldPosition(v);
  return v.toArray(); }
function screen(path) {  // where a node's origin is drawn, in pixels from the top left
  var o = node(path), v = o.position.clone(), c = viewer.renderer.domElement;
  o.getWorldPosition(v); v.project(viewer.camera);
  return [(v.x + 1) / 2 * c.width, (1 - v.y) / 2 * c.height]; }
function pixels(rgb, tol) {  // count and centroid of pixels within tol of rgb (0-255)
  viewer.render();
  var gl = viewer.renderer.getContext(), w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  var px = new Uint8Array(4 * w * h), n = 0, sx = 0, sy = 0;
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  for (var i = 0; i < w * h; i++) {
    var d = Math.abs(px[4*i] - rgb[0]) + Math.abs(px[4*i+1] - rgb[1])
      + Math.abs(px[4*i+2] - rgb[2]);
    if (d <= tol) { n++; sx += i % w; sy += h - 1 - Math.floor(i / w); }
  }
  return {n: n, c: n ? [sx / n, sy / n] : null, w: w, h: h}; }
function dominant(ch, ratio, floor) {  // pixels whose channel ch beats the others by ratio
  viewer.render();
  var gl = viewer.renderer.getContext(), w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  var px = new Uint8Array(4 * w * h), n = 0, sx = 0, sy = 0;
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  for (var i = 0; i < w * h; i++) {
    var v = px[4*i + ch], a = px[4*i + (ch + 1) % 3], b = px[4*i + (ch + 2) % 3];
    if (v >= floor && v >= ratio * a && v >= ratio * b) {
      n++; sx += i % w; sy += h - 1 - Math.floor(i / w); }
  }
  return {n: n, c: n ? [sx / n, sy / n] : null, w: w, h: h}; }
"""


def _cmd(*extra: str, user_data: str) -> list[str]:
    return [CHROMIUM, *FLAGS, f"--user-data-dir={user_data}", *extra]


def probe(page: str | os.PathLike[str], js: str, *, budget_ms: int = 4000,
          delay_ms: int = 300, timeout: float = 90.0) -> Any:
    """Run `js` (a function body that returns a value; `HELPERS` are in scope) in `page`
    and return its value. Raises AssertionError with Chromium's stderr on failure."""
    text = Path(page).read_text(encoding="utf-8")
    cut = text.rindex("</body>")
    script = _PROBE % (HELPERS + js, delay_ms)
    with tempfile.TemporaryDirectory() as tmp:
        probe_page = Path(tmp) / "probe.html"
        probe_page.write_text(text[:cut] + script + text[cut:], encoding="utf-8")
        out = subprocess.run(
            _cmd(f"--virtual-time-budget={budget_ms}", "--dump-dom",
                 probe_page.as_uri(), user_data=str(Path(tmp) / "profile")),
            capture_output=True, timeout=timeout, text=True)
    m = re.search(r"<title>PROBE(.*?)</title>", out.stdout, re.S)
    if not m:
        raise AssertionError(f"the probe did not report (exit {out.returncode}); "
                             f"stderr tail: {out.stderr[-2000:]}")
    value = json.loads(html.unescape(m.group(1)))
    if isinstance(value, dict) and "error" in value:
        raise AssertionError(f"the probe failed in the page: {value['error']}")
    return value


def screenshot(url: str, png: str | os.PathLike[str], *, budget_ms: int = 3000,
               timeout: float = 90.0) -> Path:
    """Load `url` (a page or a live viewer), let it run `budget_ms` of virtual time, and
    save an 800x600 PNG of the window."""
    with tempfile.TemporaryDirectory() as tmp:
        out = subprocess.run(_cmd(f"--virtual-time-budget={budget_ms}", f"--screenshot={png}",
                                  url, user_data=tmp), capture_output=True, timeout=timeout)
    if not Path(png).is_file():
        raise AssertionError(f"no screenshot (exit {out.returncode}): {out.stderr[-2000:]!r}")
    return Path(png)


def open_url(url: str, user_data: str) -> subprocess.Popen:
    """Start headless Chromium on `url` in its own session (stop it with `close`)."""
    return subprocess.Popen(_cmd("--remote-debugging-port=0", url, user_data=user_data),
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)


def close(proc: subprocess.Popen) -> None:
    """Stop a browser started by `open_url`, with all its helper processes (its group)."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGTERM)
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(10)
