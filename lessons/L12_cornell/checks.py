"""L12's probes: the path tracer's estimator (tracer/cpp/20_path.h): the cosine-weighted bounce,
Russian roulette, next-event estimation towards a point on an area light, the power heuristic.

Every expected value is computed here from the exact binary values of the inputs, never from
the core:

- sample_cosine(u1, u2) in closed form, (sqrt(u1) cos 2 pi u2, sqrt(u1) sin 2 pi u2,
  sqrt(1 - u1)), with pi, cos and sin as 50-digit decimals (Taylor series below); cosine_pdf
  is cos / pi to 50 digits.
- Next-event estimation from the geometry alone, with Fractions: v = y - x, r^2 = v.v,
  cos_i = v.N / r, cos_l = -v.Ng / r, the solid-angle density pick pdf_area r^2 / cos_l, and the
  estimate beta f Le cos_i w / pdf = beta f Le w G / (pick pdf_area) with the geometry term
  G = cos_i cos_l / r^2 = (v.N)(-v.Ng) / r^4, which is rational: exact.
- The power heuristic f^2 / (f^2 + g^2) and Russian roulette's beta / q as Fractions.

Tolerances (U = 2^-53, Higham's gamma(n) of n chained roundings): sample_cosine rounds 2 pi u2
(|phi| < 2 pi, so 1.5 U |phi| < 10 U), cos/sin (1 U), r (0.5 U) and their product: 16 U of the
unit vector's scale 1. cosine_pdf is one division by a rounded pi: 4 U relative. The
connection's direction and cosines are a subtraction, a dot product (3 roundings), a square
root and a division per component, then another dot product: 16 U of 1; its density adds three
products and a division of values carrying that error (cos_l >= 0.4 in every probe, so the
cosine's 16 U absolute is at most 40 U relative): 64 U relative. The estimate adds five
roundings to that: 64 U relative too (the probes' cos_l >= 0.6). The power heuristic's two
squares, a sum and a division (or the ratio form's four): 8 U relative; the roulette's 1/q and
product: 4 U relative. Every mistake this lesson's known-wrong versions make misses by a
factor (pi, cos_l, r^2, 1/q, a weight of 1 for 0.2): at least 2 %, 10^13 times the tolerance.
"""

from __future__ import annotations

from decimal import Decimal, localcontext
from fractions import Fraction

from lessons.probe import HIDDEN, RGB, XYZ, Probe, Vec, dot, sqrt_fraction, vec_text

LESSON = "L12"
BOUNCE = "light bounces many times: the cosine-weighted bounce"
ROULETTE = "each bounce attenuates light: Russian roulette"
NEE = "next-event estimation: a point on the area light"
MIS = "multiple importance sampling: the power heuristic"
# mis_weights() calls power_heuristic() (both MIS); no concept calls another's code.
DEPENDS: dict[str, tuple[str, ...]] = {}

PI = Decimal("3.14159265358979323846264338327950288419716939937510582097494")
MAX_SURVIVAL = Fraction(95, 100)  # 20_path.h roulette_max_survival (Mitsuba's cap)


def _cos_sin(x: Decimal) -> tuple[Decimal, Decimal]:
    """cos x and sin x by their Taylor series at 60 digits (|x| < 2 pi: 60 terms are plenty)."""
    with localcontext() as context:
        context.prec = 60
        cos, sin, term = Decimal(0), Decimal(0), Decimal(1)
        for k in range(120):
            if k % 2 == 0:
                cos += term if k % 4 == 0 else -term
            else:
                sin += term if k % 4 == 1 else -term
            term = term * x / (k + 1)
        return cos, sin


def _dec(x: Fraction) -> Decimal:
    with localcontext() as context:
        context.prec = 50
        return Decimal(x.numerator) / Decimal(x.denominator)


# --- the cosine-weighted bounce ------------------------------------------------------------


def cosine_sample_probe(name: str, u1: float, u2: float, visibility: str = "visible") -> Probe:
    with localcontext() as context:
        context.prec = 50
        r = Decimal(Fraction(u1).numerator) / Decimal(Fraction(u1).denominator)
        cos, sin = _cos_sin(2 * PI * _dec(Fraction(u2)))
        radius = r.sqrt()
        z = (1 - r).sqrt()
        want = (float(radius * cos), float(radius * sin), float(z))
    return Probe(
        name=name,
        lesson=LESSON,
        concept=BOUNCE,
        function="sample_cosine",
        inputs=(u1, u2),
        expected=want,
        labels=tuple(f"wi.{c}" for c in XYZ),
        ulps=16,
        visibility=visibility,
        inputs_text=f"u1 = {u1:g}, u2 = {u2:g}",
        hint="Malley's method: a point uniform on the unit disk (radius sqrt(u1), angle 2 pi u2), "
        "lifted to z = sqrt(1 - u1); z = u1 samples the hemisphere uniformly, not by the cosine",
    )


def cosine_pdf_probe(name: str, cos: float, visibility: str = "visible") -> Probe:
    with localcontext() as context:
        context.prec = 50
        want = float(_dec(Fraction(cos)) / PI)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=BOUNCE,
        function="cosine_pdf",
        inputs=(cos,),
        expected=(want,),
        labels=("pdf",),
        ulps=4,
        scale=0.0,
        visibility=visibility,
        inputs_text=f"cos(theta) = {cos:g}",
        hint="cos(theta) / pi: a density over the hemisphere integrates to one, and the "
        "integral of cos(theta) over the hemisphere is pi",
    )


# --- Russian roulette ---------------------------------------------------------------------


def roulette_probe(name: str, beta: Vec, u: float, visibility: str = "visible") -> Probe:
    q = min(max(Fraction(b) for b in beta), MAX_SURVIVAL)
    goes_on = Fraction(u) < q
    after = tuple(float(Fraction(b) / q) for b in beta) if goes_on else (None, None, None)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=ROULETTE,
        function="russian_roulette",
        inputs=(*beta, u),
        expected=(1.0 if goes_on else 0.0, *after),
        labels=("goes on", *(f"beta.{c}" for c in RGB)),
        ulps=4,
        scale=0.0,
        visibility=visibility,
        inputs_text=f"throughput beta = {vec_text(beta)}, u = {u:g} "
        f"(q = min(max channel, 0.95) = {float(q):g})",
        hint="survive when u < q, q = min(the brightest channel of beta, 0.95), and then carry "
        "beta / q: without the division the paths that survive do not make up for those that end",
    )


# --- next-event estimation ----------------------------------------------------------------


def _connection(x: Vec, n: Vec, y: Vec, ng: Vec) -> tuple[tuple[Fraction, ...], Fraction]:
    v = tuple(Fraction(a) - Fraction(b) for a, b in zip(y, x, strict=True))
    return v, sum((c * c for c in v), Fraction(0))


def connect_probe(
    name: str,
    x: Vec,
    n: Vec,
    y: Vec,
    ng: Vec,
    pdf_area: float,
    pick: float,
    visibility: str = "visible",
) -> Probe:
    v, d2 = _connection(x, n, y, ng)
    d = sqrt_fraction(d2)
    with localcontext() as context:
        context.prec = 50
        wi = tuple(_dec(c) / d for c in v)
        cos_i = _dec(dot(v, n)) / d
        cos_l = -_dec(dot(v, ng)) / d
        pdf = Decimal(pick) * Decimal(pdf_area) * _dec(d2) / cos_l if cos_l > 0 else Decimal(0)
        want = (*(float(c) for c in wi), float(cos_i), float(cos_l), float(pdf))
    return Probe(
        name=name,
        lesson=LESSON,
        concept=NEE,
        function="connect_to_light",
        inputs=(*x, *n, *y, *ng, pdf_area, pick),
        expected=want,
        labels=(*(f"wi.{c}" for c in XYZ), "cos_i", "cos_l", "pdf"),
        ulps=64,
        visibility=visibility,
        inputs_text=f"x = {vec_text(x)}, N = {vec_text(n)}; light point y = {vec_text(y)}, "
        f"its normal {vec_text(ng)}, pdf_area = {pdf_area:g}, chosen with probability {pick:g}",
        hint="wi = (y - x) / |y - x|; cos_l = -Ng.wi (the light's normal against the ray back "
        "to x); a patch dA at distance r fills cos_l dA / r^2 of solid angle, so the density per "
        "solid angle is pick * pdf_area * r^2 / cos_l (0 when the light faces away)",
    )


def estimate_probe(
    name: str,
    x: Vec,
    n: Vec,
    y: Vec,
    ng: Vec,
    pdf_area: float,
    pick: float,
    f: Vec,
    le: Vec,
    beta: Vec = (1.0, 1.0, 1.0),
    w: float = 1.0,
    visibility: str = "visible",
) -> Probe:
    v, d2 = _connection(x, n, y, ng)
    geometry = dot(v, n) * -dot(v, ng) / (d2 * d2)  # G = cos_i cos_l / r^2, exact
    assert geometry > 0, name  # a light point the surface sees
    scale = Fraction(w) * geometry / (Fraction(pick) * Fraction(pdf_area))
    want = tuple(
        float(Fraction(b) * Fraction(fc) * Fraction(e) * scale)
        for b, fc, e in zip(beta, f, le, strict=True)
    )
    return Probe(
        name=name,
        lesson=LESSON,
        concept=NEE,
        function="light_estimate",
        inputs=(*x, *n, *y, *ng, pdf_area, pick, *beta, *f, *le, w),
        expected=want,
        labels=tuple(f"L.{c}" for c in RGB),
        ulps=64,
        scale=0.0,
        visibility=visibility,
        inputs_text=f"x = {vec_text(x)}, N = {vec_text(n)}; light point y = {vec_text(y)}, "
        f"its normal {vec_text(ng)}, pdf_area = {pdf_area:g}, pick = {pick:g}; beta = "
        f"{vec_text(beta)}, f = {vec_text(f)}, Le = {vec_text(le)}, w = {w:g} "
        f"(the geometry term G = cos_i cos_l / r^2 = {float(geometry):.17g})",
        hint="beta f Le cos_i w / pdf with pdf = pick pdf_area r^2 / cos_l from "
        "connect_to_light(): the estimate is f Le G / (pick pdf_area), G = cos_i cos_l / r^2",
    )


# --- multiple importance sampling ---------------------------------------------------------


def _power(f: float, g: float) -> Fraction:
    f2, g2 = Fraction(f) ** 2, Fraction(g) ** 2
    return f2 / (f2 + g2) if f2 + g2 > 0 else Fraction(0)


def power_probe(name: str, f: float, g: float, visibility: str = "visible") -> Probe:
    return Probe(
        name=name,
        lesson=LESSON,
        concept=MIS,
        function="power_heuristic",
        inputs=(f, g),
        expected=(float(_power(f, g)),),
        labels=("w",),
        ulps=8,
        scale=0.0,
        visibility=visibility,
        inputs_text=f"f = {f:g}, g = {g:g}",
        hint="w = f^2 / (f^2 + g^2); where f^2 overflows divide by f^2 first: 1 / (1 + (g / f)^2)",
    )


def weights_probe(name: str, light: float, bsdf: float, visibility: str = "visible") -> Probe:
    return Probe(
        name=name,
        lesson=LESSON,
        concept=MIS,
        function="mis_weights",
        inputs=(light, bsdf),
        expected=(float(_power(light, bsdf)), float(_power(bsdf, light))),
        labels=("w.light", "w.bsdf"),
        ulps=8,
        scale=0.0,
        visibility=visibility,
        inputs_text=f"pdf_light = {light:g}, pdf_bsdf = {bsdf:g}",
        hint="each strategy's weight is the power heuristic of its own density against the "
        "other's; the two weights of a direction sum to one, or the light is counted twice",
    )


# --- the probes ---------------------------------------------------------------------------

UP: Vec = (0.0, 1.0, 0.0)
DOWN: Vec = (0.0, -1.0, 0.0)
# The Cornell box's light: a 0.5 x 0.5 quad at height 2 facing down (area 0.25, pdf_area 4).
QUAD_PDF = 4.0


def probes() -> list[Probe]:
    hidden = HIDDEN
    white = (1.0, 1.0, 1.0)
    warm = (17.0, 12.0, 4.0)  # the Cornell box light's radiance, roughly
    return [
        cosine_sample_probe("bounce: u = (0.25, 0), in the x-z plane", 0.25, 0.0),
        cosine_sample_probe("bounce: u = (0.5, 0.125), 45 degrees round", 0.5, 0.125),
        cosine_sample_probe("bounce: u1 = 0, straight along the normal", 0.0, 0.7),
        cosine_sample_probe("bounce: u = (0.81, 0.3)", 0.81, 0.3),
        cosine_sample_probe("bounce: u1 near 1, grazing", 0.999, 0.9),
        cosine_sample_probe("bounce: hidden variant", 0.36, 0.6, hidden),
        cosine_sample_probe("bounce: hidden, u = (0.0625, 0.55)", 0.0625, 0.55, hidden),
        cosine_pdf_probe("bounce: the pdf along the normal", 1.0),
        cosine_pdf_probe("bounce: the pdf at 60 degrees", 0.5),
        cosine_pdf_probe("bounce: hidden pdf at cos 0.8", 0.8, hidden),
        roulette_probe("roulette: q = 0.5, u = 0.3 survives", (0.2, 0.5, 0.1), 0.3),
        roulette_probe("roulette: q = 0.5, u = 0.6 ends", (0.2, 0.5, 0.1), 0.6),
        roulette_probe("roulette: a bright path, q capped at 0.95", (2.0, 1.0, 0.5), 0.9),
        roulette_probe("roulette: even a bright path ends sometimes", (2.0, 1.0, 0.5), 0.96),
        roulette_probe("roulette: hidden, q = 0.25", (0.125, 0.25, 0.0625), 0.2, hidden),
        roulette_probe("roulette: hidden, q = 0.75 ends", (0.75, 0.3, 0.6), 0.8, hidden),
        connect_probe(
            "nee: straight below the light",
            (0.0, 0.0, 0.0),
            UP,
            (0.0, 2.0, 0.0),
            DOWN,
            QUAD_PDF,
            1.0,
        ),
        connect_probe(
            "nee: a corner of the quad light, seen obliquely",
            (0.5, 0.0, 0.25),
            UP,
            (-0.25, 2.0, -0.25),
            DOWN,
            QUAD_PDF,
            0.5,
        ),
        connect_probe(
            "nee: from a wall, the light at an angle",
            (-1.0, 1.0, 0.0),
            (1.0, 0.0, 0.0),
            (0.125, 2.0, -0.125),
            DOWN,
            QUAD_PDF,
            1.0,
        ),
        connect_probe(
            "nee: the light faces away (pdf 0)",
            (0.0, 3.0, 0.0),
            DOWN,
            (0.0, 2.0, 0.0),
            DOWN,
            QUAD_PDF,
            1.0,
        ),
        connect_probe(
            "nee: hidden, a tilted light",
            (0.25, 0.0, -0.5),
            UP,
            (0.0, 1.5, 0.5),
            (0.0, -0.6, -0.8),
            2.0,
            0.25,
            hidden,
        ),
        estimate_probe(
            "nee: a small quad light seen from the floor",
            (0.5, 0.0, 0.25),
            UP,
            (0.125, 2.0, -0.125),
            DOWN,
            QUAD_PDF,
            1.0,
            (0.25, 0.2, 0.125),
            warm,
        ),
        estimate_probe(
            "nee: one of two lights, a throughput and a weight",
            (-0.5, 0.0, 0.0),
            UP,
            (0.25, 2.0, 0.25),
            DOWN,
            QUAD_PDF,
            0.5,
            (0.2, 0.2, 0.2),
            white,
            beta=(0.5, 0.25, 1.0),
            w=0.75,
        ),
        estimate_probe(
            "nee: from a wall",
            (-1.0, 1.0, 0.0),
            (1.0, 0.0, 0.0),
            (0.125, 2.0, -0.125),
            DOWN,
            QUAD_PDF,
            1.0,
            (0.125, 0.0625, 0.25),
            warm,
        ),
        estimate_probe(
            "nee: hidden, the estimate from a tilted light",
            (0.25, 0.0, -0.5),
            UP,
            (0.0, 1.5, 0.5),
            (0.0, -0.6, -0.8),
            2.0,
            0.25,
            (0.3, 0.15, 0.05),
            warm,
            w=0.5,
            visibility=hidden,
        ),
        power_probe("mis: equal densities share half and half", 1.0, 1.0),
        power_probe("mis: f = 2, g = 1", 2.0, 1.0),
        power_probe("mis: f = 1, g = 3", 1.0, 3.0),
        power_probe("mis: the other strategy cannot sample it (g = 0)", 0.5, 0.0),
        power_probe("mis: densities whose squares overflow", 1e200, 1e199),
        power_probe("mis: hidden variant", 0.75, 0.25, hidden),
        power_probe("mis: hidden, f^2 overflows, g larger", 3e170, 4e170, hidden),
        weights_probe("mis: both weights, pdf_light = 2, pdf_bsdf = 1", 2.0, 1.0),
        weights_probe("mis: both weights, pdf_light = 0.25, pdf_bsdf = 0.75", 0.25, 0.75),
        weights_probe("mis: hidden, both weights", 5.0, 0.5, hidden),
    ]
