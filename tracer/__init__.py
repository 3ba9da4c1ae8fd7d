"""rtlab's ray tracer: the course's classic algorithm, in C++, with a Python face."""

from tracer.image import load_image, save_image
from tracer.render import RenderResult, render, render_with_stats
from tracer.scene import Scene, SceneError, load_scene

__all__ = [
    "RenderResult",
    "Scene",
    "SceneError",
    "load_image",
    "load_scene",
    "render",
    "render_with_stats",
    "save_image",
]
