"""L13's probes: precision in stiff and extreme cases. The ray/sphere quadratic's discriminant
and roots without cancellation (tracer/cpp/05_sphere.h sphere_discriminant(), quadratic_roots()),
the whole intersection of L02 (the course's sphere_roots() and sphere_t(), calling yours) on
spheres far away, tiny and grazed, and the offset of a new ray's origin off the surface it
leaves (tracer/cpp/02_ray.h offset_ray_origin()).

Expected values come from the exact binary values of the inputs, never from the core: the
quadratic's a = d.d, b = f.d, c0 = f.f - r^2, D = b^2 - a c0 and the closest point of the line,
l = f - (b / a) d, as Fractions; the roots (-b -+ sqrt(D)) / a to 50 digits (in the stable
form, so that the decimal digits are not lost either); the offset d = |N|.p_error as a Fraction.

Tolerances, from the conditioning (U = 2^-53):

- The discriminant. Computing l = f - (b/a) d rounds b (3 roundings of |f||d|), b/a and the
  product, and cancels f against (b/a) d: each component of l errs by at most about 8 U |f|.
  |l|^2 then errs by 2 |l| sqrt(3) 8 U |f| + 3 U |l|^2, and r^2 - |l|^2 and the product with a
  add U (r^2 + |l|^2) and 4 U |D|. So a backward-stable discriminant errs by at most about
  32 U a (r^2 + |l|^2 + |l| |f|): tolerance 64 U of that scale. The textbook b^2 - a c0 errs by
  U (b^2 + a |c0|), about 2 U a |f|^2: |f| / r times more where the line passes near the
  centre. Every stiff probe has |f| / r >= 10^4, and the textbook form misses by 37 (a grazing
  ray, whose D is small) to 10^14 times the tolerance (tests/lessons/test_l12_l13.py runs both
  formulas in double on each probe).
- The roots from given (b, c0, D, 1/a). The stable form adds numbers of one sign only: a square
  root, a sum and a division or product, each root within 3 U of the exact root of
  a t^2 + 2 b t + c0 (D is the correctly rounded b^2 - a c0): 8 U relative. The textbook
  (-b + sqrt(D)) / a loses |b| / |a t0| ulps on the root near zero: 10^9 times the
  tolerance or more here.
- The whole intersection. A root moves by delta D / (2 a sqrt(D)) when D errs by delta D, and
  by U |f| / |d| with b: tolerance 64 U (|t| + |f| / |d| + (r^2 + |l|^2 + |l| |f|) / (2 sqrt(D)))
  (the last term is the conditioning of a near-double root: large for grazing rays).
- Misses must be decidable: every miss probe lies farther outside the rim than the robust
  discriminant's error bound (asserted below), so a correct double-precision method decides it.
- The offset. po - p is exact (Sterbenz's lemma; the probe subtracts). The solution rounds d
  (3 roundings), d N (1), p + offset (half an ulp of p) and moves one ulp further: within
  4 U (|p| + d) of the exact d N. The probes' error bounds are 10^3 to 10^4 times that, so a
  missing offset, a fixed epsilon (1e-4), an offset along the ray or to the wrong side misses by
  far more.
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext
from fractions import Fraction

from lessons.probe import HIDDEN, XYZ, Probe, U, Vec, dot, sqrt_fraction, sub, vec_text

LESSON = "L13"
DISCRIMINANT = "the robust quadratic: the discriminant without cancellation"
ROOT = "the robust quadratic: the root without cancellation"
STIFF = "stiff and extreme cases: far, tiny and grazing spheres"
OFFSET = "self-intersection offsets: along the normal, by the error bound"
# The stiff spheres run L02's sphere_t() and sphere_roots(), which call both of the above.
DEPENDS = {STIFF: (DISCRIMINANT, ROOT)}
ULPS = 64  # the discriminant's and the intersection's: 32 U from the analysis above, doubled


def _dec(x: Fraction) -> Decimal:
    with localcontext() as context:
        context.prec = 50
        return Decimal(x.numerator) / Decimal(x.denominator)


class Quadratic:
    """The ray/sphere quadratic a t^2 + 2 b t + c0 = 0 of a sphere (c, r) and a ray (o, d), with
    its exact coefficients and the scales its tolerances need."""

    def __init__(self, c: Vec, r: float, o: Vec, d: Vec) -> None:
        f = sub(o, c)
        self.a = dot(d, d)
        self.b = sum((x * Fraction(y) for x, y in zip(f, d, strict=True)), Fraction(0))
        self.c0 = sum((x * x for x in f), Fraction(0)) - Fraction(r) ** 2
        self.D = self.b * self.b - self.a * self.c0
        lvec = [x - self.b / self.a * Fraction(y) for x, y in zip(f, d, strict=True)]
        self.l2 = sum((x * x for x in lvec), Fraction(0))
        self.r2 = Fraction(r) ** 2
        self.f_len = math.sqrt(float(sum((x * x for x in f), Fraction(0))))
        self.d_len = math.sqrt(float(self.a))
        l_len = math.sqrt(float(self.l2))
        # The scale of a backward-stable discriminant's error (the module's docstring).
        self.d_scale = float(self.a) * (float(self.r2) + float(self.l2) + l_len * self.f_len)

    def decidable(self) -> bool:
        """Whether the sign of D is beyond the robust discriminant's error bound."""
        return abs(float(self.D)) > ULPS * U * self.d_scale

    def roots(self) -> tuple[float, float] | None:
        if self.D < 0:
            return None
        return stable_roots(self.a, self.b, self.c0, self.D)

    def t_scale(self, t: float) -> float:
        # A root moves by delta D / (2 a sqrt(D)): the conditioning of a near-double root.
        sqrt_d = math.sqrt(float(self.D)) if self.D > 0 else 0.0
        spread = self.d_scale / float(self.a) / (2 * sqrt_d) if sqrt_d > 0 else 0.0
        return abs(t) + self.f_len / self.d_len + spread


def stable_roots(a: Fraction, b: Fraction, c0: Fraction, D: Fraction) -> tuple[float, float]:
    """t0 <= t1 of a t^2 + 2 b t + c0 = 0 to 50 digits, in the form that cancels nothing."""
    s = sqrt_fraction(D)
    with localcontext() as context:
        context.prec = 50
        q = -(_dec(b) + (s if b >= 0 else -s))
        if q == 0:
            return (0.0, 0.0)
        t0, t1 = _dec(c0) / q, q / _dec(a)
    return (float(min(t0, t1)), float(max(t0, t1)))


def _sphere_text(c: Vec, r: float, o: Vec, d: Vec) -> str:
    return f"sphere centre {vec_text(c)}, radius {r:g}; ray o = {vec_text(o)}, d = {vec_text(d)}"


# --- the discriminant ---------------------------------------------------------------------


def discriminant_probe(
    name: str, c: Vec, r: float, o: Vec, d: Vec, visibility: str = "visible"
) -> Probe:
    q = Quadratic(c, r, o, d)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=DISCRIMINANT,
        function="sphere_discriminant",
        inputs=(*c, r, *o, *d),
        expected=(float(q.D),),
        labels=("D",),
        ulps=ULPS,
        scale=q.d_scale,
        visibility=visibility,
        inputs_text=_sphere_text(c, r, o, d) + f" (|f| / r = {q.f_len / r:.3g})",
        hint="b^2 - a c0 subtracts two numbers of size a |f|^2 that agree in almost every "
        "digit when the sphere is far or tiny: compute a (r^2 - |l|^2) with l = f - (b/a) d, the "
        "centre's offset from the ray's line (Ray Tracing Gems ch. 7, eq. 7.5)",
    )


# --- the roots ----------------------------------------------------------------------------


def roots_probe(name: str, b: float, c0: float, inv_a: float, visibility: str = "visible") -> Probe:
    a = 1 / Fraction(inv_a)
    disc = Fraction(b) ** 2 - a * Fraction(c0)
    assert disc >= 0, name
    t0, t1 = stable_roots(a, Fraction(b), Fraction(c0), disc)
    D = float(disc)  # the correctly rounded discriminant, as the best discriminant gives it
    return Probe(
        name=name,
        lesson=LESSON,
        concept=ROOT,
        function="quadratic_roots",
        inputs=(b, c0, D, inv_a),
        expected=(1.0, t0, t1),
        labels=("real", "t0", "t1"),
        ulps=8,
        scale=0.0,
        visibility=visibility,
        inputs_text=f"{float(a):g} t^2 + 2 ({b:g}) t + {c0:g} = 0: b = {b:g}, c0 = {c0:g}, "
        f"D = {D:.17g}, inv_a = {inv_a:g}",
        hint="(-b -+ sqrt(D)) / a subtracts nearly equal numbers for the root near zero: take "
        "q = -(b + sign(b) sqrt(D)), then t1 = q / a and t0 = c0 / q (their product is c0 / a), "
        "and return them ordered",
    )


# --- stiff and extreme spheres ------------------------------------------------------------


def stiff_t_probe(
    name: str, c: Vec, r: float, o: Vec, d: Vec, visibility: str = "visible"
) -> Probe:
    q = Quadratic(c, r, o, d)
    assert q.decidable(), name
    found = q.roots()
    want = math.inf
    if found is not None:
        want = next((t for t in found if t > 0), math.inf)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=STIFF,
        function="sphere_t",
        inputs=(*c, r, *o, *d, 0.0, math.inf),
        expected=(want,),
        labels=("t",),
        ulps=ULPS,
        scale=q.t_scale(0.0 if math.isinf(want) else want),
        visibility=visibility,
        inputs_text=_sphere_text(c, r, o, d) + f" (|f| / r = {q.f_len / r:.3g})",
        hint="the course's sphere_t() calls your sphere_discriminant() and quadratic_roots(): a "
        "miss taken for a hit, or a hit far off, means one of them loses digits here",
    )


def stiff_roots_probe(
    name: str, c: Vec, r: float, o: Vec, d: Vec, visibility: str = "visible"
) -> Probe:
    q = Quadratic(c, r, o, d)
    assert q.decidable(), name
    found = q.roots()
    expected = (0.0, None, None) if found is None else (1.0, *found)
    scale = q.t_scale(max(abs(t) for t in found) if found else 0.0)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=STIFF,
        function="sphere_roots",
        inputs=(*c, r, *o, *d),
        expected=expected,
        labels=("real", "t0", "t1"),
        ulps=ULPS,
        scale=scale,
        visibility=visibility,
        inputs_text=_sphere_text(c, r, o, d) + f" (|f| / r = {q.f_len / r:.3g})",
        hint="the course's sphere_roots() calls your sphere_discriminant() and quadratic_roots()",
    )


# --- self-intersection offsets ------------------------------------------------------------


def offset_probe(
    name: str, p: Vec, p_error: Vec, n: Vec, toward: Vec, visibility: str = "visible"
) -> Probe:
    d = sum((abs(Fraction(x)) * Fraction(e) for x, e in zip(n, p_error, strict=True)), Fraction(0))
    side = 1 if dot(toward, n) >= 0 else -1
    want = tuple(float(side * d * Fraction(x)) for x in n)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=OFFSET,
        function="offset_ray_origin",
        inputs=(*p, *p_error, *n, *toward),
        expected=want,
        labels=tuple(f"offset.{c}" for c in XYZ),
        ulps=4,
        scale=max(abs(x) for x in p) + float(d),
        visibility=visibility,
        inputs_text=f"p = {vec_text(p)}, p_error = {vec_text(p_error)}, N = {vec_text(n)}, "
        f"toward = {vec_text(toward)} (the offset, new origin - p, is printed)",
        hint="move p along N (not along the ray) by |N|.p_error, the farthest the error box "
        "reaches along N, to the side `toward` points to (dot(toward, N) < 0: the other side); "
        "a fixed epsilon is too small far from the origin and too large near it",
    )


# --- the probes ---------------------------------------------------------------------------

ORIGIN: Vec = (0.0, 0.0, 0.0)
Z: Vec = (0.0, 0.0, 1.0)
# Grazing rays pass at r (1 -+ 1e-6) from the centre; coordinates that are not short binary
# fractions, so that the textbook formula's roundings are not exact by luck.
RIM = 1e-6
FAR_GRAZED: Vec = (0.0, 0.0, 12345.6789)
# A sphere of radius 1e-3 whose centre lies 2^-12 (about 0.24 r) off the ray along 1e4 (3, 4, 12).
TINY_FAR: Vec = (30000.0 + 2.0**-12, 40000.0, 120000.0)


def probes() -> list[Probe]:
    hidden = HIDDEN
    gamma7 = 7 * U / (1 - 7 * U)  # a sphere hit's error bound per unit of |p| (05_sphere.h)
    far = (1e6, -2e6, 5e5)
    return [
        discriminant_probe("discriminant: a unit sphere at distance 3", (0, 0, 3), 1, ORIGIN, Z),
        discriminant_probe("discriminant: a unit sphere 1e8 away", (0, 0, 1e8), 1, ORIGIN, Z),
        discriminant_probe("discriminant: radius 1e-6 at distance 10", (0, 0, 10), 1e-6, ORIGIN, Z),
        discriminant_probe(
            "discriminant: a sphere 3e6 away, an oblique ray of length 3",
            (1000000.375, 1999999.5, -1999998.9375),
            0.5,
            (0.25, -0.5, 1),
            (1, 2, -2),
        ),
        discriminant_probe(
            "discriminant: hidden, grazing a sphere 1.2e4 away",
            FAR_GRAZED,
            1,
            (1 - RIM, 0, 0),
            Z,
            hidden,
        ),
        discriminant_probe(
            "discriminant: hidden, radius 1e-3 at 1.3e5",
            TINY_FAR,
            1e-3,
            ORIGIN,
            (3, 4, 12),
            hidden,
        ),
        roots_probe("roots: well separated, t = 2 and 4", -3, 8, 1),
        roots_probe("roots: t^2 - 2e8 t + 1 = 0, the small root 5e-9", -1e8, 1, 1),
        roots_probe("roots: b > 0, both roots negative", 1e8, 1, 1),
        roots_probe("roots: a = 4, the small root of a far sphere", -1e6, 3, 0.25),
        roots_probe("roots: from inside, t0 < 0 < t1", -0.5, -2, 1),
        roots_probe("roots: a double root", -2, 4, 1),
        roots_probe("roots: hidden, a = 2", -3e7, 0.5, 0.5, hidden),
        roots_probe("roots: hidden, b > 0", 4.5e5, 2, 1, hidden),
        stiff_t_probe("stiff: a unit sphere 1e8 away", (0, 0, 1e8), 1, ORIGIN, Z),
        stiff_t_probe("stiff: radius 1e-6 at distance 10", (0, 0, 10), 1e-6, ORIGIN, Z),
        stiff_t_probe(
            "stiff: grazing a sphere 1.2e4 away, 1e-6 inside its rim",
            FAR_GRAZED,
            1,
            (1 - RIM, 0, 0),
            Z,
        ),
        stiff_roots_probe("stiff: both roots of a sphere 1e8 away", (0, 0, 1e8), 1, ORIGIN, Z),
        stiff_t_probe(
            "stiff: hidden, 1e-6 outside the rim of a sphere 1e6 away (a miss)",
            (0, 0, 1e6),
            1,
            (1 + RIM, 0, 0),
            Z,
            hidden,
        ),
        stiff_t_probe(
            "stiff: hidden, radius 1e-3 at 1.3e5, oblique",
            TINY_FAR,
            1e-3,
            ORIGIN,
            (3, 4, 12),
            hidden,
        ),
        offset_probe(
            "offset: along +z, out of a plane",
            (1, 2, 3),
            (3e-12, 2e-12, 1e-12),
            Z,
            (0.6, 0, 0.8),
        ),
        offset_probe(
            "offset: into the surface (a ray from inside a sphere)",
            (0.6, 0, 0.8),
            (1e-12, 1e-12, 1e-12),
            (0.6, 0, 0.8),
            (-0.6, 0.1, -0.2),
        ),
        offset_probe(
            "offset: a grazing ray leaves along the normal, not along the ray",
            (0.5, -0.25, 0),
            (1e-12, 1e-12, 1e-12),
            (0, 0, 1),
            (1, 0, 1e-3),
        ),
        offset_probe(
            "offset: a hit 2e6 from the origin (error bound 1e3 gamma(7) |p|)",
            far,
            tuple(gamma7 * abs(x) * 1e3 for x in far),
            (0, 1, 0),
            (0, 1, 0),
        ),
        offset_probe(
            "offset: a hit 1e-8 from the origin",
            (1e-8, 2e-8, 0),
            (1e-22, 1e-22, 1e-22),
            Z,
            Z,
        ),
        offset_probe(
            "offset: hidden, a normal with negative components",
            (-3, 4, -5),
            (4e-12, 4e-12, 5e-12),
            (-0.48, 0.6, -0.64),
            (0.5, -1, 0.25),
            hidden,
        ),
        offset_probe(
            "offset: hidden, far and oblique",
            (-2e7, 3e7, 1e7),
            (1e-6, 2e-6, 1e-6),
            (0, 0.6, -0.8),
            (0, 1, 0),
            hidden,
        ),
    ]
