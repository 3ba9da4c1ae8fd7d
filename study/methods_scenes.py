"""The methods on issue 11's scene families (study/families_scenes.py): the textbook cylinder, and
every method on a group of shapes (nearly touching surfaces).

- rtlab traces a group through one core scene of several objects (tracer/rays.intersect names
  the object met, tracer/cpp/09_scene.h closest_hit); a cylinder through its own
  tracer/cpp/17_cylinder.h (methods.py's _core_scene takes its scene object as it is).
- The textbook's rotated box: the ray into the box's coordinates, the slab test there.
- The textbook's cylinder: the naive quadratic b^2 - 4ac across the axis (w and d less their
  parts along the unit axis), (-b -+ sqrt) / 2a, the height checked, the caps as planes; a
  group: the nearest of its members' hits, each by the method's own formulas."""

from __future__ import annotations

import functools

import numpy as np
import numpy.typing as npt

from study.methods import Array, Method, Traced, _dot
from study.shapes import Box, Cylinder, Group, RotatedBox


def textbook_cylinder(shape: Cylinder, o_in: Array, d_in: Array, dtype: type) -> Traced:
    o, d = o_in.astype(dtype), d_in.astype(dtype)
    base, top = np.array(shape.base, dtype=dtype), np.array(shape.top, dtype=dtype)
    with np.errstate(all="ignore"):
        axis = top - base
        height = np.sqrt(_dot(axis, axis))
        e = axis / height
        w = o - base
        wz, dz = _dot(w, e), _dot(d, e)
        wp, dp = w - wz[:, None] * e, d - dz[:, None] * e
        r = dtype(shape.radius)
        a, b, c = _dot(dp, dp), 2 * _dot(wp, dp), _dot(wp, wp) - r * r
        disc = b * b - 4 * a * c  # as printed
        sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
        best = np.full(len(o), np.inf, dtype=dtype)
        cands = [(-b - sq) / (2 * a), (-b + sq) / (2 * a)]
        for t in cands:
            z = wz + t * dz
            ok = (t > 0) & (z >= 0) & (z <= height) & (t < best)
            best = np.where(ok, t, best)
        side = np.isfinite(best)
        for level in (dtype(0), height):
            t = (level - wz) / dz
            pp = wp + t[:, None] * dp
            ok = (t > 0) & (_dot(pp, pp) <= r * r) & (t < best)
            best = np.where(ok, t, best)
            side &= ~ok
        hit = np.isfinite(best)
        p = o + best[:, None] * d
        rel = p - base
        across = rel - _dot(rel, e)[:, None] * e
        cap = np.where((_dot(rel, e) > height / 2)[:, None], e, -e)
        n = np.where(side[:, None], across / r, cap)
    return Traced(hit, best.astype(np.float64), p.astype(np.float64), None, n.astype(np.float64))


def textbook_rotated_box(shape: RotatedBox, o_in: Array, d_in: Array, dtype: type) -> Traced:
    """The ray taken into the box's coordinates by the inverse matrix (numpy's, in the
    precision), the slab test there (the textbook's own), the normal back by the inverse
    transpose."""
    from study.methods import _textbook

    m = np.asarray(shape.matrix(), dtype=dtype)
    inv = np.linalg.inv(m[:, :3])
    with np.errstate(all="ignore"):
        qo = (o_in.astype(dtype) - m[:, 3]) @ inv.T
        qd = d_in.astype(dtype) @ inv.T
    local = _textbook(dtype)(Box(shape.lo, shape.hi), qo.astype(np.float64),
                             qd.astype(np.float64))  # fmt: skip
    with np.errstate(all="ignore"):
        p = o_in.astype(dtype) + local.t.astype(dtype)[:, None] * d_in.astype(dtype)
        n = local.n.astype(dtype) @ inv
        n = n / np.sqrt(_dot(n, n))[:, None]
    return Traced(local.hit, local.t, p.astype(np.float64), None, n.astype(np.float64))


#: Per shape kind, the textbook's trace in a precision (study/methods.py _textbook dispatches).
TEXTBOOK = {"cylinder": textbook_cylinder, "rbox": textbook_rotated_box}


@functools.lru_cache(maxsize=64)
def _core_group(group: Group) -> object:
    import tracer
    from tracer.render import to_core

    scene = tracer.load_scene({
        "camera": {"eye": [0.0, 0.0, 1.0], "look_at": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
                   "fov_y": 30.0, "width": 1, "height": 1},
        "materials": {"m": {"color": [1.0, 1.0, 1.0]}},
        "objects": [o | {"material": "m"} for o in group.scene_objects()],
    })  # fmt: skip
    return to_core(scene)


def trace_group(method: Method, group: Group, o: Array, d: Array) -> tuple[Traced, npt.NDArray]:
    """The first hit of each ray in the group and the index of the member met (-1: a miss):
    rtlab's own scene of several objects, other methods the nearest of their members' hits."""
    if method.name == "rtlab":
        from tracer import rays

        h = rays.intersect(_core_group(group), o, d)
        return Traced(h.hit, h.t, h.p, h.p_error, h.Ng), np.where(h.hit, h.object, -1)
    parts = [method.trace(m, o, d) for m in group.members]
    ts = np.stack([np.where(p.hit, p.t, np.inf) for p in parts])
    k = np.argmin(ts, axis=0)
    rows = np.arange(len(o))
    t = ts[k, rows]
    hit = np.isfinite(t)
    p = np.stack([x.p for x in parts])[k, rows]
    n = np.stack([x.n for x in parts])[k, rows]
    # The met member's error bound, where the method keeps one (rtlab-float spawns by it).
    bounds = [x.p_error for x in parts]
    e = None if any(b is None for b in bounds) else np.stack(bounds)[k, rows]  # type: ignore[arg-type]
    return Traced(hit, t, p, e, n), np.where(hit, k, -1)


def group_method(method: Method) -> Method:
    """The method with trace() taking a group (for study/metrics.py decision())."""
    import dataclasses

    def trace(shape: object, o: Array, d: Array) -> Traced:
        assert isinstance(shape, Group)
        return trace_group(method, shape, o, d)[0]

    return dataclasses.replace(method, trace=trace)
