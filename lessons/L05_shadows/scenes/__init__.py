"""L05's scene checks (lessons/scene_checks.py): a shadow on a floor, a ball beyond the light
that must cast none, and a scene far from the origin where a shadow ray that starts on the
surface finds it again."""

from lessons.probe import HIDDEN
from lessons.scene_checks import SceneCheck

SCENES = [
    SceneCheck(
        "L05",
        "shadow_on_plane",
        "objects block light",
        "a ball over a floor casts its shadow on it",
        hint="a point is in shadow when anything lies on the shadow ray between it and the light",
    ),
    SceneCheck(
        "L05",
        "beyond_the_light",
        "the shadow ray's range",
        "a ball above the light, on the line from the floor to it but beyond it",
        visibility=HIDDEN,
        hint="only objects between the point and the light block it: the shadow ray ends at "
        "the light",
    ),
    SceneCheck(
        "L05",
        "far_from_origin",
        "where the shadow ray starts",
        "a ball on a floor with coordinates near 50",
        visibility=HIDDEN,
        hint="start the shadow ray off the surface (by the hit's error bound, along the "
        "geometric normal on the light's side), or it finds the surface it leaves",
    ),
]
