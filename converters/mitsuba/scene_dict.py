"""The scene model as a dict for ``mi.load_dict``: sensor, sampler and film; Mitsuba's own
emitters; shapes (planes as large disks, boxes as cubes, cylinders with cap disks, triangle
meshes and tessellated tori as PLY files); classic scenes with the ``rtlab_classic`` integrator
and ``rtlab_classic_material`` BSDFs, path scenes with Mitsuba's ``path`` integrator and the
path tracer's materials as BSDFs (converters.mitsuba.path_bsdf)."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import mitsuba as mi
import numpy as np

from converters.mitsuba.classic import NAME as CLASSIC_PLUGIN
from converters.mitsuba.classic_material import NAME as MATERIAL_PLUGIN
from converters.mitsuba.mixed import NAME as MIXED_PLUGIN
from converters.mitsuba.phong import NAME as PHONG_PLUGIN
from converters.tessellate import torus_mesh
from tracer.image import atomic_path
from tracer.scene import (
    Box,
    Cylinder,
    DirectionalLight,
    Plane,
    PointLight,
    Scene,
    Sphere,
    Torus,
    cylinder_height,
    frame,
    scene_extent,
    to_world,
    triangles,
)
from tracer.scene.placement import one_eye

#: Planes become Mitsuba disks of this many scene sizes in radius, centred below the camera: a
#: ray must pass within ~1/PLANE_SCALE radians of the horizon to miss one, far below a pixel's
#: angle. A disk, unlike a rectangle (a triangle mesh in Mitsuba 3.9, whose float32 vertices
#: would lie 1e6 units out), is intersected in its local frame, where the distance along the
#: normal keeps its precision whatever the radius.
PLANE_SCALE = 1.0e6
#: Mitsuba's path integrator starts Russian roulette at this depth (its own default), as the
#: core's path tracer does (tracer/cpp/20_path.h: "as Mitsuba, from the fifth bounce").
RR_DEPTH = 5


def plane_matrix(plane: Plane, radius: float, eye: tuple[float, float, float]) -> np.ndarray:
    """to_world of a disk (unit radius at z = 0, normal +z) standing in for a plane, centred on
    the point of the plane nearest the eye."""
    n = np.array(plane.normal, dtype=np.float64)
    centre = np.array(eye) - np.dot(np.array(eye) - plane.point, n) * n
    return frame(centre, plane.normal) @ np.diag([radius, radius, 1.0, 1.0])


def _sampler(scene: Scene) -> dict[str, Any]:
    if scene.render.spp == 1:  # exactly the pixel centre, as the tracer and POV-Ray -A do
        return {"type": "stratified", "sample_count": 1, "jitter": False}
    return {"type": "independent", "sample_count": scene.render.spp, "seed": scene.render.seed}


def to_mitsuba_dict(scene: Scene, *, mesh_dir: str | os.PathLike[str] | None = None) -> dict:
    """The scene as a dict for ``mi.load_dict`` (call ``use_variant`` first). Triangle meshes
    (triangles, quads, meshes, tessellated tori) go to PLY files in ``mesh_dir`` (by default a
    directory that lives as long as the process)."""
    cam, ren = scene.camera, scene.render
    meshes = Path(mesh_dir) if mesh_dir is not None else _process_mesh_dir()
    if ren.integrator == "path":
        return _path_dict(scene, meshes)
    d: dict[str, Any] = {
        "type": "scene",
        "integrator": {
            "type": CLASSIC_PLUGIN,
            "max_depth": ren.max_depth,
            "min_coefficient": ren.min_coefficient,
            "background": mi.ScalarColor3f(ren.background),
            "ambient_light": mi.ScalarColor3f(ren.ambient_light),
        },
        "sensor": _sensor(scene, _sampler(scene)),
    }
    d.update(_lights(scene))
    half = PLANE_SCALE * scene_extent(scene)
    for i, obj in enumerate(scene.objects):
        m = scene.materials[obj.material]
        bsdf: dict[str, Any] = {
            "type": MATERIAL_PLUGIN,
            "color": mi.ScalarColor3f(m.color),
            "ambient": m.ambient,
            "diffuse": m.diffuse,
            "specular": m.specular,
            "shininess": m.shininess,
            "reflectivity": m.reflectivity,
        }
        for k, shape in enumerate(_shapes(obj, i, half, cam.eye, meshes, bsdf)):
            d[f"object_{i}" + (f"_{k}" if k else "")] = {**shape, "bsdf": dict(bsdf)}
    return d


def _lights(scene: Scene) -> dict[str, Any]:
    """Mitsuba's own point (colour as intensity) and directional (colour as irradiance)
    emitters. The classic integrator reads them back as classic light colours; Mitsuba's path
    integrator uses them as the physical quantities they are."""
    out: dict[str, Any] = {}
    for i, light in enumerate(scene.lights):
        color = mi.ScalarColor3f(light.color)
        if isinstance(light, PointLight):
            out[f"light_{i}"] = {"type": "point", "position": mi.ScalarPoint3f(light.position),
                                 "intensity": color}  # fmt: skip
        elif isinstance(light, DirectionalLight):
            out[f"light_{i}"] = {"type": "directional",
                                 "direction": mi.ScalarVector3f(light.direction),
                                 "irradiance": color}  # fmt: skip
    return out


def _sensor(scene: Scene, sampler: dict[str, Any]) -> dict[str, Any]:
    cam = scene.camera
    eye, look_at, stereo = cam.eye, cam.look_at, {}
    if cam.stereo is not None:
        # One eye of a stereo pair (tracer/cpp/03_camera.h stereo_eye()): the eye moved, its
        # window shifted. Mitsuba's principal point offset is a fraction of the film's width,
        # positive moving the window to the image's right, as rtlab's shift (found by rendering:
        # the opposite sign puts 15% of the pixels over tolerance; the fraction of the height
        # instead of the width would miss by a pixel; tests/reference/test_stereo_references.py).
        eye, look_at, shift = one_eye(scene, "Mitsuba's sensor is one eye")
        plane_width = 2 * math.tan(math.radians(cam.fov_y) / 2) * cam.width / cam.height
        stereo = {"principal_point_offset_x": shift / plane_width}
    return {
        "type": "perspective",
        "fov": cam.fov_y,
        "fov_axis": "y",
        **stereo,
        "to_world": mi.ScalarTransform4f().look_at(origin=eye, target=look_at, up=cam.up),
        "sampler": sampler,
        "film": {
            "type": "hdrfilm",
            "width": cam.width,
            "height": cam.height,
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
            "component_format": "float32",
        },
    }


def path_bsdf(m: Any) -> dict[str, Any]:
    """A path-traced material as Mitsuba BSDFs: the sum albedo/pi + Phong(specular) +
    mirror(reflectivity) (20_path.h). Mitsuba's blendbsdf mixes (1 - w) A + w B; a left fold of
    blends with weights w_k / W_k (W_k the running sum of the lobes' weights w_i) gives lobe i
    the factor w_i / W, so each lobe is built W times its own strength: the sum comes out exact.
    Built-in plugins where they exist (diffuse, conductor as a perfect mirror), the Phong lobe
    in Python. Wrapped in twosided: rtlab shades both sides of a surface."""
    albedo = np.array(m.color) * m.diffuse
    a = float(albedo.max())

    def diffuse(k: float) -> dict[str, Any]:
        return {"type": "diffuse", "reflectance": mi.ScalarColor3f(albedo * k / a)}

    def phong(k: float) -> dict[str, Any]:
        return {"type": PHONG_PLUGIN, "specular": float(k), "shininess": m.shininess}

    def mirror(k: float) -> dict[str, Any]:
        reflectance = mi.ScalarColor3f(k, k, k)
        return {"type": "conductor", "material": "none", "specular_reflectance": reflectance}

    # (weight, the lobe built for a factor)
    lobes = [(w, build) for w, build in ((a, diffuse), (m.specular, phong),
                                         (m.reflectivity, mirror)) if w > 0]  # fmt: skip
    if not lobes:
        return {"type": "diffuse", "reflectance": mi.ScalarColor3f(0, 0, 0)}
    if m.reflectivity > 0 and len(lobes) > 1:  # the mirror with another lobe: see MixedLobes
        mixed = {"type": MIXED_PLUGIN, "albedo": mi.ScalarColor3f(albedo),
                 "specular": m.specular, "shininess": m.shininess,
                 "reflectivity": m.reflectivity}  # fmt: skip
        return {"type": "twosided", "bsdf": mixed}
    total = sum(w for w, _ in lobes)
    bsdf = lobes[0][1](total)
    running = lobes[0][0]
    for w, build in lobes[1:]:
        running += w
        bsdf = {"type": "blendbsdf", "weight": w / running, "bsdf_0": bsdf, "bsdf_1": build(total)}
    return {"type": "twosided", "bsdf": bsdf}


def _path_dict(scene: Scene, meshes: Path) -> dict[str, Any]:
    """A path-traced scene for Mitsuba's own path integrator (max_depth counted alike)."""
    ren = scene.render
    sampler = {"type": "independent", "sample_count": ren.spp, "seed": ren.seed}
    d: dict[str, Any] = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": ren.max_depth, "rr_depth": RR_DEPTH},
        "sensor": _sensor(scene, sampler),
    }
    if max(ren.background) > 0:
        d["environment"] = {"type": "constant", "radiance": mi.ScalarColor3f(ren.background)}
    d.update(_lights(scene))
    half = PLANE_SCALE * scene_extent(scene)
    for i, obj in enumerate(scene.objects):
        m = scene.materials[obj.material]
        for k, shape in enumerate(_shapes(obj, i, half, scene.camera.eye, meshes, {})):
            shape["bsdf"] = path_bsdf(m)
            if max(m.emission) > 0:
                shape["emitter"] = {"type": "area", "radiance": mi.ScalarColor3f(m.emission)}
            d[f"object_{i}" + (f"_{k}" if k else "")] = shape
    return d


def _transform(m: np.ndarray) -> Any:
    return mi.ScalarTransform4f(np.asarray(m, dtype=np.float64).tolist())


def _shapes(obj: Any, i: int, half: float, eye: Any, meshes: Path, bsdf: dict) -> list[dict]:
    """Mitsuba shapes for one object (a capped cylinder needs three)."""
    if isinstance(obj, Sphere):
        return [{"type": "sphere", "center": mi.ScalarPoint3f(obj.center), "radius": obj.radius}]
    if isinstance(obj, Plane):
        return [{"type": "disk", "to_world": _transform(plane_matrix(obj, half, eye))}]
    if isinstance(obj, Box):  # Mitsuba's cube is [-1, 1]^3
        lo, hi = np.array(obj.min), np.array(obj.max)
        fit = np.diag([*((hi - lo) / 2), 1.0])
        fit[:3, 3] = (hi + lo) / 2
        return [{"type": "cube", "to_world": _transform(to_world(obj) @ fit)}]
    if isinstance(obj, Cylinder):  # Mitsuba's cylinder has no caps: add two discs
        m = to_world(obj)
        h, r = cylinder_height(obj), obj.radius
        side = {"type": "cylinder", "p0": mi.ScalarPoint3f(0, 0, 0),
                "p1": mi.ScalarPoint3f(0, 0, h), "radius": r}  # fmt: skip
        shapes = [{**side, "to_world": _transform(m)}]
        if obj.capped:  # a disc's normal is its +z: the base's is turned to face down
            for z, flip in ((0.0, -1.0), (h, 1.0)):
                disc = np.diag([r, r * flip, flip, 1.0])
                disc[2, 3] = z
                shapes.append({"type": "disk", "to_world": _transform(m @ disc)})
        return shapes
    if isinstance(obj, Torus):
        vertices, faces, normals = torus_mesh(obj)
        m = to_world(obj)
        axis = m[:3, 2] / np.linalg.norm(m[:3, 2])
        scale = float(np.cbrt(abs(np.linalg.det(m[:3, :3]))))
        bsdf.update(torus_center=mi.ScalarPoint3f(m[:3, 3]), torus_axis=mi.ScalarVector3f(axis),
                    torus_major_radius=obj.major_radius * scale,
                    torus_minor_radius=obj.minor_radius * scale)  # fmt: skip
        return [_ply(meshes / f"object_{i}.ply", vertices, faces, normals)]
    vertices, faces, normals = triangles(obj)
    return [_ply(meshes / f"object_{i}.ply", vertices, faces, normals)]


#: A torus has no Mitsuba shape: converters.tessellate.torus_mesh makes it a smooth mesh of
#: 512 x 256 quads (around the ring, around the tube), which lies inside the true torus by at
#: most the sagitta (R + r)(1 - cos(pi / 512)) ~ 1.9e-5 (R + r): silhouettes move by far less
#: than a pixel. Its facets would bend the normal by up to ~pi/512 and its interpolated normals
#: by ~(pi/512)^2 / 8, which a Phong exponent of 40 makes up to ~1e-3 in value; so the
#: integrator moves each hit onto the true torus (its BSDF carries centre, axis and radii) and
#: shades it there. The expected difference is confined to silhouettes, where a ray that grazes
#: the true surface can miss the facets or the reverse (reference.metrics.MAX_SHARE_TESSELLATED).


def _ply(path: Path, vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None) -> dict:
    """Write a binary PLY (with vertex normals where smooth) and the Mitsuba shape reading it."""
    import trimesh

    path.parent.mkdir(parents=True, exist_ok=True)
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    if normals is not None:
        mesh.vertex_normals = normals
    data = trimesh.exchange.ply.export_ply(mesh, encoding="binary",
                                           vertex_normal=normals is not None)  # fmt: skip
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return {"type": "ply", "filename": str(path), "face_normals": normals is None}


_mesh_dir: Path | None = None


def _process_mesh_dir() -> Path:
    global _mesh_dir
    if _mesh_dir is None:
        import atexit
        import shutil
        import tempfile

        _mesh_dir = Path(tempfile.mkdtemp(prefix="rtlab-mitsuba-"))
        atexit.register(shutil.rmtree, _mesh_dir, True)
    return _mesh_dir
