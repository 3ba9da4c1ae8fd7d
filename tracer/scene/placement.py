"""Placement in world space, shared by the core and the converters so that every renderer
places an object the same way: object frames, object-to-world matrices, the triangles of flat
objects, smooth vertex normals, and the scene's extent."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from tracer.scene.model import (
    Box,
    Cylinder,
    Mesh,
    Object,
    Plane,
    PointLight,
    Quad,
    Sphere,
    Torus,
    Triangle,
)
from tracer.scene.vectors import Vec3, norm, sub, unit

if TYPE_CHECKING:  # scene_extent reads a whole scene; the scene's reading builds on placement
    from tracer.scene.document import Scene


def one_eye(scene: Scene, renderer: str) -> tuple[Vec3, Vec3, float]:
    """The eye, look_at and window shift of a one-eye stereo scene (Camera.one_eye()), for a
    converter whose renderer draws one camera per render; a layout that needs both eyes in one
    image is refused, naming the key and why (``renderer`` says how that renderer works)."""
    from tracer.scene.errors import SceneError

    layout = scene.camera.stereo.layout if scene.camera.stereo is not None else None
    if layout not in ("left", "right"):
        raise SceneError(
            scene.source,
            "camera.stereo.layout",
            f"expected 'left' or 'right' ({renderer}: convert each eye alone, "
            f"tracer.render.eye_scene), got {layout!r}",
        )
    return scene.camera.one_eye()


#: A frame's x axis comes from crossing the world x axis with its z axis, unless that z axis is
#: within ~26 degrees of x (|z.x| >= 0.9, where the cross product would lose digits); then from
#: the world y axis.
HELPER_SWITCH = 0.9


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


def frame(origin: Vec3, axis: Vec3) -> np.ndarray:
    """A 4x4 matrix taking the z axis to ``axis`` (unit) and the origin to ``origin``."""
    z = np.asarray(axis, dtype=np.float64)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < HELPER_SWITCH else np.array([0.0, 1.0, 0.0])
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
        axis = sub(obj.top, obj.base)
        m = frame(obj.base, unit(axis))
    elif isinstance(obj, Torus):
        m = frame(obj.center, obj.axis)
    else:
        m = np.eye(4)
    return obj.transform.matrix @ m if obj.transform is not None else m


def cylinder_height(obj: Cylinder) -> float:
    return norm(sub(obj.top, obj.base))


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
        where, extent = _points_and_size(obj)
        points += where
        size = max(size, extent)
    return size + max(float(np.max(np.abs(p))) for p in points)


def reach(obj: Object) -> float:
    """How far from the origin the object can reach: its largest coordinate plus its size."""
    where, extent = _points_and_size(obj)
    return extent + max(float(np.max(np.abs(p))) for p in where)


def _points_and_size(obj: Object) -> tuple[list[Any], float]:
    """Points the object lies around (world space) and a size it stays within about them."""
    if isinstance(obj, Sphere):
        return [obj.center], obj.radius
    if isinstance(obj, Plane):
        return [obj.point], 0.0
    if isinstance(obj, Triangle | Quad | Mesh):
        v = triangles(obj)[0]
        return [v.min(axis=0), v.max(axis=0)], 0.0
    m = to_world(obj)
    local = (
        max(np.abs(obj.min).max(), np.abs(obj.max).max())
        if isinstance(obj, Box)
        else (
            cylinder_height(obj) + obj.radius
            if isinstance(obj, Cylinder)
            else obj.major_radius + obj.minor_radius
        )
    )
    # |M v| <= 3 max|m_ij| max|v_i| for a 3x3 M: how far the transform can carry the object's
    # points from its origin.
    return [m[:3, 3]], float(np.abs(m[:3, :3]).max()) * 3 * local
