"""The whole scene: its camera, render settings, materials, lights and objects, where they came
from, and the two ways a scene changes or leaves: overrides read anew (``with_overrides``) and
the scene language again (``to_dict``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tracer.scene.brightness import check_brightness
from tracer.scene.model import Camera, Light, Material, Object, RenderSettings
from tracer.scene.settings import read_camera, read_render
from tracer.scene.unparse import unparse
from tracer.scene.values import Reader


@dataclass(frozen=True)
class Scene:
    camera: Camera
    render: RenderSettings = field(default_factory=RenderSettings)
    materials: dict[str, Material] = field(default_factory=dict)
    lights: tuple[Light, ...] = ()
    objects: tuple[Object, ...] = ()
    source: str = "<scene>"
    #: The directory relative file names in the scene are resolved against.
    base_dir: Path = field(default_factory=Path.cwd)

    def with_overrides(self, **overrides: Any) -> Scene:
        """A copy with camera/render keys replaced (``width=1920, spp=4``); None leaves a key.

        The new values are validated like the file's; the objects are kept as they are."""
        cam = dataclasses.asdict(self.camera)
        ren = dataclasses.asdict(self.render)
        for key, value in overrides.items():
            if value is None:
                continue
            if key in cam:
                cam[key] = value
            elif key in ren:
                ren[key] = value
            else:
                raise TypeError(f"unknown override {key!r}")
        plain = {k: list(v) if isinstance(v, tuple) else v for k, v in cam.items()}
        plain_render = {k: list(v) if isinstance(v, tuple) else v for k, v in ren.items()}
        r = Reader(f"{self.source} (with overrides)")
        new = dataclasses.replace(
            self, camera=read_camera(r, plain), render=read_render(r, plain_render)
        )
        check_brightness(dataclasses.replace(new, source=r.source))
        return new

    def to_dict(self) -> dict[str, Any]:
        """The scene as a plain dict in the scene language; ``parse_scene`` reads it back."""
        return unparse(self)

    def _repr_png_(self) -> bytes:
        """Jupyter shows a scene as a small render of it (tracer/display.py scene_preview)."""
        from tracer.display import scene_preview

        return scene_preview(self).png()
