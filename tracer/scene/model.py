"""The scene model's parts: camera, render settings, materials, lights and objects, as frozen
dataclasses, once they have been validated; and the language's limits.

Nothing here reads TOML (tracer.scene.reading does) or places objects in world space
(tracer.scene.placement does); the whole ``Scene`` is in tracer.scene.document.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tracer.scene.vectors import Color, Vec3, cross, rotation, sub, unit

#: Image sizes are bounded so a typo (width = 1e9) fails at once instead of exhausting memory.
MAX_IMAGE_SIDE = 32768
#: 2^20 samples per pixel: far beyond any converged render (1024 spp is the references'), and
#: small enough that spp * pixels still counts in 64 bits.
MAX_SPP = 1 << 20
#: Levels of the ray tree: deep enough for any mirror corridor, small enough that a typo
#: (max_depth = 1e9) does not spin for hours.
MAX_DEPTH = 10000
INTEGRATORS = ("classic", "aov", "path")
ACCELERATIONS = ("bvh", "bounding_box", "none")
#: Where a pixel's spp > 1 samples lie (tracer/cpp/11_render.h for_each_sample()): one
#: jittered sample in each of a grid of strata, or Sobol's (0,2)-sequence, Owen-scrambled.
SAMPLERS = ("stratified", "sobol")


#: How a stereo pair's two eyes make one image (slide "Stereoscopy"): side by side (left eye
#: left), over and under (left eye on top), a red-cyan anaglyph, or one eye alone.
STEREO_LAYOUTS = ("side_by_side", "over_under", "anaglyph", "left", "right")


@dataclass(frozen=True)
class Stereo:
    """A stereo pair of cameras: the parallel-axis asymmetric frustum (tracer/cpp/03_camera.h
    stereo_eye()). The eyes sit eye_separation apart along the camera's right vector, both
    looking along its forward direction; their frusta coincide on the plane at distance
    ``convergence`` (world units, like eye_separation)."""

    eye_separation: float
    convergence: float
    layout: str = "side_by_side"


@dataclass(frozen=True)
class Camera:
    eye: Vec3
    look_at: Vec3
    up: Vec3 = (0.0, 1.0, 0.0)
    fov_y: float = 45.0  # vertical field of view, degrees
    width: int = 320  # of one eye's image when stereo
    height: int = 240
    stereo: Stereo | None = None  # None: a single camera

    @property
    def image_shape(self) -> tuple[int, int]:
        """(rows, columns) of the rendered image: both eyes' for side_by_side and over_under."""
        layout = self.stereo.layout if self.stereo is not None else None
        if layout == "side_by_side":
            return self.height, 2 * self.width
        if layout == "over_under":
            return 2 * self.height, self.width
        return self.height, self.width

    def one_eye(self) -> tuple[Vec3, Vec3, float]:
        """A one-eye stereo layout (``left``, ``right``) as tracer/cpp/03_camera.h stereo_eye()
        makes it: the eye's position, its look_at (moved with it: parallel axes) and its image
        window's shift along the camera's right vector, in image-plane units (the plane at
        distance 1). What the converters write, one eye per render."""
        st = self.stereo
        if st is None or st.layout not in ("left", "right"):
            raise ValueError("one_eye() needs a stereo camera of layout 'left' or 'right'")
        right = unit(cross(unit(sub(self.look_at, self.eye)), self.up))
        half = (-1 if st.layout == "left" else 1) * st.eye_separation / 2
        move = (half * right[0], half * right[1], half * right[2])
        eye = (self.eye[0] + move[0], self.eye[1] + move[1], self.eye[2] + move[2])
        look_at = (self.look_at[0] + move[0], self.look_at[1] + move[1], self.look_at[2] + move[2])
        return eye, look_at, -half / st.convergence


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
    #: Where a pixel's samples lie when spp > 1 (SAMPLERS).
    sampler: str = "stratified"


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
        r[:3, :3] = rotation(self.rotate_axis, self.rotate_degrees)
        t = np.eye(4)
        t[:3, 3] = self.translate
        return t @ r @ s

    def to_dict(self) -> dict[str, Any]:
        return {
            "scale": list(self.scale),
            "rotate": {"axis": list(self.rotate_axis), "degrees": self.rotate_degrees},
            "translate": list(self.translate),
        }


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
