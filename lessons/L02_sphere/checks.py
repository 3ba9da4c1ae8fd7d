"""L02's probes: ray/sphere roots, the nearest hit in range, the five cases.

Expected values are computed here from the exact binary values of the inputs: a = d.d,
b = f.d, c0 = f.f - r^2 and D = b^2 - a c0 as Fractions (exact), the roots
(-b -+ sqrt(D)) / a to 50 digits. The inputs are chosen so that every root is well
conditioned (|b| and sqrt(D) of the same size): any correct formula, the textbook one or the
stable one of the core, then lands within a few roundings of the ray's scale, (|f| + r) / |d|,
per root; 16 ulps of that scale covers a dozen chained operations (Higham's gamma(n)) and a
wrong formula misses by far more (a factor, a sign, a swapped root).
"""

from __future__ import annotations

import math
from fractions import Fraction

from lessons.probe import HIDDEN, Probe, Vec, dot, sqrt_fraction, sub, to_float, vec_text

LESSON = "L02"
ROOTS = "the roots of the quadratic"
NEAREST = "the nearest hit in range"
CASES = "the five cases: none, once, tangent, internal, twice"
# A concept whose probes run code of another: its failures may follow from that one's.
DEPENDS = {NEAREST: (ROOTS,), CASES: (ROOTS,)}
CASE_NAMES = ("none", "once_from_inside", "tangent", "internal", "twice")


def _exact_roots(
    c: Vec, r: float, o: Vec, d: Vec
) -> tuple[Fraction, Fraction, float, float] | None:
    f = sub(o, c)
    a = dot(d, d)
    b = sum((x * Fraction(y) for x, y in zip(f, d, strict=True)), Fraction(0))
    c0 = sum((x * x for x in f), Fraction(0)) - Fraction(r) ** 2
    disc = b * b - a * c0
    if disc < 0:
        return None
    s = sqrt_fraction(disc)
    t0 = (-_dec(b) - s) / _dec(a)
    t1 = (-_dec(b) + s) / _dec(a)
    return c0, b, to_float(t0), to_float(t1)


def _dec(x: Fraction):  # noqa: ANN202 - a Decimal at the context's precision
    from decimal import Decimal, localcontext

    with localcontext() as context:
        context.prec = 50
        return Decimal(x.numerator) / Decimal(x.denominator)


def _scale(c: Vec, r: float, o: Vec, d: Vec) -> float:
    f = [x - y for x, y in zip(o, c, strict=True)]
    return (math.hypot(*f) + r) / math.hypot(*d)


def _inputs(c: Vec, r: float, o: Vec, d: Vec) -> str:
    return f"sphere centre {vec_text(c)}, radius {r:g}; ray o = {vec_text(o)}, d = {vec_text(d)}"


def roots_probe(name: str, c: Vec, r: float, o: Vec, d: Vec, visibility: str = "visible") -> Probe:
    found = _exact_roots(c, r, o, d)
    expected = (0.0, None, None) if found is None else (1.0, found[2], found[3])
    return Probe(
        name=name,
        lesson=LESSON,
        concept=ROOTS,
        function="sphere_roots",
        inputs=(*c, r, *o, *d),
        expected=expected,
        labels=("real", "t0", "t1"),
        ulps=16,
        scale=_scale(c, r, o, d),
        visibility=visibility,
        inputs_text=_inputs(c, r, o, d),
        hint="a = d.d, b = f.d, c0 = f.f - r^2 with f = o - c; real = false when the "
        "discriminant b^2 - a c0 is negative; t0 <= t1",
    )


def case_of(c: Vec, r: float, o: Vec, d: Vec) -> int:
    """The slide's five cases, from the exact roots."""
    found = _exact_roots(c, r, o, d)
    if found is None:
        return 0
    c0, b, t0, t1 = found
    if c0 == 0:  # the origin is on the surface
        if b < 0 and t1 > 0:
            return 3  # internal
        return 2 if t0 == t1 else 0
    if t1 <= 0:
        return 0
    if t0 == t1:
        return 2
    return 1 if t0 <= 0 else 4


def case_probe(name: str, c: Vec, r: float, o: Vec, d: Vec, visibility: str = "visible") -> Probe:
    case = case_of(c, r, o, d)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=CASES,
        function="sphere_case",
        inputs=(*c, r, *o, *d),
        expected=(float(case),),
        labels=(f"case (0..4 = {', '.join(CASE_NAMES)}; expected {CASE_NAMES[case]})",),
        ulps=0,
        visibility=visibility,
        inputs_text=_inputs(c, r, o, d),
        hint="none (misses, or lies behind), once from inside (t0 < 0 < t1), tangent (a double "
        "root), internal (starts on the surface, runs inside), twice (enters and leaves)",
    )


def nearest_probe(
    name: str,
    c: Vec,
    r: float,
    o: Vec,
    d: Vec,
    lo: float = 0.0,
    hi: float = math.inf,
    visibility: str = "visible",
) -> Probe:
    found = _exact_roots(c, r, o, d)
    want = math.inf
    if found is not None:
        for t in (found[2], found[3]):
            if lo < t < hi and not (t == 0 and found[0] == 0):
                want = t
                break
    return Probe(
        name=name,
        lesson=LESSON,
        concept=NEAREST,
        function="sphere_t",
        inputs=(*c, r, *o, *d, lo, hi),
        expected=(want,),
        labels=("t",),
        ulps=16,
        scale=_scale(c, r, o, d),
        visibility=visibility,
        inputs_text=f"{_inputs(c, r, o, d)}; range ({lo:g}, {hi:g})",
        hint="the smaller root inside the open range, else the larger one, else infinity: a "
        "root behind the ray or at its own start is not a hit",
    )


ORIGIN: Vec = (0.0, 0.0, 0.0)
Z: Vec = (0.0, 0.0, 1.0)


def probes() -> list[Probe]:
    hidden = HIDDEN
    return [
        roots_probe("roots: a ray through the centre, twice", ORIGIN, 1, (0, 0, -3), Z),
        roots_probe("roots: a direction of length 2 (a = d.d)", ORIGIN, 1, (0, 0, -3), (0, 0, 2)),
        roots_probe("roots: a line that misses", ORIGIN, 1, (0, 2, -3), Z),
        roots_probe("roots: a tangent line, a double root", ORIGIN, 1, (1, 0, -3), Z),
        roots_probe("roots: from the centre, t0 < 0 < t1", ORIGIN, 1, ORIGIN, Z),
        roots_probe("roots: off-centre sphere, oblique ray", (1, 2, 3), 2, ORIGIN, (1, 1, 1)),
        roots_probe(
            "roots: hidden variant", (-2, 0.5, 4), 1.5, (0.25, -1, 0), (-0.5, 0.375, 1), hidden
        ),
        roots_probe("roots: hidden miss", (3, 0, 0), 1, ORIGIN, (0, 1, 0.5), hidden),
        nearest_probe("nearest: twice, the entry t0", ORIGIN, 1, (0, 0, -3), Z),
        nearest_probe("nearest: from inside, t0 behind so t1", ORIGIN, 1, ORIGIN, Z),
        nearest_probe("nearest: the sphere behind the ray", ORIGIN, 1, (0, 0, 3), Z),
        nearest_probe("nearest: t0 before the range, so t1", ORIGIN, 1, (0, 0, -3), Z, 2.5),
        nearest_probe("nearest: both roots past the range", ORIGIN, 1, (0, 0, -3), Z, 0, 1.5),
        nearest_probe("nearest: from the surface inwards, not t = 0", ORIGIN, 1, (0, 0, -1), Z),
        nearest_probe("nearest: a line that misses", ORIGIN, 1, (0, 2, -3), Z),
        nearest_probe(
            "nearest: hidden variant", (1, 2, 3), 2, ORIGIN, (1, 1, 1), 1e-4, 100, hidden
        ),
        nearest_probe(
            "nearest: hidden, range max between", (0, 0, 10), 2, ORIGIN, (0, 0, 2), 1, 5, hidden
        ),
        case_probe("case: a line that misses (none)", ORIGIN, 1, (0, 2, -3), Z),
        case_probe("case: the sphere behind the ray (none)", ORIGIN, 1, (0, 0, 3), Z),
        case_probe("case: from inside (once)", ORIGIN, 1, ORIGIN, Z),
        case_probe("case: grazing (tangent)", ORIGIN, 1, (1, 0, -3), Z),
        case_probe("case: from the surface inwards (internal)", ORIGIN, 1, (0, 0, -1), Z),
        case_probe("case: enters and leaves (twice)", ORIGIN, 1, (0, 0, -3), Z),
        case_probe("case: from the surface outwards (none)", ORIGIN, 1, (0, 0, -1), (0, 0, -1)),
        case_probe("case: hidden tangent", (0, 0, 5), 2, (2, 0, 0), Z, hidden),
        case_probe("case: hidden twice", (1, 2, 3), 2, (-3, -2, -1), (1, 1, 1), hidden),
    ]
