"""The viewer's web server: tornado serves the page (static/, no request leaves the machine)
and each page's frames over a WebSocket, watches the scene file, and never dies of a bad file
or a failed render: the page shows the error and keeps its last good image.

Frames are binary WebSocket messages: 4 bytes (big-endian) giving the length of a JSON header,
the header (frame number, spp, render and encode times, camera, integrator: session.py
FrameMaker), then the JPEG or PNG. Everything else is JSON text. The page acknowledges each
frame once drawn; the next frame of that view renders only then, so frames never pile up in
the socket, and the time from a render's start to its acknowledgement is the end-to-end frame
time (render + encode + send + decode and draw) the panel's fps is measured from.

Only one render runs at a time, in one worker thread (the core releases the GIL while it
renders, tracer/cpp/bindings.cpp, so the event loop keeps reading messages meanwhile): moves
that arrive are merged into the view's latest state (session.apply), and when the thread is
free the latest state renders, once.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import functools
import json
import struct
import sys
import tempfile
import time
import traceback
from collections import deque
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import tornado.web
import tornado.websocket

from tracer import interrupt
from tracer.render import ImageTooLargeError
from tracer.scene import Mesh, Scene, SceneError, load_scene
from tracer.viewer.session import (
    AOV_MODES,
    FORMATS,
    MODES,
    PRESETS,
    STEREO_MODES,
    FrameMaker,
    MessageError,
    Superseded,
    ViewState,
    apply,
    frame_scene,
    target_passes,
)

STATIC = Path(__file__).resolve().parent / "static"
#: How often the scene file (and the meshes it names) is looked at, seconds.
POLL_SECONDS = 0.25
#: How long a frame waits for the page's acknowledgement before the next renders anyway (a
#: page in a background tab may not draw): the view goes on, more slowly.
ACK_TIMEOUT = 2.0
LOOPBACK = {"127.0.0.1", "localhost", "::1", "[::1]"}


def describe_error(exc: BaseException, where: str) -> dict[str, Any]:
    """An error as the page shows it: a scene's file, key and what was expected, or what
    failed."""
    if isinstance(exc, SceneError):
        return {
            "type": "error",
            "where": where,
            "file": exc.source,
            "key": exc.key,
            "message": exc.message,
            "text": str(exc),
        }
    return {
        "type": "error",
        "where": where,
        "file": "",
        "key": "",
        "message": f"{type(exc).__name__}: {exc}",
        "text": f"{type(exc).__name__}: {exc}",
    }


class Viewer:
    """The server's state: the scene (the last good one), its version, the watch, the pools."""

    def __init__(self, path: str | Path, threads: int | None = None) -> None:
        self.path = Path(path)
        self.scene: Scene = load_scene(self.path)  # a bad file at start: the verb fails
        self.version = 0
        self.error: dict[str, Any] | None = None
        self.threads = threads
        self.sockets: set[FrameSocket] = set()
        self.tasks: set[asyncio.Future[None]] = set()  # the views' render loops
        self.render_pool = ThreadPoolExecutor(1, thread_name_prefix="rtlab-render")
        self.compare_pool = ThreadPoolExecutor(1, thread_name_prefix="rtlab-compare")
        self.load_pool = ThreadPoolExecutor(1, thread_name_prefix="rtlab-load")
        self.renders = 0  # frames rendered, all views together (the tests read it)
        self._stamp = self._stamps()
        self._loading = False

    def _watched(self) -> list[Path]:
        files = [self.path]
        for obj in self.scene.objects:
            if isinstance(obj, Mesh) and obj.file:
                files.append(self.scene.base_dir / obj.file)
        return files

    def _stamps(self) -> dict[Path, tuple[int, int, int] | None]:
        stamps: dict[Path, tuple[int, int, int] | None] = {}
        for f in self._watched():
            try:
                st = f.stat()
                stamps[f] = (st.st_mtime_ns, st.st_size, st.st_ino)
            except OSError:
                stamps[f] = None
        return stamps

    async def poll(self) -> None:
        """Reload the scene when its file or a mesh it names changed."""
        if self._loading:
            return
        stamp = self._stamps()
        if stamp == self._stamp:
            return
        self._stamp = stamp
        self._loading = True
        try:
            loop = asyncio.get_running_loop()
            scene = await loop.run_in_executor(self.load_pool, load_scene, self.path)
        except Exception as exc:  # a bad save: shown, the last good scene kept
            self.error = describe_error(exc, "scene file")
            for s in list(self.sockets):
                s.send_json(self.error)
            return
        finally:
            self._loading = False
        camera_changed = scene.camera != self.scene.camera
        self.scene, self.version, self.error = scene, self.version + 1, None
        self._stamp = self._stamps()  # the meshes the new scene names
        for s in list(self.sockets):
            s.scene_changed(camera_changed)

    def close(self) -> None:
        for pool in (self.render_pool, self.compare_pool, self.load_pool):
            pool.shutdown(wait=False, cancel_futures=True)


def _check_host(handler: tornado.web.RequestHandler) -> None:
    """Refuse a request whose Host is not a loopback name when the server is bound to one: a
    page elsewhere cannot reach the viewer through a DNS name rebound to 127.0.0.1."""
    if handler.settings["loopback"]:
        host = handler.request.host
        name = host.split("]")[0] + "]" if host.startswith("[") else host.rsplit(":", 1)[0]
        if name not in LOOPBACK:
            raise tornado.web.HTTPError(403, f"not a local host: {name}")


class LocalOnly(tornado.web.RequestHandler):
    def prepare(self) -> None:
        _check_host(self)


class PageHandler(LocalOnly):
    def get(self) -> None:
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.set_header("Cache-Control", "no-store")
        # The page may load nothing but its own files and talk to nothing but this server.
        self.set_header(
            "Content-Security-Policy",
            "default-src 'self'; img-src 'self' blob: data:; "
            "connect-src 'self' ws://127.0.0.1:* ws://localhost:*",
        )
        self.write((STATIC / "index.html").read_bytes())


class NoIcon(LocalOnly):
    """The browser asks for /favicon.ico on its own; "no content" keeps its console clean."""

    def get(self) -> None:
        self.set_status(204)


class StaticHandler(tornado.web.StaticFileHandler):
    def prepare(self) -> None:
        _check_host(self)


class FrameSocket(tornado.websocket.WebSocketHandler):
    """One page's view: its state, its frames."""

    def prepare(self) -> None:
        _check_host(self)

    def open(self, *args: str, **kwargs: str) -> None:
        self.viewer: Viewer = self.settings["viewer"]
        self.viewer.sockets.add(self)
        scene = self.viewer.scene
        self.home = ViewState.of(scene)
        self.state = self.home
        self.maker = FrameMaker(self.viewer.threads)
        self.changed = asyncio.Event()
        self.acked = asyncio.Event()
        self.number = 0
        self.closed = False
        self.sent_at: dict[int, float] = {}
        self.started_at: dict[int, float] = {}
        self.e2e: deque[float] = deque(maxlen=5)
        self.comparing = False
        self.superseded = 0  # refinement passes given up for a move (tests read it)
        # Frames and acks are latency, not bandwidth: with Nagle's algorithm a small message
        # written while an earlier one is unacknowledged waits for the peer's delayed ACK
        # (40 ms on Linux), which is a quarter of a 1920x1024 frame's time.
        self.set_nodelay(True)
        self.send_json(self.hello())
        if self.viewer.error is not None:
            self.send_json(self.viewer.error)
        self.changed.set()
        self.task = asyncio.ensure_future(self.run())
        self.viewer.tasks.add(self.task)
        self.task.add_done_callback(self.viewer.tasks.discard)

    def hello(self) -> dict[str, Any]:
        c = self.viewer.scene.camera
        return {
            "type": "hello",
            "scene": str(self.viewer.path),
            "modes": list(MODES),
            "stereo": list(STEREO_MODES),
            "formats": list(FORMATS),
            "sizes": [[c.width, c.height], *[list(p) for p in PRESETS]],
            "state": self.describe(),
        }

    def describe(self) -> dict[str, Any]:
        s = self.state
        return {
            "mode": s.mode,
            "stereo": s.stereo,
            "format": s.format,
            "size": [s.width, s.height],
            "scene_spp": self.viewer.scene.render.spp,
        }

    def send_json(self, message: dict[str, Any]) -> None:
        if not self.closed:
            with contextlib.suppress(tornado.websocket.WebSocketClosedError):
                self.write_message(json.dumps(message))

    def scene_changed(self, camera_changed: bool) -> None:
        """The file was saved and read: re-render; the file's new camera wins over the mouse's
        (the rest of the view, integrator and size and stereo, stays)."""
        new_home = ViewState.of(self.viewer.scene)
        if camera_changed:
            self.state = apply(self.state, {"type": "reset"}, new_home)
        self.home = new_home
        self.send_json({"type": "scene", "version": self.viewer.version, "state": self.describe()})
        self.changed.set()

    def on_message(self, message: str | bytes) -> None:
        try:
            data = json.loads(message)
            if not isinstance(data, dict):
                raise MessageError("a message must be a JSON object")
            kind = data.get("type")
            if kind == "ack":
                self.on_ack(data)
            elif kind == "compare":
                self.start_compare()
            else:
                self.state = apply(self.state, data, self.home)
                if kind == "settings":
                    self.send_json({"type": "settings", "state": self.describe()})
                self.changed.set()
        except (MessageError, json.JSONDecodeError, TypeError) as exc:
            self.send_json(describe_error(exc, "message"))

    def on_ack(self, data: dict[str, Any]) -> None:
        number = data.get("frame")
        if not isinstance(number, int) or number not in self.started_at:
            return
        now = time.perf_counter()
        e2e = now - self.started_at.pop(number)
        self.e2e.append(e2e)
        self.sent_at.pop(number, None)
        fps = len(self.e2e) / sum(self.e2e)
        self.send_json({"type": "stats", "frame": number, "e2e_ms": 1e3 * e2e, "fps": fps})
        if number == self.number:
            self.acked.set()

    async def run(self) -> None:
        """Render this view's latest state whenever it changed, then refine it at rest."""
        loop = asyncio.get_running_loop()
        last_key: Any = None
        last_version = -1
        pass_index = 0
        while not self.closed:
            state, version, scene = self.state, self.viewer.version, self.viewer.scene
            if state.key() != last_key or version != last_version:
                pass_index = 0
            elif pass_index + 1 < target_passes(scene, state):
                pass_index += 1
            else:
                self.changed.clear()
                await self.changed.wait()
                continue
            self.changed.clear()
            self.number += 1
            number = self.number
            self.acked.clear()
            self.started_at[number] = time.perf_counter()
            try:
                frame = await loop.run_in_executor(
                    self.viewer.render_pool,
                    self.maker.make,
                    scene,
                    state,
                    pass_index,
                    number,
                    functools.partial(self.stale, state.key(), version),
                )
            except Superseded:  # a move came during a refinement pass: render the move now
                self.started_at.pop(number, None)
                self.superseded += 1
                continue
            except Exception as exc:  # a render error: shown, the last image kept
                self.started_at.pop(number, None)
                last_key, last_version = state.key(), version
                pass_index = 10**9  # this view renders again only when it changes
                self.send_json(describe_error(exc, "render"))
                if not isinstance(exc, SceneError | ImageTooLargeError | ValueError):
                    traceback.print_exc(file=sys.stderr)
                continue
            self.viewer.renders += 1
            last_key, last_version = state.key(), version
            if self.closed:
                break
            frame.header["scene_version"] = version
            frame.header["sent_at"] = time.perf_counter()  # for the benchmark's transfer time
            head = json.dumps(frame.header).encode()
            try:
                await self.write_message(
                    struct.pack(">I", len(head)) + head + frame.data, binary=True
                )
            except tornado.websocket.WebSocketClosedError:
                break
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.acked.wait(), ACK_TIMEOUT)

    def stale(self, key: tuple[Any, ...], version: int) -> bool:
        """Whether the view rendering as (``key``, scene ``version``) has moved on since."""
        return self.state.key() != key or self.viewer.version != version

    def start_compare(self) -> None:
        if self.comparing:
            self.send_json(
                {"type": "compare", "status": "busy", "message": "a comparison is already running"}
            )
            return
        state, scene = self.state, self.viewer.scene
        if state.mode in AOV_MODES:
            self.send_json(
                {
                    "type": "compare",
                    "status": "error",
                    "message": "an aov channel has no image to compare: choose classic or path",
                }
            )
            return
        self.comparing = True
        self.send_json({"type": "compare", "status": "running"})
        loop = asyncio.get_running_loop()
        future = loop.run_in_executor(
            self.viewer.compare_pool, compare_view, scene, state, self.viewer.threads
        )

        def done(f: asyncio.Future[dict[str, Any]]) -> None:
            self.comparing = False
            try:
                self.send_json(f.result())
            except Exception as exc:
                self.send_json({"type": "compare", "status": "error", "message": str(exc)})

        future.add_done_callback(done)

    def on_close(self) -> None:
        self.closed = True
        self.viewer.sockets.discard(self)
        self.changed.set()
        self.acked.set()


def compare_view(scene: Scene, state: ViewState, threads: int | None) -> dict[str, Any]:
    """rtlab against POV-Ray and Mitsuba for the view's camera (one camera: a pair's stereo is
    left out), in the compare thread: reference/compare.py's metrics and heat maps."""
    import dataclasses

    from reference.compare import _jsonable, compare_scene

    mono = dataclasses.replace(state, stereo="off", interacting=False)
    framed = frame_scene(scene, mono, scene.render.spp, scene.render.seed)
    against = ("povray", "mitsuba") if framed.render.integrator == "classic" else ("mitsuba",)
    with tempfile.TemporaryDirectory(prefix="rtlab-view-compare-") as tmp:
        rows = compare_scene(framed, against, out_dir=tmp, threads=threads, stem="view")
        shown = []
        for r in rows:
            row = {
                k: r.get(k)
                for k in (
                    "renderer",
                    "rmse",
                    "max_abs",
                    "psnr",
                    "ssim",
                    "flip",
                    "over_tolerance",
                    "agrees",
                    "verdict",
                    "trace_seconds",
                )
            }
            if r.get("heat_map"):
                png = Path(r["heat_map"]).read_bytes()
                row["heat_map"] = "data:image/png;base64," + base64.b64encode(png).decode()
            shown.append(row)
    return {
        "type": "compare",
        "status": "done",
        "rows": _jsonable(shown),
        "size": [framed.camera.width, framed.camera.height],
        "camera": {"eye": list(framed.camera.eye), "look_at": list(framed.camera.look_at)},
    }


def make_app(viewer: Viewer, host: str) -> tornado.web.Application:
    return tornado.web.Application(
        [
            (r"/", PageHandler),
            (r"/ws", FrameSocket),
            (r"/favicon.ico", NoIcon),
            (r"/static/(.*)", StaticHandler, {"path": str(STATIC)}),
        ],
        viewer=viewer,
        loopback=host in LOOPBACK,
        websocket_max_message_size=1 << 20,
    )


async def start(viewer: Viewer, host: str, port: int) -> tuple[Any, int, Any]:
    """Listen (port 0: a free one) and watch the scene; returns (server, port, watch)."""
    import tornado.httpserver
    import tornado.ioloop
    import tornado.netutil

    sockets = tornado.netutil.bind_sockets(port, address=host)
    server = tornado.httpserver.HTTPServer(make_app(viewer, host))
    server.add_sockets(sockets)
    bound = sockets[0].getsockname()[1]
    watch = tornado.ioloop.PeriodicCallback(viewer.poll, POLL_SECONDS * 1000)
    watch.start()
    return server, bound, watch


def serve(
    path: str | Path,
    host: str = "127.0.0.1",
    port: int = 8765,
    open_browser: bool = True,
    threads: int | None = None,
) -> None:
    """``rtlab view``: serve until interrupted (Ctrl-C)."""
    viewer = Viewer(path, threads)

    async def main() -> None:
        _, bound, _ = await start(viewer, host, port)
        url = f"http://{'[' + host + ']' if ':' in host else host}:{bound}/"
        print(f"rtlab view: serving {viewer.path} on {url} (Ctrl-C stops)", flush=True)
        if host not in LOOPBACK:
            print(
                f"rtlab view: warning: bound to {host}, not the loopback address: other "
                "machines can reach this viewer",
                file=sys.stderr,
                flush=True,
            )
        if open_browser:
            import webbrowser

            webbrowser.open(url)
        # Ctrl-C raises Interrupted wherever the main thread is (tracer/interrupt.py). Where that
        # is a __del__ or a weakref finaliser (a closed connection's, a frame's), Python prints
        # "Exception ignored" and serves on, and the handler ignores a second Ctrl-C while the
        # first unwinds: the viewer would never stop. So the loop also asks, every POLL_SECONDS,
        # whether a signal came, and raises it again here, where it reaches cmd_view().
        while True:
            await asyncio.sleep(POLL_SECONDS)
            interrupt.raise_if_interrupted()

    try:
        asyncio.run(main())
    finally:
        viewer.close()


@contextlib.contextmanager
def running(
    path: str | Path, host: str = "127.0.0.1", threads: int | None = None
) -> Iterator[tuple[Viewer, int]]:
    """The server on a free port in a thread of this process, with its own event loop, until
    the block ends: what ``rtlab bench viewer`` and the tests drive. Yields (viewer, port)."""
    import threading

    viewer = Viewer(path, threads)
    loop = asyncio.new_event_loop()
    ready: list[Any] = []
    started = threading.Event()

    def run() -> None:
        asyncio.set_event_loop(loop)
        try:
            ready.append(loop.run_until_complete(start(viewer, host, 0)))
        except BaseException as exc:
            ready.append(exc)
            started.set()
            return
        started.set()
        loop.run_forever()
        server, _, watch = ready[0]
        watch.stop()
        server.stop()
        for s in list(viewer.sockets):
            s.close()
        for task in list(viewer.tasks):
            task.cancel()
        loop.run_until_complete(asyncio.sleep(0.05))
        loop.close()

    thread = threading.Thread(target=run, name="rtlab-view-server", daemon=True)
    thread.start()
    started.wait()
    if isinstance(ready[0], BaseException):
        raise ready[0]
    try:
        yield viewer, ready[0][1]
    finally:
        loop.call_soon_threadsafe(loop.stop)
        thread.join(10)
        viewer.close()
