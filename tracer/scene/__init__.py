"""The scene language: TOML in, one validated scene model out.

The model is parsed and checked once; the C++ core and the converters read the model, never
the TOML. Every error names the file, the key path (``objects[2].radius``) and what was
expected; an unknown key suggests the near spelling.

One job per module, all re-exported here (``from tracer.scene import X`` is the contract):

- ``model``: the dataclasses a scene is made of, and the language's limits; ``document``: the
  whole ``Scene``;
- ``reading``, ``settings`` and ``objects``: TOML and dicts in, validated through
  ``values.Reader``; ``brightness``: scenes whose image could overflow float32 refused;
- ``unparse``: a scene back to the scene language (``Scene.to_dict``);
- ``placement``: world-space frames, matrices and triangles, shared by core and converters;
- ``errors``: ``SceneError``; ``vectors``: small tuple helpers.

Imports run one way, from ``document`` and ``reading`` down to ``vectors``.
"""

from tracer.scene.document import Scene
from tracer.scene.errors import SceneError
from tracer.scene.model import (
    ACCELERATIONS,
    INTEGRATORS,
    MAX_DEPTH,
    MAX_IMAGE_SIDE,
    MAX_SPP,
    SAMPLERS,
    STEREO_LAYOUTS,
    Box,
    Camera,
    Cylinder,
    DirectionalLight,
    Light,
    Material,
    Mesh,
    Object,
    Plane,
    PointLight,
    Quad,
    RenderSettings,
    Sphere,
    Stereo,
    Torus,
    Transform,
    Triangle,
)
from tracer.scene.objects import resolve_file
from tracer.scene.placement import (
    cylinder_height,
    frame,
    scene_extent,
    to_world,
    triangles,
    vertex_normals,
)
from tracer.scene.reading import load_scene, loads_scene, parse_scene
from tracer.scene.vectors import Color, Vec3

__all__ = [
    "ACCELERATIONS",
    "INTEGRATORS",
    "MAX_DEPTH",
    "MAX_IMAGE_SIDE",
    "MAX_SPP",
    "SAMPLERS",
    "STEREO_LAYOUTS",
    "Box",
    "Camera",
    "Color",
    "Cylinder",
    "DirectionalLight",
    "Light",
    "Material",
    "Mesh",
    "Object",
    "Plane",
    "PointLight",
    "Quad",
    "RenderSettings",
    "Scene",
    "SceneError",
    "Sphere",
    "Stereo",
    "Torus",
    "Transform",
    "Triangle",
    "Vec3",
    "cylinder_height",
    "frame",
    "load_scene",
    "loads_scene",
    "parse_scene",
    "resolve_file",
    "scene_extent",
    "to_world",
    "triangles",
    "vertex_normals",
]
