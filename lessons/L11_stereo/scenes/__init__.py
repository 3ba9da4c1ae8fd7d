"""L11's scene checks (lessons/scene_checks.py): a stereo pair side by side (its parallax),
each eye alone from an oblique camera (the parallel-axis asymmetric frustum), and a
pair over and under on a wall at the convergence distance (no parallax there, none vertical).

The references render a stereo pair one eye at a time, as the converters take it
(tracer.render.eye_scene: POV-Ray's off-axis direction, Mitsuba's principal point offset;
tests/reference/test_stereo_references.py), and the scene checks lay the eyes' images out as the
layout does. The analytic values are computed here in double precision from the slide
"Stereoscopy"'s geometry, never from the tracer.

Every picture of an eye runs both stereo_eye()'s eye separation and its window shift, so the
scenes are the concepts that follow from others in checks.py's DEPENDS: the frustum's (which
follows from the separation) and the parallax's (which follows from both). A wrong separation
is named by the separation's probes and the scenes listed as following from it; a wrong window
by the frustum's probes and scenes. A scene of the separation's own would fail for a wrong
window too and name it a wrong separation (rtlab lesson check L11 caught that)."""

import math

from lessons.probe import HIDDEN
from lessons.scene_checks import Analytic, SceneCheck

# convergence_plane: eyes at (-+0.2, 0, 4), both looking along -z, the wall z = 0 at the
# convergence distance C = 4. Each eye's window is shifted so that the pixel (i, j) of either
# eye looks at the same point of the wall: C (forward + x w right + y h up) from the centre
# eye, x = (i + 1/2) / 81 - 1/2, y = 1/2 - (j + 1/2) / 61, h = 2 tan 20 deg, w = h 81 / 61.
C, HALF = 4.0, 0.2
H = 2 * math.tan(math.radians(20.0))
W = H * 81 / 61


def wall_depth(i: int, j: int, side: int) -> float:
    """The distance from eye ``side`` (-1 left, +1 right) to the wall point of pixel (i, j)."""
    x, y = (i + 0.5) / 81 - 0.5, 0.5 - (j + 0.5) / 61
    return math.sqrt((C * x * W - side * HALF) ** 2 + (C * y * H) ** 2 + C**2)


# float32 output: half an ulp of a depth below 8 is 4.8e-7; the double arithmetic's roundings
# ~1e-15. 2e-6 holds both; an unshifted window (depth C = 4 at the centre against
# sqrt(16.04) = 4.005) or a toed-in eye is off by far more.
FLOAT32 = 2e-6
ROWS = 61  # over_under: the right eye's rows follow the left eye's

SCENES = [
    SceneCheck(
        "L11",
        "pair_side_by_side",
        "parallax: none on the convergence plane, never vertical",
        "a stereo pair side by side: three spheres before, on and behind the convergence plane",
        hint="each eye moves half the eye separation along right (the left eye to -right) and "
        "shifts its window the other way; side_by_side puts the left eye's image on the left",
    ),
    SceneCheck(
        "L11",
        "left_eye",
        "the parallel-axis asymmetric frustum",
        "the left eye of an oblique stereo camera alone",
        hint="keep the centre's forward (parallel axes, no toe-in) and shift the window by "
        "(separation / 2) / convergence, away from the side the eye moved to",
    ),
    SceneCheck(
        "L11",
        "right_eye",
        "the parallel-axis asymmetric frustum",
        "the right eye of a stereo camera above and to the left alone",
        visibility=HIDDEN,
        hint="window_shift = -(side x separation / 2) / convergence, in the image plane's units "
        "at distance 1",
    ),
    SceneCheck(
        "L11",
        "convergence_plane",
        "parallax: none on the convergence plane, never vertical",
        "a stereo pair over and under, on a wall at the convergence distance",
        visibility=HIDDEN,
        analytic=(
            Analytic(
                40,
                30,
                "depth",
                (wall_depth(40, 30, -1),),
                FLOAT32,
                "the left eye's centre pixel sees the wall's point on the axis: "
                "sqrt(C^2 + (s/2)^2)",
            ),
            Analytic(
                40,
                ROWS + 30,
                "depth",
                (wall_depth(40, 30, +1),),
                FLOAT32,
                "the right eye's centre pixel sees the same point",
            ),
            Analytic(
                10,
                50,
                "depth",
                (wall_depth(10, 50, -1),),
                FLOAT32,
                "the left eye's pixel (10, 50) sees the wall point C (forward + x w right "
                "+ y h up) from the centre eye",
            ),
            Analytic(
                10,
                ROWS + 50,
                "depth",
                (wall_depth(10, 50, +1),),
                FLOAT32,
                "the right eye's pixel (10, 50) sees the same point",
            ),
        ),
        hint="on the plane at the convergence distance both eyes' windows coincide: a point "
        "there has the same pixel in both eyes, and no point moves up or down between them",
    ),
]
