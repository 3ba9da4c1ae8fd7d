"""L11's probes: the eye separation, the parallel-axis asymmetric frustum, and the parallax it
gives (slide "Stereoscopy").

Each eye is stereo_eye() of an initialized centre camera. Everything expected is derived here
to 50 digits from the centre's exact frame (L01's closed forms: forward = unit(look_at - eye),
right = unit(forward x up), true_up = unit(right x forward); the plane's height
2 tan(fov_y / 2)) and h = side * eye_separation / 2:

- the eye sits at centre.eye + h right (the eye separation);
- it keeps the centre's frame and its axis stays parallel to the centre's (no toe-in), and its
  window moves by -h / convergence on the image plane (the frustum);
- for an image point (sx, sy), both eyes' rays meet the plane at distance `convergence` at the
  centre camera's point eye + convergence (forward + x w right + y h up) (zero parallax
  there); a point P at depth z = (P - eye).forward is seen by both eyes in the same row,
  sy = (1/2 - ((P - eye).true_up / z) / h) height (no vertical parallax), and in the column
  sx = (((P - eye).right - h) / z + h / convergence) / w + 1/2) width.

Tolerances, ulps of max(|value|, scale): the frame carries L01's 16 ulps; the eye's position
adds a product and a sum (16 ulps of |eye| + |h|); the window shift is a product and a quotient
(16 ulps of 1, the image plane's scale); the point on the convergence plane is a primary ray
(32 ulps of its direction, L01) scaled by the distance (a dot product and a quotient more):
64 ulps of the scene's scale |eye| + 2 convergence; an image point is a few dot products and
quotients of the frame's rounded vectors: 64 ulps of the image's width in pixels. The
mistakes move an eye by half the separation or more, and an image point by pixels.
"""

from __future__ import annotations

from decimal import Decimal, localcontext
from fractions import Fraction

from lessons.L01_camera.checks import cross, frac, tan_half
from lessons.probe import HIDDEN, XYZ, Probe, Vec, sub, to_float, vec_text

LESSON = "L11"
SEPARATION = "the eye separation"
FRUSTUM = "the parallel-axis asymmetric frustum"
PARALLAX = "parallax: none on the convergence plane, never vertical"
# The window shift is -h / convergence of the eye's own offset h: a wrong offset shifts it
# wrongly too. The parallax probes trace both eyes as stereo_eye() made them.
DEPENDS = {FRUSTUM: (SEPARATION,), PARALLAX: (SEPARATION, FRUSTUM)}

D3 = tuple[Decimal, Decimal, Decimal]


class Centre:
    """The centre camera: eye, look_at, up, fov_y, width, height, and its frame to 50 digits."""

    def __init__(
        self, eye: Vec, look_at: Vec, up: Vec, fov_y: float, width: int, height: int
    ) -> None:
        self.eye, self.look_at, self.up = eye, look_at, up
        self.fov_y, self.width, self.height = fov_y, width, height
        f = sub(look_at, eye)
        r = cross(f, frac(up))
        u = cross(r, f)
        with localcontext() as context:
            context.prec = 50
            self.forward, self.right, self.true_up = _unit(f), _unit(r), _unit(u)
            self.plane_height = 2 * tan_half(fov_y)
            self.plane_width = self.plane_height * width / height

    def inputs(self) -> tuple[float, ...]:
        return (*self.eye, *self.look_at, *self.up, self.fov_y, self.width, self.height)

    def text(self) -> str:
        return (
            f"the centre camera at {vec_text(self.eye)} looking at {vec_text(self.look_at)}, "
            f"up {vec_text(self.up)}, fov_y {self.fov_y:g}, {self.width} x {self.height}"
        )


def _dec(x: Fraction | float) -> Decimal:
    x = Fraction(x)
    return Decimal(x.numerator) / Decimal(x.denominator)


def _unit(v: tuple[Fraction, ...]) -> D3:
    length = _dec(sum((x * x for x in v), Fraction(0))).sqrt()
    x, y, z = (_dec(c) / length for c in v)
    return (x, y, z)


def _dot(a: tuple[Decimal, ...], b: tuple[Decimal, ...]) -> Decimal:
    return sum((x * y for x, y in zip(a, b, strict=True)), Decimal(0))


def _floats(v: tuple[Decimal, ...]) -> tuple[float, ...]:
    return tuple(to_float(x) for x in v)


def _pair(sep: float, conv: float) -> str:
    return f"eye_separation {sep:g}, convergence {conv:g}"


def eye_probe(
    name: str, c: Centre, sep: float, conv: float, side: int, visibility: str = "visible"
) -> Probe:
    with localcontext() as context:
        context.prec = 50
        h = side * _dec(sep) / 2
        want = tuple(_dec(e) + h * r for e, r in zip(c.eye, c.right, strict=True))
    return Probe(
        name=name,
        lesson=LESSON,
        concept=SEPARATION,
        function="stereo_eye",
        inputs=(0, *c.inputs(), sep, conv, side),
        expected=_floats(want),
        labels=tuple(f"eye.{x}" for x in XYZ),
        ulps=16,
        scale=max(*map(abs, c.eye), sep / 2, 1.0),
        visibility=visibility,
        inputs_text=f"{c.text()}; {_pair(sep, conv)}; the {'left' if side < 0 else 'right'} eye",
        hint="each eye sits half the eye separation from the centre, along the centre's right "
        "vector: the left eye (side -1) at eye - (separation / 2) right, the right eye at "
        "eye + (separation / 2) right",
    )


def frustum_probe(
    name: str, c: Centre, sep: float, conv: float, side: int, visibility: str = "visible"
) -> Probe:
    with localcontext() as context:
        context.prec = 50
        shift = -(side * _dec(sep) / 2) / _dec(conv)
    frame = (*c.forward, *c.right, *c.true_up, *c.forward)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=FRUSTUM,
        function="stereo_eye",
        inputs=(1, *c.inputs(), sep, conv, side),
        expected=(*_floats(frame), to_float(shift)),
        labels=(
            *(f"forward.{x}" for x in XYZ),
            *(f"right.{x}" for x in XYZ),
            *(f"true_up.{x}" for x in XYZ),
            *(f"unit(look_at - eye).{x}" for x in XYZ),
            "window_shift",
        ),
        ulps=16,
        visibility=visibility,
        inputs_text=f"{c.text()}; {_pair(sep, conv)}; the {'left' if side < 0 else 'right'} eye",
        hint="parallel axes: the eye keeps the centre's frame (forward, right, true_up) and "
        "looks along the same forward (look_at moves with the eye; never turn the eyes in, "
        "toe-in gives vertical parallax); its window moves the other way on the image plane, "
        "window_shift = -(side * separation / 2) / convergence",
    )


def convergence_probe(
    name: str,
    c: Centre,
    sep: float,
    conv: float,
    pixel: tuple[float, float],
    visibility: str = "visible",
) -> Probe:
    sx, sy = pixel
    with localcontext() as context:
        context.prec = 50
        x = _dec(sx) / c.width - Decimal("0.5")
        y = Decimal("0.5") - _dec(sy) / c.height
        a, b = x * c.plane_width, y * c.plane_height
        point = tuple(
            _dec(e) + _dec(conv) * (f + a * r + b * u)
            for e, f, r, u in zip(c.eye, c.forward, c.right, c.true_up, strict=True)
        )
    want = _floats(point)
    return Probe(
        name=name,
        lesson=LESSON,
        concept=PARALLAX,
        function="stereo_eye",
        inputs=(2, *c.inputs(), sep, conv, sx, sy),
        expected=(*want, *want),
        labels=(*(f"left.{x}" for x in XYZ), *(f"right.{x}" for x in XYZ)),
        ulps=64,
        scale=max(*map(abs, c.eye), 1.0) + 2 * conv,
        visibility=visibility,
        inputs_text=f"{c.text()}; {_pair(sep, conv)}; both eyes' rays through image point "
        f"({sx:g}, {sy:g}), met with the plane at distance {conv:g}",
        hint="on the convergence plane the two frusta coincide: both eyes' rays through the "
        "same pixel meet it at the same point (zero parallax), which the eye's shifted window "
        "(-h / convergence) achieves and toe-in does not",
    )


def parallax_probe(
    name: str,
    c: Centre,
    sep: float,
    conv: float,
    p: Vec,
    visibility: str = "visible",
) -> Probe:
    with localcontext() as context:
        context.prec = 50
        v = tuple(_dec(a) - _dec(b) for a, b in zip(p, c.eye, strict=True))
        z = _dot(v, c.forward)
        y = _dot(v, c.true_up) / z
        sy = (Decimal("0.5") - y / c.plane_height) * c.height
        out: list[float] = []
        for side in (-1, 1):
            h = side * _dec(sep) / 2
            x = (_dot(v, c.right) - h) / z + h / _dec(conv)
            out += [to_float((x / c.plane_width + Decimal("0.5")) * c.width), to_float(sy)]
    return Probe(
        name=name,
        lesson=LESSON,
        concept=PARALLAX,
        function="stereo_eye",
        inputs=(3, *c.inputs(), sep, conv, *p),
        expected=tuple(out),
        labels=("left sx", "left sy", "right sx", "right sy"),
        ulps=64,
        scale=float(c.width),
        visibility=visibility,
        inputs_text=f"{c.text()}; {_pair(sep, conv)}; the image points at which each eye sees "
        f"the point {vec_text(p)}",
        hint="with parallel axes and shifted windows a point is seen in the same row by both "
        "eyes (no vertical parallax) and in the same column only on the convergence plane; "
        "nearer points lie further right in the left eye",
    )


def probes() -> list[Probe]:
    down_z = Centre((0, 0, 0), (0, 0, -1), (0, 1, 0), 90, 64, 64)
    oblique = Centre((1, 2, 3), (4, 2, -1), (0, 1, 0), 60, 80, 60)
    above = Centre((0, 5, 5), (0, 0, 0), (0, 1, 0), 45, 100, 50)
    return [
        # The eye separation.
        eye_probe("separation: the left eye", down_z, 0.25, 4, -1),
        eye_probe("separation: the right eye", down_z, 0.25, 4, +1),
        eye_probe("separation: an oblique camera's left eye", oblique, 0.5, 10, -1),
        eye_probe("separation: a camera looking down, right eye", above, 0.125, 7, +1),
        eye_probe("separation: hidden, the right eye", oblique, 0.375, 6, +1, HIDDEN),
        eye_probe("separation: hidden, the left eye", above, 1.5, 3, -1, HIDDEN),
        # The parallel-axis asymmetric frustum.
        frustum_probe("frustum: the left eye", down_z, 0.25, 4, -1),
        frustum_probe("frustum: the right eye", down_z, 0.25, 4, +1),
        frustum_probe("frustum: an oblique camera's right eye", oblique, 0.5, 10, +1),
        frustum_probe("frustum: hidden, looking down, left", above, 0.125, 7, -1, HIDDEN),
        frustum_probe("frustum: hidden, oblique, left", oblique, 0.375, 6, -1, HIDDEN),
        # Parallax.
        convergence_probe("parallax: zero at the convergence plane", down_z, 0.25, 4, (8.5, 50.5)),
        convergence_probe("parallax: zero, oblique camera", oblique, 0.5, 10, (70.5, 10.5)),
        parallax_probe("parallax: a near point, off-centre", down_z, 0.25, 4, (0.5, 0.75, -2)),
        parallax_probe("parallax: a far point, off-centre", oblique, 0.5, 10, (10, 5, -12)),
        convergence_probe(
            "parallax: hidden, zero, looking down", above, 0.125, 7, (90.5, 45.5), HIDDEN
        ),
        parallax_probe(
            "parallax: hidden, a point in a corner", above, 0.5, 6, (-1.5, 1, 1), HIDDEN
        ),
    ]
