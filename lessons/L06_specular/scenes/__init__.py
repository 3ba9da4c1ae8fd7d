"""L06's scene checks (lessons/scene_checks.py): a Phong highlight, and a mirror ball (the
mirror vector in the highlight and in the reflection)."""

from lessons.probe import HIDDEN
from lessons.scene_checks import SceneCheck

SCENES = [
    SceneCheck(
        "L06",
        "highlight",
        "the Phong highlight",
        "a shiny ball lit by one light",
        hint="the highlight is max(R.L, 0)^shininess times the specular coefficient and the "
        "light's colour",
    ),
    SceneCheck(
        "L06",
        "mirror_ball",
        "the mirror vector R = 2(N.L)N - L",
        "a mirror ball reflecting a floor and a red ball",
        visibility=HIDDEN,
        hint="R = d - 2(d.N)N for the ray's direction d and the unit normal N",
    ),
]
