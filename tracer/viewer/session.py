"""One browser view's frames: what it asks for (ViewState), how a frame is rendered, refined
and encoded (FrameMaker, run in the render thread), and the rule that only the latest state is
ever rendered (merge, never queue).

Progressive refinement (render_progressive's seeding: pass k of a view renders with the seed
(seed * 1_000_003 + k) mod 2^64, so a given number of passes gives the same image anywhere):
at rest, passes are averaged until the view's target is reached. The classic model at 1 spp
samples the pixel centres (tracer/cpp/11_render.h) and is deterministic: averaging such passes
adds nothing, so its refinement passes take ANTIALIAS_SPP jittered, stratified samples each and
replace the centre-sampled first frame once the first of them is done. While the mouse drags,
frames render at half width and height (a quarter of the rays) and are not refined.
"""

from __future__ import annotations

import dataclasses
import io
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from tracer.display import AOV_VIEWS, aov_view
from tracer.render import (
    RenderResult,
    _render_core,
    _set_camera,
    _set_render,
    default_threads,
    pass_seed,
)
from tracer.render import to_core as _to_core
from tracer.scene import Scene, Stereo
from tracer.viewer.camera import View, orbit, pan, walk, zoom

#: What the integrator toggle offers: the two image integrators and the aov channels, each
#: shown as an image (depth as grey, near bright; object ids as colours; normals as 0.5 + N/2).
MODES = ("classic", "path", "depth", "object_id", "normal")
AOV_MODES = ("depth", "object_id", "normal")
STEREO_MODES = ("off", "anaglyph", "side_by_side")
FORMATS = ("jpeg", "png")
#: The resolution presets (the lecture's interactive figure is 1920x1024), besides the file's.
PRESETS = ((480, 256), (960, 512), (1440, 768), (1920, 1024))
#: Samples per pixel of a classic refinement pass when the scene asks for 1: a 2x2 grid of
#: jittered strata (11_render.h), the antialiasing the lecture's supersampling slide shows.
ANTIALIAS_SPP = 4
#: Refinement stops after this many passes (classic) or samples per pixel (path): beyond, a
#: viewer's image changes by less than one 8-bit level where it does not already look done.
CLASSIC_PASSES = 16
PATH_SPP = 1024
#: Without a stereo pair in the file, the toggle's pair: convergence at look_at and an eye
#: separation of a thirtieth of it (the stereographers' "1/30 rule" for comfortable depth).
SEPARATION_SHARE = 1 / 30
JPEG_QUALITY = 90

# The sRGB transfer function (tracer/image.py linear_to_srgb, IEC 61966-2-1) tabulated on 2^16
# steps of [0, 1]: its steepest slope, 12.92 near 0, makes one step 12.92 * 255 / 65535 = 0.05
# of an 8-bit level, below the rounding to 8 bits.
_LUT_STEPS = 65535
_x = np.linspace(0.0, 1.0, _LUT_STEPS + 1)
_SRGB_LUT = np.round(
    255 * np.where(_x <= 0.0031308, 12.92 * _x, 1.055 * np.power(_x, 1 / 2.4) - 0.055)
).astype(np.uint8)
del _x


@dataclass(frozen=True)
class ViewState:
    """Everything a frame depends on but the scene: merged from the page's messages."""

    view: View
    fov_y: float
    width: int
    height: int
    mode: str = "classic"
    stereo: str = "off"
    format: str = "jpeg"
    interacting: bool = False

    @classmethod
    def of(cls, scene: Scene, **changes: Any) -> ViewState:
        c = scene.camera
        mode = scene.render.integrator if scene.render.integrator != "aov" else "depth"
        stereo = c.stereo.layout if c.stereo is not None else "off"
        state = cls(
            View(c.eye, c.look_at, c.up),
            c.fov_y,
            c.width,
            c.height,
            mode,
            stereo if stereo in STEREO_MODES else "side_by_side",
        )
        return dataclasses.replace(state, **changes)

    def key(self) -> tuple[Any, ...]:
        """What makes a new frame."""
        return (
            self.view,
            self.fov_y,
            self.width,
            self.height,
            self.mode,
            self.stereo,
            self.format,
            self.interacting,
        )


class MessageError(ValueError):
    """A message from the page the viewer cannot apply: answered with an error, never fatal."""


def _number(message: dict[str, Any], key: str, default: float = 0.0) -> float:
    value = message.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise MessageError(f"{message.get('type')}: {key} must be a finite number, got {value!r}")
    return float(value)


def apply(state: ViewState, message: dict[str, Any], home: ViewState) -> ViewState:
    """The state after one message from the page. Messages are merged into the state as they
    arrive, so moves made while a frame renders all count, and only the latest state renders.
    ``home`` is the scene file's view (``reset``)."""
    kind = message.get("type")
    if kind == "orbit":
        return dataclasses.replace(
            state, view=orbit(state.view, _number(message, "yaw"), _number(message, "pitch"))
        )
    if kind == "pan":
        dx, dy = _number(message, "dx"), _number(message, "dy")
        return dataclasses.replace(state, view=pan(state.view, dx, dy, state.fov_y, state.height))
    if kind == "zoom":
        factor = _number(message, "factor", 1.0)
        if not 0.01 <= factor <= 100:
            raise MessageError(f"zoom: factor must be in [0.01, 100], got {factor}")
        floor = home.view.distance * 1e-3  # never through look_at
        return dataclasses.replace(state, view=zoom(state.view, factor, floor))
    if kind == "walk":
        # Steps are in shares of the distance to look_at: the same keys suit any scene's size.
        step = state.view.distance
        moved = walk(
            state.view,
            step * _number(message, "forward"),
            step * _number(message, "right"),
            step * _number(message, "lift"),
        )
        return dataclasses.replace(state, view=moved)
    if kind == "interact":
        return dataclasses.replace(state, interacting=bool(message.get("active")))
    if kind == "reset":
        return dataclasses.replace(
            home,
            mode=state.mode,
            stereo=state.stereo,
            format=state.format,
            width=state.width,
            height=state.height,
        )
    if kind == "settings":
        changes: dict[str, Any] = {}
        for key, choices in (("mode", MODES), ("stereo", STEREO_MODES), ("format", FORMATS)):
            if key in message:
                if message[key] not in choices:
                    raise MessageError(
                        f"settings: {key} must be one of {', '.join(choices)}, got {message[key]!r}"
                    )
                changes[key] = message[key]
        if "size" in message:
            allowed = [(home.width, home.height), *PRESETS]
            size = tuple(message["size"]) if isinstance(message["size"], list) else None
            if size not in allowed:
                raise MessageError(
                    f"settings: size must be one of {', '.join(f'{w}x{h}' for w, h in allowed)},"
                    f" got {message['size']!r}"
                )
            changes["width"], changes["height"] = size
        return dataclasses.replace(state, **changes)
    raise MessageError(f"unknown message type {kind!r}")


def frame_scene(scene: Scene, state: ViewState, spp: int, seed: int) -> Scene:
    """The scene as this view renders it: its camera moved, sized, paired or not."""
    c = scene.camera
    width, height = state.width, state.height
    if state.interacting:
        width, height = max(1, width // 2), max(1, height // 2)
    stereo = None
    if state.stereo != "off":
        if c.stereo is not None:
            separation, convergence = c.stereo.eye_separation, c.stereo.convergence
        else:
            convergence = state.view.distance
            separation = convergence * SEPARATION_SHARE
        stereo = Stereo(separation, convergence, state.stereo)
        if state.stereo == "side_by_side":  # the pair fills the chosen size: each eye half
            width = max(1, width // 2)
    camera = dataclasses.replace(
        c,
        eye=state.view.eye,
        look_at=state.view.look_at,
        up=state.view.up,
        width=width,
        height=height,
        stereo=stereo,
    )
    integrator = "aov" if state.mode in AOV_MODES else state.mode
    render = dataclasses.replace(scene.render, integrator=integrator, spp=spp, seed=seed)
    return dataclasses.replace(scene, camera=camera, render=render)


def to_display(image: npt.NDArray[np.float32], mode: str) -> npt.NDArray[np.uint8]:
    """8-bit sRGB for the page: colours through the sRGB curve (clipped to [0, 1]) by a table,
    24 ms for a 1920x1024 frame where tracer/display.py tone_map's float64 powers take 0.8 s
    (one run each on a loaded machine; the notebook's exact bytes are not needed here); an aov
    channel as the notebook shows it (tracer/display.py aov_view)."""
    if mode in ("classic", "path"):
        index = (np.clip(image, 0.0, 1.0) * _LUT_STEPS + 0.5).astype(np.uint16)
        return _SRGB_LUT[index]
    if mode in AOV_VIEWS:
        return aov_view(image, mode)
    raise ValueError(f"unknown mode {mode!r}")


def encode(pixels: npt.NDArray[np.uint8], fmt: str) -> bytes:
    from PIL import Image

    out = io.BytesIO()
    if fmt == "png":
        Image.fromarray(pixels, mode="RGB").save(out, format="PNG", compress_level=1)
    else:
        Image.fromarray(pixels, mode="RGB").save(out, format="JPEG", quality=JPEG_QUALITY)
    return out.getvalue()


def target_passes(scene: Scene, state: ViewState) -> int:
    """How many passes a view at rest is refined to (the first included)."""
    if state.interacting or state.mode in AOV_MODES:
        return 1
    if state.mode == "path":
        return max(1, PATH_SPP // scene.render.spp)
    return 1 + CLASSIC_PASSES  # the centre-sampled (or scene-spp) frame, then jittered passes


class Superseded(Exception):
    """A refinement pass given up because the view it refines has changed."""


@dataclass
class Frame:
    header: dict[str, Any]
    data: bytes


class FrameMaker:
    """Renders and encodes one view's frames, in the render thread. It keeps the core scene of
    the scene version it last built (its meshes' hierarchies are built once per version, not
    per frame) and the view's running sum of passes."""

    def __init__(self, threads: int | None = None) -> None:
        self.threads = threads or default_threads()
        self._core: Any = None
        self._core_of: Scene | None = None
        self._first: npt.NDArray[np.float32] | None = None
        self._sum: npt.NDArray[np.float64] | None = None
        self._summed = 0  # passes in _sum
        self._rays: dict[str, int] = {}
        self._spp = 0

    def make(
        self,
        scene: Scene,
        state: ViewState,
        pass_index: int,
        number: int,
        stale: Callable[[], bool] | None = None,
    ) -> Frame:
        """Pass ``pass_index`` of the view ``state`` (0: a new view; the running sum restarts).
        A refinement pass (``pass_index`` > 0) is given up, raising :class:`Superseded`, as soon
        as ``stale()`` says the view has moved on: at 1920x1024 a pass takes a quarter second,
        which a move would otherwise wait out. A new view's first pass always finishes, or a
        steady drag would never show a frame."""
        base_spp = scene.render.spp
        classic_refine = state.mode == "classic" and pass_index > 0
        spp = ANTIALIAS_SPP if classic_refine and base_spp == 1 else base_spp
        if state.interacting:
            spp = 1
        seed = pass_seed(scene.render.seed, pass_index)
        framed = frame_scene(scene, state, spp, seed)
        start = time.perf_counter()
        if self._core_of is not scene:
            self._core, self._core_of = _to_core(framed), scene
        eyes = framed.camera.stereo
        _set_camera(self._core, framed, "left" if eyes is not None else None)
        _set_render(self._core, framed)
        progress: Callable[[int, int], None] | bool = False
        if stale is not None and pass_index > 0:

            def progress(done: int, total: int) -> None:
                if stale():
                    raise Superseded

        result: RenderResult = _render_core(framed, self._core, self.threads, progress, True)
        render_s = time.perf_counter() - start
        # "encode" is everything between the render and the bytes: averaging the passes, the
        # display curve, compressing.
        start = time.perf_counter()
        image = result.image
        first_jittered = classic_refine and pass_index == 1 and base_spp == 1
        if pass_index == 0 or first_jittered:
            self._first, self._sum, self._summed, self._rays, self._spp = None, None, 0, {}, 0
        if state.mode in ("classic", "path") and target_passes(scene, state) > 1:
            # The first pass is shown as it is and kept; the float64 sum starts with the second.
            if self._summed == 0:
                self._first = image
            elif self._sum is None:
                assert self._first is not None
                self._sum = self._first.astype(np.float64) + image
            else:
                self._sum += image
            self._summed += 1
            if self._sum is not None:
                image = (self._sum / self._summed).astype(np.float32)
        for k, v in result.rays.items():
            self._rays[k] = self._rays.get(k, 0) + v
        self._spp += spp
        data = encode(to_display(image, state.mode), state.format)
        encode_s = time.perf_counter() - start
        rays = sum(result.rays.get(k, 0) for k in ("primary", "secondary", "shadow"))
        target = target_passes(scene, state)
        header = {
            "type": "frame",
            "frame": number,
            "format": state.format,
            "width": int(image.shape[1]),
            "height": int(image.shape[0]),
            "mode": state.mode,
            "integrator": result.integrator,
            "stereo": state.stereo,
            "interacting": state.interacting,
            "pass": pass_index,
            "passes": target,
            "converged": pass_index + 1 >= target,
            "spp": self._spp,  # samples per pixel in the image shown (the passes averaged)
            "pass_spp": spp,
            "render_ms": 1e3 * render_s,
            "encode_ms": 1e3 * encode_s,
            "rays": rays,
            "rays_per_s": rays / render_s if render_s > 0 else 0.0,
            "threads": result.threads,
            "camera": {
                "eye": list(state.view.eye),
                "look_at": list(state.view.look_at),
                "up": list(state.view.up),
                "fov_y": state.fov_y,
            },
            "bytes": len(data),
        }
        return Frame(header, data)
