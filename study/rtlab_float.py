"""rtlab's own robust algorithms in numpy, in a chosen precision: the method ``rtlab-float``
(issue 11, part 3: "rtlab's own algorithms in float"). The C++ core is double only; this is a
port of its primitives, function by function, with every constant that depends on the
precision derived from the dtype: gamma(n) from that type's unit roundoff, next_away() one
ulp of that type. Run in float64 it must decide every ray as the extension does and give t
within a few ulps (tests/study/test_rtlab_float.py holds it to that on the quick rays): that is
what makes the float32 run "rtlab's algorithms in float" rather than another formula.

Each function names the header and function it ports. Arithmetic is written in the order of
the C++ (the core is built with -ffp-contract=off, numpy never fuses either): dot() is
x + y + z left to right, Vec3's operator/ is a multiplication by the reciprocal, and so on.

What is not ported: the mesh's bounding volume hierarchy (16_mesh.h's traverse()); a mesh is
every triangle in turn with the range shrinking to the closest hit, which is what the
hierarchy computes (its slab tests are widened so that they never miss a box the ray touches).
A box here has the identity transform (the study's boxes are axis-aligned; 13_transform.h's
to_world() then changes no coordinate and only widens the error bound, which is ported).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from study.shapes import Box, Mesh, Plane, Shape, Sphere

Array = npt.NDArray[np.floating]


def gamma(n: int, dtype: type) -> np.floating:
    """02_ray.h gamma(): n u / (1 - n u), u the unit roundoff of ``dtype`` (2^-24 for float,
    2^-53 for double; Higham section 3.1, pbrt-v4 6.8.1)."""
    u = dtype(np.finfo(dtype).eps) * dtype(0.5)
    return (dtype(n) * u) / (dtype(1) - dtype(n) * u)


def _dot(a: Array, b: Array) -> Array:
    """01_vec3.h dot(): a.x b.x + a.y b.y + a.z b.z, left to right."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _cross(a: Array, b: Array) -> Array:
    """01_vec3.h cross()."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)  # fmt: skip


def _div(v: Array, s: Array) -> Array:
    """01_vec3.h Vec3::operator/(s): a multiplication by 1 / s."""
    inv = 1 / s
    return v * (inv[..., None] if np.ndim(inv) else inv)


def _normalize(v: Array) -> Array:
    """01_vec3.h normalize(): v / length(v)."""
    return _div(v, np.sqrt(_dot(v, v)))


def next_away(v: Array, off: Array) -> Array:
    """02_ray.h next_away(): the next number of v's type after v in the direction of off's sign
    (v itself where off is 0; the smallest subnormal of that sign where v is 0)."""
    inf = np.array(np.inf, dtype=v.dtype)
    return np.where(off == 0, v, np.nextafter(v, np.where(off > 0, inf, -inf)))


def offset_ray_origin(p: Array, p_error: Array, n: Array, toward: Array) -> Array:
    """02_ray.h offset_ray_origin() (pbrt-v4 6.8.6): p moved along the unit normal n by the
    distance its error box reaches along n, to the side ``toward`` points to, then one ulp
    further."""
    d = _dot(np.abs(n), p_error)
    offset = d[:, None] * n
    offset = np.where((_dot(toward, n) < 0)[:, None], -offset, offset)
    po = p + offset
    return next_away(po, offset)


# ------------------------------------------------------------------------------ 05_sphere.h


def sphere_t(c: Array, r: np.floating, o: Array, d: Array, tmax: Array) -> Array:
    """05_sphere.h sphere_t() with sphere_discriminant() (Haines et al. 2019, eq. 7.5) and
    quadratic_roots() (eq. 7.7) inlined: the nearest root in (0, tmax), or infinity."""
    inf = np.array(np.inf, dtype=o.dtype)
    f = o - c
    b = _dot(f, d)
    r2 = r * r
    c0 = _dot(f, f) - r2
    away = (c0 > 0) & (b > 0)  # outside and moving away: both roots negative
    a = _dot(d, d)
    inv_a = 1 / a
    l_ = f - (b * inv_a)[:, None] * d  # sphere_discriminant(): centre -> closest point
    disc = a * (r2 - _dot(l_, l_))
    q = -(b + np.copysign(np.sqrt(np.where(disc >= 0, disc, 0)), b))  # quadratic_roots()
    zero = q == 0  # b = D = 0: the double root t = 0
    qq = np.where(zero, 1, q)
    t0, t1 = np.where(zero, 0, c0 / qq), np.where(zero, 0, qq * inv_a)
    t0, t1 = np.minimum(t0, t1), np.maximum(t0, t1)
    t = np.where((t0 > 0) & (t0 < tmax), t0, np.where((t1 > 0) & (t1 < tmax), t1, inf))
    return np.where(away | ~(disc >= 0), inf, t)


def sphere_hit(c: Array, r: np.floating, o: Array, d: Array, t: Array) -> tuple[Array, ...]:
    """05_sphere.h sphere_hit(): the point projected onto the sphere (pbrt-v4 6.8.5), its
    error gamma(5) |local| + gamma(1) (|c| + |local|), the normal local / r."""
    g5, g1 = gamma(5, o.dtype.type), gamma(1, o.dtype.type)
    local = (o + t[:, None] * d) - c
    length = np.sqrt(_dot(local, local))
    degenerate = ~(length > 0)  # the point fell on the centre: take the side facing the ray
    local = np.where(degenerate[:, None], -d, local)
    length = np.where(degenerate, np.sqrt(_dot(local, local)), length)
    local = local * (r / length)[:, None]
    p = c + local
    p_error = g5 * np.abs(local) + g1 * (np.abs(c) + np.abs(local))
    return p, p_error, _div(local, r)


# ------------------------------------------------------------------------------- 06_plane.h


def plane_t(a: Array, n: Array, o: Array, d: Array) -> Array:
    """06_plane.h plane_t(): (a - o).n / d.n; infinity for a ray parallel to the plane."""
    denom = _dot(d, n)
    t = _dot(a - o, n) / np.where(denom == 0, 1, denom)
    return np.where(denom == 0, np.inf, t).astype(o.dtype)


def plane_hit(a: Array, n: Array, o: Array, d: Array, t: Array) -> tuple[Array, ...]:
    """06_plane.h plane_hit(): o + t d projected back onto the plane, error gamma(8) times the
    sum of |p| and |a|."""
    p = o + t[:, None] * d
    p = p - _dot(p - a, n)[:, None] * n
    ap = np.abs(p)
    e = gamma(8, o.dtype.type) * (ap[:, 0] + ap[:, 1] + ap[:, 2] + abs(a[0]) + abs(a[1])
                                  + abs(a[2]))  # fmt: skip
    return p, np.repeat(e[:, None], 3, axis=1), np.broadcast_to(n, p.shape).copy()


# ---------------------------------------------------------------------------- 13_transform.h

_IDENTITY = ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0))


def apply_identity(v: Array, w: int) -> Array:
    """13_transform.h Transform::apply() with a box's default transform, the identity, written
    out as the C++ computes it: M[i][0] v.x + M[i][1] v.y + M[i][2] v.z + M[i][3] w. Not a
    no-op: a direction component -0.0 comes out +0.0 (-0 + 0 = +0), and the slab test's
    answer for a ray in a face's plane depends on that sign ((face - o) / d = 0 * +-inf)."""
    dt = v.dtype.type
    return np.stack([dt(m[0]) * v[:, 0] + dt(m[1]) * v[:, 1] + dt(m[2]) * v[:, 2] + dt(m[3] * w)
                     for m in _IDENTITY], axis=1)  # fmt: skip


# --------------------------------------------------------------------------------- 14_box.h


def box_crossing(lo: Array, hi: Array, o: Array, d: Array, tmax: Array) -> tuple[Array, ...]:
    """14_box.h slab_interval() and box_crossing(): the overlap of the three slabs (a NaN slab,
    0 * infinity, fails both strict comparisons and changes nothing); the entry if in range,
    else the exit, with its axis and whether the ray enters there."""
    n = len(o)
    with np.errstate(divide="ignore"):
        inv_d = 1 / d
    t_enter = np.full(n, -np.inf, dtype=o.dtype)
    t_leave = np.full(n, np.inf, dtype=o.dtype)
    enter_axis = np.zeros(n, dtype=int)
    leave_axis = np.zeros(n, dtype=int)
    for axis in range(3):
        t0 = (lo[axis] - o[:, axis]) * inv_d[:, axis]
        t1 = (hi[axis] - o[:, axis]) * inv_d[:, axis]
        t0, t1 = np.where(t0 > t1, t1, t0), np.where(t0 > t1, t0, t1)
        later, earlier = t0 > t_enter, t1 < t_leave
        t_enter, enter_axis = np.where(later, t0, t_enter), np.where(later, axis, enter_axis)
        t_leave, leave_axis = np.where(earlier, t1, t_leave), np.where(earlier, axis, leave_axis)
    meets = t_enter <= t_leave
    enter = meets & (t_enter > 0) & (t_enter < tmax)
    leave = meets & ~enter & (t_leave > 0) & (t_leave < tmax)
    t = np.where(enter, t_enter, np.where(leave, t_leave, np.inf)).astype(o.dtype)
    return t, np.where(enter, enter_axis, leave_axis), enter


def box_hit(lo: Array, hi: Array, o: Array, d: Array, t: Array, axis: Array,
            entering: Array) -> tuple[Array, ...]:  # fmt: skip
    """14_box.h Box::hit() after box_crossing(): the point put on the face it crossed (exact),
    the other two coordinates' error gamma(5) (|o| + |t d|); then 13_transform.h to_world()
    with the identity: point_error() = (1 + gamma(3)) e + gamma(3) |p| (the products with the
    matrix's zeros and ones are exact), point() and normal() through apply_identity()."""
    dt = o.dtype.type
    rows = np.arange(len(o))
    p = o + t[:, None] * d
    d_axis = d[rows, axis]
    face = np.where(entering == (d_axis > 0), lo[axis], hi[axis])
    e = gamma(5, dt) * (np.abs(o) + np.abs(t[:, None] * d))
    p[rows, axis] = face
    e[rows, axis] = 0
    n = np.zeros_like(p)
    n[rows, axis] = np.where(face == lo[axis], -1, 1)
    e = (1 + gamma(3, dt)) * e + gamma(3, dt) * np.abs(p)
    return apply_identity(p, 1), e, _normalize(apply_identity(n, 0))


# ---------------------------------------------------------------------------- 15_triangle.h


def _watertight_ray(d: Array) -> tuple[Array, ...]:
    """15_triangle.h WatertightRay: the axis of d's largest component becomes z (kz), x and y
    keep the winding; the shear Sx, Sy, Sz."""
    a = np.abs(d)
    kz = np.where(a[:, 0] > a[:, 1], np.where(a[:, 0] > a[:, 2], 0, 2),
                  np.where(a[:, 1] > a[:, 2], 1, 2))  # fmt: skip
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    rows = np.arange(len(d))
    dz = d[rows, kz]
    return kx, ky, kz, -d[rows, kx] / dz, -d[rows, ky] / dz, 1 / dz


def triangle_t_error(xs: list[Array], ys: list[Array], zs: list[Array], e: list[Array],
                     inv_det: Array) -> Array:  # fmt: skip
    """15_triangle.h triangle_t_error(): pbrt-v4's conservative deltaT (6.8.3)."""
    dt = inv_det.dtype.type

    def mx(v: list[Array]) -> Array:
        return np.fmax(np.abs(v[0]), np.fmax(np.abs(v[1]), np.abs(v[2])))

    max_z, max_x, max_y = mx(zs), mx(xs), mx(ys)
    delta_z = gamma(3, dt) * max_z
    delta_x, delta_y = gamma(5, dt) * (max_x + max_z), gamma(5, dt) * (max_y + max_z)
    delta_e = 2 * (gamma(2, dt) * max_x * max_y + delta_y * max_x + delta_x * max_y)
    max_e = mx(e)
    return (3 * (gamma(3, dt) * max_e * max_z + delta_e * max_z + delta_z * max_e)
            * np.abs(inv_det))  # fmt: skip


def starts_off_the_plane_heading_in(p0: Array, p1: Array, p2: Array, o: Array,
                                    d: Array) -> Array:  # fmt: skip
    """15_triangle.h starts_off_the_plane_heading_in(): h = (o - p0).n and d.n with forward
    error bounds gamma(8), gamma(7) times the sums of absolute values."""
    dt = o.dtype.type
    v, e1, e2 = o - p0, p1 - p0, p2 - p0
    n = _cross(e1, e2)
    size = np.array([abs(e1[1] * e2[2]) + abs(e1[2] * e2[1]),
                     abs(e1[2] * e2[0]) + abs(e1[0] * e2[2]),
                     abs(e1[0] * e2[1]) + abs(e1[1] * e2[0])], dtype=dt)  # fmt: skip
    h, dn = _dot(v, n), _dot(d, n)
    h_error = gamma(8, dt) * _dot(np.abs(v), size)
    dn_error = gamma(7, dt) * _dot(np.abs(d), size)
    return (np.abs(h) > h_error) & (np.abs(dn) > dn_error) & ((h > 0) != (dn > 0))


@functools.cache
def _libm_fma() -> Callable[[float, float, float], float]:
    libm = ctypes.CDLL(ctypes.util.find_library("m") or "libm.so.6")
    libm.fma.restype = ctypes.c_double
    libm.fma.argtypes = (ctypes.c_double,) * 3
    return libm.fma  # type: ignore[no-any-return]


def fma(a: Array, b: Array, c: Array) -> Array:
    """a b + c rounded once, as std::fma. Double: the C library's fma, element by element (numpy
    has none; the faithfulness test in float64 needs the core's very bits). Float: the product
    of two floats is exact in double, the sum rounded to double and then to float (a double
    rounding, one float ulp off a true float fma in rare ties; the study measures float's errors
    in millions of ulps)."""
    if a.dtype == np.float64:
        f = np.frompyfunc(_libm_fma(), 3, 1)
        return f(a, b, c).astype(np.float64)  # type: ignore[no-any-return]
    wide = a.astype(np.float64) * b.astype(np.float64) + c.astype(np.float64)
    return wide.astype(a.dtype)


def difference_of_products(a: Array, b: Array, c: Array, d: Array) -> Array:
    """15_triangle.h difference_of_products(): a b - c d by Kahan's algorithm."""
    cd = c * d
    error = fma(-c, d, cd)
    return fma(a, b, -cd) + error


def intersect_triangle(p0: Array, p1: Array, p2: Array, o: Array, d: Array, ray: tuple,
                       tmax: Array) -> tuple[Array, Array]:  # fmt: skip
    """15_triangle.h intersect_triangle() (Woop, Benthin and Wald 2013; range (0, tmax]):
    t (infinity: no hit) and the barycentric coordinates (b0, b1, b2) as rows."""
    kx, ky, kz, sx, sy, sz = ray
    rows = np.arange(len(o))
    a, b, c = p0 - o, p1 - o, p2 - o

    def sheared(v: Array) -> tuple[Array, Array, Array]:
        vz = v[rows, kz]
        return v[rows, kx] + sx * vz, v[rows, ky] + sy * vz, sz * vz

    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = sheared(a), sheared(b), sheared(c)
    e0 = difference_of_products(bx, cy, by, cx)
    e1 = difference_of_products(cx, ay, cy, ax)
    e2 = difference_of_products(ax, by, ay, bx)
    outside = ((e0 < 0) | (e1 < 0) | (e2 < 0)) & ((e0 > 0) | (e1 > 0) | (e2 > 0))
    det = e0 + e1 + e2
    t_scaled = e0 * az + e1 * bz + e2 * cz
    lo = 0 * det  # range.min * det, range.min = 0
    with np.errstate(invalid="ignore"):  # tmax = inf and det = 0 (refused anyway)
        hi = tmax * det
    out_of_range = np.where(det < 0, (t_scaled >= lo) | (t_scaled < hi),
                            (t_scaled <= lo) | (t_scaled > hi))  # fmt: skip
    reject = outside | (det == 0) | out_of_range
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_det = 1 / det
        t = t_scaled * inv_det
        guard = t <= 0 + triangle_t_error([ax, bx, cx], [ay, by, cy], [az, bz, cz],
                                          [e0, e1, e2], inv_det)  # fmt: skip
    reject |= guard & ~starts_off_the_plane_heading_in(p0, p1, p2, o, d)
    bary = np.stack([e0 * inv_det, e1 * inv_det, e2 * inv_det], axis=1)
    return np.where(reject, np.inf, t).astype(o.dtype), bary


def triangle_hit(p0: Array, p1: Array, p2: Array, bary: Array) -> tuple[Array, ...]:
    """15_triangle.h triangle_hit(): p from the barycentric coordinates, its error gamma(7)
    (|b0 p0| + |b1 p1| + |b2 p2|) (pbrt-v4 eq. 6.29), the unit normal of the counter-clockwise
    side."""
    dt = p0.dtype.type
    b0, b1, b2 = (bary[:, k : k + 1] for k in range(3))
    p = b0 * p0 + b1 * p1 + b2 * p2
    e = gamma(7, dt) * (np.abs(b0 * p0) + np.abs(b1 * p1) + np.abs(b2 * p2))
    n = _normalize(_cross(p1 - p0, p2 - p0))
    return p, e, np.broadcast_to(n, p.shape).copy()


# ----------------------------------------------------------------------------- the method


def _triangles(shape: Shape, dt: type) -> list[tuple[Array, Array, Array]]:
    tris = shape.triangles() if isinstance(shape, Mesh) else [shape]
    return [tuple(np.array(v, dtype=dt) for v in (t.a, t.b, t.c)) for t in tris]  # type: ignore[misc]


def _first(shape: Shape, o: Array, d: Array, tmax: Array, want_hit: bool) -> tuple:
    """t of the closest hit in (0, tmax) (a triangle's range is (0, tmax]) and, when asked,
    the hit record (p, p_error, n) of each ray."""
    dt = o.dtype.type
    n = len(o)
    if isinstance(shape, Sphere):
        c, r = np.array(shape.center, dtype=dt), dt(shape.radius)
        t = sphere_t(c, r, o, d, tmax)
        return t, (sphere_hit(c, r, o, d, np.where(np.isfinite(t), t, 0)) if want_hit else None)
    if isinstance(shape, Plane):
        # 06_plane.h's normal is unit length: the scene loader makes it so in double
        # (tracer/scene/vectors.py unit()), bindings.cpp add_plane() normalises it again.
        from tracer.scene.vectors import unit

        a, nn = np.array(shape.point, dtype=dt), _normalize(np.array(unit(shape.normal), dtype=dt))
        with np.errstate(divide="ignore", invalid="ignore"):
            t = plane_t(a, nn, o, d)
        t = np.where((t > 0) & (t < tmax), t, np.inf).astype(dt)
        return t, (plane_hit(a, nn, o, d, np.where(np.isfinite(t), t, 0)) if want_hit else None)
    if isinstance(shape, Box):
        lo, hi = np.array(shape.lo, dtype=dt), np.array(shape.hi, dtype=dt)
        o, d = apply_identity(o, 1), apply_identity(d, 0)  # 14_box.h Box::hit(): to_object()
        with np.errstate(invalid="ignore"):
            t, axis, entering = box_crossing(lo, hi, o, d, tmax)
        rec = box_hit(lo, hi, o, d, np.where(np.isfinite(t), t, 0), axis, entering)
        return t, (rec if want_hit else None)
    # 16_mesh.h leaf_hit(): every triangle, the range shrinking to the closest hit so far.
    ray = _watertight_ray(d)
    best = np.array(tmax, dtype=dt, copy=True) if np.ndim(tmax) else np.full(n, tmax, dtype=dt)
    found = np.zeros(n, dtype=bool)
    p = np.zeros((n, 3), dtype=dt)
    e = np.zeros((n, 3), dtype=dt)
    nn = np.zeros((n, 3), dtype=dt)
    for p0, p1, p2 in _triangles(shape, dt):
        t, bary = intersect_triangle(p0, p1, p2, o, d, ray, best)
        closer = np.isfinite(t)
        if not closer.any():
            continue
        best = np.where(closer, t, best)
        found |= closer
        if want_hit:
            hp, he, hn = triangle_hit(p0, p1, p2, np.where(closer[:, None], bary, 0))
            p, e, nn = (np.where(closer[:, None], new, old)
                        for new, old in ((hp, p), (he, e), (hn, nn)))  # fmt: skip
    return np.where(found, best, np.inf).astype(dt), ((p, e, nn) if want_hit else None)


def port(dtype: type) -> tuple[Callable, Callable, Callable]:
    """The method's trace, spawn and occluded in ``dtype`` (np.float32: rtlab-float). The
    scene and the rays are rounded to dtype first, as a float renderer holds them."""
    from study.methods import Traced

    def trace(shape: Shape, o_in: npt.NDArray[np.float64], d_in: npt.NDArray[np.float64]) -> Traced:
        o, d = o_in.astype(dtype), d_in.astype(dtype)
        with np.errstate(all="ignore"):
            t, (p, e, n) = _first(shape, o, d, np.array(np.inf, dtype=dtype), True)
        hit = np.isfinite(t)
        f64 = np.float64
        return Traced(hit, t.astype(f64), p.astype(f64), e.astype(f64), n.astype(f64))

    def spawn(tr: Traced, toward: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        with np.errstate(all="ignore"):  # a missed ray's record is not spawned
            out = offset_ray_origin(tr.p.astype(dtype), tr.p_error.astype(dtype),  # type: ignore[union-attr]
                                    tr.n.astype(dtype), toward.astype(dtype))  # fmt: skip
        return out.astype(np.float64)

    def occluded(shape: Shape, o_in: npt.NDArray[np.float64], d_in: npt.NDArray[np.float64],
                 tmax: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]:  # fmt: skip
        """09_scene.h any_hit(): anything with t in (0, tmax) (sphere_blocks, plane_blocks,
        Object::blocks)."""
        o, d = o_in.astype(dtype), d_in.astype(dtype)
        with np.errstate(all="ignore"):
            t, _ = _first(shape, o, d, tmax.astype(dtype), False)
        return np.isfinite(t)

    return trace, spawn, occluded
