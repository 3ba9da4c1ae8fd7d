"""L03's scene checks (lessons/scene_checks.py): a floor whose point a is not the origin, and a
ceiling seen from below with a wall behind the eye."""

import math

from lessons.probe import HIDDEN
from lessons.scene_checks import Analytic, SceneCheck

# float32 output: half an ulp of 5.6 is 2.4e-7; the double arithmetic ~1e-15 relative.
FLOAT32 = 1e-6

SCENES = [
    SceneCheck(
        "L03",
        "floor",
        "the plane (p - a).n = 0",
        "a floor at y = -0.5 (its point a = (3, -0.5, -2)) seen at an angle, a ball on it",
        analytic=(
            Analytic(
                40,
                30,
                "depth",
                (1.25 * math.sqrt(20.0),),
                FLOAT32,
                "the centre ray from (0, 2, 4) towards the origin falls 2.5 to y = -0.5: "
                "t = 1.25 sqrt(20)",
            ),
            Analytic(40, 30, "normal", (0.0, 1.0, 0.0), FLOAT32, "the floor's normal"),
        ),
        hint="t = ((a - o).n) / (d.n), with a the plane's point",
    ),
    SceneCheck(
        "L03",
        "behind",
        "the hit in range",
        "a ceiling seen from below, a wall behind the eye",
        visibility=HIDDEN,
        hint="a plane behind the eye gives t < 0: no hit",
    ),
]
