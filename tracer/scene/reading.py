"""Reading a scene: TOML (a file, a string) or nested dicts in, a validated ``Scene`` out.

The scene's top level, camera, render settings, materials and lights are read here; objects in
tracer.scene.objects. Every error is a ``SceneError`` naming the file, the key path and what
was expected.
"""

from __future__ import annotations

import dataclasses
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from tracer.scene.brightness import check_brightness
from tracer.scene.errors import SceneError
from tracer.scene.model import (
    ACCELERATIONS,
    INTEGRATORS,
    MAX_DEPTH,
    MAX_IMAGE_SIDE,
    MAX_SPP,
    Camera,
    DirectionalLight,
    Light,
    Material,
    PointLight,
    RenderSettings,
    Scene,
)
from tracer.scene.objects import read_object
from tracer.scene.values import Reader, join_key, suggest
from tracer.scene.vectors import cross, norm, sub, unit

#: Up and the viewing direction whose angle has a sine below this are parallel: the camera's
#: right vector, their cross product, would be rounding noise.
PARALLEL_UP = 1e-12
#: The core's seed is an unsigned 64-bit integer (tracer/cpp/09_scene.h).
MAX_SEED = 2**64 - 1


def load_scene(source: str | os.PathLike[str] | Mapping[str, Any]) -> Scene:
    """Load a scene from a TOML file path, a TOML string, or a dict in the scene language.

    A ``str`` is taken as a path when it names an existing file or ends in ``.toml``, and as
    TOML text otherwise.
    """
    if isinstance(source, Mapping):
        return parse_scene(source, source="<dict>")
    if isinstance(source, str) and not (os.path.isfile(source) or source.endswith(".toml")):
        return loads_scene(source)
    path = Path(source)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise SceneError(str(path), "", f"cannot read the scene file: {reason}") from exc
    return loads_scene(text, source=str(path), base_dir=path.resolve().parent)


def loads_scene(text: str, *, source: str = "<string>", base_dir: Path | None = None) -> Scene:
    """Load a scene from TOML text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(source, "", f"invalid TOML: {exc}") from exc
    return parse_scene(data, source=source, base_dir=base_dir)


def parse_scene(
    data: Mapping[str, Any], *, source: str = "<dict>", base_dir: Path | None = None
) -> Scene:
    """Validate a scene given as nested dicts and lists, as ``tomllib`` returns it."""
    r = Reader(source)
    top = r.table(data, "", {"camera", "render", "materials", "lights", "objects"})
    if "camera" not in top:
        raise SceneError(source, "camera", "missing: the scene needs a [camera] table")
    camera = _camera(r, top["camera"])
    render = _render(r, top.get("render", {}))
    materials = _materials(r, top.get("materials", {}))
    lights = tuple(_light(r, item, f"lights[{i}]") for i, item in enumerate(r.array(top, "lights")))
    base = base_dir if base_dir is not None else Path.cwd()
    objects = tuple(
        read_object(r, item, f"objects[{i}]", materials, base)
        for i, item in enumerate(r.array(top, "objects"))
    )
    scene = Scene(
        camera=camera,
        render=render,
        materials=materials,
        lights=lights,
        objects=objects,
        source=source,
        base_dir=base_dir if base_dir is not None else Path.cwd(),
    )
    check_brightness(scene)
    return scene


# --------------------------------------------------------------------------- the parts


def _camera(r: Reader, data: Any) -> Camera:
    t = r.table(data, "camera", {"eye", "look_at", "up", "fov_y", "width", "height"})
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
    return Camera(eye=eye, look_at=look_at, up=up, fov_y=fov_y, width=width, height=height)


def _render(r: Reader, data: Any) -> RenderSettings:
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
    )


def _materials(r: Reader, data: Any) -> dict[str, Material]:
    t = r.table(data, "materials", None)
    out: dict[str, Material] = {}
    keys = {f.name for f in dataclasses.fields(Material)} - {"name"}
    for name, value in t.items():
        path = join_key("materials", name)
        m = r.table(value, path, keys)
        d = Material(name=name)
        out[name] = Material(
            name=name,
            color=r.color(m, path, "color", default=d.color),
            ambient=r.number(m, path, "ambient", default=d.ambient, low=0),
            diffuse=r.number(m, path, "diffuse", default=d.diffuse, low=0),
            specular=r.number(m, path, "specular", default=d.specular, low=0),
            shininess=r.number(m, path, "shininess", default=d.shininess, above=0),
            reflectivity=r.number(m, path, "reflectivity", default=d.reflectivity, low=0),
            emission=r.color(m, path, "emission", default=d.emission),
        )
    return out


_LIGHT_KEYS = {
    "point": {"type", "position", "color"},
    "directional": {"type", "direction", "color"},
}


def _light(r: Reader, data: Any, path: str) -> Light:
    kind = r.kind(data, path, _LIGHT_KEYS)
    t = r.table(data, path, _LIGHT_KEYS[kind], what=f"a {kind} light")
    color = r.color(t, path, "color", default=(1.0, 1.0, 1.0))
    if kind == "point":
        return PointLight(position=r.vec3(t, path, "position", required=True), color=color)
    direction = r.vec3(t, path, "direction", required=True, nonzero=True)
    return DirectionalLight(direction=unit(direction), color=color)


def read_overrides(scene: Scene, camera: Mapping[str, Any], render: Mapping[str, Any]) -> Scene:
    """``scene`` with its camera and render settings read anew from plain values (the
    overrides of ``Scene.with_overrides``), validated like the file's."""
    r = Reader(f"{scene.source} (with overrides)")
    new = dataclasses.replace(scene, camera=_camera(r, camera), render=_render(r, render))
    check_brightness(dataclasses.replace(new, source=r.source))
    return new
