"""The methods side by side. Each has a name, a version string and three functions on a batch
of rays: ``trace`` (the first hit: hit, t, the point, its error bound where the method keeps
one, the normal), ``spawn`` (where a ray leaving a hit towards a direction starts) and
``occluded`` (whether anything lies at t in (0, tmax): a shadow ray).

- ``rtlab``: the renderer's own code through the extension (tracer/rays.py: closest_hit,
  any_hit, offset_ray_origin), in double.
- ``textbook-double`` / ``textbook-float``: the formulas as textbooks print them, in numpy in
  float64 / float32: the naive quadratic b^2 - 4ac and (-b -+ sqrt) / 2a, Moeller-Trumbore,
  the slab test, t = (p0 - o).n / d.n, and a fixed offset of 1e-4 along the normal for spawned
  rays. The float one rounds the scene and the rays to float32 first, as a float renderer does:
  that rounding is part of its error (it is judged on the double rays, like every method).
- ``rtlab-float``: rtlab's own robust algorithms (the same headers, ported to numpy in
  study/rtlab_float.py) in float32, with gamma(n) of float's unit roundoff and its own spawn
  (offset_ray_origin by its own error bound) and occluded: what robustness buys in float,
  beside textbook-float.
- ``mitsuba-scalar_rgb`` / ``mitsuba-llvm_ad_rgb``: mi.Scene.ray_intersect on the same rays
  (spheres; triangles, meshes and boxes as an mi.Mesh of their triangles), version
  mi.__version__; spawned rays by Mitsuba's own SurfaceInteraction3f.spawn_ray (offset by its
  own error estimate), shadow rays by Scene.ray_test, shortened as spawn_ray_to does.
- ``embree`` / ``embree-robust``: Embree's rtcIntersect1 through embreex (its EmbreeScene's
  ``robust`` flag sets RTC_SCENE_FLAG_ROBUST), triangles, meshes and boxes as triangles in
  float, version "embreex X / Embree Y"; shadow rays by rtcOccluded1; Embree has no spawn, so
  what its user does: tnear = 0.001f on a ray from the hit point (Embree's tutorials).
"""

from __future__ import annotations

import contextlib
import functools
import gc
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from study import methods_torus, rtlab_float
from study.shapes import Mesh, Plane, Shape, Sphere, Torus, Triangle, as_mesh

Array = npt.NDArray[np.float64]
#: The textbook's fixed offset for spawned rays (the 1e-4 of countless course tracers).
EPSILON = 1e-4


@dataclass(frozen=True)
class Traced:
    hit: npt.NDArray[np.bool_]
    t: Array  # inf on a miss
    p: Array
    p_error: Array | None  # None: the method keeps no error bound
    n: Array  # the geometric normal (outward for closed shapes, the plane's own)


@dataclass(frozen=True)
class Method:
    name: str
    version: str
    kinds: frozenset[str]  # the shapes it applies to
    trace: Callable[[Shape, Array, Array], Traced]
    spawn: Callable[[Traced, Array], Array]
    occluded: Callable[[Shape, Array, Array, Array], npt.NDArray[np.bool_]]
    precision: str  # "double" or "float"
    #: The case protocols (study/families.py) it is measured on: first hits only where spawn and
    #: occluded are not written for it.
    protocols: frozenset[str] = frozenset({"decision", "spawn", "shadow", "scale"})
    #: Whether its hits carry a t: POV-Ray's image tells hit from miss only (its t is a
    #: placeholder, and the t metrics are left out of its rows).
    reports_t: bool = True


# ------------------------------------------------------------------------------------ rtlab


@functools.lru_cache(maxsize=64)
def _core_scene(shape: Shape) -> object:
    import tracer
    from tracer.render import to_core

    # A triangle as a one-triangle mesh: the scene language refuses a zero-area "triangle", a
    # mesh's face it keeps (the same flat-mesh code path, tracer/render.py).
    described = as_mesh(shape) if isinstance(shape, Triangle) else shape
    obj = described.scene_object() | {"material": "m"}
    scene = tracer.load_scene(
        {
            "camera": {
                "eye": [0.0, 0.0, 1.0],
                "look_at": [0.0, 0.0, 0.0],
                "up": [0.0, 1.0, 0.0],
                "fov_y": 30.0,
                "width": 1,
                "height": 1,
            },
            "materials": {"m": {"color": [1.0, 1.0, 1.0]}},
            "objects": [obj],
        }
    )
    return to_core(scene)


def _rtlab_trace(shape: Shape, o: Array, d: Array) -> Traced:
    from tracer import rays

    h = rays.intersect(_core_scene(shape), o, d)
    return Traced(h.hit, h.t, h.p, h.p_error, h.Ng)


def _rtlab_spawn(tr: Traced, toward: Array) -> Array:
    from tracer import rays

    return rays.offset_ray_origin(tr.p, tr.p_error, tr.n, toward)


def _rtlab_occluded(shape: Shape, o: Array, d: Array, tmax: Array) -> npt.NDArray[np.bool_]:
    from tracer import rays

    return rays.occluded(_core_scene(shape), o, d, tmax)


# --------------------------------------------------------------------------------- textbook


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _nearest(parts: list[Traced]) -> Traced:
    """The nearest hit of each ray over the parts (a mesh's triangles)."""
    ts = np.stack([p.t for p in parts])
    k = np.argmin(ts, axis=0)
    rows = np.arange(ts.shape[1])
    pick = np.stack([p.p for p in parts])[k, rows]
    nn = np.stack([p.n for p in parts])[k, rows]
    t = ts[k, rows]
    return Traced(np.isfinite(t), t, pick, None, nn)


def _textbook(dtype: type) -> Callable[[Shape, Array, Array], Traced]:
    def trace(shape: Shape, o_in: Array, d_in: Array) -> Traced:
        if isinstance(shape, Mesh):
            return _nearest([trace(tr, o_in, d_in) for tr in shape.triangles()])
        if shape.kind in ("cylinder", "rbox"):  # issue 11's scenes: study/methods_scenes.py
            from study.methods_scenes import TEXTBOOK

            return TEXTBOOK[shape.kind](shape, o_in, d_in, dtype)
        if shape.kind in PLACED:  # under a transform: study/methods_placed.py
            from study.methods_placed import TEXTBOOK as PLACED_TEXTBOOK

            return PLACED_TEXTBOOK[shape.kind](shape, o_in, d_in, dtype)  # type: ignore[arg-type]
        if isinstance(shape, Torus):  # Suffern's quartic, Schwarze's solver: study/methods_torus.py
            return methods_torus.textbook_trace(dtype)(shape, o_in, d_in)  # type: ignore[operator]
        o, d = o_in.astype(dtype), d_in.astype(dtype)
        with np.errstate(all="ignore"):
            if isinstance(shape, Sphere):
                c, r = np.array(shape.center, dtype=dtype), dtype(shape.radius)
                f = o - c
                a, b, c0 = _dot(d, d), 2 * _dot(f, d), _dot(f, f) - r * r
                disc = b * b - 4 * a * c0  # b^2 - 4ac, as printed
                sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
                t0, t1 = (-b - sq) / (2 * a), (-b + sq) / (2 * a)
                t = np.where(t0 > 0, t0, np.where(t1 > 0, t1, np.inf))
                t = np.where(disc >= 0, t, np.inf)
                hit = np.isfinite(t)
                p = o + t[:, None] * d
                n = (p - c) / r
            elif isinstance(shape, Plane):
                nn = np.array(shape.normal, dtype=dtype)
                nn = nn / np.sqrt(_dot(nn, nn))
                den = _dot(d, nn)
                t = _dot(np.array(shape.point, dtype=dtype) - o, nn) / den
                hit = (t > 0) & np.isfinite(t)
                t = np.where(hit, t, np.inf)
                p = o + t[:, None] * d
                n = np.broadcast_to(nn, o.shape)
            elif isinstance(shape, Triangle):
                # Moeller and Trumbore 1997, with det == 0 as the parallel test (the paper's
                # fixed 1e-6 would refuse every triangle below 1e-3 in size: another story).
                v0, v1, v2 = (np.array(v, dtype=dtype) for v in (shape.a, shape.b, shape.c))
                e1, e2 = v1 - v0, v2 - v0
                pv = np.cross(d, e2)
                det = _dot(pv, np.broadcast_to(e1, pv.shape))
                inv = 1 / det
                s = o - v0
                u = _dot(s, pv) * inv
                q = np.cross(s, e1)
                v = _dot(d, q) * inv
                t = _dot(np.broadcast_to(e2, q.shape), q) * inv
                hit = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
                t = np.where(hit, t, np.inf)
                p = o + t[:, None] * d
                ng = np.cross(e1, e2)
                n = np.broadcast_to(ng / np.sqrt(_dot(ng, ng)), o.shape)
            else:
                lo, hi = np.array(shape.lo, dtype=dtype), np.array(shape.hi, dtype=dtype)
                inv = 1 / d
                ta, tb = (lo - o) * inv, (hi - o) * inv
                near = np.max(np.minimum(ta, tb), axis=1)
                far = np.min(np.maximum(ta, tb), axis=1)
                t = np.where(near > 0, near, far)
                hit = (near <= far) & (t > 0)
                t = np.where(hit, t, np.inf)
                p = o + t[:, None] * d
                # The face whose slab the hit lies on: the axis of the nearest bound.
                dist = np.minimum(np.abs(p - lo), np.abs(p - hi))
                axis = np.argmin(dist, axis=1)
                sign = np.where(np.abs(p - hi) < np.abs(p - lo), 1, -1)[np.arange(len(p)), axis]
                n = np.zeros_like(p)
                n[np.arange(len(p)), axis] = sign
        return Traced(hit, t.astype(np.float64), p.astype(np.float64), None,
                      np.asarray(n, dtype=np.float64))  # fmt: skip

    return trace


def _textbook_spawn(dtype: type) -> Callable[[Traced, Array], Array]:
    def spawn(tr: Traced, toward: Array) -> Array:
        p, n = tr.p.astype(dtype), tr.n.astype(dtype)
        with np.errstate(all="ignore"):  # a missed ray's point is inf: it is not spawned
            side = np.where(_dot(toward.astype(dtype), n) < 0, -1, 1).astype(dtype)
            return (p + (dtype(EPSILON) * side)[:, None] * n).astype(np.float64)

    return spawn


def _textbook_occluded(dtype: type) -> Callable[[Shape, Array, Array, Array], np.ndarray]:
    trace = _textbook(dtype)

    def occluded(shape: Shape, o: Array, d: Array, tmax: Array) -> npt.NDArray[np.bool_]:
        tr = trace(shape, o, d)
        return tr.hit & (tr.t < tmax.astype(dtype))

    return occluded


# ---------------------------------------------------------------------------------- Mitsuba


@functools.lru_cache(maxsize=4)
def _mitsuba(variant: str) -> object:
    import mitsuba as mi

    from converters.mitsuba import variants  # noqa: F401  (sets DRJIT_LIBLLVM_PATH first)

    mi.set_variant(variant)
    return mi


def _use(mi: Any, variant: str) -> None:
    """Switch Mitsuba to ``variant`` only if it is not the current one: a switch costs about
    5 ms (measured: 1200 round trips scalar_rgb <-> llvm_ad_rgb in 11.5 s), which a timed call
    would otherwise count as the method's time."""
    if mi.variant() != variant:
        mi.set_variant(variant)


@functools.lru_cache(maxsize=32)
def _mi_scene(variant: str, shape: Shape) -> object:
    mi = _mitsuba(variant)
    _use(mi, variant)
    if isinstance(shape, Sphere):
        return mi.load_dict(
            {
                "type": "scene",
                "s": {"type": "sphere", "center": list(shape.center), "radius": shape.radius},
            }
        )
    if shape.kind == "cylinder":  # no caps: measured on rays that cannot meet one (grazing)
        c = shape.scene_object()  # type: ignore[attr-defined]
        cyl = {"type": "cylinder", "p0": c["base"], "p1": c["top"], "radius": c["radius"]}
        level = mi.log_level()  # its float frame warns of a shear of an ulp: its own rounding
        mi.set_log_level(mi.LogLevel.Error)
        try:
            return mi.load_dict({"type": "scene", "c": cyl})
        finally:
            mi.set_log_level(level)
    if shape.kind == "placed-cylinder":  # study/methods_placed.py
        from study.methods_placed import mitsuba_cylinder

        level = mi.log_level()
        mi.set_log_level(mi.LogLevel.Error)
        try:
            return mi.load_dict({"type": "scene", "c": mitsuba_cylinder(mi, shape)})  # type: ignore[arg-type]
        finally:
            mi.set_log_level(level)
    # Triangles: an mi.Mesh filled through traverse() (Mitsuba keeps vertices in float32).
    mesh = as_mesh(shape)  # type: ignore[arg-type]
    v = np.asarray(mesh.vertices, dtype=np.float32).ravel()
    f = np.asarray(mesh.faces, dtype=np.uint32).ravel()
    m = mi.Mesh("m", vertex_count=len(mesh.vertices), face_count=len(mesh.faces),
                has_vertex_normals=False, has_vertex_texcoords=False)  # fmt: skip
    params = mi.traverse(m)
    scalar = variant.startswith("scalar")
    params["vertex_positions"] = v.tolist() if scalar else mi.Float(v)
    params["faces"] = f.tolist() if scalar else mi.UInt32(f)
    params.update()
    return mi.load_dict({"type": "scene", "m": m})


def _mitsuba_trace(variant: str) -> Callable[[Shape, Array, Array], Traced]:
    def trace(shape: Shape, o: Array, d: Array) -> Traced:
        mi = _mitsuba(variant)
        _use(mi, variant)
        scene = _mi_scene(variant, shape)
        n = len(o)
        t = np.full(n, np.inf)
        p = np.zeros((n, 3))
        nn = np.zeros((n, 3))
        with _no_gc():
            return _mitsuba_intersect(mi, variant, scene, o, d, t, p, nn)

    return trace


def _mitsuba_intersect(mi: Any, variant: str, scene: Any, o: Array, d: Array, t: Array,
                       p: Array, nn: Array) -> Traced:  # fmt: skip
    """Scene.ray_intersect on each ray (scalar_rgb: one call a ray; llvm: one call for all)."""
    n = len(o)
    if variant.startswith("scalar"):
        for i in range(n):
            si = scene.ray_intersect(mi.Ray3f(mi.Point3f(*o[i]), mi.Vector3f(*d[i])))
            if si.is_valid():
                t[i], p[i], nn[i] = si.t, list(si.p), list(si.n)
    else:
        ox, oy, oz = (o[:, k].astype(np.float32) for k in range(3))
        dx, dy, dz = (d[:, k].astype(np.float32) for k in range(3))
        ray = mi.Ray3f(mi.Point3f(ox, oy, oz), mi.Vector3f(dx, dy, dz))
        si = scene.ray_intersect(ray)
        valid = np.array(si.is_valid(), dtype=bool)
        t = np.where(valid, np.array(si.t, dtype=np.float64), np.inf)
        p = np.array(si.p, dtype=np.float64).reshape(3, n).T
        nn = np.array(si.n, dtype=np.float64).reshape(3, n).T
    return Traced(np.isfinite(t), t, p, None, nn)


@contextlib.contextmanager
def _no_gc() -> Iterator[None]:
    """No cycle collection while Dr.Jit runs: a plugin instance freed by the collector in the
    middle of a call is what "callable 0 returned an empty/uninitialized Dr.Jit array" means
    (reports/plots.py, which collects before and disables the collector during a render)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _mitsuba_spawn(variant: str) -> Callable[[Traced, Array], Array]:
    """Mitsuba's own spawn: SurfaceInteraction3f.spawn_ray(d) on the hit's point and normal
    (si.p, si.n as its ray_intersect returned them); its offset_p() moves p along n by
    (1 + max |p_i|) RayEpsilon (RayEpsilon = 1500 float epsilons: Mitsuba's own estimate of the
    hit point's error, relative to the point's size), to the side d points to."""

    def spawn(tr: Traced, toward: Array) -> Array:
        mi = _mitsuba(variant)
        _use(mi, variant)
        with _no_gc():
            if variant.startswith("scalar"):
                out = np.zeros_like(tr.p)
                for i in range(len(tr.p)):
                    si = mi.SurfaceInteraction3f()
                    si.p, si.n = mi.Point3f(*tr.p[i]), mi.Normal3f(*tr.n[i])
                    out[i] = list(si.spawn_ray(mi.Vector3f(*toward[i])).o)
                return out
            si = mi.SurfaceInteraction3f()
            si.p = mi.Point3f(*(mi.Float(tr.p[:, k].astype(np.float32)) for k in range(3)))
            si.n = mi.Normal3f(*(mi.Float(tr.n[:, k].astype(np.float32)) for k in range(3)))
            d = mi.Vector3f(*(mi.Float(toward[:, k].astype(np.float32)) for k in range(3)))
            o = si.spawn_ray(d).o
            return np.array(o, dtype=np.float64).reshape(3, -1).T

    return spawn


def _mitsuba_occluded(variant: str) -> Callable[[Shape, Array, Array, Array], np.ndarray]:
    """Mitsuba's shadow test: Scene.ray_test on the ray with maxt = tmax (1 - ShadowEpsilon),
    the shortening its spawn_ray_to() gives a ray towards a point (ShadowEpsilon = 10
    RayEpsilon), so that the point's own surface does not block it."""

    def occluded(shape: Shape, o: Array, d: Array, tmax: Array) -> npt.NDArray[np.bool_]:
        mi = _mitsuba(variant)
        _use(mi, variant)
        scene = _mi_scene(variant, shape)
        reach = tmax * (1 - float(mi.math.ShadowEpsilon))
        with _no_gc():
            if variant.startswith("scalar"):
                out = np.zeros(len(o), dtype=bool)
                for i in range(len(o)):
                    ray = mi.Ray3f(mi.Point3f(*o[i]), mi.Vector3f(*d[i]))
                    ray.maxt = float(reach[i])
                    out[i] = bool(scene.ray_test(ray))
                return out
            o3 = (mi.Float(o[:, k].astype(np.float32)) for k in range(3))
            d3 = (mi.Float(d[:, k].astype(np.float32)) for k in range(3))
            ray = mi.Ray3f(mi.Point3f(*o3), mi.Vector3f(*d3))
            ray.maxt = mi.Float(reach.astype(np.float32))
            return np.array(scene.ray_test(ray), dtype=bool)

    return occluded


# ----------------------------------------------------------------------------------- Embree


@functools.lru_cache(maxsize=32)
def _embree_scene(robust: bool, shape: Shape) -> object:
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    mesh = as_mesh(shape)  # type: ignore[arg-type]
    tris = np.asarray(mesh.vertices, dtype=np.float64)[np.asarray(mesh.faces)]
    scene = rtcore_scene.EmbreeScene(robust=robust)  # robust: RTC_SCENE_FLAG_ROBUST
    TriangleMesh(scene, np.ascontiguousarray(tris, dtype=np.float32))
    return scene


def _embree_trace(robust: bool) -> Callable[[Shape, Array, Array], Traced]:
    def trace(shape: Shape, o: Array, d: Array) -> Traced:
        scene = _embree_scene(robust, shape)
        o32 = np.ascontiguousarray(o, dtype=np.float32)
        d32 = np.ascontiguousarray(d, dtype=np.float32)
        r = scene.run(o32, d32, query="INTERSECT", output=1)  # type: ignore[attr-defined]
        hit = np.asarray(r["geomID"]) >= 0
        t32 = np.asarray(r["tfar"], dtype=np.float32)
        t = np.where(hit, t32.astype(np.float64), np.inf)
        with np.errstate(invalid="ignore", over="ignore"):
            # The hit point as Embree's tutorials compute it, ray.org + ray.tfar * ray.dir, in
            # float (Embree returns t, not a point).
            p = (o32 + t32[:, None] * d32).astype(np.float64)
        n = np.asarray(r["Ng"], dtype=np.float64)
        return Traced(hit, t, p, None, n)

    return trace


#: Embree has no spawn: its user starts the new ray at the hit point with a ray segment that
#: begins a little ahead, tnear; 0.001f is the value of Embree's own tutorials ("Ray
#: shadow(ray.org + ray.tfar*ray.dir, neg(lightDir), 0.001f, inf)").
EMBREE_TNEAR = np.float32(1e-3)


def _embree_spawn(tr: Traced, toward: Array) -> Array:
    """The ray from the hit point with tnear = EMBREE_TNEAR along the unit direction. embreex
    fixes tnear at 0, so the origin is moved there instead, p + tnear d (in float, like the
    point: the same ray segment in real arithmetic, one more rounding of the size of p's ulp)."""
    p = tr.p.astype(np.float32)
    with np.errstate(all="ignore"):  # missed rays (an infinite point) are not spawned
        d = toward / np.linalg.norm(toward, axis=1)[:, None]
        return (p + EMBREE_TNEAR * d.astype(np.float32)).astype(np.float64)


def _embree_occluded(robust: bool) -> Callable[[Shape, Array, Array, Array], np.ndarray]:
    """rtcOccluded1 through embreex (query "OCCLUDED"): anything in (tnear = 0, tfar = tmax)."""

    def occluded(shape: Shape, o: Array, d: Array, tmax: Array) -> npt.NDArray[np.bool_]:
        scene = _embree_scene(robust, shape)
        o32 = np.ascontiguousarray(o, dtype=np.float32)
        d32 = np.ascontiguousarray(d, dtype=np.float32)
        far = np.ascontiguousarray(np.broadcast_to(tmax, len(o)), dtype=np.float32)
        ids = scene.run(o32, d32, dists=far, query="OCCLUDED")  # type: ignore[attr-defined]
        return np.asarray(ids) >= 0  # the geometry's id where occluded, -1 where not

    return occluded


def embree_version() -> str:
    """embreex's version and the Embree library it bundles (the version string compiled in)."""
    import importlib.metadata
    import re
    from pathlib import Path

    import embreex

    ours = importlib.metadata.version("embreex")
    libs = Path(embreex.__file__).resolve().parent.parent / "embreex.libs"
    found = ""
    for lib in sorted(libs.glob("libembree*")):
        m = re.search(rb"\x00(\d+\.\d+\.\d+)\x00", lib.read_bytes())
        found = m.group(1).decode() if m else ""
    return f"embreex {ours} / Embree {found or 'unknown'}"


def mitsuba_version() -> str:
    import mitsuba as mi

    return str(mi.__version__)


ALL = ("sphere", "plane", "triangle", "box", "mesh")
#: The shapes study/rtlab_float.py ports (not the cylinder nor the rotated box).
PORTED = ALL
ALL = (*ALL, "cylinder", "rbox")  # study/methods_scenes.py
ALL = (*ALL, "torus", "torus-camera")  # study/methods_torus.py
#: Cylinders and tori under a transform (study/methods_placed.py).
PLACED = ("placed-cylinder", "placed-elliptic-cylinder", "placed-torus")
ALL = (*ALL, *PLACED)


def _unsupported_spawn(tr: Traced, toward: Array) -> Array:
    raise NotImplementedError("POV-Ray traces only its own camera's rays: nothing is spawned")


def _unsupported_occluded(shape: Shape, o: Array, d: Array, tmax: Array) -> np.ndarray:
    raise NotImplementedError("POV-Ray traces only its own camera's rays: no shadow rays")


def methods(include_mitsuba: bool = True, include_embree: bool = True) -> list[Method]:
    """Every method, in the order the report lists them."""
    out = [
        Method("rtlab", "1", frozenset(ALL), _rtlab_trace, _rtlab_spawn, _rtlab_occluded,
               "double"),
        Method("textbook-double", "1", frozenset(ALL), _textbook(np.float64),
               _textbook_spawn(np.float64), _textbook_occluded(np.float64), "double"),
        Method("textbook-float", "1", frozenset(ALL), _textbook(np.float32),
               _textbook_spawn(np.float32), _textbook_occluded(np.float32), "float"),
        Method("rtlab-float", "1", frozenset(PORTED), *rtlab_float.port(np.float32), "float"),
    ]  # fmt: skip
    if include_mitsuba:
        version = mitsuba_version()
        for variant in ("scalar_rgb", "llvm_ad_rgb"):
            out.append(
                Method(
                    f"mitsuba-{variant}",
                    version,
                    frozenset({"sphere", "triangle", "mesh", "box", "cylinder", "placed-cylinder"}),
                    _mitsuba_trace(variant),
                    _mitsuba_spawn(variant),
                    _mitsuba_occluded(variant),
                    "float",
                )
            )
    for sturm in (True, False):  # POV-Ray's torus, on its own camera's rays (methods_torus.py)
        out.append(Method("povray-sturm" if sturm else "povray", methods_torus.povray_version(),
                          frozenset({"torus-camera"}), methods_torus.povray_trace(sturm),  # type: ignore[arg-type]
                          _unsupported_spawn, _unsupported_occluded, "double",
                          frozenset({"decision"}), reports_t=False))  # fmt: skip
    if include_embree:
        version = embree_version()
        for robust in (False, True):
            out.append(Method("embree-robust" if robust else "embree", version,
                              frozenset({"triangle", "mesh", "box"}), _embree_trace(robust),
                              _embree_spawn, _embree_occluded(robust), "float"))  # fmt: skip
    return out


def ulps(computed: Array, exact: Array) -> Array:
    """|computed - exact| in units of the last place of exact (both doubles; exact the true t
    rounded to nearest, which costs at most half an ulp)."""
    spacing = np.spacing(np.abs(exact))
    with np.errstate(invalid="ignore"):
        return np.abs(computed - exact) / np.where(spacing > 0, spacing, math.inf)
