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

import numpy as np

Vec3 = tuple[float, float, float]
Color = tuple[float, float, float]

#: Image sizes are bounded so a typo (width = 1e9) fails at once instead of exhausting memory.
MAX_IMAGE_SIDE = 32768
MAX_SPP = 1 << 20
MAX_DEPTH = 10000
INTEGRATORS = ("classic", "aov", "path")
ACCELERATIONS = ("bvh", "bounding_box", "none")


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
    integrator: str = "classic"  # "aov": depth, object id and normal; "path": path tracing
    max_depth: int = 5  # the primary ray is level 1
    min_coefficient: float = 0.0  # a level whose chain coefficient is below this is black
    spp: int = 1
    seed: int = 0
    background: Color = (0.0, 0.0, 0.0)
    ambient_light: Color = (1.0, 1.0, 1.0)
    #: How meshes are searched: a bounding volume hierarchy, only the bounding box of the whole
    #: mesh, or every triangle (the slide "Intersecting a Complex Object", step by step).
    acceleration: str = "bvh"


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
    #: Radiance leaving the front side (the path tracer's area lights; the classic model has
    #: no emitting surfaces and ignores it).
    emission: Color = (0.0, 0.0, 0.0)


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


@dataclass(frozen=True, eq=False)
class Transform:
    """Scale, then rotate (axis, degrees), then translate: ``matrix`` is T R S (4x4)."""

    scale: Vec3 = (1.0, 1.0, 1.0)
    rotate_axis: Vec3 = (0.0, 0.0, 1.0)
    rotate_degrees: float = 0.0
    translate: Vec3 = (0.0, 0.0, 0.0)

    @property
    def matrix(self) -> np.ndarray:
        s = np.diag([*self.scale, 1.0])
        r = np.eye(4)
        r[:3, :3] = _rotation(self.rotate_axis, self.rotate_degrees)
        t = np.eye(4)
        t[:3, 3] = self.translate
        return t @ r @ s

    def to_dict(self) -> dict[str, Any]:
        return {
            "scale": list(self.scale),
            "rotate": {"axis": list(self.rotate_axis), "degrees": self.rotate_degrees},
            "translate": list(self.translate),
        }


def _rotation(axis: Vec3, degrees: float) -> np.ndarray:
    """Rodrigues' rotation matrix: right-handed, counter-clockwise looking down the axis."""
    k = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    a = np.radians(degrees)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) * np.cos(a) + np.sin(a) * cross + (1 - np.cos(a)) * np.outer(k, k)


@dataclass(frozen=True)
class Box:
    min: Vec3
    max: Vec3
    material: str
    transform: Transform | None = None
    type: str = "box"


@dataclass(frozen=True)
class Triangle:
    vertices: tuple[Vec3, Vec3, Vec3]  # the front is where they run counter-clockwise
    material: str
    type: str = "triangle"


@dataclass(frozen=True)
class Quad:
    corner: Vec3
    edge1: Vec3
    edge2: Vec3  # the front is the side of edge1 x edge2
    material: str
    transform: Transform | None = None
    type: str = "quad"


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh, its vertices already in world space (transform applied)."""

    vertices: np.ndarray  # (n, 3) float64
    faces: np.ndarray  # (m, 3) int32, counter-clockwise seen from the front
    material: str
    smooth: bool = False
    normals: np.ndarray | None = None  # (n, 3) unit vertex normals when smooth
    file: str | None = None  # as written in the scene (relative to the scene file)
    transform: Transform | None = None
    type: str = "mesh"


@dataclass(frozen=True)
class Cylinder:
    base: Vec3
    top: Vec3
    radius: float
    material: str
    capped: bool = True
    transform: Transform | None = None
    type: str = "cylinder"


@dataclass(frozen=True)
class Torus:
    center: Vec3
    axis: Vec3  # unit length
    major_radius: float
    minor_radius: float
    material: str
    transform: Transform | None = None
    type: str = "torus"


Light = PointLight | DirectionalLight
Object = Sphere | Plane | Box | Triangle | Quad | Mesh | Cylinder | Torus


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
        r = _Reader(f"{self.source} (with overrides)")
        plain = {k: list(v) if isinstance(v, tuple) else v for k, v in cam.items()}
        plain_render = {k: list(v) if isinstance(v, tuple) else v for k, v in ren.items()}
        return dataclasses.replace(self, camera=_camera(r, plain), render=_render(r, plain_render))

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
    base = base_dir if base_dir is not None else Path.cwd()
    objects = tuple(
        _object(r, item, f"objects[{i}]", materials, base)
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
        acceleration=r.choice(t, "render", "acceleration", ACCELERATIONS, default=d.acceleration),
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
            emission=r.color(m, path, "emission", default=d.emission),
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
    "box": {"type", "min", "max", "material", "transform"},
    "triangle": {"type", "vertices", "material"},
    "quad": {"type", "corner", "edge1", "edge2", "material", "transform"},
    "mesh": {"type", "file", "vertices", "faces", "smooth", "material", "transform"},
    "cylinder": {"type", "base", "top", "radius", "capped", "material", "transform"},
    "torus": {"type", "center", "axis", "major_radius", "minor_radius", "material", "transform"},
}


def _object(
    r: _Reader, data: Any, path: str, materials: Mapping[str, Material], base_dir: Path
) -> Object:
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
    transform = _transform(r, t, path) if "transform" in t else None
    if kind == "sphere":
        center = r.vec3(t, path, "center", required=True)
        radius = r.number(t, path, "radius", required=True, above=0)
        return Sphere(center=center, radius=radius, material=material)
    if kind == "plane":
        point = r.vec3(t, path, "point", required=True)
        normal = r.vec3(t, path, "normal", required=True, nonzero=True)
        return Plane(point=point, normal=_unit(normal), material=material)
    if kind == "box":
        lo = r.vec3(t, path, "min", required=True)
        hi = r.vec3(t, path, "max", required=True)
        if not all(a < b for a, b in zip(lo, hi, strict=True)):
            raise r.fail(
                f"{path}.max", f"expected each coordinate above min {list(lo)}, got {list(hi)}"
            )
        return Box(min=lo, max=hi, material=material, transform=transform)
    if kind == "triangle":
        vs = r.points(t, path, "vertices", count=3)
        if _norm(_cross(_sub(vs[1], vs[0]), _sub(vs[2], vs[0]))) == 0:
            raise r.fail(f"{path}.vertices", "expected a triangle of non-zero area")
        return Triangle(vertices=(vs[0], vs[1], vs[2]), material=material)
    if kind == "quad":
        corner = r.vec3(t, path, "corner", required=True)
        e1 = r.vec3(t, path, "edge1", required=True, nonzero=True)
        e2 = r.vec3(t, path, "edge2", required=True, nonzero=True)
        if _norm(_cross(e1, e2)) == 0:
            raise r.fail(f"{path}.edge2", "expected an edge not parallel to edge1")
        return Quad(corner=corner, edge1=e1, edge2=e2, material=material, transform=transform)
    if kind == "mesh":
        return _mesh(r, t, path, material, transform, base_dir)
    if kind == "cylinder":
        base = r.vec3(t, path, "base", required=True)
        top = r.vec3(t, path, "top", required=True)
        if base == top:
            raise r.fail(f"{path}.top", "expected a point other than base")
        radius = r.number(t, path, "radius", required=True, above=0)
        capped = r.boolean(t, path, "capped", default=True)
        return Cylinder(base=base, top=top, radius=radius, capped=capped, material=material,
                        transform=transform)  # fmt: skip
    center = r.vec3(t, path, "center", required=True)
    axis = r.vec3(t, path, "axis", required=True, nonzero=True)
    major = r.number(t, path, "major_radius", required=True, above=0)
    minor = r.number(t, path, "minor_radius", required=True, above=0)
    return Torus(center=center, axis=_unit(axis), major_radius=major, minor_radius=minor,
                 material=material, transform=transform)  # fmt: skip


def _transform(r: _Reader, t: Mapping[str, Any], path: str) -> Transform:
    where = f"{path}.transform"
    tt = r.table(t["transform"], where, {"scale", "rotate", "translate"})
    scale = r.vec3(tt, where, "scale", default=(1.0, 1.0, 1.0))
    if not all(scale):
        raise r.fail(f"{where}.scale", f"expected three non-zero numbers, got {list(scale)}")
    axis, degrees = (0.0, 0.0, 1.0), 0.0
    if "rotate" in tt:
        rot = r.table(tt["rotate"], f"{where}.rotate", {"axis", "degrees"})
        axis = r.vec3(rot, f"{where}.rotate", "axis", required=True, nonzero=True)
        degrees = r.number(rot, f"{where}.rotate", "degrees", required=True)
    translate = r.vec3(tt, where, "translate")
    return Transform(scale=scale, rotate_axis=axis, rotate_degrees=degrees, translate=translate)


def _mesh(
    r: _Reader,
    t: Mapping[str, Any],
    path: str,
    material: str,
    transform: Transform | None,
    base_dir: Path,
) -> Mesh:
    smooth = r.boolean(t, path, "smooth", default=False)
    file = None
    if "file" in t:
        if "vertices" in t or "faces" in t:
            raise r.fail(f"{path}.file", "expected either file or vertices and faces, not both")
        file = r.string(t, path, "file", required=True)
        vertices, faces = _read_mesh_file(
            r, f"{path}.file", resolve_file(r, f"{path}.file", file, base_dir)
        )
    else:
        if "vertices" not in t or "faces" not in t:
            missing = "vertices" if "vertices" not in t else "faces"
            raise r.fail(f"{path}.{missing}", "missing; a mesh needs a file, or vertices and faces")
        vertices = np.array(r.points(t, path, "vertices"), dtype=np.float64)
        faces = _triangulate(r, t["faces"], f"{path}.faces", len(vertices))
    if transform is not None:
        m = transform.matrix
        vertices = vertices @ m[:3, :3].T + m[:3, 3]
    normals = vertex_normals(vertices, faces) if smooth else None
    return Mesh(vertices=vertices, faces=faces, material=material, smooth=smooth,
                normals=normals, file=file, transform=transform)  # fmt: skip


def resolve_file(r: _Reader | None, key: str, name: str, base_dir: Path) -> Path:
    """A file named in a scene: relative to the scene file's directory, or, written
    ``package:NAME/path``, inside the installed Python package NAME (data that ships in a
    wheel, such as the Stanford bunny in pymeshfix, is read where it is installed)."""
    if not name.startswith("package:"):
        return base_dir / name
    package, _, inner = name[len("package:") :].partition("/")
    import importlib.util

    spec = importlib.util.find_spec(package) if package.isidentifier() else None
    if spec is None or not spec.submodule_search_locations:
        message = f"no installed Python package {package!r} (from {name!r})"
        if r is None:
            raise FileNotFoundError(message)
        raise r.fail(key, message)
    return Path(next(iter(spec.submodule_search_locations))) / inner


def _read_mesh_file(r: _Reader, key: str, file: Path) -> tuple[np.ndarray, np.ndarray]:
    """A PLY or OBJ file's triangles, read with trimesh (no merging or reordering)."""
    if file.suffix.lower() not in (".ply", ".obj"):
        raise r.fail(key, f"expected a .ply or .obj file, got {file.name!r}")
    if not file.is_file():
        raise r.fail(key, f"cannot read mesh file {str(file)!r}: no such file")
    import trimesh

    try:
        loaded = trimesh.load(str(file), process=False, force="mesh")
    except Exception as exc:  # trimesh raises many kinds; all mean "not a mesh we can read"
        raise r.fail(key, f"cannot read mesh file {str(file)!r}: {exc}") from exc
    vertices = np.asarray(loaded.vertices, dtype=np.float64)
    faces = np.asarray(loaded.faces, dtype=np.int32)
    if len(faces) == 0 or not np.all(np.isfinite(vertices)):
        raise r.fail(key, f"mesh file {str(file)!r} has no triangles or non-finite vertices")
    return vertices, faces


def _triangulate(r: _Reader, value: Any, key: str, n_vertices: int) -> np.ndarray:
    """Faces as lists of vertex indices (three or more, counter-clockwise): fans of triangles."""
    if not isinstance(value, list) or not value:
        raise r.fail(key, f"expected an array of faces, got {_describe(value)}")
    out = []
    for i, face in enumerate(value):
        indices = isinstance(face, list) and all(
            isinstance(v, int) and not isinstance(v, bool) for v in face
        )
        if not indices or len(face) < 3:
            raise r.fail(
                f"{key}[{i}]", f"expected three or more vertex indices, got {_describe(face)}"
            )
        bad = [v for v in face if not 0 <= v < n_vertices]
        if bad:
            raise r.fail(f"{key}[{i}]", f"vertex index {bad[0]} out of range 0..{n_vertices - 1}")
        out += [[face[0], face[k], face[k + 1]] for k in range(1, len(face) - 1)]
    return np.array(out, dtype=np.int32)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Smooth-shading normals: at each vertex the sum of its faces' normals weighted by their
    areas (the unnormalised cross products), normalised. A vertex no face uses keeps (0, 0, 1)."""
    v = vertices[faces]
    face_n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    normals = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(normals, faces[:, k], face_n)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    unused = length[:, 0] == 0
    normals[unused] = (0.0, 0.0, 1.0)
    length[unused] = 1.0
    return normals / length


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

    def boolean(self, t: Mapping[str, Any], path: str, key: str, *, default: bool) -> bool:
        value = t.get(key, default)
        if not isinstance(value, bool):
            raise self.fail(f"{path}.{key}", f"expected true or false, got {_describe(value)}")
        return value

    def choice(
        self, t: Mapping[str, Any], path: str, key: str, choices: tuple[str, ...], *, default: str
    ) -> str:
        value = self.string(t, path, key, default=default)
        if value not in choices:
            raise self.fail(
                f"{path}.{key}",
                f"expected one of {', '.join(map(repr, choices))}, got {value!r}"
                + _suggest(value, choices),
            )
        return value

    def points(
        self, t: Mapping[str, Any], path: str, key: str, *, count: int | None = None
    ) -> list[Vec3]:
        value = self._get(t, path, key, True)
        full = f"{path}.{key}"
        if not isinstance(value, list) or (count is not None and len(value) != count):
            n = f"{count}" if count is not None else "one or more"
            raise self.fail(full, f"expected an array of {n} points, got {_describe(value)}")
        return [self.vec3({"p": p}, full, "p", required=True) for p in value]

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

    def unparse_object(obj: Any) -> dict[str, Any]:
        if isinstance(obj, Mesh):
            d: dict[str, Any] = {"type": "mesh", "material": obj.material, "smooth": obj.smooth}
            if obj.file is not None:
                d["file"] = str(resolve_file(None, "", obj.file, scene.base_dir))
                if obj.transform is not None:
                    d["transform"] = obj.transform.to_dict()
            else:  # the vertices as they are now, the transform already applied
                d["vertices"] = obj.vertices.tolist()
                d["faces"] = obj.faces.tolist()
            return d
        d = {k: getattr(obj, k) for k in (f.name for f in dataclasses.fields(obj))}
        for k, v in list(d.items()):
            if isinstance(v, Transform):
                d[k] = v.to_dict()
            elif v is None:
                del d[k]
            elif isinstance(v, tuple):
                d[k] = [list(x) if isinstance(x, tuple) else x for x in v]
        return d

    return {
        "camera": plain(scene.camera),
        "render": plain(scene.render),
        "materials": {name: plain(m, ("name",)) for name, m in scene.materials.items()},
        "lights": [plain(light) for light in scene.lights],
        "objects": [unparse_object(obj) for obj in scene.objects],
    }


# --------------------------------------------------------------------------- world placement
# Shared by the core and the converters, so that every renderer places an object the same way.


def frame(origin: Vec3, axis: Vec3) -> np.ndarray:
    """A 4x4 matrix taking the z axis to ``axis`` (unit) and the origin to ``origin``."""
    z = np.asarray(axis, dtype=np.float64)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, y, z, origin
    return m


def to_world(obj: Box | Cylinder | Torus) -> np.ndarray:
    """The object's 4x4 object-to-world matrix: a box's own frame is the world's; a cylinder's
    has its base at the origin and its axis along +z; a torus's its centre at the origin and its
    axis along +z. The object's transform applies after that."""
    if isinstance(obj, Cylinder):
        axis = _sub(obj.top, obj.base)
        m = frame(obj.base, _unit(axis))
    elif isinstance(obj, Torus):
        m = frame(obj.center, obj.axis)
    else:
        m = np.eye(4)
    return obj.transform.matrix @ m if obj.transform is not None else m


def cylinder_height(obj: Cylinder) -> float:
    return _norm(_sub(obj.top, obj.base))


def triangles(obj: Triangle | Quad | Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """World-space vertices (n, 3), faces (m, 3) counter-clockwise from the front, and vertex
    normals (smooth meshes) or None."""
    if isinstance(obj, Mesh):
        return obj.vertices, obj.faces, obj.normals
    if isinstance(obj, Triangle):
        return np.array(obj.vertices, dtype=np.float64), np.array([[0, 1, 2]], np.int32), None
    c, e1, e2 = (np.asarray(v, dtype=np.float64) for v in (obj.corner, obj.edge1, obj.edge2))
    v = np.array([c, c + e1, c + e1 + e2, c + e2])
    if obj.transform is not None:
        m = obj.transform.matrix
        v = v @ m[:3, :3].T + m[:3, 3]
    return v, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32), None


def scene_extent(scene: Scene) -> float:
    """A length at least as big as the scene around the origin: the largest coordinate of the
    camera, lights and objects plus the largest object size. Converters use it to put parallel
    lights and stand-in planes far beyond everything."""
    points: list[Any] = [scene.camera.eye, scene.camera.look_at]
    points += [light.position for light in scene.lights if isinstance(light, PointLight)]
    size = 1.0
    for obj in scene.objects:
        if isinstance(obj, Sphere):
            points.append(obj.center)
            size = max(size, obj.radius)
        elif isinstance(obj, Plane):
            points.append(obj.point)
        elif isinstance(obj, Triangle | Quad | Mesh):
            v = triangles(obj)[0]
            points += [v.min(axis=0), v.max(axis=0)]
        else:
            m = to_world(obj)
            points.append(m[:3, 3])
            local = (
                max(np.abs(obj.min).max(), np.abs(obj.max).max())
                if isinstance(obj, Box)
                else (
                    cylinder_height(obj) + obj.radius
                    if isinstance(obj, Cylinder)
                    else obj.major_radius + obj.minor_radius
                )
            )
            size = max(size, float(np.abs(m[:3, :3]).max()) * 3 * local)
    return size + max(float(np.max(np.abs(p))) for p in points)
