"""Triangle meshes for the shapes a renderer lacks: Mitsuba has no torus, a rasteriser
(pyrender) has only triangles. Every mesh here has its vertices on the true surface and the
true surface's normals at them, so the error is the sagitta of its facets, stated per shape."""

from __future__ import annotations

import numpy as np

from tracer.scene import Cylinder, Plane, Sphere, Torus, cylinder_height, frame, to_world

Mesh = tuple[np.ndarray, np.ndarray, np.ndarray]  # vertices, faces (counter-clockwise), normals

#: Segments around a torus's ring (and half as many around its tube): sagitta ~1.9e-5 (R + r).
TORUS_SEGMENTS = 512


def _grid_faces(n_u: int, n_v: int, wrap_v: bool = True) -> np.ndarray:
    """Two triangles per cell of an n_u x n_v grid of vertices, wrapping around u (and v)."""
    i, j = np.meshgrid(np.arange(n_u), np.arange(n_v if wrap_v else n_v - 1), indexing="ij")
    a = i * n_v + j
    b = ((i + 1) % n_u) * n_v + j
    c = ((i + 1) % n_u) * n_v + (j + 1) % n_v
    d = i * n_v + (j + 1) % n_v
    return np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                           np.stack([a, c, d], -1).reshape(-1, 3)]).astype(np.int32)  # fmt: skip


def _place(points: np.ndarray, normals: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    points = points @ m[:3, :3].T + m[:3, 3]
    normals = normals @ np.linalg.inv(m[:3, :3])  # the inverse transpose, applied to rows
    return points, normals / np.linalg.norm(normals, axis=1, keepdims=True)


def torus_mesh(obj: Torus, segments: int = TORUS_SEGMENTS) -> Mesh:
    n_ring, n_tube = segments, segments // 2
    u = np.linspace(0, 2 * np.pi, n_ring, endpoint=False)
    v = np.linspace(0, 2 * np.pi, n_tube, endpoint=False)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    R, r = obj.major_radius, obj.minor_radius
    normal = np.stack([np.cos(vv) * np.cos(uu), np.cos(vv) * np.sin(uu), np.sin(vv)], -1)
    ring = np.stack([R * np.cos(uu), R * np.sin(uu), np.zeros_like(uu)], -1)
    points = (ring + r * normal).reshape(-1, 3)
    points, normals = _place(points, normal.reshape(-1, 3), to_world(obj))
    return points, _grid_faces(n_ring, n_tube), normals


def sphere_mesh(obj: Sphere, segments: int = 256) -> Mesh:
    """A latitude-longitude sphere: sagitta r (1 - cos(pi / segments)) ~ 7.5e-5 r at 256."""
    n_lon, n_lat = segments, segments // 2 + 1
    lon = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    lat = np.linspace(-np.pi / 2, np.pi / 2, n_lat)
    ll, bb = np.meshgrid(lon, lat, indexing="ij")
    normal = np.stack([np.cos(bb) * np.cos(ll), np.cos(bb) * np.sin(ll), np.sin(bb)], -1)
    normal = normal.reshape(-1, 3)
    points = np.asarray(obj.center) + obj.radius * normal
    return points, _grid_faces(n_lon, n_lat, wrap_v=False), normal


def cylinder_mesh(obj: Cylinder, segments: int = 256) -> Mesh:
    """The side (and the caps when capped) of a cylinder: sagitta r (1 - cos(pi / segments))."""
    h, r = cylinder_height(obj), obj.radius
    a = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    ring = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], -1)
    side = np.concatenate([r * ring, r * ring + [0, 0, h]])
    side_n = np.concatenate([ring, ring])
    k = np.arange(segments)
    faces = [np.stack([k, (k + 1) % segments, segments + (k + 1) % segments], -1),
             np.stack([k, segments + (k + 1) % segments, segments + k], -1)]  # fmt: skip
    points, normals = [side], [side_n]
    if obj.capped:
        for z, up in ((0.0, -1.0), (h, 1.0)):
            base = sum(len(p) for p in points)
            points.append(np.concatenate([[[0, 0, z]], r * ring + [0, 0, z]]))
            normals.append(np.tile([0, 0, up], (segments + 1, 1)))
            fan = np.stack([np.zeros_like(k), 1 + k, 1 + (k + 1) % segments], -1) + base
            faces.append(fan if up > 0 else fan[:, [0, 2, 1]])
    p, n = _place(np.concatenate(points), np.concatenate(normals).astype(float), to_world(obj))
    return p, np.concatenate(faces).astype(np.int32), n


def plane_mesh(obj: Plane, centre: np.ndarray, half_size: float) -> Mesh:
    """A square of the plane, centred on ``centre``'s foot on it: two triangles."""
    n = np.asarray(obj.normal, dtype=np.float64)
    foot = centre - np.dot(centre - np.asarray(obj.point), n) * n
    m = frame(tuple(foot), tuple(n))
    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * half_size
    points = corners @ m[:3, :3].T + m[:3, 3]
    return points, np.array([[0, 1, 2], [0, 2, 3]], np.int32), np.tile(n, (4, 1))
