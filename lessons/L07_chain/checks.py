"""L07's probes: the colour of one hit, the reflection-coefficient chain and its three stops
(slides "Specular Reflected Light" and "Simple Ray Tracing Algorithm").

trace() is probed in scenes of mirror planes whose sequence of hits is known from the
geometry (argued at each scene below): no mirror, one floor, a corner (floor then wall, then
the ray escapes), and two parallel mirrors (the ray bounces between them for ever, so only
max_depth or min_coefficient stops it). Every mirror returns its ambient term alone
(C_k = colour * ambient, ambient light white; no lights). chain() below is the slide's
algorithm run on that known sequence in exact Fractions: color = black, coef = 1; at each level
stop past max_depth or when coef < min_coefficient, add coef * background and stop where
nothing is hit, else add coef * C_k and multiply coef by alpha_k. Here, as in the core, the
primary hit is weighted 1: C1 + alpha1 C2 + alpha1 alpha2 C3 + ... (the slide's
alpha1 (C1 + alpha2 (C2 + ...)) with alpha1 read as the eye's own coefficient, 1).
counts.secondary is the number of levels traced after the first. The colours and coefficients
are dyadic (0.5, 0.25, 0.75, ...), so every product and sum of the chain is exact in double:
the tolerance of 4 ulps of max(|value|, 1) only allows an equivalent order of additions.

local_color() is probed at an exact hit point with point and directional lights and sphere
blockers placed clearly between or clearly aside (decided from the exact roots, as L05's
in_shadow probes do): C = colour * ambient * ambient_light + sum over the lights with N.L > 0
and nothing between of diffuse (N.L) colour * light + specular max(R.L, 0)^shininess light.
L is a normalisation (about 5 roundings), N.L a dot product, the power multiplies the
cosine's relative error by the shininess (4 here) and each term adds a few products: 32 ulps
of max(|value|, 1) covers it; the mistakes miss by a whole light's term.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from decimal import Decimal, localcontext
from fractions import Fraction
from itertools import cycle

from lessons.L05_shadows.checks import spheres_block
from lessons.probe import HIDDEN, RGB, Probe, Vec, sub, to_float, vec_text

LESSON = "L07"
LOCAL = "the colour of one hit: ambient, and N.L diffuse if not in shadow"
CHAIN = "the reflection-coefficient chain"
MISS = "stop when no intersection"
COEF = "stop when coef << 1"
DEPTH = "stop at the maximum number of bounces"
# Every trace() probe adds each hit's local colour; the stops are checked on the chain.
DEPENDS = {CHAIN: (LOCAL,), MISS: (CHAIN, LOCAL), COEF: (CHAIN, LOCAL), DEPTH: (CHAIN, LOCAL)}

Colour = tuple[float, float, float]


@dataclass(frozen=True)
class Mirror:
    """A mirror plane: a point, its normal, its colour, ambient and reflectivity alpha."""

    point: Vec
    normal: Vec
    colour: Colour
    ambient: float
    alpha: float

    def inputs(self) -> tuple[float, ...]:
        return (*self.point, *self.normal, *self.colour, self.ambient, self.alpha)

    def local(self) -> tuple[Fraction, ...]:
        return tuple(Fraction(c) * Fraction(self.ambient) for c in self.colour)


def chain(
    hits: Iterable[Mirror], max_depth: int, min_coefficient: float, background: Colour
) -> tuple[tuple[Fraction, ...], int]:
    """The slide's algorithm on a known sequence of hits (the ray escapes after the last):
    the colour and the number of levels traced after the first (counts.secondary)."""
    colour = [Fraction(0)] * 3
    coef = Fraction(1)
    level, traced = 1, 0
    sequence: Iterator[Mirror] = iter(hits)
    while level <= max_depth and coef >= Fraction(min_coefficient):
        traced += 1
        mirror = next(sequence, None)
        if mirror is None:  # nothing hit: the background, weighted by the chain so far
            colour = [c + coef * Fraction(b) for c, b in zip(colour, background, strict=True)]
            break
        colour = [c + coef * k for c, k in zip(colour, mirror.local(), strict=True)]
        if mirror.alpha == 0:
            break
        coef *= Fraction(mirror.alpha)
        level += 1
    return tuple(colour), traced - 1


# The scenes. A: a floor y = 0 (normal +y), the ray from (0, 1, 0) along (0.6, -0.8, 0): it
# hits the floor once and leaves upwards, where nothing is. B: the floor and a wall x = 0
# (normal +x), the ray from (3, 2, 0) along (-0.6, -0.8, 0): it meets the floor at t = 2.5
# (x = 1.5; the wall's plane lies at t = 5), then travels (-0.6, 0.8) to the wall at (0, 2),
# then (0.6, 0.8), away from both. C: two parallel mirrors y = 0 and y = 1 facing each other,
# the ray from (0, 0.5, 0) along (0.6, 0.8, 0): top, bottom, top, ... for ever.
WARM = Mirror((0, 0, 0), (0, 1, 0), (1.0, 0.5, 0.25), 0.5, 0.5)
COOL = Mirror((0, 0, 0), (1, 0, 0), (0.25, 0.5, 1.0), 0.75, 0.25)
TOP = Mirror((0, 1, 0), (0, -1, 0), (0.5, 0.75, 1.0), 0.5, 0.5)
BOTTOM = Mirror((0, 0, 0), (0, 1, 0), (1.0, 0.25, 0.5), 0.25, 0.5)
SKY: Colour = (0.25, 0.5, 1.0)
DOWN: tuple[Vec, Vec] = ((0, 1, 0), (0.6, -0.8, 0))
CORNER: tuple[Vec, Vec] = ((3, 2, 0), (-0.6, -0.8, 0))
BETWEEN: tuple[Vec, Vec] = ((0, 0.5, 0), (0.6, 0.8, 0))


def trace_probe(
    name: str,
    concept: str,
    mirrors: list[Mirror],
    hits: Iterable[Mirror],
    ray: tuple[Vec, Vec],
    max_depth: int = 5,
    min_coefficient: float = 0.0,
    background: Colour = (0.0, 0.0, 0.0),
    visibility: str = "visible",
    scene: str = "",
) -> Probe:
    colour, secondary = chain(hits, max_depth, min_coefficient, background)
    flat = [x for m in mirrors for x in m.inputs()]
    listed = "; ".join(
        f"a mirror through {vec_text(m.point)} facing {vec_text(m.normal)}, C = "
        f"{vec_text(tuple(map(float, m.local())))}, alpha = {m.alpha:g}"  # type: ignore[arg-type]
        for m in mirrors
    )
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="trace",
        inputs=(max_depth, min_coefficient, *background, len(mirrors), *flat, *ray[0], *ray[1]),
        expected=(*map(float, colour), float(secondary)),
        labels=(*(f"color.{c}" for c in RGB), "counts.secondary (reflected rays traced)"),
        ulps=4,
        visibility=visibility,
        inputs_text=f"{scene}: {listed or 'no objects'}; background {vec_text(background)}, "
        f"max_depth {max_depth}, min_coefficient {min_coefficient:g}; the ray from "
        f"{vec_text(ray[0])} along {vec_text(ray[1])}",
        hint={
            CHAIN: "add coef * C_k at each hit, then coef *= reflectivity: "
            "C1 + alpha1 C2 + alpha1 alpha2 C3 + ...; redirect the ray to d - 2(d.N)N",
            MISS: "a ray that hits nothing adds coef * background (the chain so far times the "
            "background) and the loop stops",
            COEF: "a level whose coef is below min_coefficient is not traced (coef equal to it "
            "still is); nothing is added for it",
            DEPTH: "max_depth counts levels, the primary ray being level 1: levels past it are "
            "black, and no background is added for them",
        }[concept],
    )


def _unit(v: tuple[Fraction, ...]) -> tuple[Fraction, ...]:
    with localcontext() as context:
        context.prec = 50
        length = _dec(sum((x * x for x in v), Fraction(0))).sqrt()
        return tuple(Fraction(_dec(x) / length) for x in v)


def _dec(x: Fraction) -> Decimal:
    return Decimal(x.numerator) / Decimal(x.denominator)


Light = tuple[bool, Vec, Colour]  # directional?, its position or direction of travel, colour


def local_probe(
    name: str,
    material: tuple[Colour, float, float, float, float],
    p: Vec,
    n: Vec,
    r: Vec,
    lights: list[Light],
    blockers: list[tuple[Vec, float]],
    visibility: str = "visible",
) -> Probe:
    colour, ambient, diffuse, specular, shininess = material
    white = (1.0, 1.0, 1.0)
    total = [Fraction(c) * Fraction(ambient) for c in colour]
    for directional, where, light in lights:
        if directional:
            to_l = tuple(-Fraction(x) for x in where)
            blocked = spheres_block(p, tuple(-x for x in where), float("inf"), blockers)
        else:
            to_l = _unit(sub(where, p))
            blocked = spheres_block(
                p, tuple(a - b for a, b in zip(where, p, strict=True)), 1, blockers
            )
        nl = sum((Fraction(a) * b for a, b in zip(n, to_l, strict=True)), Fraction(0))
        if nl <= 0 or blocked:
            continue
        rl = sum((Fraction(a) * b for a, b in zip(r, to_l, strict=True)), Fraction(0))
        highlight = Fraction(0)
        if rl > 0 and specular:
            with localcontext() as context:
                context.prec = 50
                highlight = Fraction((_dec(rl).ln() * Decimal(shininess)).exp())
        for k in range(3):
            total[k] += Fraction(diffuse) * nl * Fraction(colour[k]) * Fraction(light[k])
            total[k] += Fraction(specular) * highlight * Fraction(light[k])
    flat_lights = [
        x
        for directional, where, light in lights
        for x in (
            1 if directional else 0,
            *(where if not directional else (0, 0, 0)),
            *(where if directional else (0, 0, 0)),
            *light,
        )
    ]
    flat_blockers = [x for c, radius in blockers for x in (*c, radius)]
    described = "; ".join(
        f"a {'directional light along' if d else 'point light at'} {vec_text(w)}, colour "
        f"{vec_text(c)}"
        for d, w, c in lights
    )
    shade = "; ".join(f"a sphere at {vec_text(c)} of radius {rad:g}" for c, rad in blockers)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=LOCAL,
        function="local_color",
        inputs=(
            *colour,
            ambient,
            diffuse,
            specular,
            shininess,
            0.0,
            *white,
            *p,
            *n,
            *r,
            len(lights),
            *flat_lights,
            len(blockers),
            *flat_blockers,
        ),
        expected=tuple(to_float(x) for x in total),
        labels=tuple(f"color.{c}" for c in RGB),
        ulps=32,
        visibility=visibility,
        inputs_text=f"material colour {vec_text(colour)}, ambient {ambient:g}, diffuse "
        f"{diffuse:g}, specular {specular:g}, shininess {shininess:g}; white ambient light; "
        f"the hit p = {vec_text(p)}, N = {vec_text(n)}, R = {vec_text(r)}; {described}"
        + (f"; {shade}" if shade else ""),
        hint="C_k = ambient term + for each light with N.L > 0 that no object shadows "
        "(in_shadow(shadow_ray(...))): diffuse * N.L * colour * light colour, plus "
        "specular * phong_term(R, L, shininess) * light colour",
    )


def probes() -> list[Probe]:
    up: Vec = (0.0, 1.0, 0.0)
    red: Colour = (1.0, 0.25, 0.25)
    white: Colour = (1.0, 1.0, 1.0)
    plain = ((0.8, 0.6, 0.4), 0.1, 0.7, 0.0, 4.0)
    shiny = ((0.8, 0.6, 0.4), 0.1, 0.5, 0.5, 4.0)
    above: Light = (False, (0.0, 10.0, 0.0), white)
    oblique: Light = (False, (3.0, 4.0, 0.0), red)
    sun: Light = (True, (0.0, -0.6, -0.8), (0.5, 0.5, 1.0))
    behind: Light = (False, (0.0, -5.0, 1.0), white)
    ball = ((0.0, 5.0, 0.0), 1.0)
    aside = ((4.0, 5.0, 0.0), 1.0)
    beyond = ((0.0, 15.0, 0.0), 2.0)
    corner = [WARM, COOL]
    mirrors = [TOP, BOTTOM]
    for_ever = cycle([TOP, BOTTOM])
    return [
        # The colour of one hit.
        local_probe("C_k: one light straight above", plain, (0, 0, 0), up, up, [above], []),
        local_probe("C_k: a coloured light at an angle", plain, (0, 0, 0), up, up, [oblique], []),
        local_probe("C_k: the light shadowed", plain, (0, 0, 0), up, up, [above], [ball]),
        local_probe(
            "C_k: a sphere aside, not in the way", plain, (0, 0, 0), up, up, [above], [aside]
        ),
        local_probe("C_k: a light behind the surface", plain, (0, 0, 0), up, up, [behind], []),
        local_probe(
            "C_k: two lights, one shadowed",
            shiny,
            (0, 0, 0),
            up,
            (0.6, 0.8, 0.0),
            [above, oblique],
            [ball],
        ),
        local_probe(
            "C_k: hidden, sun and a sphere beyond the light",
            shiny,
            (1.0, 0.0, 2.0),
            up,
            (0.0, 0.8, 0.6),
            [sun, above],
            [((1.0, 15.0, 2.0), 2.0)],
            HIDDEN,
        ),
        local_probe(
            "C_k: hidden, three lights",
            plain,
            (0, 0, 0),
            up,
            up,
            [above, oblique, behind],
            [beyond],
            HIDDEN,
        ),
        # The chain.
        trace_probe("chain: a floor, then the sky", CHAIN, [WARM], [WARM], DOWN, scene="A"),
        trace_probe("chain: floor, wall, out", CHAIN, corner, [WARM, COOL], CORNER, scene="B"),
        trace_probe(
            "chain: hidden, floor, wall, out",
            CHAIN,
            [BOTTOM, COOL],
            [BOTTOM, COOL],
            CORNER,
            visibility=HIDDEN,
            scene="B",
        ),
        # Stop when no intersection.
        trace_probe("miss: nothing at all", MISS, [], [], DOWN, background=SKY, scene="empty"),
        trace_probe(
            "miss: a floor, then the sky",
            MISS,
            [WARM],
            [WARM],
            DOWN,
            background=SKY,
            scene="A",
        ),
        trace_probe(
            "miss: floor, wall, then the sky",
            MISS,
            corner,
            [WARM, COOL],
            CORNER,
            background=SKY,
            scene="B",
        ),
        trace_probe(
            "miss: hidden, the sky after two mirrors",
            MISS,
            [BOTTOM, COOL],
            [BOTTOM, COOL],
            CORNER,
            background=(1.0, 0.75, 0.5),
            visibility=HIDDEN,
            scene="B",
        ),
        # Stop at the maximum number of bounces.
        trace_probe(
            "depth: 1, the first hit alone", DEPTH, mirrors, for_ever, BETWEEN, 1, scene="C"
        ),
        trace_probe(
            "depth: 4 between two mirrors",
            DEPTH,
            mirrors,
            cycle([TOP, BOTTOM]),
            BETWEEN,
            4,
            scene="C",
        ),
        trace_probe(
            "depth: 2, the sky beyond is not added",
            DEPTH,
            corner,
            [WARM, COOL],
            CORNER,
            2,
            background=SKY,
            scene="B",
        ),
        trace_probe(
            "depth: hidden, 7 between two mirrors",
            DEPTH,
            mirrors,
            cycle([TOP, BOTTOM]),
            BETWEEN,
            7,
            visibility=HIDDEN,
            scene="C",
        ),
        # Stop when coef << 1.
        trace_probe(
            "coef: 0.2 stops after coef 0.25",
            COEF,
            mirrors,
            cycle([TOP, BOTTOM]),
            BETWEEN,
            40,
            0.2,
            scene="C",
        ),
        trace_probe(
            "coef: a level with coef = min_coefficient is traced",
            COEF,
            mirrors,
            cycle([TOP, BOTTOM]),
            BETWEEN,
            40,
            0.125,
            scene="C",
        ),
        trace_probe(
            "coef: hidden, 0.01",
            COEF,
            mirrors,
            cycle([TOP, BOTTOM]),
            BETWEEN,
            40,
            0.01,
            visibility=HIDDEN,
            scene="C",
        ),
    ]
