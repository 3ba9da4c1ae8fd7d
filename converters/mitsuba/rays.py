"""The shared vocabulary (tracer/cpp's names) for the rays the classic integrator spawns.

The C++ core's ``face_the_ray``, ``secondary_ray``, ``shadow_ray_to`` and
``shadow_ray_towards`` (pbrt-v4's SpawnRay and SpawnRayTo, RTIOW's set_face_normal), written on
Dr.Jit for the integrator that runs the classic model inside Mitsuba. Mitsuba's hit carries no
error bound, so where the core moves an origin off the surface by the hit's ``p_error`` along
Ng, these move it by ``ray_offset(p)`` along the new ray's own direction: the ray stays on the
line through p, and the offset clears Mitsuba's float32 intersection error (see ray_offset).
Points and directions are double (Point3d, Vector3d); the rays handed to Mitsuba are float32.
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi

#: How far a new ray starts along its direction, relative to the size of the hit's coordinates:
#: 2^-16 is ~256 float32 ulps (float32 has a 24-bit significand), clear of Mitsuba's float32
#: intersection error, yet far below any feature of a scene in the unit range.
RAY_OFFSET = 2.0**-16
#: The length of a shadow ray towards a light infinitely far away: beyond any scene whose
#: float32 coordinates Mitsuba can intersect with meaning (a plane's stand-in disk is 1e6 scene
#: sizes across).
FAR = 1e30


def ray_offset(p: Any) -> Any:
    """How far a ray leaving the hit p starts off the surface (the core's p_error)."""
    return (1.0 + dr.max(dr.abs(p))) * RAY_OFFSET


def face_the_ray(Ng: Any, N: Any, d: Any) -> tuple[Any, Any]:
    """The geometric normal Ng turned to the side the incoming direction d comes from, and the
    shading normal N turned to Ng's side: "the side we see is the side we shade". Returns
    (N, Ng), both facing the ray."""
    Ng = dr.select(dr.dot(Ng, d) > 0, -Ng, Ng)
    N = dr.select(dr.dot(N, Ng) < 0, -N, N)
    return N, Ng


def secondary_ray(p: Any, p_error: Any, direction: Any) -> tuple[Any, Any]:
    """A ray leaving the surface at p towards ``direction``, its origin moved off the surface
    by ``p_error`` along the direction: (origin, direction), in double."""
    return p + p_error * direction, direction


def shadow_ray_to(p: Any, p_error: Any, point: Any) -> Any:
    """A float32 ray from the surface at p to ``point``, blocked by anything between them.

    Mitsuba's rays carry a unit direction and a ``maxt``; the segment is the one from the offset
    origin to the point (the core's t in (0, 1) is this ray's (0, maxt))."""
    to = mi.Point3d(point) - p
    distance = dr.norm(to)
    L = to / distance
    ray = mi.Ray3f(mi.Point3f(p + p_error * L), mi.Vector3f(L))
    ray.maxt = mi.Float(distance - p_error)
    return ray


def shadow_ray_towards(p: Any, p_error: Any, direction: Any) -> Any:
    """A float32 ray from the surface at p towards a light infinitely far along ``direction``
    (unit), blocked by anything on the way."""
    ray = mi.Ray3f(mi.Point3f(p + p_error * direction), mi.Vector3f(direction))
    ray.maxt = mi.Float(mi.Float64(FAR) - p_error)
    return ray
