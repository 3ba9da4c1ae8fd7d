"""rtlab's ray tracer: the course's classic algorithm, in C++, with a Python face."""

from tracer.display import Picture, picture, show
from tracer.image import load_exr_channels, load_image, save_aov, save_image
from tracer.render import ImageTooLargeError, RenderResult, aov_channels, render, render_with_stats
from tracer.scene import Scene, SceneError, load_scene

__all__ = [
    "ImageTooLargeError",
    "Picture",
    "RenderResult",
    "Scene",
    "SceneError",
    "aov_channels",
    "load_exr_channels",
    "load_image",
    "load_scene",
    "picture",
    "render",
    "render_with_stats",
    "save_aov",
    "save_image",
    "show",
]
