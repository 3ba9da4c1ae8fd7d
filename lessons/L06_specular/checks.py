"""L06's probes: the mirror vector and the Phong highlight.

reflect(d, N) = d - 2(d.N)N is computed here exactly (Fractions) and rounded once; the core
rounds a dot product (3 products, 2 sums), a product by 2 (exact), three products and three
subtractions: 8 ulps of |d| (1 here). phong_term(R, L, n) = max(R.L, 0)^n: the cosine carries
4 ulps, which the power multiplies by n, and power() adds |n ln x| 2^-53 (power.h), so
4 (n + |n ln x| + 4) ulps of the value itself.
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext
from fractions import Fraction

from lessons.probe import HIDDEN, XYZ, Probe, Vec, dot, vec_text

LESSON = "L06"
MIRROR = "the mirror vector R = 2(N.L)N - L"
PHONG = "the Phong highlight"
DEPENDS: dict[str, tuple[str, ...]] = {}


def reflect_probe(name: str, d: Vec, n: Vec, visibility: str = "visible") -> Probe:
    dn = dot(d, n)
    want = tuple(float(Fraction(x) - 2 * dn * Fraction(y)) for x, y in zip(d, n, strict=True))
    return Probe(
        name=name,
        lesson=LESSON,
        concept=MIRROR,
        function="reflect",
        inputs=(*d, *n),
        expected=want,
        labels=tuple(f"R.{c}" for c in XYZ),
        ulps=8,
        visibility=visibility,
        inputs_text=f"d = {vec_text(d)}, N = {vec_text(n)}",
        hint="R = d - 2(d.N)N: the tangential part of d kept, the normal part turned back",
    )


def phong_probe(name: str, r: Vec, l_: Vec, n: float, visibility: str = "visible") -> Probe:
    cos = dot(r, l_)
    if cos <= 0:
        want = 0.0
        ulps = 0.0
    else:
        with localcontext() as context:
            context.prec = 50
            c = Decimal(cos.numerator) / Decimal(cos.denominator)
            want = float((c.ln() * Decimal(n)).exp())
        ulps = 4 * (n + abs(n * math.log(float(cos))) + 4)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=PHONG,
        function="phong_term",
        inputs=(*r, *l_, n),
        expected=(want,),
        labels=("highlight",),
        ulps=ulps,
        scale=0.0,
        visibility=visibility,
        inputs_text=f"R = {vec_text(r)}, L = {vec_text(l_)}, shininess {n:g}",
        hint="(R.L)^shininess (power()), and 0 when R.L <= 0: no highlight from behind",
    )


def probes() -> list[Probe]:
    up = (0.0, 1.0, 0.0)
    return [
        reflect_probe("mirror: straight down onto a floor", (0, -1, 0), up),
        reflect_probe("mirror: at 45 degrees", (0.6, -0.8, 0), up),
        reflect_probe("mirror: a tilted normal", (0, 0, -1), (0, 0.6, 0.8)),
        reflect_probe("mirror: hidden variant", (0.48, -0.6, 0.64), (0.0, 0.8, 0.6), HIDDEN),
        phong_probe("Phong: R points at the light", up, up, 40),
        phong_probe("Phong: 37 degrees off, shininess 10", up, (0.6, 0.8, 0), 10),
        phong_probe("Phong: shininess 2 (an even power)", up, (0.0, -0.6, 0.8), 2),
        phong_probe("Phong: the light behind, shininess 3", up, (0.0, -0.8, 0.6), 3),
        phong_probe("Phong: hidden variant", (0.0, 0.6, 0.8), (0.0, 0.8, 0.6), 25, HIDDEN),
    ]
