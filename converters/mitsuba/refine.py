"""The double-precision hit refinement of the classic integrator.

Mitsuba decides visibility in float32 (``ray_intersect``, ``ray_test``); the shading, as in the
C++ core, is done in double: the hit is recomputed from the shape's own parameters, so that a
comparison measures the model and Mitsuba's visibility, not float32 round-off in the shading.
The shape's parameters come as a row of the integrator's shape table (``g``, keyed by
converters.mitsuba.classic.ROW): its kind, a point (``ax, ay, az``), a radius, a normal or axis
(``nx, ny, nz``) and a torus's minor radius.
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi

#: The kinds of shape the table knows: spheres, planes (disks), tori (tessellated meshes that
#: carry their true shape) and everything else, whose hit Mitsuba's own float32 one stays.
SPHERE, PLANE, OTHER, TORUS = 0.0, 1.0, 2.0, 3.0
#: Newton steps on the torus: the tessellated hit lies within a sagitta (~1e-5 of the radii) of
#: the true one and each step squares the relative error, 1e-5 -> 1e-10 -> 1e-20: two reach
#: double precision, the third is margin for hits farther off (near silhouettes).
TORUS_NEWTON_STEPS = 3
#: A Newton step along a ray that meets the torus at a glancing angle (|N.d| below this) would
#: throw t far off; it is not taken, and the tessellated hit is kept.
GRAZING_SLOPE = 1e-3


def sphere_hit(g: dict[str, Any], o: Any, d: Any, t_mitsuba: Any) -> tuple[Any, Any]:
    """The root of the robust quadratic (tracer/cpp/05_sphere.h) nearest to Mitsuba's t."""
    center = mi.Point3d(g["ax"], g["ay"], g["az"])
    f = o - center
    a = dr.dot(d, d)
    b = dr.dot(f, d)
    r2 = g["radius"] * g["radius"]
    l = f - (b / a) * d  # noqa: E741  (Haines et al.'s name)
    disc = dr.maximum(a * (r2 - dr.dot(l, l)), 0.0)
    q = -(b + dr.copysign(dr.sqrt(disc), b))
    t0, t1 = (dr.dot(f, f) - r2) / q, q / a
    t = dr.select(dr.abs(t0 - t_mitsuba) < dr.abs(t1 - t_mitsuba), t0, t1)
    # A ray that grazes the sphere exactly (q = 0) has no stable second root: keep Mitsuba's.
    t = _finite_or(t, t_mitsuba)
    return t, (o + t * d - center) / g["radius"]


def plane_hit(g: dict[str, Any], o: Any, d: Any) -> tuple[Any, Any]:
    """(a - o).n / (d.n), the plane's implicit form."""
    n = mi.Vector3d(g["nx"], g["ny"], g["nz"])
    t = dr.dot(mi.Point3d(g["ax"], g["ay"], g["az"]) - o, n) / dr.dot(d, n)
    return t, n


def _finite_or(t: Any, fallback: Any) -> Any:
    """A ray parallel to a plane in double that Mitsuba's float32 still counted as a hit: keep
    Mitsuba's t rather than an infinite one."""
    return dr.select(dr.isfinite(t), t, fallback)


def torus_hit(g: dict[str, Any], o: Any, d: Any, t_mitsuba: Any) -> tuple[Any, Any]:
    """The hit on the true torus, and its normal: Newton's method on the torus's distance
    function along the ray, from the tessellated mesh's hit, which lies within a sagitta
    (~1e-5 of the radii) of it. The distance function's gradient is the unit normal N, so each
    step is t -= (|p - ring| - r) / (N.d); three steps reach double precision from there. (Near
    grazing, N.d -> 0, a step is not taken.)"""
    centre = mi.Point3d(g["ax"], g["ay"], g["az"])
    axis = mi.Vector3d(g["nx"], g["ny"], g["nz"])
    t = t_mitsuba
    n = mi.Vector3d(0.0)
    for _ in range(TORUS_NEWTON_STEPS):
        p = o + t * d
        local = p - centre
        radial = local - dr.dot(local, axis) * axis
        ring = centre + radial * (g["radius"] / dr.norm(radial))
        to_p = p - ring
        distance = dr.norm(to_p)
        n = to_p / distance
        slope = dr.dot(n, d)
        step = (distance - g["minor"]) / slope
        t = dr.select(dr.abs(slope) > GRAZING_SLOPE, t - step, t)
    return t, n


def refine_hit(
    g: dict[str, Any], o: Any, d: Any, t_mitsuba: Any, N_mitsuba: Any, Ng_mitsuba: Any
) -> tuple[Any, Any, Any]:
    """The hit's t, its shading normal N and its geometric normal Ng (outward, unit) in double,
    from the shape's parameters. A sphere's, a plane's and a torus's N is their Ng; any other
    shape keeps Mitsuba's (a smooth mesh's interpolated N, its triangle's Ng)."""
    if not dr.is_jit_v(mi.Float):  # scalar: one ray, one kind of shape
        if g["kind"] == SPHERE:
            t, n = sphere_hit(g, o, d, t_mitsuba)
        elif g["kind"] == PLANE:
            t, n = plane_hit(g, o, d)
            t = _finite_or(t, t_mitsuba)
        elif g["kind"] == TORUS:
            t, n = torus_hit(g, o, d, t_mitsuba)
        else:
            return t_mitsuba, dr.normalize(N_mitsuba), dr.normalize(Ng_mitsuba)
        n = dr.normalize(n)
        return t, n, n
    t_sphere, n_sphere = sphere_hit(g, o, d, t_mitsuba)
    t_plane, n_plane = plane_hit(g, o, d)
    t_plane = _finite_or(t_plane, t_mitsuba)
    t_torus, n_torus = torus_hit(g, o, d, t_mitsuba)
    is_sphere, is_plane, is_torus = g["kind"] == SPHERE, g["kind"] == PLANE, g["kind"] == TORUS
    analytic = is_sphere | is_plane | is_torus
    t = dr.select(is_sphere, t_sphere, dr.select(is_plane, t_plane, t_mitsuba))
    n = dr.select(is_sphere, n_sphere, dr.select(is_plane, n_plane, N_mitsuba))
    t = dr.select(is_torus, t_torus, t)
    n = dr.select(is_torus, n_torus, n)
    N = dr.normalize(n)
    Ng = dr.select(analytic, N, dr.normalize(Ng_mitsuba))
    return t, N, Ng
