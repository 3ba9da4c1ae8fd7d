"""L02's scene checks (lessons/scene_checks.py): the sphere seen from inside, and the nearest of
overlapping spheres with one behind the eye."""

from lessons.probe import HIDDEN
from lessons.scene_checks import Analytic, SceneCheck

# float32 output: half an ulp of 3.5 is 1.2e-7; the double quadratic's roundings are ~1e-15
# relative. 1e-6 holds both with room.
FLOAT32 = 1e-6

SCENES = [
    SceneCheck(
        "L02",
        "inside",
        "the five cases: none, once, tangent, internal, twice",
        "the inner wall of a sphere around the camera (the case 'once': t0 < 0 < t1)",
        analytic=(
            Analytic(
                40,
                30,
                "depth",
                (3.5,),
                FLOAT32,
                "the centre ray from z = 0.5 meets the wall of radius 3 at z = -3",
            ),
            Analytic(
                40,
                30,
                "normal",
                (0.0, 0.0, -1.0),
                FLOAT32,
                "the outward normal of the sphere at (0, 0, -3)",
            ),
        ),
        hint="from inside the sphere t0 < 0 < t1: the hit is t1, the far root",
    ),
    SceneCheck(
        "L02",
        "nearest",
        "the nearest hit in range",
        "two overlapping spheres, and a third behind the eye",
        visibility=HIDDEN,
        hint="of the roots in range (t > 0, below the current nearest) take the smallest; a "
        "sphere behind the eye has both roots negative and is not hit",
    ),
]
