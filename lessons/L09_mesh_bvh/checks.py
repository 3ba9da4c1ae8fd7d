"""L09's probes: the bounding box's slab test within a range, the closest hit of a mesh's
hierarchy, and the triangles a box that the ray misses spares.

Expected values, from the exact binary values of the inputs (Fractions):

- the bounding box: the slab intervals of lessons/L08_box_triangle/checks.py exact_slabs()
  clipped to the range, [max(range.min, t_enter), min(range.max, t_leave)]; a hit when that is
  not empty, t_near its start. The core widens the far planes by 1 + 2 gamma(3) so that
  rounding never misses a box (no probe lies within that margin of a boundary); t_near is a
  subtraction and a product with a rounded reciprocal (3 u |t|): 8 ulps of max(|t|, 1);
- the closest hit: brute force, every triangle by Cramer's rule (L08's exact_triangle()), a hit
  when all barycentric coordinates are >= 0 and range.min < t <= range.max, the least t (no
  ties, no probe near an edge); the tolerance of L08's triangle, 64 ulps of max(1, reach);
- the culling: the number of ray/triangle tests is at most the triangles of the boxes the ray
  reaches before its closest hit, counted from the scene's construction (two clusters of four
  far apart: the hierarchy puts each in a leaf of its own; a leaf holds at most 4 triangles);
  an upper bound, so a traversal that tests less (a box test per child as it is visited) also
  passes. A count is an integer: exact.
"""

from __future__ import annotations

import math

from lessons.L08_box_triangle.checks import exact_slabs, exact_triangle
from lessons.probe import HIDDEN, Probe, Vec, vec_text

LESSON = "L09"
BOX = "the bounding box of the object"
CLOSEST = "the closest hit in the hierarchy"
CULL = "a ray that misses a box skips the triangles in it"
# The traversal tests boxes with slab_test() (the bounding box) and keeps the closest hit;
# what it skips depends on both.
DEPENDS: dict[str, tuple[str, ...]] = {CLOSEST: (BOX,), CULL: (BOX, CLOSEST)}

INF = math.inf
BOUNDING_BOX, BVH = 1, 2
Triangle = tuple[Vec, Vec, Vec]


def box_probe(
    name: str,
    lo: Vec,
    hi: Vec,
    o: Vec,
    d: Vec,
    rmin: float = 0.0,
    rmax: float = INF,
    visibility: str = "visible",
) -> Probe:
    enter, leave, _, _ = exact_slabs(lo, hi, o, d)
    start = max(enter, rmin)
    end = min(leave, rmax)
    expected = (1.0, float(start)) if start <= end else (0.0, None)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=BOX,
        function="slab_test",
        inputs=(*lo, *hi, *o, *d, rmin, rmax),
        expected=expected,
        labels=("hit", "t_near"),
        ulps=8,
        visibility=visibility,
        inputs_text=f"box min {vec_text(lo)}, max {vec_text(hi)}; ray o = {vec_text(o)}, "
        f"d = {vec_text(d)}; range ({rmin:g}, {rmax:g})",
        hint="the slabs' overlap [t_enter, t_leave] clipped to the range: a hit when it is not "
        "empty, t_near its start; near and far planes from the signs of d (r.near_x ...); a "
        "box entirely behind the ray, or beyond range.max (a closer hit), is a miss",
    )


def closest(tris: list[Triangle], o: Vec, d: Vec, lo: float, hi: float):  # noqa: ANN201
    """(t, index, b0, b1, b2) of the closest hit by brute force, or None."""
    best = None
    for i, (p0, p1, p2) in enumerate(tris):
        found = exact_triangle(p0, p1, p2, o, d)
        if found is None or min(found[1:]) < 0 or not lo < found[0] <= hi:
            continue
        assert best is None or found[0] != best[0], "a tie: choose other inputs"
        if best is None or found[0] < best[0]:
            best = (found[0], i, *found[1:])
    return best


def mesh_probe(
    name: str,
    concept: str,
    mode: int,
    tris: list[Triangle],
    o: Vec,
    d: Vec,
    lo: float = 0.0,
    hi: float = INF,
    max_triangle_tests: int | None = None,
    visibility: str = "visible",
) -> Probe:
    best = closest(tris, o, d, lo, hi)
    if concept == CULL:
        assert max_triangle_tests is not None
        expected: tuple = (None,) * 7 + (("<=", float(max_triangle_tests)),)
    elif best is None:
        expected = (0.0, *(None,) * 7)
    else:
        t, index, b0, b1, b2 = best
        expected = (1.0, float(t), float(index), float(b0), float(b1), float(b2), None, None)
    reach = max(math.dist(p, o) for tri in tris for p in tri) / math.hypot(*d)
    what = "one bounding box" if mode == BOUNDING_BOX else "a hierarchy"
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="traverse",
        inputs=(
            float(mode),
            float(len(tris)),
            *(x for tri in tris for p in tri for x in p),
            *o,
            *d,
            lo,
            hi,
        ),
        expected=expected,
        labels=("found", "t", "triangle", "b0", "b1", "b2", "box tests", "triangle tests"),
        ulps=64,
        scale=max(1.0, reach),
        visibility=visibility,
        inputs_text=f"a mesh of {len(tris)} triangles in {what}: "
        + "; ".join(f"{i}: {', '.join(vec_text(p) for p in tri)}" for i, tri in enumerate(tris))
        + f"; ray o = {vec_text(o)}, d = {vec_text(d)}; range ({lo:g}, {hi:g})",
        hint="the closest of all hits, whatever the order the boxes and triangles are met in: "
        "each hit shrinks the range, a box (or a waiting child) that starts beyond the closest "
        "hit so far is skipped, and the nearer child is visited first"
        if concept != CULL
        else "a box the ray misses, or one that starts beyond the closest hit so far, must "
        "not have its triangles tested: visit the nearer child first and skip a waiting child "
        "that lies beyond the closest hit",
    )


# --- the scenes ------------------------------------------------------------------------------


def small(x: float, y: float, z: float, s: float = 1.0) -> Triangle:
    """A triangle in the plane z, around (x, y): covers (x, y) but not (x + 0.9s, y + 0.8s)."""
    return ((x - s, y - s, z), (x + s, y - s, z), (x, y + s, z))


def wide(x: float, y: float, z: float, s: float = 1.0) -> Triangle:
    """A triangle in the plane z that covers (x + 0.9s, y + 0.8s) (below its diagonal)."""
    return ((x - s, y - s, z), (x + s, y - s, z), (x + s, y + s, z))


# Four triangles stacked along z, the closest to z = -infinity second in order, the closest to
# +infinity third: a leaf that keeps its first or its last hit is wrong from either side.
STACK = [small(0, 0, 2.5), small(0, 0, 2), small(0, 0, 2.75), small(0, 0, 2.25)]
# Two clusters far apart along z: the hierarchy's two leaves.
TWO_Z = [*STACK, wide(0, 0, 10.5), wide(0, 0, 10), wide(0, 0, 10.75), wide(0, 0, 10.25)]
# Two clusters far apart along x, with a gap between them.
TWO_X = [small(-3, 0, z) for z in (2.5, 2, 2.75, 2.25)] + [
    small(3, 0, z) for z in (10.5, 10, 10.75, 10.25)
]
# Overlapping boxes: a long tilted triangle (met at z = 11.2) whose box the ray enters first
# (at z = 0), with three triangles beside it; the stack's box, entered later, holds the
# closest hit (z = 2).
TILTED: Triangle = ((-1.0, -2.0, 12.0), (-1.0, 2.0, 12.0), (14.0, 0.0, 0.0))
OVERLAP = [TILTED, small(10, 0, 0.5), small(10, 0, 1), small(11, 0, 0.75), *STACK]
UP: Vec = (0.0, 0.0, 1.0)
DOWN: Vec = (0.0, 0.0, -1.0)


def probes() -> list[Probe]:
    h = HIDDEN
    lo, hi = (-1.0, -2.0, 0.5), (3.0, 1.0, 2.5)
    return [
        # The bounding box within a range.
        box_probe("box: ahead of the ray", lo, hi, (0, 0, -2), UP),
        box_probe("box: along -z (the near plane is max.z)", lo, hi, (0, 0, 6), DOWN),
        box_probe("box: oblique, negative components", lo, hi, (5, 3, -1), (-1, -0.75, 0.5)),
        box_probe("box: behind the ray", lo, hi, (0, 0, 4), UP),
        box_probe("box: beyond range.max (a closer hit)", lo, hi, (0, 0, -2), UP, 0, 2),
        box_probe("box: from inside, t_near = range.min", lo, hi, (0, 0, 1), UP),
        box_probe("box: a miss beside it", lo, hi, (5, 0, -2), UP),
        box_probe("box: in the plane of the face x = max", lo, hi, (3, 0, -2), UP),
        box_probe("box: hidden, range.min inside the box", lo, hi, (0, 0, -2), UP, 3, 10, h),
        box_probe("box: hidden oblique miss", lo, hi, (-4, 4, 4), (1, 0.25, -0.5), visibility=h),
        box_probe("box: hidden, behind along -x", lo, hi, (-3, 0, 1), (-1, 0.5, 0), visibility=h),
        box_probe("box: hidden, in the face y = min", lo, hi, (0, -2, 0), (0.25, 0, 1), 1, 9, h),
        # The closest hit.
        mesh_probe(
            "closest: one box, a stack seen from below",
            CLOSEST,
            BOUNDING_BOX,
            STACK,
            (0, 0, -5),
            UP,
        ),
        mesh_probe(
            "closest: one box, a stack seen from above",
            CLOSEST,
            BOUNDING_BOX,
            STACK,
            (0.25, 0, 8),
            DOWN,
        ),
        mesh_probe("closest: two leaves, from below", CLOSEST, BVH, TWO_Z, (0, 0, -5), UP),
        mesh_probe("closest: two leaves, from above", CLOSEST, BVH, TWO_Z, (0, -0.25, 20), DOWN),
        mesh_probe(
            "closest: through the first box without a hit in it",
            CLOSEST,
            BVH,
            TWO_Z,
            (0.9, 0.8, -5),
            UP,
        ),
        mesh_probe(
            "closest: overlapping boxes, the first box's hit is not the closest",
            CLOSEST,
            BVH,
            OVERLAP,
            (0, 0, -5),
            UP,
        ),
        mesh_probe("closest: nothing within the range", CLOSEST, BVH, TWO_Z, (0, 0, -5), UP, 0, 6),
        mesh_probe(
            "closest: range.min past the first hit", CLOSEST, BVH, TWO_Z, (0, 0, -5), UP, 7.125, INF
        ),
        mesh_probe(
            "closest: hidden, oblique into the near leaf",
            CLOSEST,
            BVH,
            TWO_Z,
            (0, 0.125, -4),
            (0.03125, 0, 1),
            visibility=h,
        ),
        mesh_probe(
            "closest: hidden, overlapping boxes, off-centre",
            CLOSEST,
            BVH,
            OVERLAP,
            (0, 0.125, -3),
            (0, 0, 1),
            visibility=h,
        ),
        mesh_probe(
            "closest: hidden, one box, a stack within a range",
            CLOSEST,
            BOUNDING_BOX,
            STACK,
            (0, 0.25, 8),
            DOWN,
            5.375,
            20,
            h,
        ),
        mesh_probe("closest: hidden miss", CLOSEST, BVH, TWO_X, (0, 0, -5), UP, visibility=h),
        # What the boxes spare.
        mesh_probe(
            "skip: the far leaf, from below", CULL, BVH, TWO_Z, (0, 0, -5), UP, max_triangle_tests=4
        ),
        mesh_probe(
            "skip: the far leaf, from above",
            CULL,
            BVH,
            TWO_Z,
            (0, 0, 20),
            DOWN,
            max_triangle_tests=4,
        ),
        mesh_probe(
            "skip: a ray through the gap between two boxes",
            CULL,
            BVH,
            TWO_X,
            (0, 0, -5),
            UP,
            max_triangle_tests=0,
        ),
        mesh_probe(
            "skip: a ray that misses the bounding box",
            CULL,
            BOUNDING_BOX,
            STACK,
            (5, 0, -5),
            UP,
            max_triangle_tests=0,
        ),
        mesh_probe(
            "skip: hidden, the far leaf, oblique from above",
            CULL,
            BVH,
            TWO_Z,
            (0.25, -0.125, 21),
            (0.0625, 0, -1),
            max_triangle_tests=4,
            visibility=h,
        ),
        mesh_probe(
            "skip: hidden, the far leaf beyond range.max",
            CULL,
            BVH,
            TWO_X,
            (-3, 0, -5),
            UP,
            0,
            20,
            max_triangle_tests=4,
            visibility=h,
        ),
        mesh_probe(
            "skip: hidden, from below in the other cluster",
            CULL,
            BVH,
            TWO_X,
            (3, 0.25, 30),
            DOWN,
            max_triangle_tests=4,
            visibility=h,
        ),
    ]
