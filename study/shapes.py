"""The primitives a study case is made of, as the scene language describes them: the same
numbers go to every method and to the ground truth (study/truth.py), nothing else."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

Vec = tuple[float, float, float]


def _scale(v: Vec, s: float) -> Vec:
    return (v[0] * s, v[1] * s, v[2] * s)


@dataclass(frozen=True)
class Sphere:
    center: Vec
    radius: float
    kind = "sphere"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "sphere", "center": list(self.center), "radius": self.radius}

    def scaled(self, s: float) -> Sphere:
        return Sphere(_scale(self.center, s), self.radius * s)


@dataclass(frozen=True)
class Plane:
    point: Vec
    normal: Vec  # as described; the core normalises it, the truth need not (same plane)
    kind = "plane"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "plane", "point": list(self.point), "normal": list(self.normal)}

    def scaled(self, s: float) -> Plane:
        return Plane(_scale(self.point, s), self.normal)


@dataclass(frozen=True)
class Triangle:
    a: Vec
    b: Vec
    c: Vec
    kind = "triangle"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "triangle", "vertices": [list(self.a), list(self.b), list(self.c)]}

    def scaled(self, s: float) -> Triangle:
        return Triangle(_scale(self.a, s), _scale(self.b, s), _scale(self.c, s))


@dataclass(frozen=True)
class Box:
    lo: Vec
    hi: Vec
    kind = "box"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "box", "min": list(self.lo), "max": list(self.hi)}

    def scaled(self, s: float) -> Box:
        return Box(_scale(self.lo, s), _scale(self.hi, s))


@dataclass(frozen=True)
class Mesh:
    """Triangles sharing vertices (a closed mesh: every edge in two faces, opposite ways)."""

    vertices: tuple[Vec, ...]
    faces: tuple[tuple[int, int, int], ...]
    kind = "mesh"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "mesh", "vertices": [list(v) for v in self.vertices],
                "faces": [list(f) for f in self.faces]}  # fmt: skip

    def scaled(self, s: float) -> Mesh:
        return Mesh(tuple(_scale(v, s) for v in self.vertices), self.faces)

    def triangles(self) -> list[Triangle]:
        v = self.vertices
        return [Triangle(v[i], v[j], v[k]) for i, j, k in self.faces]


def as_mesh(shape: Triangle | Box | Mesh) -> Mesh:
    """The shape as triangles: a triangle as a one-triangle mesh, a box as its 12 triangles
    (each face two, counter-clockwise seen from outside), for renderers that only have meshes."""
    if isinstance(shape, Mesh):
        return shape
    if isinstance(shape, Triangle):
        return Mesh((shape.a, shape.b, shape.c), ((0, 1, 2),))
    lo, hi = shape.lo, shape.hi
    corners = tuple(tuple(hi[k] if i >> k & 1 else lo[k] for k in range(3)) for i in range(8))
    quads = ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5))
    faces = tuple(f for a, b, c, d in quads for f in ((a, b, c), (a, c, d)))
    return Mesh(corners, faces)


# ------------------------------------------------- appended for issue 11's scene families
# (study/families_scenes.py, study/truth_scenes.py: cylinders, nearly touching surfaces)


@dataclass(frozen=True)
class Cylinder:
    """A capped cylinder from ``base`` to ``top`` (its axis the segment between them), as the
    scene language describes it (tracer/scene/objects.py); the core places its own z axis on
    the segment with a frame matrix (tracer/scene/placement.py frame()), exact for an axis
    along a coordinate axis."""

    base: Vec
    top: Vec
    radius: float
    kind = "cylinder"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "cylinder", "base": list(self.base), "top": list(self.top),
                "radius": self.radius}  # fmt: skip

    def scaled(self, s: float) -> Cylinder:
        return Cylinder(_scale(self.base, s), _scale(self.top, s), self.radius * s)


@dataclass(frozen=True)
class Group:
    """Several shapes in one scene (its scene objects are the members', in order): the first
    surface a ray meets is one of them, named by its index."""

    members: tuple[Sphere | Plane | Cylinder, ...]
    kind = "group"

    def scene_objects(self) -> list[dict[str, Any]]:
        return [m.scene_object() for m in self.members]

    def scene_object(self) -> dict[str, Any]:
        return {"type": "group", "members": self.scene_objects()}

    def scaled(self, s: float) -> Group:
        return Group(tuple(m.scaled(s) for m in self.members))


@dataclass(frozen=True)
class RotatedBox(Box):
    """A box [lo, hi] in its own coordinates, placed by the scene language's transform (rotate
    about ``axis`` by ``degrees``, then translate): the world box is A p + b for the 3x4 matrix
    [A | b] that tracer/scene/model.py Transform.matrix computes in double, the very numbers the
    core is given (tracer/render.py). The truth (study/truth_scenes.py) takes that matrix as
    exact: the rounding of the rotation to doubles is the scene's, shared by every method."""

    axis: Vec = (0.0, 0.0, 1.0)
    degrees: float = 0.0
    translate: Vec = (0.0, 0.0, 0.0)
    kind = "rbox"

    def scene_object(self) -> dict[str, Any]:
        return super().scene_object() | {"transform": {
            "rotate": {"axis": list(self.axis), "degrees": self.degrees},
            "translate": list(self.translate)}}  # fmt: skip

    def scaled(self, s: float) -> RotatedBox:
        return RotatedBox(_scale(self.lo, s), _scale(self.hi, s), self.axis, self.degrees,
                          _scale(self.translate, s))  # fmt: skip

    def matrix(self) -> Any:
        """The 3x4 object-to-world matrix, as the core gets it."""
        from tracer.scene.model import Transform

        return Transform(rotate_axis=self.axis, rotate_degrees=self.degrees,
                         translate=self.translate).matrix[:3]  # fmt: skip


@dataclass(frozen=True)
class PinholeCamera:
    """A pinhole camera given as POV-Ray's perspective camera takes it, every vector explicit
    (no look_at, no angle: nothing for the renderer to compute): pixel (i, j) of a width x
    height image looks along direction + x0 right + y0 up (study/families_torus.py pixel_rays())."""

    location: Vec
    direction: Vec
    right: Vec
    up: Vec
    width: int
    height: int


@dataclass(frozen=True)
class Torus:
    """A ring torus around the axis z through ``center``: the points at distance
    ``minor_radius`` from the circle of radius ``major_radius`` in the plane z = center.z (the
    scene language's torus with axis (0, 0, 1): its frame moves by the centre alone, exactly).
    ``camera``: set where the case's rays are that camera's pixel rays, row by row (POV-Ray
    traces nothing else); it changes the kind, not the surface."""

    center: Vec
    major_radius: float
    minor_radius: float
    camera: PinholeCamera | None = None

    @property
    def kind(self) -> str:
        return "torus" if self.camera is None else "torus-camera"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "torus", "center": list(self.center), "axis": [0.0, 0.0, 1.0],
                "major_radius": self.major_radius, "minor_radius": self.minor_radius}  # fmt: skip

    def scaled(self, s: float) -> Torus:
        return Torus(_scale(self.center, s), self.major_radius * s, self.minor_radius * s)


Shape = Sphere | Plane | Triangle | Box | Mesh | Torus


# ------------------------------------- appended for issue 11's transformed self-intersection
# (study/families_placed.py, study/truth_placed.py: cylinders and tori under random transforms)


@dataclass(frozen=True)
class Placement:
    """The scene language's transform (tracer/scene/objects.py): scale, then rotate about
    ``axis`` by ``degrees``, then translate."""

    scale: Vec = (1.0, 1.0, 1.0)
    axis: Vec = (0.0, 0.0, 1.0)
    degrees: float = 0.0
    translate: Vec = (0.0, 0.0, 0.0)

    def scene_transform(self) -> dict[str, Any]:
        return {"scale": list(self.scale),
                "rotate": {"axis": list(self.axis), "degrees": self.degrees},
                "translate": list(self.translate)}  # fmt: skip

    def scaled(self, s: float) -> Placement:
        """The placement followed by a scale by s: s T R S = T(s t) R (s S), exact for s a
        power of two."""
        return Placement(_scale(self.scale, s), self.axis, self.degrees, _scale(self.translate, s))


@functools.lru_cache(maxsize=256)
def _placed_matrix(shape: PlacedCylinder | PlacedTorus) -> tuple[tuple[float, ...], ...]:
    return _core_matrix(shape.scene_object())


def _core_matrix(obj: dict[str, Any]) -> tuple[tuple[float, ...], ...]:
    """The 3x4 object-to-world matrix the core is given for a cylinder or torus scene object:
    the scene read by the scene language, then tracer/scene/placement.py to_world(), as
    tracer/render.py to_core() does (the object's own frame, then its transform)."""
    import tracer
    from tracer.scene.placement import to_world

    scene = tracer.load_scene({
        "camera": {"eye": [0.0, 0.0, 1.0], "look_at": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
                   "fov_y": 30.0, "width": 1, "height": 1},
        "materials": {"m": {"color": [1.0, 1.0, 1.0]}},
        "objects": [obj | {"material": "m"}],
    })  # fmt: skip
    return tuple(tuple(float(x) for x in row) for row in to_world(scene.objects[0])[:3])


@dataclass(frozen=True)
class PlacedCylinder:
    """A capped cylinder in its own coordinates (base at the origin, axis +z, ``height`` long)
    placed in the world by ``placement``: the core's cylinder (tracer/cpp/17_cylinder.h) with
    the matrix ``matrix()``, which the truth takes as exact. The kind says whether the cross
    section stays a circle (equal x and y scale: Mitsuba's cylinder can take it) or not."""

    radius: float
    height: float
    placement: Placement
    kind_circular = "placed-cylinder"
    kind_elliptic = "placed-elliptic-cylinder"

    @property
    def kind(self) -> str:
        s = self.placement.scale
        return self.kind_circular if s[0] == s[1] else self.kind_elliptic

    def local(self) -> Cylinder:
        return Cylinder((0.0, 0.0, 0.0), (0.0, 0.0, self.height), self.radius)

    def scene_object(self) -> dict[str, Any]:
        return self.local().scene_object() | {"transform": self.placement.scene_transform()}

    def scaled(self, s: float) -> PlacedCylinder:
        return PlacedCylinder(self.radius, self.height, self.placement.scaled(s))

    def matrix(self) -> tuple[tuple[float, ...], ...]:
        return _placed_matrix(self)


@dataclass(frozen=True)
class PlacedTorus:
    """A ring torus in its own coordinates (centre at the origin, axis +z) placed in the world
    by ``placement`` (tracer/cpp/18_torus.h with the matrix ``matrix()``)."""

    major_radius: float
    minor_radius: float
    placement: Placement
    kind = "placed-torus"

    def local(self) -> Torus:
        return Torus((0.0, 0.0, 0.0), self.major_radius, self.minor_radius)

    def scene_object(self) -> dict[str, Any]:
        return self.local().scene_object() | {"transform": self.placement.scene_transform()}

    def scaled(self, s: float) -> PlacedTorus:
        return PlacedTorus(self.major_radius, self.minor_radius, self.placement.scaled(s))

    def matrix(self) -> tuple[tuple[float, ...], ...]:
        return _placed_matrix(self)


Placed = PlacedCylinder | PlacedTorus
