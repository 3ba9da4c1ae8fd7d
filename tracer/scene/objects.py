"""Reading the objects of a scene: spheres, planes, boxes, triangles, quads, meshes (inline or
from PLY/OBJ files), cylinders and tori, and their transforms."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from tracer.scene.errors import SceneError
from tracer.scene.model import (
    Box,
    Cylinder,
    Material,
    Mesh,
    Object,
    Plane,
    Quad,
    Sphere,
    Torus,
    Transform,
    Triangle,
)
from tracer.scene.placement import vertex_normals
from tracer.scene.values import Reader, describe, suggest
from tracer.scene.vectors import cross, norm, sub, unit

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


def read_object(
    r: Reader, data: Any, path: str, materials: Mapping[str, Material], base_dir: Path
) -> Object:
    kind = r.kind(data, path, _OBJECT_KEYS)
    t = r.table(data, path, _OBJECT_KEYS[kind], what=f"a {kind}")
    material = r.string(t, path, "material", required=True)
    if material not in materials:
        known = ", ".join(sorted(materials)) or "none are defined"
        raise SceneError(
            r.source,
            f"{path}.material",
            f"unknown material {material!r}{suggest(material, materials)} (defined: {known})",
        )
    transform = _transform(r, t, path) if "transform" in t else None
    if kind == "sphere":
        center = r.vec3(t, path, "center", required=True)
        radius = r.number(t, path, "radius", required=True, above=0)
        return Sphere(center=center, radius=radius, material=material)
    if kind == "plane":
        point = r.vec3(t, path, "point", required=True)
        normal = r.vec3(t, path, "normal", required=True, nonzero=True)
        return Plane(point=point, normal=unit(normal), material=material)
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
        if norm(cross(sub(vs[1], vs[0]), sub(vs[2], vs[0]))) == 0:
            raise r.fail(f"{path}.vertices", "expected a triangle of non-zero area")
        return Triangle(vertices=(vs[0], vs[1], vs[2]), material=material)
    if kind == "quad":
        corner = r.vec3(t, path, "corner", required=True)
        e1 = r.vec3(t, path, "edge1", required=True, nonzero=True)
        e2 = r.vec3(t, path, "edge2", required=True, nonzero=True)
        if norm(cross(e1, e2)) == 0:
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
    if minor > major:
        # A spindle torus passes through itself: its quartic's roots then include the inner
        # ("lemon") surface, which 18_torus.h's refinement would move onto the outer one.
        raise r.fail(
            f"{path}.minor_radius",
            f"expected at most major_radius ({major:g}), got {minor:g}: a torus whose tube is "
            "wider than its ring (a spindle torus) passes through itself",
        )
    return Torus(center=center, axis=unit(axis), major_radius=major, minor_radius=minor,
                 material=material, transform=transform)  # fmt: skip


def _transform(r: Reader, t: Mapping[str, Any], path: str) -> Transform:
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
    r: Reader,
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


def resolve_file(r: Reader | None, key: str, name: str, base_dir: Path) -> Path:
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


def _read_mesh_file(r: Reader, key: str, file: Path) -> tuple[np.ndarray, np.ndarray]:
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


def _triangulate(r: Reader, value: Any, key: str, n_vertices: int) -> np.ndarray:
    """Faces as lists of vertex indices (three or more, counter-clockwise): fans of triangles."""
    if not isinstance(value, list) or not value:
        raise r.fail(key, f"expected an array of faces, got {describe(value)}")
    out = []
    for i, face in enumerate(value):
        indices = isinstance(face, list) and all(
            isinstance(v, int) and not isinstance(v, bool) for v in face
        )
        if not indices or len(face) < 3:
            raise r.fail(
                f"{key}[{i}]", f"expected three or more vertex indices, got {describe(face)}"
            )
        bad = [v for v in face if not 0 <= v < n_vertices]
        if bad:
            raise r.fail(
                f"{key}[{i}]",
                f"expected vertex indices 0..{n_vertices - 1} (the mesh has {n_vertices} "
                f"vertices), got {bad[0]}",
            )
        out += [[face[0], face[k], face[k + 1]] for k in range(1, len(face) - 1)]
    return np.array(out, dtype=np.int32)
