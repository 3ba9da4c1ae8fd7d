"""L04's probes: ambient light, Lambert's N.L, the direction to the light, the normal facing the
ray, coloured lights.

The expected values are exact products and dot products of the inputs (Fractions) rounded once
to double; the functions round each product and sum once, so a few ulps: ambient_term() is two
products per channel (4 ulps of the value), lambert_term() a dot product of unit vectors
(3 products, 2 sums: 4 ulps of 1), to_light() a subtraction, a length and a division
(8 ulps of 1). face_the_ray() only negates: exact.
"""

from __future__ import annotations

import math
from fractions import Fraction

from lessons.probe import HIDDEN, RGB, XYZ, Probe, Vec, dot, vec_text

LESSON = "L04"
AMBIENT = "ambient light"
DIFFUSE = "diffuse (Lambertian) reflection N.L"
TO_LIGHT = "the direction to the light L"
FACING = "the normal facing the ray"
COLOURED = "coloured lights"
DEPENDS: dict[str, tuple[str, ...]] = {}


def ambient_probe(
    name: str, concept: str, colour: Vec, ambient: float, light: Vec, visibility: str = "visible"
) -> Probe:
    want = tuple(
        float(Fraction(c) * Fraction(ambient) * Fraction(li))
        for c, li in zip(colour, light, strict=True)
    )
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="ambient_term",
        inputs=(*colour, ambient, *light),
        expected=want,
        labels=tuple(f"colour.{c}" for c in RGB),
        ulps=4,
        scale=0.0,
        visibility=visibility,
        inputs_text=f"material colour {vec_text(colour)}, ambient {ambient:g}; "
        f"ambient light {vec_text(light)}",
        hint="per channel: material colour x ambient coefficient x the ambient light's colour",
    )


def lambert_probe(name: str, n: Vec, l_: Vec, visibility: str = "visible") -> Probe:
    value = float(dot(n, l_))
    # Back-facing: the solution returns N.L as it is, a student may clamp it to 0; local_color()
    # skips both, so anything up to 0 (plus the rounding of 4 ulps) passes.
    expected = (("<=", 4 * 2.0**-53),) if value < 0 else (value,)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=DIFFUSE,
        function="lambert_term",
        inputs=(*n, *l_),
        expected=expected,
        labels=("N.L",),
        ulps=4,
        visibility=visibility,
        inputs_text=f"N = {vec_text(n)}, L = {vec_text(l_)}",
        hint="the cosine N.L of the unit normal and the unit direction towards the light; a light "
        "behind the surface (N.L < 0) gives no light, never |N.L|",
    )


def to_light_probe(
    name: str, directional: bool, where: Vec, p: Vec, visibility: str = "visible"
) -> Probe:
    if directional:
        want = tuple(-x for x in where)
        text = f"a directional light travelling along {vec_text(where)}; p = {vec_text(p)}"
    else:
        v = [a - b for a, b in zip(where, p, strict=True)]
        length = math.sqrt(float(sum(Fraction(x) ** 2 for x in v)))
        want = tuple(x / length for x in v)
        text = f"a point light at {vec_text(where)}; p = {vec_text(p)}"
    return Probe(
        name=name,
        lesson=LESSON,
        concept=TO_LIGHT,
        function="to_light",
        inputs=(
            1.0 if directional else 0.0,
            *(where if not directional else p),
            *(where if directional else p),
            *p,
        ),
        expected=want,
        labels=tuple(f"L.{c}" for c in XYZ),
        ulps=8,
        visibility=visibility,
        inputs_text=text,
        hint="L points from p towards the light and has unit length; a directional light lies "
        "against its direction of travel: L = -direction",
    )


def facing_probe(name: str, n: Vec, ng: Vec, d: Vec, visibility: str = "visible") -> Probe:
    ng_out = tuple(-x for x in ng) if dot(ng, d) > 0 else ng
    n_out = tuple(-x for x in n) if dot(n, ng_out) < 0 else n
    return Probe(
        name=name,
        lesson=LESSON,
        concept=FACING,
        function="face_the_ray",
        inputs=(*n, *ng, *d),
        expected=(*map(float, n_out), *map(float, ng_out)),
        labels=(*(f"N.{c}" for c in XYZ), *(f"Ng.{c}" for c in XYZ)),
        ulps=0,
        visibility=visibility,
        inputs_text=f"hit.N = {vec_text(n)}, hit.Ng = {vec_text(ng)}, "
        f"ray direction d = {vec_text(d)}",
        hint="Ng turned against d (Ng.d < 0: the side the ray comes from), then N turned to "
        "Ng's side (N.Ng > 0)",
    )


def probes() -> list[Probe]:
    warm = (0.8, 0.4, 0.2)
    white = (1.0, 1.0, 1.0)
    up = (0.0, 1.0, 0.0)
    return [
        ambient_probe("ambient: a coloured material in white light", AMBIENT, warm, 0.25, white),
        ambient_probe("ambient: coefficient 0.1", AMBIENT, (0.5, 0.5, 1.0), 0.1, white),
        ambient_probe("ambient: hidden variant", AMBIENT, (0.3, 0.9, 0.6), 0.2, white, HIDDEN),
        ambient_probe(
            "coloured: a white material in coloured light", COLOURED, white, 0.5, (0.2, 0.4, 0.8)
        ),
        ambient_probe("coloured: colour times colour", COLOURED, warm, 0.5, (0.25, 0.5, 1.0)),
        ambient_probe(
            "coloured: hidden variant", COLOURED, (0.9, 0.1, 0.5), 0.3, (0.5, 1.0, 0.25), HIDDEN
        ),
        lambert_probe("N.L: the light straight above", up, up),
        lambert_probe("N.L: a light at 53 degrees", up, (0.6, 0.8, 0.0)),
        lambert_probe("N.L: a tilted normal", (0.0, 0.6, 0.8), (0.0, 0.8, 0.6)),
        lambert_probe("N.L: the light behind the surface", up, (0.0, -0.6, 0.8)),
        lambert_probe(
            "N.L: hidden, behind at a grazing angle",
            (0.0, 0.8, 0.6),
            (0.0, -0.6, 0.8 - 1e-3),
            HIDDEN,
        ),
        lambert_probe("N.L: hidden variant", (0.6, 0.0, 0.8), (0.8, 0.0, 0.6), HIDDEN),
        to_light_probe("L: a point light straight above", False, (0, 10, 0), (0, 0, 0)),
        to_light_probe("L: a point light at (3, 4, 0)", False, (3, 4, 0), (0, 0, 0)),
        to_light_probe("L: a point light, p off the origin", False, (1, 2, 3), (4, 6, 3)),
        to_light_probe("L: a directional light shining down", True, (0, -1, 0), (5, 0, 1)),
        to_light_probe("L: an oblique directional light", True, (0.6, -0.8, 0), (0, 0, 0)),
        to_light_probe("L: hidden point light", False, (-2, 5, 1), (1, 1, 1), HIDDEN),
        facing_probe("facing: the ray meets the front", up, up, (0, -1, 0)),
        facing_probe("facing: the ray meets the back", up, up, (0, 1, 0)),
        facing_probe("facing: a smooth N on the far side of Ng", (0.6, -0.8, 0), up, (0, -1, 0)),
        facing_probe("facing: the back, N and Ng both turn", (0.6, 0.8, 0), up, (1, 1, 0)),
        facing_probe(
            "facing: hidden, an oblique back hit",
            (0.0, 0.6, 0.8),
            (0.0, 0.0, 1.0),
            (0.5, 0.5, 0.5),
            HIDDEN,
        ),
    ]
