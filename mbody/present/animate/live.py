"""The live viewer: meshcat's server in a child process, bound to 127.0.0.1 only.

`LiveViewer` starts it, pushes commands to it over ZMQ (packed by `wire.pack`, so
keyframes travel as Float32Arrays here too: the server stores and forwards the bytes
as they are), and stops it cleanly; the server also stops by itself when its parent
process goes away.
"""

from __future__ import annotations

import contextlib
import os
import selectors
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from typing import TYPE_CHECKING, Any

from mbody.errors import MbodyError
from mbody.present.animate.scene import Scene
from mbody.present.animate.wire import pack

if TYPE_CHECKING:
    import zmq

HOST = "127.0.0.1"


def _serve(parent_pid: int) -> None:  # pragma: no cover - runs in the server process
    """meshcat's ZMQ/websocket bridge, listening on 127.0.0.1 only.

    meshcat 0.3.2 calls ``app.listen(port)``, which binds every interface; the app's
    `listen` is wrapped to pass the loopback address. The server stops when its parent
    goes away (so a killed mbody leaves nothing behind) and ignores Ctrl-C, which the
    parent handles by terminating it.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        import tornado.ioloop
        from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class LoopbackBridge(ZMQWebSocketBridge):
        def make_app(self):
            app = super().make_app()
            listen = app.listen
            app.listen = lambda port, **kw: listen(port, address=HOST, **kw)
            return app

    bridge = LoopbackBridge(host=HOST)
    print(f"zmq_url={bridge.zmq_url}")
    print(f"web_url={bridge.web_url}", flush=True)

    def orphaned() -> None:
        if os.getppid() != parent_pid:
            tornado.ioloop.IOLoop.current().stop()

    tornado.ioloop.PeriodicCallback(orphaned, 500).start()
    bridge.run()


class LiveViewer:
    """meshcat's live viewer on 127.0.0.1, in its own server process; a context manager.

        with LiveViewer() as v:
            print(v.url); v.show(scene)        # browsers that connect later get the scene

    `close()` terminates and reaps the server, closes its pipes and the ZMQ socket.
    """

    def __init__(self, *, timeout: float = 15.0):
        import zmq

        self._stderr = tempfile.TemporaryFile()  # noqa: SIM115 - closed in close()
        self.proc: subprocess.Popen | None = subprocess.Popen(
            [sys.executable, "-u", "-c",
             f"from mbody.present.animate.live import _serve; _serve({os.getpid()})"],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=self._stderr)
        self._ctx: zmq.Context[zmq.Socket[bytes]] | None = zmq.Context()
        self._sock: zmq.Socket[bytes] | None = None
        self.timeout = timeout
        try:
            urls = self._read_urls(timeout)
            self.zmq_url, self.url = urls["zmq_url"], urls["web_url"]
            self._connect()
        except BaseException:
            self.close()
            raise

    @property
    def pid(self) -> int | None:
        return self.proc.pid if self.proc else None

    def _read_urls(self, timeout: float) -> dict[str, str]:
        assert self.proc is not None and self.proc.stdout is not None
        out, urls = b"", {}
        deadline = time.monotonic() + timeout
        with selectors.DefaultSelector() as sel:
            sel.register(self.proc.stdout, selectors.EVENT_READ)
            while "web_url" not in urls:
                left = deadline - time.monotonic()
                if left <= 0 or not sel.select(left):
                    raise MbodyError(f"the meshcat server did not start within {timeout:g} s"
                                     + self._server_log())
                chunk = os.read(self.proc.stdout.fileno(), 4096)
                if not chunk:
                    raise MbodyError("the meshcat server exited while starting"
                                     + self._server_log())
                out += chunk
                for line in out.decode("utf-8", "replace").split("\n")[:-1]:  # whole lines
                    key, sep, value = line.partition("=")
                    if sep and key in ("zmq_url", "web_url"):
                        urls[key] = value.strip()
        return urls

    def _server_log(self) -> str:
        self._stderr.seek(0)
        text = self._stderr.read().decode("utf-8", "replace").strip()
        return f": {text.splitlines()[-1]}" if text else ""

    def _connect(self) -> None:
        import zmq

        if self._sock is not None:
            self._sock.close(linger=0)
        if self._ctx is None:
            raise MbodyError("the live viewer is closed")
        sock = self._ctx.socket(zmq.REQ)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.SNDTIMEO, int(self.timeout * 1000))
        sock.connect(self.zmq_url)
        self._sock = sock

    def _request(self, frames: list[bytes], timeout: float | None = None) -> bytes | None:
        """One REQ/REP exchange; None on timeout (the socket is then replaced: a REQ
        socket that missed its reply cannot send again)."""
        import zmq

        if self._sock is None:
            raise MbodyError("the live viewer is closed")
        self._sock.send_multipart(frames)
        wait = self.timeout if timeout is None else timeout
        if self._sock.poll(int(wait * 1000), zmq.POLLIN):
            return self._sock.recv()
        self._connect()
        return None

    def send(self, command: dict[str, Any]) -> None:
        """Send one lowered meshcat command (as built by `build_scene`)."""
        reply = self._request([command["type"].encode(), command["path"].encode(),
                               pack(command)])
        if reply is None:
            raise MbodyError(f"the meshcat server did not answer within {self.timeout:g} s")

    def show(self, scene: Scene) -> None:
        """Push a whole scene (objects, transforms and the animation)."""
        for command in scene.commands:
            self.send(command)

    def wait_for_browser(self, timeout: float = 10.0) -> bool:
        """True once a browser is connected (False after `timeout` s)."""
        return self._request([b"wait"], timeout) is not None

    def close(self) -> None:
        """Stop the server and release everything; safe to call twice. (meshcat 0.3.2's
        own `Visualizer.close()` raises, and its server would outlive a killed parent.)"""
        if self._sock is not None:
            self._sock.close(linger=0)
            self._sock = None
        if self._ctx is not None:  # destroy: whatever socket is left closes unsent first
            self._ctx.destroy(linger=0)
            self._ctx = None
        if self.proc is not None:
            proc, self.proc = self.proc, None
            proc.terminate()
            try:
                proc.wait(5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(5)
            if proc.stdout:
                proc.stdout.close()
        if not self._stderr.closed:
            self._stderr.close()

    def __enter__(self) -> LiveViewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()

