"""``rtlab bench viewer``: the viewer's frames measured headless, through a real WebSocket
client (tornado's) against the real server, for the demo scene (Ex 25) at 1920x1024.

Each frame is a new view (the client orbits a little after each frame, so nothing is refined
or cached) and is acknowledged on arrival, as the page does once it has drawn it. Per frame:
``render`` and ``encode`` are the server's times (its frame header), ``transfer`` runs from the
server handing the frame to the socket to the client holding the whole message (both in this
process, one clock), and ``fps`` is frames over the wall time of the whole run, the client's
orbit message to the ack included: end to end, as the page's panel measures it.
"""

from __future__ import annotations

import asyncio
import json
import struct
import tempfile
import time
from pathlib import Path
from typing import Any

from tracer.scenes import demo_scene_path

WIDTH, HEIGHT = 1920, 1024


async def _frames(port: int, n: int, fmt: str) -> dict[str, Any]:
    from tornado.websocket import websocket_connect

    ws = await websocket_connect(f"ws://127.0.0.1:{port}/ws", max_message_size=64 << 20)
    # As a browser does (Chromium sets TCP_NODELAY on its sockets): without it the ack, written
    # right after the orbit message, waits for the server's delayed ACK of that one, 40 ms.
    ws.protocol.set_nodelay(True)
    await ws.write_message(json.dumps({"type": "settings", "size": [WIDTH, HEIGHT], "format": fmt}))
    render, encode, transfer, sizes = [], [], [], []
    start = None
    wanted = 0
    while len(render) < n:
        m = await ws.read_message()
        received = time.perf_counter()
        if m is None:
            raise RuntimeError("the viewer closed the connection")
        if not isinstance(m, bytes):
            continue
        length = struct.unpack(">I", m[:4])[0]
        h = json.loads(m[4 : 4 + length])
        if h["width"] != WIDTH or h["pass"] != 0:
            await ws.write_message(json.dumps({"type": "ack", "frame": h["frame"]}))
            continue  # the file's size before the settings took, or a refinement pass
        # The next view before the ack, as a page's drag sends it: the server, free once
        # acknowledged, renders that view rather than refining this one.
        if len(render) + 1 < n or not wanted:
            await ws.write_message(json.dumps({"type": "orbit", "yaw": 0.01, "pitch": 0.0}))
        await ws.write_message(json.dumps({"type": "ack", "frame": h["frame"]}))
        if wanted:  # the first full-size frame is a warm-up: the core scene is built for it
            render.append(h["render_ms"])
            encode.append(h["encode_ms"])
            transfer.append(1e3 * (received - h["sent_at"]))
            sizes.append(h["bytes"])
        else:
            start = time.perf_counter()
        wanted += 1
    assert start is not None
    wall = time.perf_counter() - start
    ws.close()
    return {
        "render": render,
        "encode": encode,
        "transfer": transfer,
        "bytes": sizes,
        "fps": n / wall,
    }


def suite_viewer(frames: int = 12, threads: tuple[int, ...] = (1, 2)) -> list[dict[str, Any]]:
    """Rows per thread count and encoding: median render, encode and transfer ms, end-to-end
    fps, and the frame's size in bytes."""
    import statistics

    from tracer.viewer.server import running

    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="rtlab-bench-viewer-") as tmp:
        scene = Path(tmp) / "ex25.toml"
        scene.write_text(demo_scene_path().read_text())
        for n in threads:
            for fmt in ("jpeg", "png"):
                with running(scene, threads=n) as (_, port):
                    got = asyncio.run(_frames(port, frames, fmt))
                case = f"ex25-{WIDTH}x{HEIGHT}-view-{fmt}"
                common = {"case": case, "renderer": "rtlab", "threads": n, "repeats": frames}
                for metric in ("render", "encode", "transfer"):
                    rows.append(
                        {
                            **common,
                            "metric": f"{metric}_ms",
                            "value": statistics.median(got[metric]),
                            "unit": "ms",
                        }
                    )
                rows.append(
                    {
                        **common,
                        "metric": "frame_bytes",
                        "value": statistics.median(got["bytes"]),
                        "unit": "bytes",
                    }
                )
                # last: the bench's "1 -> 2 threads" line reports a case's last metric
                rows.append({**common, "metric": "fps", "value": got["fps"], "unit": "frames/s"})
    return rows
