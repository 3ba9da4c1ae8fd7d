"""L03's probes: the plane (p - a).n = 0, a ray parallel to it, the hit in range.

t = (a - o).n / (d.n) is computed here as a Fraction of the inputs' exact values. The core's
plane_t() rounds two dot products (3 products and 2 sums each), a subtraction per component
and a division: a dozen roundings of the magnitudes involved, so 16 ulps of max(|t|, 1)
(the inputs are of size 1 to 4). A wrong formula misses by a sign or a factor |d|.
"""

from __future__ import annotations

import math

from lessons.probe import HIDDEN, Probe, Vec, dot, sub, to_float, vec_text

LESSON = "L03"
PLANE = "the plane (p - a).n = 0"
PARALLEL = "a ray parallel to the plane"
IN_RANGE = "the hit in range"
DEPENDS = {IN_RANGE: (PLANE,), PARALLEL: ()}

Y: Vec = (0.0, 1.0, 0.0)
ORIGIN: Vec = (0.0, 0.0, 0.0)


def _t(a: Vec, n: Vec, o: Vec, d: Vec) -> float:
    denominator = dot(d, n)
    if denominator == 0:
        return math.inf
    numerator = sum((x * y for x, y in zip(sub(a, o), map(float, n), strict=True)), 0 * denominator)
    return to_float(numerator / denominator)


def _inputs(a: Vec, n: Vec, o: Vec, d: Vec) -> str:
    return f"plane a = {vec_text(a)}, n = {vec_text(n)}; ray o = {vec_text(o)}, d = {vec_text(d)}"


def t_probe(
    name: str, concept: str, a: Vec, n: Vec, o: Vec, d: Vec, visibility: str = "visible"
) -> Probe:
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="plane_t",
        inputs=(*a, *n, *o, *d),
        expected=(_t(a, n, o, d),),
        labels=("t",),
        ulps=16,
        visibility=visibility,
        inputs_text=_inputs(a, n, o, d),
        hint="t = (a - o).n / (d.n); infinity when d.n = 0 (the ray runs parallel)"
        if concept == PARALLEL
        else "t = (a - o).n / (d.n), the parameter of o + t d (not a distance: d need not be unit)",
    )


def hit_probe(
    name: str,
    concept: str,
    a: Vec,
    n: Vec,
    o: Vec,
    d: Vec,
    lo: float = 0.0,
    hi: float = math.inf,
    visibility: str = "visible",
) -> Probe:
    t = _t(a, n, o, d)
    if lo < t < hi:
        p = tuple(x + t * y for x, y in zip(o, d, strict=True))
        expected: tuple = (1.0, t, *p, *n)
    else:
        expected = (0.0, None, None, None, None, None, None, None)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="intersect_plane",
        inputs=(*a, *n, *o, *d, lo, hi),
        expected=expected,
        labels=("found", "hit.t", "hit.p.x", "hit.p.y", "hit.p.z", "hit.N.x", "hit.N.y", "hit.N.z"),
        ulps=16,
        scale=4.0,  # |o| + |t d| of these inputs: p's rounding is relative to it
        visibility=visibility,
        inputs_text=f"{_inputs(a, n, o, d)}; range ({lo:g}, {hi:g})",
        hint="a hit only when range.min < t < range.max (open: t = range.min, the ray's own "
        "start, is no hit); then fill the record with plane_hit()",
    )


def probes() -> list[Probe]:
    hidden = HIDDEN
    tilted = (0.0, 0.6, 0.8)
    return [
        t_probe("plane: straight down onto the floor", PLANE, ORIGIN, Y, (0, 2, 0), (0, -1, 0)),
        t_probe(
            "plane: a tilted plane, an oblique ray", PLANE, (1, 2, 3), tilted, ORIGIN, (1, 1, 1)
        ),
        t_probe(
            "plane: a direction of length 4 (t is a parameter)",
            PLANE,
            ORIGIN,
            Y,
            (0, 2, 0),
            (0, -4, 0),
        ),
        t_probe("plane: the plane behind the ray, t < 0", PLANE, ORIGIN, Y, (0, 2, 0), (0, 1, 0)),
        t_probe(
            "plane: hidden variant",
            PLANE,
            (0.5, -1, 2),
            tilted,
            (3, 1, -2),
            (-0.5, -2, 0.25),
            hidden,
        ),
        t_probe("parallel: above the plane", PARALLEL, ORIGIN, Y, (0, 2, 0), (1, 0, 0)),
        t_probe("parallel: below the plane", PARALLEL, ORIGIN, Y, (0, -2, 0), (0, 0, 1)),
        t_probe("parallel: in the plane itself", PARALLEL, ORIGIN, Y, (1, 0, 1), (1, 0, 0)),
        hit_probe(
            "parallel: intersect_plane finds no hit", PARALLEL, ORIGIN, Y, (0, 2, 0), (1, 0, 0)
        ),
        t_probe(
            "parallel: hidden, a tilted plane",
            PARALLEL,
            (1, 2, 3),
            tilted,
            ORIGIN,
            (0, 0.8, -0.6),
            hidden,
        ),
        hit_probe("in range: a hit ahead", IN_RANGE, ORIGIN, Y, (0.5, 2, 0.25), (0, -1, 0)),
        hit_probe(
            "in range: the plane behind the ray", IN_RANGE, ORIGIN, Y, (0.5, 2, 0.25), (0, 1, 0)
        ),
        hit_probe(
            "in range: past the range's end", IN_RANGE, ORIGIN, Y, (0, 2, 0), (0, -1, 0), 0, 1.5
        ),
        hit_probe(
            "in range: at the ray's own start, t = 0", IN_RANGE, ORIGIN, Y, ORIGIN, (0, 1, 1)
        ),
        hit_probe(
            "in range: at the range's end, t = range.max",
            IN_RANGE,
            ORIGIN,
            Y,
            (0, 2, 0),
            (0, -1, 0),
            0,
            2,
        ),
        hit_probe(
            "in range: inside a range (1, 3)", IN_RANGE, ORIGIN, Y, (0, 2, 0), (0, -1, 0), 1, 3
        ),
        hit_probe(
            "in range: hidden, before the range",
            IN_RANGE,
            ORIGIN,
            Y,
            (0, 2, 0),
            (0, -1, 0),
            2.5,
            9,
            hidden,
        ),
    ]
