"""L01's probes: the ray p = o + t d, the camera's frame, primary rays through pixel centres.

Expected values come from the inputs' exact binary values: p = o + t d as Fractions rounded
once; the frame as exact cross products (Fractions) normalised once to 50 digits (forward =
unit(look_at - eye), right = unit(forward x up) = unit((look_at - eye) x up), since scaling
forward by a positive number does not turn the cross product, and true_up = right x forward =
unit(right' x forward') for the unnormalised pair, which are perpendicular); the plane's
height 2 tan(fov_y / 2) from closed forms of the tangent (tan 45 = 1, tan 30 = 1/sqrt 3,
tan 60 = sqrt 3, tan 22.5 = sqrt 2 - 1, tan 15 = 2 - sqrt 3); a primary ray's direction
unit(forward + (x w + shift) right + (y h) true_up) with x = sx/width - 1/2 and
y = 1/2 - sy/height as exact Fractions, normalised once.

Tolerances (ulps of max(|value|, 1), U = 2^-53):
- at(): one product and one sum per component: 2 roundings of |o| + |t d|; 4 ulps of that scale.
- initialize(): forward is a subtraction (exact here), three squares, two sums, a square root
  and a division (about 4 u); right a cross product of the rounded forward and normalised
  again (about 10 u); true_up a cross product of two rounded unit vectors (about 12 u); the
  plane's height: pi rounded (0.35 u), fov_y * pi and / 360 (1 u), times tan's relative
  condition 2x / sin 2x (2.4 at 60 degrees, the widest here) plus tan's own rounding and the
  aspect's product and quotient: about 7 u. 16 ulps covers all; every mistake the lesson
  names misses by a sign, a factor or more than 1e-3.
- primary_ray(): x and y (a division, a subtraction), three scaled sums, a length and a
  division: at most about 14 roundings of |d| before normalising, whose components are at
  most sqrt 3 times the unit result's: 32 ulps of 1. Half a pixel of a 4-pixel-wide image
  moves the direction by more than 0.1.
"""

from __future__ import annotations

from decimal import Decimal, localcontext
from fractions import Fraction

from lessons.probe import HIDDEN, XYZ, Probe, Vec, sub, to_float, vec_text

LESSON = "L01"
RAY = "the ray p = o + t d"
FRAME = "the camera's frame"
PIXEL = "primary rays through pixel centres"
# primary_ray() is probed with its frame given, not derived by initialize(): no dependence.
DEPENDS: dict[str, tuple[str, ...]] = {}

FracVec = tuple[Fraction, Fraction, Fraction]


def _dec(x: Fraction) -> Decimal:
    return Decimal(x.numerator) / Decimal(x.denominator)


def unit(v: FracVec) -> Vec:
    """v / |v| for an exact vector, to 50 digits, rounded once per component."""
    with localcontext() as context:
        context.prec = 50
        length = _dec(sum((x * x for x in v), Fraction(0))).sqrt()
        x, y, z = (to_float(_dec(c) / length) for c in v)
    return (x, y, z)


def cross(a: FracVec, b: FracVec) -> FracVec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def frac(v: Vec) -> FracVec:
    return (Fraction(v[0]), Fraction(v[1]), Fraction(v[2]))


def tan_half(fov_y: float) -> Decimal:
    """tan(fov_y / 2) for the angles whose tangent has a closed form (to 50 digits)."""
    with localcontext() as context:
        context.prec = 50
        root2, root3 = Decimal(2).sqrt(), Decimal(3).sqrt()
        closed = {90: Decimal(1), 60: 1 / root3, 120: root3, 45: root2 - 1, 30: 2 - root3}
        if fov_y not in closed:
            raise ValueError(f"no closed form of tan({fov_y} / 2) here")
        return +closed[int(fov_y)]


def at_probe(name: str, o: Vec, d: Vec, t: float, visibility: str = "visible") -> Probe:
    want = tuple(float(Fraction(x) + Fraction(t) * Fraction(y)) for x, y in zip(o, d, strict=True))
    scale = max(abs(x) for x in o) + abs(t) * max(abs(x) for x in d)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=RAY,
        function="at",
        inputs=(*o, *d, t),
        expected=want,
        labels=tuple(f"p.{c}" for c in XYZ),
        ulps=4,
        scale=scale,
        visibility=visibility,
        inputs_text=f"ray o = {vec_text(o)}, d = {vec_text(d)}; t = {t:g}",
        hint="p = o + t d: start at the origin and go t times the direction (d as it is, not "
        "normalised: t is the ray's parameter)",
    )


def initialize_probe(
    name: str,
    eye: Vec,
    look_at: Vec,
    up: Vec,
    fov_y: float,
    width: int,
    height: int,
    visibility: str = "visible",
) -> Probe:
    f = sub(look_at, eye)
    r = cross(f, frac(up))  # forward x up: right-handed
    u = cross(r, f)
    with localcontext() as context:
        context.prec = 50
        plane_height = 2 * tan_half(fov_y)
        plane_width = plane_height * width / height
    return Probe(
        name=name,
        lesson=LESSON,
        concept=FRAME,
        function="initialize",
        inputs=(*eye, *look_at, *up, fov_y, width, height),
        expected=(*unit(f), *unit(r), *unit(u), to_float(plane_height), to_float(plane_width)),
        labels=(
            *(f"forward.{c}" for c in XYZ),
            *(f"right.{c}" for c in XYZ),
            *(f"true_up.{c}" for c in XYZ),
            "plane_height",
            "plane_width",
        ),
        ulps=16,
        visibility=visibility,
        inputs_text=f"eye {vec_text(eye)}, look_at {vec_text(look_at)}, up {vec_text(up)}, "
        f"fov_y {fov_y:g} degrees, {width} x {height} pixels",
        hint="forward = unit(look_at - eye); right = unit(forward x up) (right-handed); "
        "true_up = right x forward; plane_height = 2 tan(fov_y / 2) with the angle in radians "
        "(half the field of view), plane_width = plane_height * width / height",
    )


def primary_probe(
    name: str,
    frame: tuple[Vec, Vec, Vec, Vec],
    plane: tuple[float, float],
    size: tuple[int, int],
    pixel: tuple[float, float],
    shift: float = 0.0,
    visibility: str = "visible",
) -> Probe:
    """A ray through the image-plane point `pixel` = (sx, sy) in pixel units (the centre of
    pixel (i, j) is (i + 0.5, j + 0.5)) of a camera whose frame is given."""
    eye, forward, right, true_up = frame
    plane_width, plane_height = plane
    width, height = size
    sx, sy = pixel
    x = Fraction(sx) / width - Fraction(1, 2)
    y = Fraction(1, 2) - Fraction(sy) / height
    a = x * Fraction(plane_width) + Fraction(shift)
    b = y * Fraction(plane_height)
    d = tuple(
        Fraction(f) + a * Fraction(r) + b * Fraction(u)
        for f, r, u in zip(forward, right, true_up, strict=True)
    )
    shifted = f", window shift {shift:g}" if shift else ""
    return Probe(
        name=name,
        lesson=LESSON,
        concept=PIXEL,
        function="primary_ray",
        inputs=(*eye, *forward, *right, *true_up, *plane, *size, shift, sx, sy),
        expected=(*eye, *unit(d)),  # type: ignore[arg-type]
        labels=(*(f"o.{c}" for c in XYZ), *(f"d.{c}" for c in XYZ)),
        ulps=32,
        visibility=visibility,
        inputs_text=f"eye {vec_text(eye)}, forward {vec_text(forward)}, right "
        f"{vec_text(right)}, true_up {vec_text(true_up)}; image plane {plane_width:g} x "
        f"{plane_height:g}, {width} x {height} pixels{shifted}; (sx, sy) = ({sx:g}, {sy:g}), "
        f"the centre of pixel ({sx - 0.5:g}, {sy - 0.5:g})",
        hint="x = sx / width - 0.5 across, y = 0.5 - sy / height up (row 0 is the top); "
        "d = forward + (x plane_width + window_shift) right + (y plane_height) true_up, made "
        "unit length; the ray starts at the eye",
    )


ORIGIN: Vec = (0.0, 0.0, 0.0)
Y: Vec = (0.0, 1.0, 0.0)
# A camera at the origin looking down -z, and one looking along (0.6, 0, -0.8) from (1, 2, 3).
DOWN_Z = (ORIGIN, (0.0, 0.0, -1.0), (1.0, 0.0, 0.0), Y)
OBLIQUE = ((1.0, 2.0, 3.0), (0.6, 0.0, -0.8), (0.8, 0.0, 0.6), Y)


def probes() -> list[Probe]:
    return [
        at_probe("p = o + t d: from the origin", ORIGIN, (0, 0, -1), 2.5),
        at_probe("p = o + t d: off the origin", (1, 2, 3), (0.5, -1, 2), 3),
        at_probe("p = o + t d: d not of unit length", (0, 1, 0), (0, 0, -2), 1.5),
        at_probe("p = o + t d: t = 0 is the origin", (4, -2, 1), (0.6, 0.8, 0), 0),
        at_probe("p = o + t d: hidden variant", (-3, 0.5, 7), (1.5, 2, -0.25), 0.75, HIDDEN),
        initialize_probe("frame: looking down -z, 90 degrees", (0, 0, 5), ORIGIN, Y, 90, 4, 4),
        initialize_probe("frame: a wide image, 60 degrees", ORIGIN, (0, 0, -1), Y, 60, 320, 240),
        initialize_probe("frame: looking down at the origin", (0, 3, 4), ORIGIN, Y, 45, 200, 100),
        initialize_probe("frame: looking along +x", (1, 1, 1), (5, 1, 1), Y, 120, 64, 48),
        initialize_probe(
            "frame: hidden, z up", (1, 2, 3), (4, 6, 3), (0, 0, 1), 30, 100, 150, HIDDEN
        ),
        initialize_probe(
            "frame: hidden, oblique", (2, 0, 1), (-1, 4, 1), (0, 0, 1), 60, 640, 480, HIDDEN
        ),
        primary_probe("ray: the image's centre", DOWN_Z, (2, 2), (4, 4), (2, 2)),
        primary_probe("ray: the top-left pixel's centre", DOWN_Z, (2, 2), (4, 4), (0.5, 0.5)),
        primary_probe("ray: the bottom-right pixel's centre", DOWN_Z, (4, 2), (4, 2), (3.5, 1.5)),
        primary_probe("ray: a wide image, pixel (1, 0)", DOWN_Z, (4, 2), (4, 2), (1.5, 0.5)),
        primary_probe(
            "ray: an oblique camera off the origin", OBLIQUE, (2, 1.5), (8, 6), (2.5, 4.5)
        ),
        primary_probe(
            "ray: a shifted window (a stereo eye's)", DOWN_Z, (2, 2), (4, 4), (2, 2), shift=0.25
        ),
        primary_probe(
            "ray: hidden, pixel (7, 0)", OBLIQUE, (2, 1.5), (8, 6), (7.5, 0.5), 0, HIDDEN
        ),
        primary_probe(
            "ray: hidden, a shifted window", DOWN_Z, (1.5, 1), (6, 4), (4.5, 3.5), -0.125, HIDDEN
        ),
    ]
