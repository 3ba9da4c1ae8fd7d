"""The scene language: TOML in, one validated scene model out.

The model is parsed and checked once; the C++ core and the converters read the model, never
the TOML. Every error names the file, the key path (``objects[2].radius``) and what was
expected; an unknown key suggests the near spelling.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

Vec3 = tuple[float, float, float]
Color = tuple[float, float, float]

#: Image sizes are bounded so a typo (width = 1e9) fails at once instead of exhausting memory.
MAX_IMAGE_SIDE = 32768
MAX_SPP = 1 << 20
MAX_DEPTH = 10000
INTEGRATORS = ("classic",)


class SceneError(ValueError):
    """A scene that cannot be rendered: says which file, which key, and what was expected."""

    def __init__(self, source: str, key: str, message: str) -> None:
        self.source = source
        self.key = key
        self.message = message
        where = f"{source}: {key}" if key else source
        super().__init__(f"{where}: {message}")


@dataclass(frozen=True)
class Camera:
    eye: Vec3
    look_at: Vec3
    up: Vec3 = (0.0, 1.0, 0.0)
    fov_y: float = 45.0  # vertical field of view, degrees
    width: int = 320
    height: int = 240


@dataclass(frozen=True)
class RenderSettings:
    integrator: str = "classic"
    max_depth: int = 5  # the primary ray is level 1
    min_coefficient: float = 0.0  # a level whose chain coefficient is below this is black
    spp: int = 1
    seed: int = 0
    background: Color = (0.0, 0.0, 0.0)
    ambient_light: Color = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class Material:
    """Defaults are POV-Ray 3.7's finish defaults, so an omitted term means the same there."""

    name: str
    color: Color = (1.0, 1.0, 1.0)
    ambient: float = 0.1
    diffuse: float = 0.6
    specular: float = 0.0
    shininess: float = 40.0
    reflectivity: float = 0.0


@dataclass(frozen=True)
class PointLight:
    position: Vec3
    color: Color = (1.0, 1.0, 1.0)
    type: str = "point"


@dataclass(frozen=True)
class DirectionalLight:
    direction: Vec3  # the direction the light travels, unit length
    color: Color = (1.0, 1.0, 1.0)
    type: str = "directional"


@dataclass(frozen=True)
class Sphere:
    center: Vec3
    radius: float
    material: str
    type: str = "sphere"


@dataclass(frozen=True)
class Plane:
    point: Vec3
    normal: Vec3  # unit length
    material: str
    type: str = "plane"


Light = PointLight | DirectionalLight
Object = Sphere | Plane


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
        """A copy with camera/render keys replaced (``width=1920, spp=4``); None leaves a key."""
        cam: dict[str, Any] = {}
        ren: dict[str, Any] = {}
        for key, value in overrides.items():
            if value is None:
                continue
            if key in {f.name for f in dataclasses.fields(Camera)}:
                cam[key] = value
            elif key in {f.name for f in dataclasses.fields(RenderSettings)}:
                ren[key] = value
            else:
                raise TypeError(f"unknown override {key!r}")
        data = _unparse(self)
        data["camera"].update(cam)
        data["render"].update(ren)
        return parse_scene(data, source=f"{self.source} (with overrides)", base_dir=self.base_dir)

    def to_dict(self) -> dict[str, Any]:
        """The scene as a plain dict in the scene language; ``parse_scene`` reads it back."""
        return _unparse(self)


# --------------------------------------------------------------------------- loading


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
    r = _Reader(source)
    top = r.table(data, "", {"camera", "render", "materials", "lights", "objects"})
    if "camera" not in top:
        raise SceneError(source, "camera", "missing: the scene needs a [camera] table")
    camera = _camera(r, top["camera"])
    render = _render(r, top.get("render", {}))
    materials = _materials(r, top.get("materials", {}))
    lights = tuple(_light(r, item, f"lights[{i}]") for i, item in enumerate(r.array(top, "lights")))
    objects = tuple(
        _object(r, item, f"objects[{i}]", materials)
        for i, item in enumerate(r.array(top, "objects"))
    )
    return Scene(
        camera=camera,
        render=render,
        materials=materials,
        lights=lights,
        objects=objects,
        source=source,
        base_dir=base_dir if base_dir is not None else Path.cwd(),
    )


# --------------------------------------------------------------------------- the parts


def _camera(r: _Reader, data: Any) -> Camera:
    t = r.table(data, "camera", {"eye", "look_at", "up", "fov_y", "width", "height"})
    d = Camera(eye=(0, 0, 0), look_at=(0, 0, -1))
    eye = r.vec3(t, "camera", "eye", required=True)
    look_at = r.vec3(t, "camera", "look_at", required=True)
    up = r.vec3(t, "camera", "up", default=d.up, nonzero=True)
    fov_y = r.number(t, "camera", "fov_y", default=d.fov_y, above=0.0, below=180.0)
    width = r.integer(t, "camera", "width", default=d.width, low=1, high=MAX_IMAGE_SIDE)
    height = r.integer(t, "camera", "height", default=d.height, low=1, high=MAX_IMAGE_SIDE)
    forward = _sub(look_at, eye)
    if _norm(forward) == 0.0:
        raise SceneError(r.source, "camera.look_at", "must differ from camera.eye")
    side = _cross(forward, up)
    if _norm(side) <= 1e-12 * _norm(forward) * _norm(up):
        raise SceneError(r.source, "camera.up", "must not be parallel to the viewing direction")
    return Camera(eye=eye, look_at=look_at, up=up, fov_y=fov_y, width=width, height=height)


def _render(r: _Reader, data: Any) -> RenderSettings:
    keys = {f.name for f in dataclasses.fields(RenderSettings)}
    t = r.table(data, "render", keys)
    d = RenderSettings()
    integrator = r.string(t, "render", "integrator", default=d.integrator)
    if integrator not in INTEGRATORS:
        raise SceneError(
            r.source,
            "render.integrator",
            f"expected one of {', '.join(map(repr, INTEGRATORS))}, got {integrator!r}"
            + _suggest(integrator, INTEGRATORS),
        )
    return RenderSettings(
        integrator=integrator,
        max_depth=r.integer(t, "render", "max_depth", default=d.max_depth, low=1, high=MAX_DEPTH),
        min_coefficient=r.number(t, "render", "min_coefficient", default=d.min_coefficient, low=0),
        spp=r.integer(t, "render", "spp", default=d.spp, low=1, high=MAX_SPP),
        seed=r.integer(t, "render", "seed", default=d.seed, low=0, high=2**64 - 1),
        background=r.color(t, "render", "background", default=d.background),
        ambient_light=r.color(t, "render", "ambient_light", default=d.ambient_light),
    )


def _materials(r: _Reader, data: Any) -> dict[str, Material]:
    t = r.table(data, "materials", None)
    out: dict[str, Material] = {}
    keys = {f.name for f in dataclasses.fields(Material)} - {"name"}
    for name, value in t.items():
        path = f"materials.{name}"
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
        )
    return out


_LIGHT_KEYS = {
    "point": {"type", "position", "color"},
    "directional": {"type", "direction", "color"},
}


def _light(r: _Reader, data: Any, path: str) -> Light:
    kind = r.kind(data, path, _LIGHT_KEYS)
    t = r.table(data, path, _LIGHT_KEYS[kind], what=f"a {kind} light")
    color = r.color(t, path, "color", default=(1.0, 1.0, 1.0))
    if kind == "point":
        return PointLight(position=r.vec3(t, path, "position", required=True), color=color)
    direction = r.vec3(t, path, "direction", required=True, nonzero=True)
    return DirectionalLight(direction=_unit(direction), color=color)


_OBJECT_KEYS = {
    "sphere": {"type", "center", "radius", "material"},
    "plane": {"type", "point", "normal", "material"},
}


def _object(r: _Reader, data: Any, path: str, materials: Mapping[str, Material]) -> Object:
    kind = r.kind(data, path, _OBJECT_KEYS)
    t = r.table(data, path, _OBJECT_KEYS[kind], what=f"a {kind}")
    material = r.string(t, path, "material", required=True)
    if material not in materials:
        known = ", ".join(sorted(materials)) or "none are defined"
        raise SceneError(
            r.source,
            f"{path}.material",
            f"unknown material {material!r}{_suggest(material, materials)} (defined: {known})",
        )
    if kind == "sphere":
        center = r.vec3(t, path, "center", required=True)
        radius = r.number(t, path, "radius", required=True, above=0)
        return Sphere(center=center, radius=radius, material=material)
    point = r.vec3(t, path, "point", required=True)
    normal = r.vec3(t, path, "normal", required=True, nonzero=True)
    return Plane(point=point, normal=_unit(normal), material=material)


# --------------------------------------------------------------------------- checking values


def _suggest(word: str, choices: Any) -> str:
    near = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {near[0]!r}?)" if near else ""


def _describe(value: Any) -> str:
    kind = {bool: "boolean", str: "string", int: "integer", float: "number", list: "array"}
    name = "table" if isinstance(value, Mapping) else kind.get(type(value), type(value).__name__)
    text = repr(value)
    return f"{name} {text if len(text) <= 40 else text[:37] + '...'}"


class _Reader:
    """Reads values out of nested tables, knowing the file it reports errors against."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, key: str, message: str) -> SceneError:
        return SceneError(self.source, key, message)

    def table(
        self, data: Any, path: str, allowed: set[str] | None, *, what: str | None = None
    ) -> Mapping[str, Any]:
        if not isinstance(data, Mapping):
            raise self.fail(path or "<top level>", f"expected a table, got {_describe(data)}")
        if allowed is not None:
            for key in data:
                if key not in allowed:
                    where = f" for {what}" if what else ""
                    raise self.fail(
                        f"{path}.{key}" if path else key,
                        f"unknown key{where}{_suggest(key, allowed)}; expected one of "
                        + ", ".join(sorted(allowed)),
                    )
        return data

    def array(self, t: Mapping[str, Any], key: str) -> list[Any]:
        value = t.get(key, [])
        if not isinstance(value, list):
            raise self.fail(key, f"expected an array of tables ([[{key}]]), got {_describe(value)}")
        return value

    def kind(self, data: Any, path: str, kinds: Mapping[str, set[str]]) -> str:
        t = self.table(data, path, None)
        if "type" not in t:
            raise self.fail(f"{path}.type", f"missing; expected one of {', '.join(kinds)}")
        kind = t["type"]
        if kind not in kinds:
            raise self.fail(
                f"{path}.type",
                f"expected one of {', '.join(kinds)}, got {_describe(kind)}"
                + (_suggest(kind, kinds) if isinstance(kind, str) else ""),
            )
        return str(kind)

    def _get(self, t: Mapping[str, Any], path: str, key: str, required: bool) -> Any:
        if key not in t and required:
            raise self.fail(f"{path}.{key}", "missing; this key is required")
        return t.get(key)

    def string(
        self,
        t: Mapping[str, Any],
        path: str,
        key: str,
        *,
        default: str = "",
        required: bool = False,
    ) -> str:
        value = self._get(t, path, key, required)
        if value is None:
            return default
        if not isinstance(value, str):
            raise self.fail(f"{path}.{key}", f"expected a string, got {_describe(value)}")
        return value

    def _finite(self, value: Any, key: str, what: str = "a number") -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, f"expected {what}, got {_describe(value)}")
        if not math.isfinite(value):
            raise self.fail(key, f"expected a finite number, got {value}")
        return float(value)

    def number(
        self,
        t: Mapping[str, Any],
        path: str,
        key: str,
        *,
        default: float = 0.0,
        required: bool = False,
        low: float | None = None,
        above: float | None = None,
        below: float | None = None,
    ) -> float:
        value = self._get(t, path, key, required)
        if value is None:
            return default
        full = f"{path}.{key}"
        x = self._finite(value, full)
        if low is not None and x < low:
            raise self.fail(full, f"expected a number >= {low:g}, got {x:g}")
        if above is not None and x <= above:
            words = "a positive number" if above == 0 else f"a number > {above:g}"
            raise self.fail(full, f"expected {words}, got {x:g}")
        if below is not None and x >= below:
            raise self.fail(full, f"expected a number < {below:g}, got {x:g}")
        return x

    def integer(
        self, t: Mapping[str, Any], path: str, key: str, *, default: int, low: int, high: int
    ) -> int:
        value = t.get(key)
        if value is None:
            return default
        full = f"{path}.{key}"
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(full, f"expected an integer, got {_describe(value)}")
        if not low <= value <= high:
            raise self.fail(full, f"expected an integer from {low} to {high}, got {value}")
        return value

    def vec3(
        self,
        t: Mapping[str, Any],
        path: str,
        key: str,
        *,
        default: Vec3 = (0.0, 0.0, 0.0),
        required: bool = False,
        nonzero: bool = False,
    ) -> Vec3:
        value = self._get(t, path, key, required)
        if value is None:
            return default
        full = f"{path}.{key}"
        if not isinstance(value, list) or len(value) != 3:
            raise self.fail(full, f"expected an array of three numbers, got {_describe(value)}")
        v = tuple(self._finite(x, f"{full}[{i}]") for i, x in enumerate(value))
        if nonzero and not any(v):
            raise self.fail(full, "expected a non-zero vector, got length 0")
        return (v[0], v[1], v[2])

    def color(self, t: Mapping[str, Any], path: str, key: str, *, default: Color) -> Color:
        c = self.vec3(t, path, key, default=default)
        if min(c) < 0:
            raise self.fail(f"{path}.{key}", f"expected three numbers >= 0, got {list(c)}")
        return c


# --------------------------------------------------------------------------- small vector helpers


def _sub(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _norm(a: Vec3) -> float:
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def _unit(a: Vec3) -> Vec3:
    n = _norm(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def _unparse(scene: Scene) -> dict[str, Any]:
    def plain(obj: Any, drop: tuple[str, ...] = ()) -> dict[str, Any]:
        return {
            k: list(v) if isinstance(v, tuple) else v
            for k, v in dataclasses.asdict(obj).items()
            if k not in drop
        }

    return {
        "camera": plain(scene.camera),
        "render": plain(scene.render),
        "materials": {name: plain(m, ("name",)) for name, m in scene.materials.items()},
        "lights": [plain(light) for light in scene.lights],
        "objects": [plain(obj) for obj in scene.objects],
    }
