"""The methods on cylinders and tori under a transform (study/shapes.py PlacedCylinder,
PlacedTorus; study/families_placed.py).

- rtlab: the scene object with its ``transform`` (study/methods.py _core_scene takes it as it
  is): tracer/cpp/17_cylinder.h and 18_torus.h behind tracer/cpp/13_transform.h.
- The textbook's instance: the ray taken into the object's coordinates by the inverse matrix
  (numpy's, in the method's precision), the textbook's own untransformed cylinder or torus there
  (study/methods_scenes.py textbook_cylinder, study/methods_torus.py textbook_trace), t shared,
  the point o + t d in the world, the normal back by the inverse transpose (as the rotated box,
  study/methods_scenes.py textbook_rotated_box).
- Mitsuba: its cylinder (uncapped; the family's rays meet no cap) with ``to_world`` the core's
  matrix times the unit cylinder's scale (r, r, height): a circular cross section only
  (PlacedCylinder.kind_circular), for Mitsuba refuses a non-uniform scale across its axis. It
  has no torus.
- rtlab-float ports neither shape (study/rtlab_float.py), Embree traces triangles, POV-Ray its
  own camera's rays: no rows from them here."""

from __future__ import annotations

from typing import Any

import numpy as np

from study.methods import Array, Traced, _dot
from study.shapes import PlacedCylinder, PlacedTorus


def textbook_placed(shape: PlacedCylinder | PlacedTorus, o_in: Array, d_in: Array,
                    dtype: type) -> Traced:  # fmt: skip
    from study import methods_torus
    from study.methods_scenes import textbook_cylinder

    m = np.asarray(shape.matrix(), dtype=dtype)
    inv = np.linalg.inv(m[:, :3])
    with np.errstate(all="ignore"):
        qo = ((o_in.astype(dtype) - m[:, 3]) @ inv.T).astype(np.float64)
        qd = (d_in.astype(dtype) @ inv.T).astype(np.float64)
    if isinstance(shape, PlacedCylinder):
        local = textbook_cylinder(shape.local(), qo, qd, dtype)
    else:
        local = methods_torus.textbook_trace(dtype)(shape.local(), qo, qd)  # type: ignore[operator]
    with np.errstate(all="ignore"):
        p = o_in.astype(dtype) + local.t.astype(dtype)[:, None] * d_in.astype(dtype)
        n = local.n.astype(dtype) @ inv
        n = n / np.sqrt(_dot(n, n))[:, None]
    return Traced(local.hit, local.t, p.astype(np.float64), None, n.astype(np.float64))


def mitsuba_cylinder(mi: Any, shape: PlacedCylinder) -> dict[str, Any]:
    """Mitsuba's unit cylinder (p0 = 0, p1 = (0, 0, 1), radius 1) placed by the core's matrix
    times diag(r, r, height)."""
    m = np.eye(4)
    m[:3] = np.asarray(shape.matrix())
    m = m @ np.diag([shape.radius, shape.radius, shape.height, 1.0])
    return {"type": "cylinder", "to_world": mi.ScalarTransform4f(m.tolist())}


#: Per shape kind, the textbook's trace in a precision (study/methods.py _textbook dispatches).
TEXTBOOK = dict.fromkeys(
    (PlacedCylinder.kind_circular, PlacedCylinder.kind_elliptic, PlacedTorus.kind),
    textbook_placed,
)
