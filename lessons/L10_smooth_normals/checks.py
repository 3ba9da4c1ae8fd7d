"""L10's probes: Gouraud shading's interpolated vertex normals.

The expected normal is the exact blend n = b0 n0 + b1 n1 + b2 n2 of the inputs (Fractions),
divided by its length to 50 digits (sqrt of the exact |n|^2), rounded once to double; Ng where
the blend is exactly zero. The core rounds 3 products and 2 sums per component, then a length
(3 products, 2 sums, a square root) and a division: about a dozen roundings, each at most u of
a value of size <= 1 relative to |n|. The blends here have |n| >= 1/2, so 16 ulps of 1 is a few
times the worst case; a wrong weight or a missing normalisation is off by a visible fraction.

The first concept's probes sit where the blend is already unit length (at a vertex, or where
the normals that carry weight are equal), so that they name the weights alone; the second's
sit between different normals, where only a renormalised blend is right.
"""

from __future__ import annotations

from decimal import Decimal, localcontext
from fractions import Fraction

from lessons.probe import HIDDEN, XYZ, Probe, Vec, sqrt_fraction, vec_text

LESSON = "L10"
WEIGHTS = "Gouraud shading: the vertex normals weighted by the barycentric coordinates"
UNIT = "Gouraud shading: the interpolated normal made unit length again"
# The renormalisation's probes run the blend too.
DEPENDS: dict[str, tuple[str, ...]] = {UNIT: (WEIGHTS,)}


def _dec(x: Fraction) -> Decimal:
    with localcontext() as context:
        context.prec = 50
        return Decimal(x.numerator) / Decimal(x.denominator)


def smooth_probe(
    name: str,
    concept: str,
    b: Vec,
    normals: tuple[Vec, Vec, Vec],
    ng: Vec,
    visibility: str = "visible",
) -> Probe:
    assert sum(Fraction(x) for x in b) == 1  # exact barycentric coordinates
    blend = [
        sum((Fraction(bi) * Fraction(n[k]) for bi, n in zip(b, normals, strict=True)), Fraction(0))
        for k in range(3)
    ]
    squared = sum(x * x for x in blend)
    if squared == 0:
        want = tuple(float(x) for x in ng)
    else:
        length = sqrt_fraction(squared)
        with localcontext() as context:
            context.prec = 50
            want = tuple(float(_dec(x) / length) for x in blend)
    if concept == WEIGHTS:  # its probes must not need the renormalisation (see above): the
        # blend is unit length up to the rounding of the inputs (0.6 is not 3/5), 2 ulps.
        assert squared == 0 or abs(squared - 1) < 4 * 2.0**-53, name
    n0, n1, n2 = normals
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="smooth_normal",
        inputs=(*b, *n0, *n1, *n2, *ng),
        expected=want,
        labels=tuple(f"N.{c}" for c in XYZ),
        ulps=16,
        visibility=visibility,
        inputs_text=f"barycentric coordinates (b0, b1, b2) = {vec_text(b)}; vertex normals "
        f"n0 = {vec_text(n0)}, n1 = {vec_text(n1)}, n2 = {vec_text(n2)}; face normal "
        f"Ng = {vec_text(ng)}",
        hint="N = (b0 n0 + b1 n1 + b2 n2) / |b0 n0 + b1 n1 + b2 n2|: b0 weighs p0's normal n0, "
        "b1 weighs n1, b2 weighs n2; Ng only where the blend has zero length",
    )


# Unit normals with rational components, all different.
A: Vec = (0.0, 0.0, 1.0)
B: Vec = (0.6, 0.0, 0.8)
C: Vec = (0.0, 0.6, 0.8)
D: Vec = (-0.8, 0.0, 0.6)
E: Vec = (0.0, -0.28, 0.96)
NG: Vec = (0.0, 0.0, 1.0)
NG2: Vec = (0.6, 0.8, 0.0)


def probes() -> list[Probe]:
    h = HIDDEN
    return [
        smooth_probe(
            "weights: a flat region, all three normals equal",
            WEIGHTS,
            (0.25, 0.25, 0.5),
            (C, C, C),
            NG,
        ),
        smooth_probe("weights: at vertex p0", WEIGHTS, (1, 0, 0), (B, C, D), NG),
        smooth_probe("weights: at vertex p1", WEIGHTS, (0, 1, 0), (B, C, D), NG),
        smooth_probe("weights: at vertex p2", WEIGHTS, (0, 0, 1), (B, C, D), NG),
        smooth_probe(
            "weights: on edge p0 p1, both normals equal", WEIGHTS, (0.25, 0.75, 0), (C, C, B), NG
        ),
        smooth_probe(
            "weights: inside, n1 = n2, b0 = 0", WEIGHTS, (0, 0.375, 0.625), (D, E, E), NG2
        ),
        smooth_probe("weights: hidden, at vertex p1", WEIGHTS, (0, 1, 0), (E, D, B), NG2, h),
        smooth_probe(
            "weights: hidden, on edge p0 p2, equal normals",
            WEIGHTS,
            (0.5, 0, 0.5),
            (D, B, D),
            NG,
            h,
        ),
        smooth_probe("weights: hidden, at vertex p2", WEIGHTS, (0, 0, 1), (A, C, E), NG, h),
        smooth_probe("unit: the centre", UNIT, (0.25, 0.25, 0.5), (B, C, D), NG),
        smooth_probe("unit: midway along edge p0 p1", UNIT, (0.5, 0.5, 0), (B, C, A), NG),
        smooth_probe("unit: near vertex p2", UNIT, (0.125, 0.125, 0.75), (A, B, C), NG),
        smooth_probe(
            "unit: opposite normals blend to zero: the face normal",
            UNIT,
            (0.5, 0.5, 0),
            ((0, 0, 1), (0, 0, -1), B),
            NG2,
        ),
        smooth_probe("unit: hidden, inside", UNIT, (0.5, 0.25, 0.25), (D, E, C), NG, h),
        smooth_probe("unit: hidden, on an edge", UNIT, (0, 0.75, 0.25), (A, B, E), NG, h),
    ]
