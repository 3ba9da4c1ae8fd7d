"""Scene model -> pyrender (offscreen OpenGL rasterisation), for the geometry alone.

A rasteriser shares no code and no algorithm with a ray tracer, which makes it a good judge of
the camera, of visibility (which object covers each pixel centre) and of depth. It sees
triangles only: spheres, cylinders and tori are tessellated (converters/tessellate.py, error
stated there), planes become squares PLANE_SCALE scene sizes wide. Its depth buffer holds the
depth along the camera's axis, not the distance along the ray: ``ray_depth`` converts.
"""

from __future__ import annotations

import os

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")  # headless; before OpenGL is imported

import numpy as np

from converters.tessellate import cylinder_mesh, plane_mesh, sphere_mesh, torus_mesh
from tracer.scene import (
    Box,
    Cylinder,
    Mesh,
    Plane,
    Quad,
    Scene,
    Sphere,
    Torus,
    Triangle,
    to_world,
    triangles,
)

#: Planes become squares reaching this many times the camera's distance to the farthest other
#: object; the far clipping plane lies just beyond them. The depth buffer's precision falls with
#: far/near, so neither is made bigger than the scene needs.
PLANE_SCALE = 20.0
#: The near clipping plane, as a share of the distance from the eye to look_at.
NEAR_SHARE = 0.02


def object_mesh(obj: object, eye: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    """World-space vertices and faces of one object."""
    if isinstance(obj, Sphere):
        v, f, _ = sphere_mesh(obj)
    elif isinstance(obj, Plane):
        v, f, _ = plane_mesh(obj, eye, half)
    elif isinstance(obj, Cylinder):
        v, f, _ = cylinder_mesh(obj)
    elif isinstance(obj, Torus):
        v, f, _ = torus_mesh(obj)
    elif isinstance(obj, Box):
        import trimesh

        box = trimesh.creation.box(bounds=[obj.min, obj.max])
        m = to_world(obj)
        v, f = np.asarray(box.vertices) @ m[:3, :3].T + m[:3, 3], np.asarray(box.faces)
    elif isinstance(obj, Triangle | Quad | Mesh):
        v, f, _ = triangles(obj)
    else:
        raise TypeError(f"no pyrender conversion for {type(obj).__name__}")
    return np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64)


def camera_pose(scene: Scene) -> np.ndarray:
    """Camera-to-world: OpenGL cameras look down -z with +y up and +x to the right."""
    cam = scene.camera
    eye, at, up = (np.asarray(v, dtype=np.float64) for v in (cam.eye, cam.look_at, cam.up))
    forward = (at - eye) / np.linalg.norm(at - eye)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = right, true_up, -forward, eye
    return pose


def render_geometry(scene: Scene) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Rasterise the scene: camera-axis depth (0 where nothing), the index of the object in
    [[objects]] covering each pixel centre (-1 where nothing), the near clipping distance and
    the half size of the squares standing in for planes."""
    import pyrender
    import trimesh

    cam = scene.camera
    if cam.stereo is not None:  # an off-axis window is no pyrender.PerspectiveCamera
        raise ValueError(f"{scene.source}: camera.stereo: pyrender renders single cameras only")
    eye = np.asarray(cam.eye, dtype=np.float64)
    meshes = {i: object_mesh(obj, eye, 0.0) for i, obj in enumerate(scene.objects)
              if not isinstance(obj, Plane)}  # fmt: skip
    reach = max([np.linalg.norm(v - eye, axis=1).max() for v, _ in meshes.values()]
                + [np.linalg.norm(np.asarray(cam.look_at) - eye)])  # fmt: skip
    half = PLANE_SCALE * reach
    out = pyrender.Scene(bg_color=[0, 0, 0, 0])
    seg = {}
    for i, obj in enumerate(scene.objects):
        v, f = meshes[i] if i in meshes else object_mesh(obj, eye, half)
        # Both windings: a ray tracer sees back faces too, which OpenGL culls (pyrender's
        # segmentation pass culls even with a double-sided material).
        both = np.concatenate([f, f[:, ::-1]])
        mesh = trimesh.Trimesh(vertices=v, faces=both, process=False)
        node = out.add(pyrender.Mesh.from_trimesh(mesh, smooth=False))
        # The segmentation colour is the object's index + 1, spread over three bytes.
        k = i + 1
        seg[node] = [k & 0xFF, (k >> 8) & 0xFF, (k >> 16) & 0xFF]
    # A 24-bit depth buffer resolves camera depth z to about z^2 / (near 2^24): the relative
    # error z / (near 2^24) grows with far/near, so near sits as far out as is safe: geometry
    # nearer the eye than 2% of its distance to look_at would be clipped (and show as pixels
    # whose object differs from the tracer's).
    far = 2 * half
    near = NEAR_SHARE * float(np.linalg.norm(np.asarray(cam.look_at) - eye))
    aspect = cam.width / cam.height
    camera = pyrender.PerspectiveCamera(yfov=np.radians(cam.fov_y), aspectRatio=aspect,
                                        znear=near, zfar=far)  # fmt: skip
    out.add(camera, pose=camera_pose(scene))
    renderer = pyrender.OffscreenRenderer(cam.width, cam.height)
    try:
        depth = renderer.render(out, flags=pyrender.RenderFlags.DEPTH_ONLY)
        colors, _ = renderer.render(out, flags=pyrender.RenderFlags.SEG, seg_node_map=seg)
    finally:
        renderer.delete()
    ids = colors[..., 0].astype(np.int64) | (colors[..., 1].astype(np.int64) << 8)
    ids |= colors[..., 2].astype(np.int64) << 16
    return np.asarray(depth, dtype=np.float64), ids - 1, near, half


def ray_depth(scene: Scene) -> np.ndarray:
    """Per pixel, the factor from camera-axis depth to distance along the primary ray through
    the pixel centre: 1 / cos(angle to the axis) = |(x w, y h, 1)| on the image plane."""
    cam = scene.camera
    h = 2 * np.tan(np.radians(cam.fov_y) / 2)
    w = h * cam.width / cam.height
    x = (np.arange(cam.width) + 0.5) / cam.width - 0.5
    y = 0.5 - (np.arange(cam.height) + 0.5) / cam.height
    xx, yy = np.meshgrid(x * w, y * h)
    return np.sqrt(xx**2 + yy**2 + 1)
