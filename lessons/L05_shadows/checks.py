"""L05's probes: objects block light, the shadow ray towards the light, its range, and where it
starts.

- The reach (point lights): the far end o + max_t d of the shadow ray must be the light itself,
  whether d is left unnormalised with max_t = 1 (the core) or made unit with max_t the distance;
  for a directional light the reach is unbounded (max_t = infinity, exactly). The end is a
  subtraction point - o and an addition back (2 roundings), or a normalisation and a product
  (6): 8 ulps of the scene's scale max(|p|, |light|).
- The direction: unit(d) of a directional light's shadow ray is the direction towards the light
  (-light.direction): the given unit vector normalised again, a few roundings: 8 ulps of 1.
- Where it starts: two properties the lesson's idea implies and that need no formula for the
  offset. (1) A convex sphere cannot lie between a point on it and a light that lights the point
  (N.L > 0.05, away from the terminator): of a grid of hits on a sphere a thousand units in size
  far from the origin, none may be shadowed by the sphere itself (shadow acne: a ray started at
  the computed hit point, which lies off the surface by rounding, meets its own surface about
  half the time). (2) A scene 1e-10 in size, its hit point exact (p_error 0 or 1e-25): a blocker
  3e-11 above the surface must still block; a fixed epsilon (1e-4, 1e-6, 1e-9 ...) starts the
  ray beyond it.
- Objects block light: in_shadow() of a given shadow ray against spheres; whether one has a
  root of |o + t d - c|^2 = r^2 strictly inside (0, max_t) is decided here from the exact
  roots (Fractions, the square root to 50 digits), the inputs chosen well away from the range's
  ends; and the shadow ray is counted once (counts.shadow = 1).
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext
from fractions import Fraction

from lessons.probe import HIDDEN, XYZ, Probe, Vec, dot, sub, to_float, vec_text

LESSON = "L05"
BLOCK = "objects block light"
TOWARDS = "the shadow ray towards the light"
RANGE = "the shadow ray's range"
START = "where the shadow ray starts"
# Where the ray starts is checked by tracing it: that needs its direction and reach right too.
DEPENDS = {START: (TOWARDS, RANGE)}

ZERO: Vec = (0.0, 0.0, 0.0)
Y: Vec = (0.0, 1.0, 0.0)
UNIT = tuple(f"unit(d).{c}" for c in XYZ)
END = tuple(f"(o + max_t d).{c}" for c in XYZ)


def _unit(v: tuple[Fraction, ...]) -> tuple[float, ...]:
    with localcontext() as context:
        context.prec = 50
        length = _dec(sum((x * x for x in v), Fraction(0))).sqrt()
        return tuple(to_float(_dec(x) / length) for x in v)


def _dec(x: Fraction) -> Decimal:
    return Decimal(x.numerator) / Decimal(x.denominator)


def _hit_text(p: Vec, p_error: Vec, ng: Vec) -> str:
    err = f", p_error {vec_text(p_error)}" if any(p_error) else ""
    return f"hit p = {vec_text(p)}{err}, Ng = {vec_text(ng)}"


def reach_probe(
    name: str, p: Vec, p_error: Vec, ng: Vec, light: Vec, visibility: str = "visible"
) -> Probe:
    """shadow_ray_to(): its reach ends at the light."""
    return Probe(
        name=name,
        lesson=LESSON,
        concept=RANGE,
        function="shadow_ray_to",
        inputs=(0, *p, *p_error, *ng, *light),
        expected=(None, None, None, *light),
        labels=(*UNIT, *END),
        ulps=8,
        scale=max(*map(abs, p), *map(abs, light)),
        visibility=visibility,
        inputs_text=f"{_hit_text(p, p_error, ng)}; a point light at {vec_text(light)}",
        hint="the reach must end at the light: with d = light - o the light is at t = 1, so "
        "max_t = 1 (with a unit d, max_t is the distance); an unbounded reach lets objects "
        "behind the light cast shadows",
    )


def towards_probe(
    name: str,
    concept: str,
    p: Vec,
    ng: Vec,
    direction: Vec,
    visibility: str = "visible",
) -> Probe:
    """shadow_ray_towards(): TOWARDS checks the direction, RANGE the unbounded reach."""
    direction_expected = _unit(tuple(map(Fraction, direction))) if concept == TOWARDS else None
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="shadow_ray_towards",
        inputs=(0, *p, *ZERO, *ng, *direction),
        expected=(
            *((None,) * 3 if direction_expected is None else direction_expected),
            math.inf if concept == RANGE else None,
        ),
        labels=(*UNIT, "max_t"),
        ulps=8,
        visibility=visibility,
        inputs_text=f"{_hit_text(p, ZERO, ng)}; a light infinitely far along "
        f"{vec_text(direction)} (the unit direction towards it)",
        hint="towards a light infinitely far along `direction`: the ray goes along direction "
        "and nothing ahead is beyond the light, so max_t = infinity"
        if concept == RANGE
        else "the shadow ray goes along the direction towards the light, as given",
    )


def dispatch_probe(
    name: str,
    directional: bool,
    where: Vec,
    p: Vec,
    ng: Vec,
    visibility: str = "visible",
    concept: str = TOWARDS,
) -> Probe:
    """shadow_ray(): a directional light travelling along `where` (TOWARDS checks the
    direction, RANGE the unbounded reach), or a point light at it (RANGE)."""
    if directional:
        unit = _unit(tuple(-Fraction(x) for x in where))
        if concept == TOWARDS:
            expected: tuple[float | None, ...] = (*unit, None, None, None, None)
        else:
            expected = (None, None, None, 0.0, None, None, None)
        text = f"a directional light travelling along {vec_text(where)}"
        inputs = (1, *p, *where)
        hint = "a directional light lies against its direction of travel: the shadow ray goes "
        hint += "along -light.direction, and its reach is unbounded"
    else:
        concept = RANGE
        expected = (None, None, None, 1.0, *where)
        text = f"a point light at {vec_text(where)}"
        inputs = (0, *where, *ZERO)
        hint = "a point light: the shadow ray to its position, its reach ending there"
    return Probe(
        name=name,
        lesson=LESSON,
        concept=concept,
        function="shadow_ray",
        inputs=(*inputs, *p, *ng),
        expected=expected,
        labels=(*UNIT, "bounded (1 = max_t finite)", *END),
        ulps=8,
        scale=max(*map(abs, p), *map(abs, where), 1.0),
        visibility=visibility,
        inputs_text=f"{_hit_text(p, ZERO, ng)}; {text}",
        hint=hint,
    )


def acne_probe(
    name: str,
    directional: bool,
    centre: Vec,
    radius: float,
    eye: Vec,
    light: Vec,
    n: int = 16,
    visibility: str = "visible",
) -> Probe:
    kind = "towards a directional light along" if directional else "to a point light at"
    return Probe(
        name=name,
        lesson=LESSON,
        concept=START,
        function="shadow_ray_towards" if directional else "shadow_ray_to",
        inputs=(1, *centre, radius, *eye, *light, n),
        expected=(0.0, None),
        labels=("hits shadowed by their own sphere", "lit hits tested"),
        ulps=0,
        visibility=visibility,
        inputs_text=f"a sphere at {vec_text(centre)} of radius {radius:g}, seen from "
        f"{vec_text(eye)} through a {n} x {n} grid; shadow rays {kind} {vec_text(light)}",
        hint="the computed hit point lies a little off the surface, on either side: start the "
        "shadow ray just outside the hit's error bound on the side it leaves to "
        "(offset_ray_origin(hit.p, hit.p_error, Ng, towards the light)), not at hit.p "
        "(shadow acne) and not on the other side of the surface",
    )


def near_blocker_probe(
    name: str,
    directional: bool,
    p: Vec,
    p_error: Vec,
    ng: Vec,
    light: Vec,
    blocker: tuple[Vec, float],
    visibility: str = "visible",
) -> Probe:
    centre, radius = blocker
    kind = "towards a directional light along" if directional else "to a point light at"
    return Probe(
        name=name,
        lesson=LESSON,
        concept=START,
        function="shadow_ray_towards" if directional else "shadow_ray_to",
        inputs=(2, *p, *p_error, *ng, *light, *centre, radius),
        expected=(1.0,),
        labels=("the blocker blocks",),
        ulps=0,
        visibility=visibility,
        inputs_text=f"a scene 1e-10 in size: {_hit_text(p, p_error, ng)}; shadow ray {kind} "
        f"{vec_text(light)}; a sphere at {vec_text(centre)} of radius {radius:g} between",
        hint="a fixed epsilon is wrong at some scale: here it starts the ray beyond the "
        "blocker; offset by the hit's own error bound (offset_ray_origin), which scales with "
        "the scene",
    )


def spheres_block(o: Vec, d: Vec, max_t: float, spheres: list[tuple[Vec, float]]) -> bool:
    """Whether any sphere has a root strictly inside (0, max_t), from the exact roots."""
    for centre, radius in spheres:
        f = sub(o, centre)
        a = dot(d, d)
        b = sum((x * Fraction(y) for x, y in zip(f, d, strict=True)), Fraction(0))
        c0 = sum((x * x for x in f), Fraction(0)) - Fraction(radius) ** 2
        disc = b * b - a * c0
        if disc <= 0:  # a miss, or a tangent line: the probes keep away from tangents
            continue
        with localcontext() as context:
            context.prec = 50
            s = _dec(disc).sqrt()
            for t in ((-_dec(b) - s) / _dec(a), (-_dec(b) + s) / _dec(a)):
                if t > 0 and (math.isinf(max_t) or t < Decimal(max_t)):
                    return True
    return False


def block_probe(
    name: str,
    o: Vec,
    d: Vec,
    max_t: float,
    spheres: list[tuple[Vec, float]],
    visibility: str = "visible",
) -> Probe:
    flat = [x for centre, radius in spheres for x in (*centre, radius)]
    listed = "; ".join(f"a sphere at {vec_text(c)} of radius {r:g}" for c, r in spheres)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=BLOCK,
        function="in_shadow",
        inputs=(*o, *d, max_t, len(spheres), *flat),
        expected=(1.0 if spheres_block(o, d, max_t, spheres) else 0.0, 1.0),
        labels=("in shadow", "counts.shadow"),
        ulps=0,
        visibility=visibility,
        inputs_text=f"shadow ray o = {vec_text(o)}, d = {vec_text(d)}, reach (0, {max_t:g}); "
        + (listed or "no objects"),
        hint="in shadow when any object lies on the ray strictly within its reach (0, max_t) "
        "(any_hit): what lies behind the light does not block it; count the shadow ray once "
        "(counts.shadow)",
    )


def probes() -> list[Probe]:
    big = (1000.0, 2000.0, -5000.0)
    tiny_p: Vec = (2e-10, 0.0, -1e-10)
    tiny_err: Vec = (1e-25, 1e-25, 1e-25)
    tiny_blocker = ((2e-10, 5e-11, -1e-10), 2e-11)
    sky = (0.0, 10.0, 0.0)
    return [
        # Objects block light.
        block_probe("block: a sphere between", ZERO, sky, 1, [((0, 5, 0), 1)]),
        block_probe("block: nothing in the way", ZERO, sky, 1, []),
        block_probe("block: a sphere beside the ray", ZERO, sky, 1, [((3, 5, 0), 1)]),
        block_probe("block: a sphere behind the light", ZERO, sky, 1, [((0, 15, 0), 2)]),
        block_probe("block: a sphere behind the point", ZERO, sky, 1, [((0, -4, 0), 2)]),
        block_probe(
            "block: one beyond the light, one between",
            ZERO,
            sky,
            1,
            [((0, 14, 0), 1), ((0.5, 3, 0), 1)],
        ),
        block_probe("block: a directional light's ray", ZERO, Y, math.inf, [((1, 40, 0), 3)]),
        block_probe(
            "block: hidden, behind a distant light",
            (1, 1, 1),
            (2, 4, -4),
            1,
            [((4, 7, -5), 1.5)],
            HIDDEN,
        ),
        block_probe(
            "block: hidden, between, off the axis",
            (1, 1, 1),
            (2, 4, -4),
            1,
            [((5, 5, 5), 1), ((2.5, 3, -1), 0.75)],
            HIDDEN,
        ),
        # The shadow ray towards the light.
        towards_probe("towards: a light straight above", TOWARDS, ZERO, Y, Y),
        towards_probe("towards: an oblique light", TOWARDS, (1, 0, 2), Y, (0.6, 0.8, 0)),
        dispatch_probe("towards: a directional light shining down", True, (0, -1, 0), ZERO, Y),
        dispatch_probe("towards: an oblique directional light", True, (0.6, -0.8, 0), ZERO, Y),
        towards_probe(
            "towards: hidden variant", TOWARDS, (3, 1, -2), (0, 0, 1), (0, 0.6, 0.8), HIDDEN
        ),
        dispatch_probe(
            "towards: hidden directional light", True, (0, -0.8, -0.6), (5, 0, 5), Y, HIDDEN
        ),
        # The shadow ray's range.
        reach_probe("range: a point light above", ZERO, ZERO, Y, (0, 10, 0)),
        reach_probe("range: an oblique point light", (1, 0, 2), ZERO, Y, (4, 4, 2)),
        reach_probe("range: a hit with an error bound", (3, 1, 4), (1e-15,) * 3, Y, (-2, 6, 1)),
        towards_probe("range: a directional light has no end", RANGE, ZERO, Y, Y),
        dispatch_probe("range: the ray to a point light", False, (2, 8, -1), (1, 0, 1), Y),
        dispatch_probe(
            "range: a directional light's ray is unbounded",
            True,
            (0, -1, 0),
            ZERO,
            Y,
            concept=RANGE,
        ),
        reach_probe("range: hidden variant", (-5, 2, 3), ZERO, (0, 0, 1), (1, 2, 11), HIDDEN),
        dispatch_probe("range: hidden point light", False, (-3, 4, 12), ZERO, (0, 0, 1), HIDDEN),
        towards_probe("range: hidden directional", RANGE, (1, 2, 3), Y, (0.6, 0.8, 0), HIDDEN),
        # Where the shadow ray starts.
        acne_probe("start: no acne on a big sphere", False, big, 1000, ZERO, (5000, 8000, 0)),
        acne_probe("start: no acne, a directional light", True, big, 1000, ZERO, (0.6, 0.8, 0)),
        near_blocker_probe(
            "start: a tiny scene, a point light",
            False,
            tiny_p,
            tiny_err,
            Y,
            (2e-10, 1e-10, -1e-10),
            tiny_blocker,
        ),
        near_blocker_probe(
            "start: a tiny scene, a directional light",
            True,
            tiny_p,
            tiny_err,
            Y,
            Y,
            tiny_blocker,
        ),
        acne_probe(
            "start: hidden, acne on another sphere",
            False,
            (-300.0, 700.0, 2500.0),
            400,
            (10.0, 20.0, 30.0),
            (-3000.0, 5000.0, 0.0),
            12,
            HIDDEN,
        ),
        near_blocker_probe(
            "start: hidden, a tiny scene",
            False,
            (0.0, 0.0, 3e-9),
            ZERO,
            (0, 0, 1),
            (1e-9, 1e-9, 4e-9),
            ((5e-10, 5e-10, 3.5e-9), 1e-10),
            HIDDEN,
        ),
    ]
