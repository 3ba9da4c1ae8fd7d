"""Many rays at once through a built scene, as the renderer traces them: the closest hit of each
ray (the core's closest_hit, tracer/cpp/09_scene.h) and whether a shadow ray is blocked
(any_hit). The numerical study (study/) measures the renderer's own code through these."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tracer import _core
from tracer.render import to_core
from tracer.scene import Scene

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Hits:
    """One entry per ray: ``hit`` (bool), ``t`` (inf on a miss), the point ``p`` refined onto
    the surface, its per-component error bound ``p_error``, the geometric normal ``Ng`` and the
    index of the object in the scene's [[objects]] (-1 on a miss)."""

    hit: npt.NDArray[np.bool_]
    t: Array
    p: Array
    p_error: Array
    Ng: Array
    object: npt.NDArray[np.int64]


def _rays(origins: npt.ArrayLike, directions: npt.ArrayLike) -> tuple[Array, Array]:
    o = np.ascontiguousarray(origins, dtype=np.float64)
    d = np.ascontiguousarray(directions, dtype=np.float64)
    if o.ndim != 2 or o.shape[1] != 3 or d.shape != o.shape:
        raise ValueError(f"origins and directions must both be (N, 3); got {o.shape}, {d.shape}")
    return o, d


def core_scene(scene: Scene | _core.Scene) -> _core.Scene:
    """The core's scene: a model (tracer.load_scene) is built once; a built one is kept."""
    return scene if isinstance(scene, _core.Scene) else to_core(scene)


def intersect(
    scene: Scene | _core.Scene,
    origins: npt.ArrayLike,
    directions: npt.ArrayLike,
    tmax: float = float("inf"),
) -> Hits:
    """The closest hit of each ray, as the renderer finds it: t in (0, tmax). (The renderer's
    rays all start at t = 0, so there is no tmin.) Directions need not be unit length."""
    o, d = _rays(origins, directions)
    hit, t, p, e, ng, obj = _core.intersect(core_scene(scene), o, d, float(tmax))
    return Hits(hit > 0, np.array(t), np.array(p), np.array(e), np.array(ng),
                obj.astype(np.int64))  # fmt: skip


def occluded(
    scene: Scene | _core.Scene,
    origins: npt.ArrayLike,
    directions: npt.ArrayLike,
    tmax: npt.ArrayLike,
) -> npt.NDArray[np.bool_]:
    """Whether anything lies at t in (0, tmax) along each ray, as a shadow ray asks (any_hit):
    with direction = light - origin and tmax = 1, whether the light is blocked."""
    o, d = _rays(origins, directions)
    reach = np.ascontiguousarray(np.broadcast_to(np.asarray(tmax, dtype=np.float64), len(o)))
    return _core.occluded(core_scene(scene), o, d, reach) > 0


def offset_ray_origin(p: Array, p_error: Array, normal: Array, toward: Array) -> Array:
    """The core's offset_ray_origin (tracer/cpp/02_ray.h) for each row: where a ray spawned at
    hit point p towards ``toward`` starts (pbrt-v4 6.8.6)."""
    return np.array(
        [
            _core.offset_ray_origin(list(a), list(b), list(c), list(w))
            for a, b, c, w in zip(p, p_error, normal, toward, strict=True)
        ],
        dtype=np.float64,
    ).reshape(-1, 3)
