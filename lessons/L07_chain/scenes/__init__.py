"""L07's scene checks (lessons/scene_checks.py): two facing mirrors (the chain), the same with
max_depth 3 and with min_coefficient 0.4 (its stops), and a mirror ball under an open sky."""

from lessons.probe import HIDDEN
from lessons.scene_checks import SceneCheck

SCENES = [
    SceneCheck(
        "L07",
        "two_mirrors",
        "the reflection-coefficient chain",
        "two facing mirrors and a ball between them (max_depth 6)",
        hint="color += coef x C_k at each level, then coef *= reflectivity",
    ),
    SceneCheck(
        "L07",
        "open_sky",
        "stop when no intersection",
        "a mirror ball under an open sky",
        visibility=HIDDEN,
        hint="a ray that hits nothing adds coef x background and ends the chain",
    ),
    SceneCheck(
        "L07",
        "small_coefficient",
        "stop when coef << 1",
        "the mirrors with min_coefficient 0.4",
        visibility=HIDDEN,
        hint="a level whose coefficient is below min_coefficient adds nothing and stops",
    ),
    SceneCheck(
        "L07",
        "three_bounces",
        "stop at the maximum number of bounces",
        "the mirrors with max_depth 3",
        visibility=HIDDEN,
        hint="the primary ray is level 1: at most max_depth levels",
    ),
]
