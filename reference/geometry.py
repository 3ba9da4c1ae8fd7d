"""Geometry cross-checks: what the primary ray through each pixel centre hits, its distance
and its normal, from rtlab's aov integrator, from a rasteriser (pyrender) and from Mitsuba's own
``aov`` integrator. No shading model is involved: these check cameras, visibility and hits."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tracer.render import aov_channels, render
from tracer.scene import Scene


@dataclass(frozen=True)
class Geometry:
    depth: np.ndarray  # distance along the primary ray; inf where nothing
    object_id: np.ndarray  # index into [[objects]]; -1 where nothing
    normal: np.ndarray | None  # (h, w, 3) shading normal, front side; None if not known
    compare: np.ndarray  # pixels where this renderer can be compared at all


def rtlab_geometry(scene: Scene) -> Geometry:
    ch = aov_channels(render(scene.with_overrides(integrator="aov"), progress=False))
    normal = np.stack([ch["N.X"], ch["N.Y"], ch["N.Z"]], axis=-1)
    ids = ch["object_id"].astype(np.int64)
    return Geometry(ch["depth"].astype(np.float64), ids, normal, np.ones(ids.shape, bool))


def pyrender_geometry(scene: Scene) -> tuple[Geometry, np.ndarray]:
    """The rasteriser's view, and each pixel's depth tolerance (relative): a 24-bit depth
    buffer resolves camera depth z to z / (near 2^24) relative (doubled here), plus 1e-4 for the
    tessellation of curved shapes (converters/tessellate.py: sagitta <= 7.5e-5 of the radius,
    so at most that relative to the depth of any point in front of the eye). Pixels beyond the
    squares that stand in for planes cannot be compared."""
    from converters.pyrender import ray_depth, render_geometry

    z_axis, ids, near, half = render_geometry(scene)
    to_ray = ray_depth(scene)
    depth = np.where(ids >= 0, z_axis * to_ray, np.inf)
    ours = rtlab_geometry(scene).depth
    ours_far = np.isfinite(ours) & (ours / to_ray > 0.9 * half)
    tolerance = z_axis / (near * 2.0**23) + 1e-4
    return Geometry(depth, ids, None, ~ours_far), tolerance


def mitsuba_geometry(scene: Scene) -> Geometry:
    """Mitsuba's ``aov`` integrator (scalar_rgb: there shape_index is 1 + the shape's position in
    scene.shapes(), whose ids name our objects). Its rays start on the near plane: the depth is
    corrected by near_clip / cos."""
    import mitsuba as mi

    import converters.mitsuba as cm
    from converters.pyrender import ray_depth

    cm.use_variant("scalar_rgb")
    d = cm.to_mitsuba_dict(scene)
    d["integrator"] = {"type": "aov", "aovs": "dd:depth,nn:sh_normal,id:shape_index"}
    near = 1e-4
    d["sensor"]["near_clip"] = near
    mi_scene = mi.load_dict(d)
    out = np.array(mi.render(mi_scene), dtype=np.float64)
    index = np.full(len(mi_scene.shapes()) + 1, -1, dtype=np.int64)
    for k, shape in enumerate(mi_scene.shapes()):
        index[k + 1] = int(shape.id().split("_")[1])  # object_3, object_3_1 (a cylinder cap)
    ids = index[np.rint(out[..., 4]).astype(np.int64)]
    depth = np.where(ids >= 0, out[..., 0] + near * ray_depth(scene), np.inf)
    return Geometry(depth, ids, out[..., 1:4], np.ones(ids.shape, bool))
