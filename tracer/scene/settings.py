"""Reading the [camera] and [render] tables: from a scene file, and again from the overrides of
``Scene.with_overrides``, so both are validated alike."""

from __future__ import annotations

import dataclasses
from typing import Any

from tracer.scene.errors import SceneError
from tracer.scene.model import (
    ACCELERATIONS,
    INTEGRATORS,
    MAX_DEPTH,
    MAX_IMAGE_SIDE,
    MAX_SPP,
    SAMPLERS,
    STEREO_LAYOUTS,
    Camera,
    RenderSettings,
    Stereo,
)
from tracer.scene.values import Reader, suggest
from tracer.scene.vectors import cross, norm, sub

#: Up and the viewing direction whose angle has a sine below this are parallel: the camera's
#: right vector, their cross product, would be rounding noise.
PARALLEL_UP = 1e-12
#: A stereo pair's eyes are at most this many convergence distances apart. Each window shifts
#: (e/2)/C on the image plane (tracer/cpp/03_camera.h stereo_eye()): at 1e6 it is already
#: 5e5 plane units, far past any image (the eyes share nothing on screen), yet a ray direction
#: that large still squares without overflow; an unbounded ratio (convergence = 1e-300) would
#: make the shift infinite and every ray NaN. Eyes converging at a sensible distance have
#: e/C around 0.03 (6.5 cm at 2 m).
MAX_SEPARATION_RATIO = 1e6
#: The core's seed is an unsigned 64-bit integer (tracer/cpp/09_scene.h).
MAX_SEED = 2**64 - 1


def read_camera(r: Reader, data: Any) -> Camera:
    t = r.table(data, "camera", {"eye", "look_at", "up", "fov_y", "width", "height", "stereo"})
    d = Camera(eye=(0, 0, 0), look_at=(0, 0, -1))
    eye = r.vec3(t, "camera", "eye", required=True)
    look_at = r.vec3(t, "camera", "look_at", required=True)
    up = r.vec3(t, "camera", "up", default=d.up, nonzero=True)
    fov_y = r.number(t, "camera", "fov_y", default=d.fov_y, above=0.0, below=180.0)
    width = r.integer(t, "camera", "width", default=d.width, low=1, high=MAX_IMAGE_SIDE)
    height = r.integer(t, "camera", "height", default=d.height, low=1, high=MAX_IMAGE_SIDE)
    forward = sub(look_at, eye)
    if norm(forward) == 0.0:
        raise SceneError(r.source, "camera.look_at", "must differ from camera.eye")
    side = cross(forward, up)
    if norm(side) <= PARALLEL_UP * norm(forward) * norm(up):
        raise SceneError(r.source, "camera.up", "must not be parallel to the viewing direction")
    stereo = read_stereo(r, t["stereo"]) if t.get("stereo") is not None else None
    return Camera(
        eye=eye, look_at=look_at, up=up, fov_y=fov_y, width=width, height=height, stereo=stereo
    )


def read_stereo(r: Reader, data: Any) -> Stereo:
    """``[camera] stereo = { eye_separation = ..., convergence = ..., layout = ... }``."""
    path = "camera.stereo"
    t = r.table(data, path, {"eye_separation", "convergence", "layout"}, what="a stereo pair")
    separation = r.number(t, path, "eye_separation", required=True, above=0.0)
    convergence = r.number(t, path, "convergence", required=True, above=0.0)
    if separation > MAX_SEPARATION_RATIO * convergence:
        raise SceneError(
            r.source,
            f"{path}.convergence",
            f"expected at least eye_separation / {MAX_SEPARATION_RATIO:g} = "
            f"{separation / MAX_SEPARATION_RATIO:g}, got {convergence:g} (the eyes' windows would "
            "shift past any image)",
        )
    layout = r.choice(t, path, "layout", STEREO_LAYOUTS, default="side_by_side")
    return Stereo(eye_separation=separation, convergence=convergence, layout=layout)


def read_render(r: Reader, data: Any) -> RenderSettings:
    keys = {f.name for f in dataclasses.fields(RenderSettings)}
    t = r.table(data, "render", keys)
    d = RenderSettings()
    integrator = r.string(t, "render", "integrator", default=d.integrator)
    if integrator not in INTEGRATORS:
        raise SceneError(
            r.source,
            "render.integrator",
            f"expected one of {', '.join(map(repr, INTEGRATORS))}, got {integrator!r}"
            + suggest(integrator, INTEGRATORS),
        )
    return RenderSettings(
        integrator=integrator,
        max_depth=r.integer(t, "render", "max_depth", default=d.max_depth, low=1, high=MAX_DEPTH),
        min_coefficient=r.number(t, "render", "min_coefficient", default=d.min_coefficient, low=0),
        spp=r.integer(t, "render", "spp", default=d.spp, low=1, high=MAX_SPP),
        seed=r.integer(t, "render", "seed", default=d.seed, low=0, high=MAX_SEED),
        background=r.color(t, "render", "background", default=d.background),
        ambient_light=r.color(t, "render", "ambient_light", default=d.ambient_light),
        acceleration=r.choice(t, "render", "acceleration", ACCELERATIONS, default=d.acceleration),
        sampler=r.choice(t, "render", "sampler", SAMPLERS, default=d.sampler),
    )
