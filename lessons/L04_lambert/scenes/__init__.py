"""L04's scene checks (lessons/scene_checks.py): a white sphere under a coloured light, Lambert
with a point and a directional light, and the inner wall of a sphere lit from inside."""

import math

from lessons.probe import HIDDEN
from lessons.scene_checks import Analytic, SceneCheck

# The centre pixel of coloured_light.toml: the ray from (0, 0, 5) meets the unit sphere at
# (0, 0, 1), N = (0, 0, 1), the light at (2, 2, 5) is along (2, 2, 4), N.L = 4 / sqrt(24).
# Colour = colour x ambient x ambient light + diffuse x N.L x colour x light (white material).
NL = 4 / math.sqrt(24.0)
CENTRE = tuple(
    0.1 * a + 0.9 * NL * c for a, c in zip((0.2, 0.3, 0.4), (1.0, 0.5, 0.1), strict=True)
)
# float32 output: half an ulp of values below 1 is 6e-8; double arithmetic ~1e-15.
FLOAT32 = 1e-6

SCENES = [
    SceneCheck(
        "L04",
        "coloured_light",
        "coloured lights",
        "a white sphere under an orange light in a bluish ambient light",
        analytic=(
            Analytic(
                40,
                30,
                "color",
                CENTRE,
                FLOAT32,
                "0.1 x (0.2, 0.3, 0.4) + 0.9 x N.L x (1, 0.5, 0.1), N.L = 4 / sqrt(24)",
            ),
        ),
        hint="each channel: material colour x light colour x diffuse x N.L, plus the ambient "
        "term with the ambient light's colour",
    ),
    SceneCheck(
        "L04",
        "two_lights",
        "diffuse (Lambertian) reflection N.L",
        "a clay sphere on a floor under a point light and a directional light",
        visibility=HIDDEN,
        hint="N.L with the unit direction towards each light; a directional light's direction "
        "is the way its light travels, so L is its opposite",
    ),
    SceneCheck(
        "L04",
        "inside_lit",
        "the normal facing the ray",
        "the inner wall of a sphere, seen and lit from inside",
        visibility=HIDDEN,
        hint="turn the normal towards the ray before shading: the side we see is the side we shade",
    ),
]
