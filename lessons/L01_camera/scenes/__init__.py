"""L01's scene checks (lessons/scene_checks.py): a sphere whose silhouette falls between two
known pixels (the field of view and the aspect), an oblique look-at with an up vector not
perpendicular to the view (the frame), a wide image (primary rays through pixel centres) and a
sphere on the axis whose distances and shades follow from p = o + t d.

The analytic values are computed here in double precision from the scene's numbers and the
lecture's formulas (slide "Perspective Ray Tracing"), never from the tracer."""

import math

from lessons.probe import HIDDEN, Vec
from lessons.scene_checks import Analytic, SceneCheck, cross, dot, sub, unit


def ray(eye: Vec, look_at: Vec, up: Vec, fov_y: float, width: int, height: int, i: int,
        j: int) -> Vec:  # fmt: skip
    """The unit direction through the centre of pixel (i, j), row 0 at the top: forward +
    x w right + y h up, x = (i + 1/2) / width - 1/2, y = 1/2 - (j + 1/2) / height."""
    forward = unit(sub(look_at, eye))
    right = unit(cross(forward, up))
    true_up = cross(right, forward)
    h = 2 * math.tan(math.radians(fov_y) / 2)
    w = h * width / height
    x = (i + 0.5) / width - 0.5
    y = 0.5 - (j + 0.5) / height
    return unit(
        tuple(f + x * w * r + y * h * u for f, r, u in zip(forward, right, true_up, strict=True))
    )  # type: ignore[return-value]


def sphere_t(o: Vec, d: Vec, centre: Vec, radius: float) -> float:
    """The nearer root of |o + t d - c|^2 = r^2 for a unit d."""
    f = sub(o, centre)
    b = dot(f, d)
    disc = b * b - (dot(f, f) - radius * radius)
    assert disc > 0, "the ray misses the sphere"
    return -b - math.sqrt(disc)


# fov_edge: the centre ray meets the unit sphere 5 away at t = 4; pixel (55, 30) is the last
# of the middle row on the sphere, (56, 30) the first beyond its silhouette.
EDGE = ((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 44.0, 81, 61)
EDGE_T = sphere_t(EDGE[0], ray(*EDGE, 55, 30), (0.0, 0.0, 0.0), 1.0)

# oblique: the centre ray is the axis towards look_at, the grey sphere's centre.
OBLIQUE_T = math.sqrt(2.5**2 + 3.2**2 + 3.5**2) - 0.6

# wide_aspect: the bottom-left pixel's ray meets the floor y = 0.
WIDE = ((0.0, 1.0, 6.0), (0.0, 0.6, 0.0), (0.0, 1.0, 0.0), 20.0, 121, 41)
WIDE_D = ray(*WIDE, 0, 40)
WIDE_T = -WIDE[0][1] / WIDE_D[1]

# ray_length: the unit sphere 4 away; at pixel (50, 22) the hit p = o + t d, its normal p and
# the light at (0, 0, 6) give the Lambert shade (ambient 0.1, diffuse 0.8, white light).
AXIS = ((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 40.0, 81, 61)
AXIS_D = ray(*AXIS, 50, 22)
AXIS_T = sphere_t(AXIS[0], AXIS_D, (0.0, 0.0, 0.0), 1.0)
AXIS_P: Vec = tuple(o + AXIS_T * d for o, d in zip(AXIS[0], AXIS_D, strict=True))  # type: ignore[assignment]
AXIS_NL = dot(AXIS_P, unit(sub((0.0, 0.0, 6.0), AXIS_P)))
AXIS_COLOR = tuple(0.1 * c + 0.8 * AXIS_NL * c for c in (0.9, 0.85, 0.8))

# float32 output: half an ulp of a value below 8 is 4.8e-7 (of the background's 0.1, 3.7e-9);
# the double arithmetic's roundings are ~1e-15 relative. 2e-6 holds both with room and is far
# below what each check separates: the half pixel added twice moves wide_aspect's floor
# distance by 0.09 (4.690 against 4.780), a frame scaled by a wrong field of view moves
# fov_edge's silhouette by pixels.
FLOAT32 = 2e-6

SCENES = [
    SceneCheck(
        "L01",
        "fov_edge",
        "the camera's frame",
        "a unit sphere whose silhouette falls between pixels 55 and 56 of the middle row",
        analytic=(
            Analytic(40, 30, "depth", (4.0,), FLOAT32, "the axis meets the sphere 5 - 1 away"),
            Analytic(
                55,
                30,
                "depth",
                (EDGE_T,),
                FLOAT32,
                "the nearer root along pixel 55's centre ray, fov_y 44, aspect 81/61",
            ),
            Analytic(
                56,
                30,
                "color",
                (0.1, 0.2, 0.3),
                FLOAT32,
                "pixel 56's ray passes 0.2120 off the axis, the silhouette at "
                "1/sqrt(24) = 0.2041: the background",
            ),
            Analytic(
                40,
                14,
                "color",
                (0.1, 0.2, 0.3),
                FLOAT32,
                "row 14 is 16 pixels above the axis: beyond the silhouette, the background",
            ),
        ),
        hint="plane_height = 2 tan(fov_y / 2) with fov_y in radians, plane_width = "
        "plane_height x width / height; right = forward x up",
    ),
    SceneCheck(
        "L01",
        "oblique",
        "the camera's frame",
        "three coloured spheres and a floor seen from above and aside, the up vector tilted",
        visibility=HIDDEN,
        analytic=(
            Analytic(
                40,
                30,
                "depth",
                (OBLIQUE_T,),
                FLOAT32,
                "the axis meets the grey sphere at look_at: |look_at - eye| - 0.6",
            ),
        ),
        hint="forward, right = forward x up and true_up = right x forward, each unit length: "
        "an up vector not perpendicular to the view is made so",
    ),
    SceneCheck(
        "L01",
        "wide_aspect",
        "primary rays through pixel centres",
        "three spheres in a row above a floor in a wide image (121 x 41)",
        analytic=(
            Analytic(
                0,
                40,
                "depth",
                (WIDE_T,),
                FLOAT32,
                "the bottom-left pixel centre's ray meets the floor y = 0 at -eye_y / d_y",
            ),
        ),
        hint="x = (i + 0.5) / width - 0.5 and y = 0.5 - (j + 0.5) / height: the centre of each "
        "pixel, row 0 at the top",
    ),
    SceneCheck(
        "L01",
        "ray_length",
        "the ray p = o + t d",
        "a unit sphere on the camera's axis, lit from behind the eye",
        visibility=HIDDEN,
        analytic=(
            Analytic(40, 30, "depth", (3.0,), FLOAT32, "the axis meets the sphere 4 - 1 away"),
            Analytic(
                50,
                22,
                "depth",
                (AXIS_T,),
                FLOAT32,
                "the nearer root along pixel (50, 22)'s unit direction",
            ),
            Analytic(
                50,
                22,
                "color",
                AXIS_COLOR,
                FLOAT32,
                "0.1 c + 0.8 N.L c at p = o + t d, N = p, L towards (0, 0, 6)",
            ),
        ),
        hint="p = o + t d with a unit d: t is the distance along the ray",
    ),
]
