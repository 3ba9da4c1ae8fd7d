"""Reading a scene: TOML (a file, a string) or nested dicts in, a validated ``Scene`` out.

The scene's top level, materials and lights are read here; the camera and render settings in
tracer.scene.settings, objects in tracer.scene.objects. Every error is a ``SceneError`` naming
the file, the key path and what was expected.
"""

from __future__ import annotations

import dataclasses
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from tracer.scene.brightness import check_brightness
from tracer.scene.document import Scene
from tracer.scene.errors import SceneError
from tracer.scene.model import DirectionalLight, Light, Material, Object, PointLight
from tracer.scene.objects import read_object
from tracer.scene.placement import reach
from tracer.scene.settings import read_camera, read_render
from tracer.scene.values import MAX_MAGNITUDE, Reader, join_key
from tracer.scene.vectors import unit


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
    camera = read_camera(r, top["camera"])
    render = read_render(r, top.get("render", {}))
    materials = _materials(r, top.get("materials", {}))
    lights = tuple(_light(r, item, f"lights[{i}]") for i, item in enumerate(r.array(top, "lights")))
    base = base_dir if base_dir is not None else Path.cwd()
    objects = tuple(
        _within_reach(r, read_object(r, item, f"objects[{i}]", materials, base), f"objects[{i}]")
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

#: The core computes the highlight max(R.L, 0)^n as exp(n ln x) (tracer/cpp/power.h), rounding
#: n ln x / ln 2 with a 1.5 * 2^52 shifter, which holds while that is below 2^51; ln x >=
#: ln 2^-1074 ~ -744.4, so n up to 1e12 keeps it below 1.1e15 for every x (shininess 1.17e16
#: gave the packet tracer 3 inf pixels). A highlight of exponent 1e12 is already a point: it
#: falls to half within ~1.2e-6 radians.
MAX_SHININESS = 1e12
_SHININESS_WHY = " (the core's highlight x^n holds only for exponents up to ~2e12)"


def _within_reach(r: Reader, obj: Object, path: str) -> Object:
    """The object, once its world-space reach (after its transform, or a mesh file's vertices,
    which no number check has seen) is within MAX_MAGNITUDE like every number of the scene."""
    far = reach(obj)
    if not far <= MAX_MAGNITUDE:
        where = f"{path}.transform" if getattr(obj, "transform", None) is not None else path
        raise r.fail(
            where,
            f"expected an object within {MAX_MAGNITUDE:g} of the origin, got one reaching "
            f"{far:g} (the renderers square coordinates; no scene needs more)",
        )
    return obj


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
            shininess=r.number(
                m,
                path,
                "shininess",
                default=d.shininess,
                above=0,
                high=MAX_SHININESS,
                why=_SHININESS_WHY,
            ),
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
