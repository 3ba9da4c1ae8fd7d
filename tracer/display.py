"""Images for a person to look at: the tracer's linear radiance tone-mapped to 8-bit sRGB, shown
inline in Jupyter (IPython calls ``_repr_png_``) or in the desktop's image viewer elsewhere.

The tracer's images are linear: a value is proportional to radiance and may exceed 1 (a
highlight, a light seen directly). A screen wants 8-bit sRGB. Two tone maps are offered:

- ``"clip"``: scale by 2^exposure, clip to [0, 1], encode as sRGB. It is what a PNG written by
  ``tracer.save_image`` holds (at exposure 0 the bytes are the same), so what a student sees
  inline is what the grader's PNGs show.
- ``"reinhard"``: Reinhard et al. 2002, "Photographic Tone Reproduction for Digital Images",
  eq. 3, on the luminance: each pixel's colour is scaled by 1 / (1 + Y) with Y its Rec. 709
  luminance (after the exposure), so no highlight clips and hues stay. Use it for path-traced
  images with bright lights in view.

An aov render has no colour; one of its channels is shown: ``"normal"`` (N mapped from
[-1, 1] to [0, 1] per axis, the usual normal-map colours), ``"depth"`` (near is bright, scaled
by the largest finite depth) or ``"object_id"`` (one colour per object, misses black).
"""

from __future__ import annotations

import io
import sys
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from tracer.image import linear_to_srgb

if TYPE_CHECKING:
    from tracer.render import RenderResult

TONE_MAPS = ("clip", "reinhard")
AOV_VIEWS = ("normal", "depth", "object_id")

# Rec. 709 / sRGB luminance weights (ITU-R BT.709-6, item 3.3): the primaries the tracer's RGB
# is meant in, as POV-Ray and Mitsuba's rgb variants read them.
_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


class Picture:
    """An 8-bit sRGB image of shape (height, width, 3) ready to be looked at: Jupyter shows it
    inline (``_repr_png_``); ``png()`` gives the bytes of a PNG file."""

    def __init__(self, pixels: npt.NDArray[np.uint8], title: str = "") -> None:
        if pixels.dtype != np.uint8 or pixels.ndim != 3 or pixels.shape[2] != 3:
            raise ValueError(
                f"a Picture is uint8 of shape (height, width, 3), got {pixels.dtype} {pixels.shape}"
            )
        self.pixels = pixels
        self.title = title

    @property
    def size(self) -> tuple[int, int]:
        """(width, height), as image files and browsers give sizes."""
        return self.pixels.shape[1], self.pixels.shape[0]

    def png(self) -> bytes:
        from PIL import Image

        buffer = io.BytesIO()
        Image.fromarray(self.pixels, mode="RGB").save(buffer, format="PNG")
        return buffer.getvalue()

    def _repr_png_(self) -> bytes:
        return self.png()

    def __repr__(self) -> str:
        width, height = self.size
        title = f" {self.title}" if self.title else ""
        return f"<Picture{title} {width}x{height}>"


def _check_choice(name: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")


def tone_map(
    image: npt.ArrayLike, *, tone: str = "clip", exposure: float = 0.0
) -> npt.NDArray[np.uint8]:
    """Linear RGB of shape (height, width, 3) to 8-bit sRGB (see the module's text). Values that
    are not finite or are negative (none should be; a student's tracer may make them) show
    black, so one bad pixel cannot spoil the picture."""
    _check_choice("tone", tone, TONE_MAPS)
    rgb = np.asarray(image, dtype=np.float64)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"expected an image of shape (height, width, 3), got {rgb.shape}")
    rgb = np.where(np.isfinite(rgb) & (rgb > 0.0), rgb, 0.0) * 2.0**exposure
    if tone == "reinhard":
        rgb = rgb / (1.0 + rgb @ _LUMINANCE)[..., None]
    encoded = linear_to_srgb(np.clip(rgb, 0.0, 1.0))
    return np.round(encoded * 255.0).astype(np.uint8)


def aov_view(image: npt.ArrayLike, channel: str = "normal") -> npt.NDArray[np.uint8]:
    """One channel of an aov render (tracer.render.AOV_CHANNELS) as colours (the notebook's and
    ``rtlab view``'s)."""
    _check_choice("channel", channel, AOV_VIEWS)
    aov = np.asarray(image, dtype=np.float64)
    if aov.ndim != 3 or aov.shape[2] != 5:
        raise ValueError(f"expected an aov image of shape (height, width, 5), got {aov.shape}")
    hit = aov[..., 1] >= 0  # object_id is -1 on a miss
    if channel == "normal":
        colours = np.where(hit[..., None], (aov[..., 2:5] + 1.0) / 2.0, 0.0)
        return np.round(np.clip(colours, 0.0, 1.0) * 255.0).astype(np.uint8)
    if channel == "depth":  # the nearest hit white, the farthest 20% grey, a miss black
        depth = aov[..., 0]
        finite = hit & np.isfinite(depth)
        grey = np.zeros(depth.shape)
        if finite.any():
            near, far = float(depth[finite].min()), float(depth[finite].max())
            grey[finite] = 1.0 - 0.8 * (depth[finite] - near) / max(far - near, 1e-12)
        return np.repeat(np.round(grey * 255.0).astype(np.uint8)[..., None], 3, axis=2)
    # A hue per object, stepped by the golden ratio's fraction of the circle, so that any two
    # neighbouring indices (and any number of objects) look apart.
    ids = np.where(hit, aov[..., 1], 0).astype(np.int64)
    hue = (ids * 0.6180339887) % 1.0
    rgb = 0.55 + 0.45 * np.cos(2 * np.pi * (hue[..., None] + np.array([0.0, 1 / 3, 2 / 3])))
    return np.where(hit[..., None], np.round(rgb * 255.0), 0).astype(np.uint8)


def picture(
    image: npt.ArrayLike | RenderResult,
    *,
    tone: str = "clip",
    exposure: float = 0.0,
    channel: str = "normal",
) -> Picture:
    """A render (an array from ``tracer.render``, or a ``RenderResult``) as a Picture: a colour
    image tone-mapped, an aov render's ``channel`` shown."""
    from tracer.render import RenderResult

    title = ""
    if isinstance(image, RenderResult):
        title = image.integrator
        image = image.image
    array = np.asarray(image)
    if array.ndim == 3 and array.shape[2] == 5:
        return Picture(aov_view(array, channel), title or f"aov {channel}")
    return Picture(tone_map(array, tone=tone, exposure=exposure), title)


def _in_kernel() -> bool:
    """Whether this process is a Jupyter kernel: IPython is running (so already imported; it is
    not imported here) with a kernel attached. A terminal IPython has no kernel and cannot show
    images inline."""
    ipython: Any = sys.modules.get("IPython")
    if ipython is None:
        return False
    shell = ipython.get_ipython()
    return shell is not None and getattr(shell, "kernel", None) is not None


def show(
    image: npt.ArrayLike | RenderResult,
    *,
    tone: str = "clip",
    exposure: float = 0.0,
    channel: str = "normal",
) -> None:
    """Show a render to a person: inline in a Jupyter notebook, else in the desktop's image
    viewer (Pillow's ``Image.show``). Like matplotlib's ``show`` it returns nothing, so a cell
    ending in it shows the image once; ``picture()`` gives the image as an object."""
    shown = picture(image, tone=tone, exposure=exposure, channel=channel)
    if _in_kernel():
        from IPython.display import display

        display(shown)
        return
    from PIL import Image

    Image.fromarray(shown.pixels, mode="RGB").show(title=shown.title or "rtlab")


def scene_preview(scene: Any, *, longest_side: int = 320, max_spp: int = 16) -> Picture:
    """A quick look at a scene: rendered at most ``longest_side`` pixels along its longer side
    (the aspect kept) and at most ``max_spp`` samples per pixel, otherwise as the scene says
    (its integrator, its stereo layout). ``tracer.render`` renders the real thing."""
    from tracer.render import render

    camera = scene.camera
    scale = min(1.0, longest_side / max(camera.width, camera.height))
    small = scene.with_overrides(
        width=max(1, round(camera.width * scale)),
        height=max(1, round(camera.height * scale)),
        spp=min(scene.render.spp, max_spp),
    )
    title = f"{scene.source} ({small.camera.width}x{small.camera.height} preview)"
    result = picture(render(small, progress=False))
    return Picture(result.pixels, title)
