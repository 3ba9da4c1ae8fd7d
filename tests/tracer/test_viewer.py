"""rtlab view without a browser: the camera moves against closed forms, the rule that moves
arriving during a render are merged (never queued), honest frame headers, and bad input (a
broken save, a render that fails, a bad message) that the server survives. The server is the
real one, in a thread of this process, driven by tornado's WebSocket client."""

import asyncio
import json
import math
import struct
import time

import numpy as np
import pytest

from tracer.scenes import demo_scene_path
from tracer.viewer.camera import POLE_MARGIN, View, orbit, pan, walk, zoom
from tracer.viewer.server import running
from tracer.viewer.session import ViewState, apply, to_display

# Each move is a few float64 operations on values of order 10: 1e-12 is far above their
# rounding (1e-15 relative) and far below any real error (a wrong axis moves metres).
TOL = 1e-12


def test_orbit_about_up_is_the_rotation_about_y():
    view = View((1.0, 2.0, 5.0), (0.5, 1.0, -1.0), (0.0, 1.0, 0.0))
    a = 0.7
    got = orbit(view, a, 0.0)
    x, y, z = np.subtract(view.eye, view.look_at)
    # R_y(a): counter-clockwise seen from +y.
    want = np.add(
        view.look_at, [x * math.cos(a) + z * math.sin(a), y, -x * math.sin(a) + z * math.cos(a)]
    )
    assert np.allclose(got.eye, want, atol=TOL, rtol=0)
    assert got.look_at == view.look_at and got.up == view.up
    assert got.distance == pytest.approx(view.distance, abs=TOL)


def _polar_azimuth(view):
    x, y, z = np.subtract(view.eye, view.look_at)
    r = math.sqrt(x * x + y * y + z * z)
    return math.acos(y / r), math.atan2(x, z)


def test_orbit_pitch_changes_the_polar_angle_only_and_stops_short_of_the_pole():
    view = View((0.0, 2.4, 8.0), (0.0, 1.0, 0.0), (0.0, 1.0, 0.0))
    polar, azimuth = _polar_azimuth(view)
    got = orbit(view, 0.0, 0.3)
    new_polar, new_azimuth = _polar_azimuth(got)
    assert new_polar == pytest.approx(polar - 0.3, abs=TOL)  # positive pitch: the eye rises
    assert new_azimuth == pytest.approx(azimuth, abs=TOL)
    assert got.distance == pytest.approx(view.distance, abs=TOL)
    over = orbit(view, 0.0, 10.0)  # far past the pole: clamped
    assert _polar_azimuth(over)[0] == pytest.approx(POLE_MARGIN, abs=TOL)
    under = orbit(view, 0.0, -10.0)
    assert _polar_azimuth(under)[0] == pytest.approx(math.pi - POLE_MARGIN, abs=TOL)


def test_orbit_keeps_the_distance_for_any_up():
    rng = np.random.default_rng(3)
    for _ in range(50):
        eye, look, up = rng.normal(size=(3, 3)) * 4
        view = View(tuple(eye), tuple(look), tuple(up))
        got = orbit(view, *rng.uniform(-3, 3, 2))
        assert got.distance == pytest.approx(view.distance, rel=1e-12)


def test_pan_moves_eye_and_look_at_by_the_image_plane_at_look_at():
    # Looking down -z from 5 units: right = +x, up = +y. At fov 90 the plane through look_at
    # is 2 * 5 * tan(45 deg) = 10 units tall over 100 pixels: 0.1 per pixel.
    view = View((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    got = pan(view, 10.0, 20.0, 90.0, 100)
    # Dragging right moves the camera left (the scene follows the mouse); down (screen y):
    # the camera up.
    assert np.allclose(got.eye, (-1.0, 2.0, 5.0), atol=TOL, rtol=0)
    assert np.allclose(got.look_at, (-1.0, 2.0, 0.0), atol=TOL, rtol=0)
    rng = np.random.default_rng(5)
    for _ in range(20):
        eye, look = rng.normal(size=(2, 3)) * 3
        v = View(tuple(eye), tuple(look), (0.0, 1.0, 0.0))
        p = pan(v, *rng.uniform(-50, 50, 2), 40.0, 240)
        moved = np.subtract(p.eye, v.eye)
        assert np.allclose(np.subtract(p.look_at, v.look_at), moved, atol=TOL)
        assert abs(np.dot(moved, v.basis()[0])) < 1e-9  # within the image plane


def test_zoom_moves_the_eye_along_the_view_direction():
    view = View((1.0, 2.0, 3.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    got = zoom(view, 0.5)
    assert np.allclose(got.eye, (0.5, 1.0, 1.5), atol=TOL, rtol=0)
    assert got.look_at == view.look_at
    assert zoom(view, 1e-9, min_distance=0.1).distance == pytest.approx(0.1, abs=TOL)
    with pytest.raises(ValueError, match="positive"):
        zoom(view, 0.0)


def test_walk_moves_both_along_the_camera_frame():
    view = View((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    got = walk(view, 1.0, 2.0, 3.0)  # forward -z, right +x, up +y
    assert np.allclose(got.eye, (2.0, 3.0, 4.0), atol=TOL, rtol=0)
    assert np.allclose(got.look_at, (2.0, 3.0, -1.0), atol=TOL, rtol=0)


def test_messages_merge_into_one_state():
    """The merge rule on the state itself: thirty small orbits are one orbit of their sum
    (about the same axis), whatever the order they arrive in."""
    from tracer.scene import load_scene

    home = ViewState.of(load_scene(demo_scene_path()))
    state = home
    for _ in range(30):
        state = apply(state, {"type": "orbit", "yaw": 0.01, "pitch": 0.0}, home)
    once = apply(home, {"type": "orbit", "yaw": 0.3, "pitch": 0.0}, home)
    assert np.allclose(state.view.eye, once.view.eye, atol=1e-12, rtol=0)


def test_display_of_colours_is_the_srgb_curve():
    from tracer.image import linear_to_srgb

    x = np.random.default_rng(1).uniform(-0.2, 1.5, (16, 16, 3)).astype(np.float32)
    want = np.round(linear_to_srgb(x) * 255)
    # The table's step (2^-16) moves a value by at most 0.05 of a level (session.py): a
    # rounding may go the other way, never further than one level.
    assert np.max(np.abs(to_display(x, "classic").astype(int) - want)) <= 1


# ------------------------------------------------------------------ the server, in-process


def _scene(tmp_path, width=96, height=64, extra=""):
    text = demo_scene_path().read_text()
    text = text.replace("width = 640", f"width = {width}").replace(
        "height = 480", f"height = {height}"
    )
    path = tmp_path / "scene.toml"
    path.write_text(text + extra)
    return path, text


class Client:
    def __init__(self, ws):
        self.ws = ws
        self.texts = []

    async def send(self, **message):
        await self.ws.write_message(json.dumps(message))

    async def next(self, want, timeout=20.0):
        """The next message (a frame's header, or a JSON text) for which want(m) holds; each
        frame is acknowledged as it arrives, as the page does once it drew it."""
        deadline = time.monotonic() + timeout
        while True:
            m = await asyncio.wait_for(self.ws.read_message(), deadline - time.monotonic())
            assert m is not None, "the server closed the connection"
            if isinstance(m, bytes):
                n = struct.unpack(">I", m[:4])[0]
                h = json.loads(m[4 : 4 + n])
                h["data"] = m[4 + n :]
                await self.send(type="ack", frame=h["frame"])
            else:
                h = json.loads(m)
                self.texts.append(h)
            if want(h):
                return h


def drive(path, script, threads=1):
    from tornado.websocket import websocket_connect

    with running(path, threads=threads) as (viewer, port):

        async def main():
            ws = await websocket_connect(f"ws://127.0.0.1:{port}/ws")
            try:
                return await script(Client(ws), viewer)
            finally:
                ws.close()

        return asyncio.run(main())


def is_frame(h):
    return h.get("type") == "frame"


def test_moves_during_a_render_are_merged_not_queued(tmp_path):
    path, _ = _scene(tmp_path)

    async def script(c, viewer):
        first = await c.next(is_frame)
        home = View(*(tuple(first["camera"][k]) for k in ("eye", "look_at", "up")))
        # Acknowledged: the server starts the next pass (a refinement) at once; thirty moves
        # arrive while it renders.
        for _ in range(30):
            await c.send(type="orbit", yaw=0.01, pitch=0.0)
        want = orbit(home, 0.3, 0.0)
        seen = []
        while True:
            h = await c.next(is_frame)
            seen.append(h)
            if np.allclose(h["camera"]["eye"], want.eye, atol=1e-9):
                break
            assert len(seen) < 4, f"moves were queued: {[s['camera']['eye'] for s in seen]}"
        return seen

    seen = drive(path, script)
    # At most the refinement pass already running, then one frame of all thirty moves.
    assert len(seen) <= 2
    assert seen[-1]["pass"] == 0


def test_frames_state_their_spp_and_times(tmp_path):
    path, _ = _scene(tmp_path, extra="")

    async def script(c, viewer):
        await c.send(type="settings", mode="path")
        frames = []
        while len(frames) < 3:
            h = await c.next(is_frame)
            if h["mode"] == "path":
                frames.append(h)
        stats = await c.next(lambda m: m.get("type") == "stats")
        return frames, stats

    frames, stats = drive(path, script)
    # Path passes of the scene's 1 spp, averaged: the image shown holds pass + 1 samples.
    assert [f["pass"] for f in frames] == [0, 1, 2]
    assert [f["spp"] for f in frames] == [1, 2, 3]
    for f in frames:
        assert (f["width"], f["height"]) == (96, 64)
        assert f["integrator"].startswith("path")
        assert f["render_ms"] > 0 and f["encode_ms"] > 0 and f["rays"] >= 96 * 64
        assert f["data"][:3] == b"\xff\xd8\xff"  # a JPEG
    assert stats["e2e_ms"] > 0 and stats["fps"] > 0
    # Successive passes differ (new seeds), so refinement is real.
    assert frames[0]["data"] != frames[1]["data"]


def test_a_broken_save_shows_its_error_and_keeps_the_scene(tmp_path):
    path, text = _scene(tmp_path)

    async def script(c, viewer):
        await c.next(is_frame)
        renders = viewer.renders
        path.write_text(text.replace("fov_y = 40.0", 'fov_y = "wide"'))
        error = await c.next(lambda m: m.get("type") == "error")
        assert viewer.scene.camera.fov_y == 40.0  # the last good scene kept
        # Fixed: the viewer renders the new scene.
        path.write_text(text.replace("fov_y = 40.0", "fov_y = 30.0"))
        await c.next(lambda m: m.get("type") == "scene")
        again = await c.next(lambda m: is_frame(m) and m["scene_version"] == 1)
        return error, renders, again

    error, _, again = drive(path, script)
    assert error["where"] == "scene file"
    assert error["file"] == str(path) and error["key"] == "camera.fov_y"
    assert "number" in error["message"]
    assert again["camera"]["fov_y"] == 30.0  # the file's camera changed: the view follows it


def test_a_failed_render_and_bad_messages_leave_the_server_running(tmp_path):
    path, _ = _scene(tmp_path)

    async def script(c, viewer):
        await c.next(is_frame)
        # The core refuses an anaglyph of aov channels (they are no colours): a render error.
        await c.send(type="settings", mode="depth", stereo="anaglyph")
        render_error = await c.next(lambda m: m.get("type") == "error")
        await c.send(type="zoom", factor="near")
        message_error = await c.next(lambda m: m.get("type") == "error")
        await c.send(type="settings", size=[123, 45])
        size_error = await c.next(lambda m: m.get("type") == "error")
        await c.send(type="settings", stereo="side_by_side")
        pair = await c.next(lambda m: is_frame(m) and m["stereo"] == "side_by_side")
        return render_error, message_error, size_error, pair

    render_error, message_error, size_error, pair = drive(path, script)
    assert render_error["where"] == "render" and render_error["key"] == "camera.stereo.layout"
    assert "factor must be a finite number" in message_error["message"]
    assert "size must be one of 96x64" in size_error["message"]
    assert (pair["width"], pair["height"], pair["mode"]) == (96, 64, "depth")


def test_compare_renders_the_references_for_the_current_camera(tmp_path):
    path, _ = _scene(tmp_path, width=64, height=48)

    async def script(c, viewer):
        await c.next(is_frame)
        await c.send(type="orbit", yaw=0.4, pitch=0.1)
        moved = await c.next(lambda m: is_frame(m) and m["pass"] == 0 and m["frame"] > 1)
        await c.send(type="compare")
        running = await c.next(lambda m: m.get("type") == "compare")
        done = await c.next(lambda m: m.get("type") == "compare", timeout=120)
        return moved, running, done

    moved, running, done = drive(path, script, threads=2)
    assert running["status"] == "running"
    assert done["status"] == "done", done
    rows = {r["renderer"]: r for r in done["rows"]}
    assert set(rows) >= {"rtlab", "povray"} and any(k.startswith("mitsuba") for k in rows)
    for name, r in rows.items():
        if name != "rtlab":
            # The classic model at 1 spp: the references agree with rtlab for this camera.
            assert r["agrees"] is True, r["verdict"]
            assert r["heat_map"].startswith("data:image/png;base64,")
    assert done["size"] == [64, 48]
    assert done["camera"]["eye"] == moved["camera"]["eye"]  # the view's camera, not the file's


def test_a_stale_refinement_pass_is_given_up_and_a_first_pass_never(tmp_path):
    """The core cancels a render whose progress callback raises (bindings.cpp render()); the
    viewer's callback raises once the view has moved on, for refinement passes only."""
    from tracer.scene import load_scene
    from tracer.viewer.session import FrameMaker, Superseded

    path, _ = _scene(tmp_path)
    scene = load_scene(path)
    state = ViewState.of(scene)
    maker = FrameMaker(threads=1)
    asked = []

    def stale():
        asked.append(True)
        return True

    first = maker.make(scene, state, 0, 1, stale)  # a new view's first pass always finishes
    assert first.header["pass"] == 0 and not asked
    with pytest.raises(Superseded):
        maker.make(scene, state, 1, 2, stale)
    assert asked
    # Not stale: the pass renders (classic's first jittered pass starts the average afresh: its
    # 4 samples replace the pixel centres); a stale pass after it leaves no samples behind.
    assert maker.make(scene, state, 1, 3, lambda: False).header["spp"] == 4
    with pytest.raises(Superseded):
        maker.make(scene, state, 2, 4, stale)
    assert maker.make(scene, state, 2, 5, lambda: False).header["spp"] == 8


# ------------------------------------------------------------------ `rtlab view`, a process

# `rtlab view` as the CLI runs it, but with one thing added: half a second after it starts
# serving, the main thread drops an object whose __del__ receives SIGINT. The handler raises
# Interrupted inside __del__, where Python prints "Exception ignored" and goes on: the way a real
# Ctrl-C is lost when it lands in a closed connection's or a frame's finaliser.
LOSES_THE_FIRST_INTERRUPT = """
import asyncio, signal, sys, time
import tracer.viewer.server as server

class LosesTheInterrupt:
    def __del__(self):
        signal.raise_signal(signal.SIGINT)
        deadline = time.monotonic() + 2
        while time.monotonic() < deadline:  # bytecode runs: the handler raises in here
            pass

original = server.start

async def start(*args, **kwargs):
    got = await original(*args, **kwargs)
    asyncio.get_running_loop().call_later(0.5, LosesTheInterrupt)  # made and dropped at once
    return got

server.start = start
from tracer.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_a_ctrl_c_lost_in_a_finaliser_still_stops_the_viewer(tmp_path):
    import subprocess
    import sys

    path, _ = _scene(tmp_path)
    script = tmp_path / "view.py"
    script.write_text(LOSES_THE_FIRST_INTERRUPT)
    proc = subprocess.Popen(
        [sys.executable, str(script), "view", str(path), "--port", "0", "--no-browser"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        out, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        pytest.fail(f"the viewer did not stop after its lost Ctrl-C; stderr:\n{err[-3000:]}")
    # The interrupt was lost as intended: raised inside __del__ and ignored there.
    assert "Exception ignored" in err and "Interrupted" in err, err
    assert "rtlab view: serving" in out
    assert proc.returncode == 0, err  # Ctrl-C is how a viewer stops
    assert "rtlab view: stopped" in err
