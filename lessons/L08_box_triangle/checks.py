"""L08's probes: the slab test of an axis-aligned box, the box's nearest hit in range, the
generic (watertight, two-sided) triangle, and a triangle hit's point and normal.

Every expected value is computed here from the exact binary values of the inputs (Fractions):

- the slab test: per axis t = (plane - o) / d exactly, the nearer of the two planes is where the
  ray enters that slab; a zero component of d puts no bound on t when o lies in the closed slab
  (o on a face's plane included: that is where 0 * infinity = NaN must change nothing), and
  empties the box when o lies outside it. The core computes (plane - o) * (1 / d): a
  subtraction, a reciprocal and a product, each rounded once, so |error| <= 3 u |t|; a student
  dividing by d rounds twice. 8 ulps of max(|t|, 1) covers both; a wrong plane, a missing swap
  or a NaN is off by far more (a whole t, or not a number);
- the box's hit picks one of the values it is given: exact (0 ulps);
- the triangle: Cramer's rule on o + t d = p0 + b1 (p1 - p0) + b2 (p2 - p0), b0 = 1 - b1 - b2,
  a hit when every b >= 0 and range.min < t <= range.max (no probe lies near a boundary). The
  core's sheared edge functions (Woop et al. 2013) lose a few roundings of the product of the
  triangle's and the ray's extents, divided by the determinant; for the well-shaped triangles
  here (sizes 1 to 5, determinants of the same order) that is below 64 u of
  max(1, |p - o| / |d|) for t and the barycentric coordinates; a wrong formula misses by a
  visible fraction;
- the hit record: p = b0 p0 + b1 p1 + b2 p2 (3 products and 2 sums per component: <= 5 u of
  the vertices' scale) and N = cross(p1 - p0, p2 - p0) / |...| (a subtraction, a cross product,
  a square root and a division: well under 16 u); 16 ulps of max(1, |p_i|).
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext
from fractions import Fraction

from lessons.probe import HIDDEN, XYZ, Probe, Vec, sqrt_fraction, to_float, vec_text

LESSON = "L08"
SLAB = "the axis-aligned box (slab test)"
BOX_HIT = "the box's nearest hit in range"
TRIANGLE = "the generic triangle"
SIDES = "the triangle seen from both sides"
NORMAL = "the triangle's point and normal"
# The triangle's two concepts run the same function, intersect_triangle(): a break of either
# may show in the other's probes, and the one with the larger share failing is named.
DEPENDS: dict[str, tuple[str, ...]] = {TRIANGLE: (SIDES,), SIDES: (TRIANGLE,)}

F = Fraction
INF = math.inf


def _ray_text(o: Vec, d: Vec) -> str:
    return f"ray o = {vec_text(o)}, d = {vec_text(d)}"


# --- the slab test ---------------------------------------------------------------------------


def exact_slabs(lo: Vec, hi: Vec, o: Vec, d: Vec) -> tuple[F | float, F | float, list, list]:
    """(t_enter, t_leave, the axes that give t_enter, the axes that give t_leave) exactly; an
    empty box gives t_enter > t_leave (or +-infinity)."""
    enter: F | float = -INF
    leave: F | float = INF
    enter_axes: list[int] = []
    leave_axes: list[int] = []
    for axis in range(3):
        a, b, oo, dd = F(lo[axis]), F(hi[axis]), F(o[axis]), F(d[axis])
        if dd == 0:
            if not a <= oo <= b:
                return INF, -INF, [], []
            continue
        t0, t1 = (a - oo) / dd, (b - oo) / dd
        if t0 > t1:
            t0, t1 = t1, t0
        if t0 > enter:
            enter, enter_axes = t0, [axis]
        elif t0 == enter:
            enter_axes.append(axis)
        if t1 < leave:
            leave, leave_axes = t1, [axis]
        elif t1 == leave:
            leave_axes.append(axis)
    return enter, leave, enter_axes, leave_axes


def slab_probe(name: str, lo: Vec, hi: Vec, o: Vec, d: Vec, visibility: str = "visible") -> Probe:
    enter, leave, ea, la = exact_slabs(lo, hi, o, d)
    if enter > leave:
        expected: tuple = (0.0, None, None, None, None)
    else:
        expected = (
            1.0,
            float(enter),
            float(leave),
            float(ea[0]) if len(ea) == 1 else None,  # a tie (an edge): either axis is right
            float(la[0]) if len(la) == 1 else None,
        )
    return Probe(
        name=name,
        lesson=LESSON,
        concept=SLAB,
        function="slab_interval",
        inputs=(*lo, *hi, *o, *d),
        expected=expected,
        labels=("inside (t_enter <= t_leave)", "t_enter", "t_leave", "enter_axis", "leave_axis"),
        ulps=8,
        visibility=visibility,
        inputs_text=f"box min {vec_text(lo)}, max {vec_text(hi)}; {_ray_text(o, d)}",
        hint="per axis t0 = (min - o) / d, t1 = (max - o) / d, swapped when d < 0; t_enter is the "
        "largest t0, t_leave the smallest t1; a zero component of d bounds nothing when o is in "
        "the slab (also on its plane, where 0 * infinity = NaN) and empties the box when not",
    )


# --- the box's hit ---------------------------------------------------------------------------


def crossing_probe(
    name: str,
    enter: float,
    leave: float,
    axes: tuple[int, int],
    lo: float = 0.0,
    hi: float = INF,
    visibility: str = "visible",
) -> Probe:
    if enter > leave:
        expected: tuple = (0.0, None, None, None)
    elif lo < enter < hi:
        expected = (1.0, enter, float(axes[0]), 1.0)
    elif lo < leave < hi:
        expected = (1.0, leave, float(axes[1]), 0.0)
    else:
        expected = (0.0, None, None, None)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=BOX_HIT,
        function="box_crossing",
        inputs=(enter, leave, float(axes[0]), float(axes[1]), lo, hi),
        expected=expected,
        labels=("found", "t", "axis", "entering"),
        ulps=0,
        visibility=visibility,
        inputs_text=f"slabs: the ray enters at t = {enter:g} (axis {axes[0]}) and leaves at "
        f"t = {leave:g} (axis {axes[1]}); range ({lo:g}, {hi:g})",
        hint="no hit when the overlap is empty; the entry when it lies inside the open range, "
        "else the exit (the ray starts inside the box), else no hit",
    )


# --- the triangle ----------------------------------------------------------------------------


def _sub(a: Vec, b: Vec) -> tuple[F, F, F]:
    return (F(a[0]) - F(b[0]), F(a[1]) - F(b[1]), F(a[2]) - F(b[2]))


def _cross(a: tuple, b: tuple) -> tuple[F, F, F]:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a: tuple, b: tuple) -> F:
    return sum((F(x) * F(y) for x, y in zip(a, b, strict=True)), F(0))


def exact_triangle(p0: Vec, p1: Vec, p2: Vec, o: Vec, d: Vec) -> tuple[F, F, F, F] | None:
    """(t, b0, b1, b2) where the line o + t d meets the triangle's plane (Cramer's rule), or
    None for a line parallel to it."""
    e1, e2, s = _sub(p1, p0), _sub(p2, p0), _sub(o, p0)
    dd = tuple(F(x) for x in d)
    pvec = _cross(dd, e2)
    det = _dot(e1, pvec)
    if det == 0:
        return None
    b1 = _dot(s, pvec) / det
    qvec = _cross(s, e1)
    b2 = _dot(dd, qvec) / det
    t = _dot(e2, qvec) / det
    return t, 1 - b1 - b2, b1, b2


def facing(p0: Vec, p1: Vec, p2: Vec, d: Vec) -> F:
    """N.d with N = cross(p1 - p0, p2 - p0): < 0 when the ray meets the front."""
    return _dot(_cross(_sub(p1, p0), _sub(p2, p0)), d)


def triangle_probe(
    name: str,
    concept: str,
    tri: tuple[Vec, Vec, Vec],
    o: Vec,
    d: Vec,
    lo: float = 0.0,
    hi: float = INF,
    visibility: str = "visible",
) -> Probe:
    p0, p1, p2 = tri
    found = exact_triangle(p0, p1, p2, o, d)
    hit = found is not None and min(found[1:]) >= 0 and lo < found[0] <= hi
    expected: tuple = (0.0, None, None, None, None)
    if hit:
        assert found is not None
        expected = (1.0, *(float(x) for x in found))
    reach = max(math.dist(p, o) for p in tri) / math.hypot(*d)
    side = "front" if facing(p0, p1, p2, d) < 0 else "back"
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="intersect_triangle",
        inputs=(*p0, *p1, *p2, *o, *d, lo, hi),
        expected=expected,
        labels=("found", "t", "b0", "b1", "b2"),
        ulps=64,
        scale=max(1.0, reach),
        visibility=visibility,
        inputs_text=f"triangle p0 = {vec_text(p0)}, p1 = {vec_text(p1)}, p2 = {vec_text(p2)}; "
        f"{_ray_text(o, d)}; range ({lo:g}, {hi:g}); the ray meets the plane from the "
        f"{side} (the front: the side from which p0, p1, p2 run counter-clockwise)",
        hint="a hit when the point is inside all three edges (b0, b1, b2 >= 0, b0 + b1 + b2 = 1), "
        "from either side of the triangle, and t lies in (range.min, range.max]",
    )


def hit_record_probe(
    name: str, tri: tuple[Vec, Vec, Vec], t: float, b: Vec, visibility: str = "visible"
) -> Probe:
    p0, p1, p2 = tri
    assert sum(F(x) for x in b) == 1  # exact barycentric coordinates
    p = tuple(sum(F(bi) * F(pi[k]) for bi, pi in zip(b, tri, strict=True)) for k in range(3))
    n = _cross(_sub(p1, p0), _sub(p2, p0))
    length = sqrt_fraction(sum(x * x for x in n))
    unit = tuple(to_float(_dec(x) / length) for x in n)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=NORMAL,
        function="triangle_hit",
        inputs=(*p0, *p1, *p2, t, *b),
        expected=(t, *(float(x) for x in p), *unit, *unit),
        labels=("t", *(f"p.{c}" for c in XYZ), *(f"N.{c}" for c in XYZ), *(f"Ng.{c}" for c in XYZ)),
        ulps=16,
        scale=max(1.0, *(abs(x) for v in tri for x in v)),
        visibility=visibility,
        inputs_text=f"triangle p0 = {vec_text(p0)}, p1 = {vec_text(p1)}, p2 = {vec_text(p2)}; "
        f"t = {t:g}, barycentric coordinates {vec_text(b)}",
        hint="p = b0 p0 + b1 p1 + b2 p2; N = Ng = the unit vector along cross(p1 - p0, p2 - p0) "
        "(the side from which p0, p1, p2 run counter-clockwise)",
    )


def _dec(x: F) -> Decimal:
    with localcontext() as context:
        context.prec = 50
        return Decimal(x.numerator) / Decimal(x.denominator)


# --- the probes ------------------------------------------------------------------------------

CUBE = ((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
SLAB_BOX = ((-1.0, -2.0, 0.5), (3.0, 1.0, 2.5))
T1 = ((0.0, 0.0, 0.0), (2.0, 0.0, 0.0), (0.0, 2.0, 0.0))  # front: +z
T1R = (T1[0], T1[2], T1[1])  # the same triangle, wound the other way (front: -z)
T3 = ((1.0, 2.0, 3.0), (4.0, 2.5, 3.5), (2.0, 5.0, 2.0))
T4 = ((0.0, -1.0, -1.0), (0.5, 2.0, -1.0), (-0.25, 0.0, 2.0))  # facing +x, met along x
T4R = (T4[0], T4[2], T4[1])
DOWN: Vec = (0.0, 0.0, -1.0)
UP: Vec = (0.0, 0.0, 1.0)


def probes() -> list[Probe]:
    h = HIDDEN
    lo, hi = CUBE
    blo, bhi = SLAB_BOX
    return [
        # The slab test.
        slab_probe("slab: along +z through the box", lo, hi, (0, 0, -5), UP),
        slab_probe("slab: along -z (t0 > t1 for d.z < 0)", lo, hi, (0, 0, 5), DOWN),
        slab_probe(
            "slab: oblique, two negative components", blo, bhi, (5, 3, -1), (-1, -0.75, 0.5)
        ),
        slab_probe("slab: from inside, t_enter < 0", blo, bhi, (0, 0, 1), (0.5, 0.25, 1)),
        slab_probe("slab: d.y = 0 outside the y slab misses", lo, hi, (0, 3, -5), UP),
        slab_probe("slab: oblique, slabs that do not overlap", lo, hi, (-3, 0, -3), (1, 0, 0.125)),
        slab_probe(
            "slab: in the plane of the face z = max (0 * inf)", lo, hi, (0, -5, 1), (0, 1, 0)
        ),
        slab_probe("slab: in the plane of the face x = min (0 * inf)", lo, hi, (-1, 0, -5), UP),
        slab_probe("slab: hidden oblique", blo, bhi, (-4, 4, 4), (1, -1.25, -0.5), h),
        slab_probe("slab: hidden, in the face z = min", blo, bhi, (-3, 0, 0.5), (1, 0.125, 0), h),
        slab_probe("slab: hidden, in the face y = max", blo, bhi, (0, 1, -2), (0.25, 0, 1), h),
        slab_probe("slab: hidden miss past a corner", lo, hi, (-3, -3, 0), (1, 0.25, 0), h),
        # The box's hit.
        crossing_probe("box: the entry", 2, 5, (0, 1)),
        crossing_probe("box: from inside, the exit", -1, 3, (2, 0)),
        crossing_probe("box: behind the ray", -5, -2, (1, 2)),
        crossing_probe("box: an empty overlap (a miss)", 4, 3, (0, 1)),
        crossing_probe("box: beyond range.max", 2, 5, (0, 1), 0, 1.5),
        crossing_probe("box: the entry before range.min, so the exit", 2, 5, (1, 2), 3),
        crossing_probe("box: hidden entry", 0.5, 0.75, (2, 1), 1e-4, 10, h),
        crossing_probe("box: hidden, both outside the range", 2, 5, (0, 2), 2.5, 4, h),
        crossing_probe("box: hidden, from inside", -0.25, 0.125, (1, 0), 0, 100, h),
        # The generic triangle (rays that meet its front).
        triangle_probe("triangle: straight down onto it", TRIANGLE, T1, (0.5, 0.5, 3), DOWN),
        triangle_probe("triangle: oblique", TRIANGLE, T1, (-1, -1, 4), (0.375, 0.5, -1)),
        triangle_probe(
            "triangle: beyond the edge p1 p2 (b1 + b2 > 1)", TRIANGLE, T1, (1.5, 1.5, 3), DOWN
        ),
        triangle_probe(
            "triangle: outside the edge p0 p2 (b1 < 0)", TRIANGLE, T1, (-0.5, 0.5, 3), DOWN
        ),
        triangle_probe("triangle: behind the ray (t < 0)", TRIANGLE, T1, (0.5, 0.5, -3), DOWN),
        triangle_probe("triangle: beyond range.max", TRIANGLE, T1, (0.5, 0.5, 3), DOWN, 0, 2),
        triangle_probe(
            "triangle: t in (range.min, range.max)", TRIANGLE, T1, (0.5, 0.5, 3), DOWN, 1, 5
        ),
        triangle_probe(
            "triangle: a ray parallel to its plane", TRIANGLE, T1, (-1, 0.5, 1), (1, 0, 0)
        ),
        triangle_probe(
            "triangle: hidden oblique", TRIANGLE, T3, (2.5, 3.5, 8), (-0.25, -0.5, -2), visibility=h
        ),
        triangle_probe(
            "triangle: hidden, outside the edge p0 p1",
            TRIANGLE,
            T3,
            (2.5, 1, 8),
            (0, 0, -1),
            visibility=h,
        ),
        triangle_probe(
            "triangle: hidden, behind the ray",
            TRIANGLE,
            T3,
            (2.5, 3.5, 8),
            (0.25, 0.5, 2),
            0,
            10,
            h,
        ),
        # Both sides: each triangle from both sides, wound both ways.
        triangle_probe("sides: the front, from above", SIDES, T1, (0.5, 0.25, 3), DOWN),
        triangle_probe("sides: the back, from below", SIDES, T1, (0.5, 0.25, -3), UP),
        triangle_probe("sides: wound the other way, from above", SIDES, T1R, (0.5, 0.25, 3), DOWN),
        triangle_probe("sides: wound the other way, from below", SIDES, T1R, (0.5, 0.25, -3), UP),
        triangle_probe(
            "sides: hidden, front along -x", SIDES, T4, (3, 0.25, 0.125), (-1, 0, 0), visibility=h
        ),
        triangle_probe(
            "sides: hidden, back along +x", SIDES, T4, (-3, 0.25, 0.125), (1, 0, 0), visibility=h
        ),
        triangle_probe(
            "sides: hidden, wound the other way, along -x",
            SIDES,
            T4R,
            (3, 0.25, 0.125),
            (-1, 0.0625, 0),
            visibility=h,
        ),
        triangle_probe(
            "sides: hidden, wound the other way, along +x",
            SIDES,
            T4R,
            (-3, 0.25, 0.125),
            (1, 0, 0.0625),
            visibility=h,
        ),
        # The hit record.
        hit_record_probe("record: a hit on the triangle in z = 0", T1, 3, (0.5, 0.25, 0.25)),
        hit_record_probe(
            "record: a normal of length 7 made unit",
            ((1, 0, 0), (0, 3, 0), (0, 0, 2)),
            2.5,
            (0.25, 0.25, 0.5),
        ),
        hit_record_probe(
            "record: wound the other way, the normal turns",
            ((1, 0, 0), (0, 0, 2), (0, 3, 0)),
            2.5,
            (0.25, 0.5, 0.25),
        ),
        hit_record_probe("record: hidden oblique", T3, 4.75, (0.125, 0.375, 0.5), h),
        hit_record_probe("record: hidden, at a vertex", T4, 1.5, (0.0, 0.0, 1.0), h),
    ]
