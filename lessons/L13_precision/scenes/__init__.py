"""L13's scene checks (lessons/scene_checks.py): stiff scenes where the textbook forms (the
GIVEN lines of tracer/cpp/05_sphere.h and 02_ray.h) visibly fail, compared only with the
references that are themselves right there (each scene file says which, and
tests/lessons/test_l13_scenes.py checks them against exact arithmetic), and with closed forms."""

import math

from lessons.probe import HIDDEN
from lessons.scene_checks import Analytic, SceneCheck

# tiny_blocker.toml's centre pixel: the floor (N = +y) at (1e-5, 0, 0) in the sphere's shadow,
# so the ambient term alone: 0.2 x 0.9 x ambient light 1. Lit, it would add 0.8 x 0.9 x N.L,
# N.L = 1 / sqrt(2): 0.689 more. float32 output: half an ulp below 1 is 6e-8.
SHADOWED = 0.2 * 0.9
LIT = SHADOWED + 0.8 * 0.9 / math.sqrt(2.0)
FLOAT32 = 1e-6
# far_sphere.toml's centre pixel: the primary ray along the axis meets the sphere head on;
# ambient 1 x white x ambient light 1.

SCENES = [
    SceneCheck(
        "L13",
        "far_sphere",
        "the robust quadratic: the discriminant without cancellation",
        "a unit sphere 10^8 away, through a field of view of 1.6e-6 degrees",
        references=("mitsuba",),
        aov=False,  # Mitsuba's aov (scalar_rgb) misses this sphere altogether: not a reference
        analytic=(Analytic(16, 12, "color", (1.0, 1.0, 1.0), FLOAT32, "ambient 1, head on"),),
        hint="for a sphere far away b^2 and a c0 are huge and nearly equal: compute the "
        "discriminant from the centre's distance to the ray's line, a (r^2 - |l|^2)",
    ),
    SceneCheck(
        "L13",
        "far_small_sphere",
        "the robust quadratic: the discriminant without cancellation",
        "a unit sphere 3e7 away, through a field of view of 5.5e-6 degrees",
        visibility=HIDDEN,
        references=("mitsuba",),
        aov=False,  # as far_sphere
        hint="the discriminant a (r^2 - |l|^2) keeps its digits where b^2 - a c0 cannot",
    ),
    SceneCheck(
        "L13",
        "tiny_blocker",
        "self-intersection offsets: along the normal, by the error bound",
        "a sphere of radius 3e-6 casting its shadow on a floor 1e-5 below it",
        references=(),  # both render this scale black (see the scene file)
        aov=False,  # Mitsuba's float32 hits on a floor 1e-5 wide: not a reference here
        rays=False,  # counted from Mitsuba's hits: as aov
        analytic=(
            Analytic(
                40,
                30,
                "color",
                (SHADOWED,) * 3,
                FLOAT32,
                "in the shadow: ambient 0.2 x 0.9; lit would be 0.18 + 0.72 / sqrt(2)",
            ),
            # Pixel (40, 50) sees the floor at (2.2e-5, 0, 1.5e-5), whose ray towards the
            # light passes the sphere at 1.1e-5 from its centre: lit, with no acne.
            Analytic(40, 50, "color", (LIT,) * 3, FLOAT32, "lit: 0.2 x 0.9 + 0.8 x 0.9 / sqrt(2)"),
        ),
        hint="offset a new ray's origin by the hit point's error bound (|N|.p_error), not a "
        "fixed epsilon: 1e-4 is ten times the size of this scene",
    ),
]
