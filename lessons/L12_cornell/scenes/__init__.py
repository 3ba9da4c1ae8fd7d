"""L12's scene checks (lessons/scene_checks.py, PathSceneCheck): path-traced scenes compared
with Mitsuba's path tracer in the statistical sense, as the reference suite compares the Cornell
box (reference/stats.py): next-event estimation on a small light, the cosine-weighted bounce in
the Cornell box's colour bleeding, multiple importance sampling on a glossy floor, and Russian
roulette in a furnace whose every pixel is known in closed form."""

from lessons.probe import HIDDEN
from lessons.scene_checks import PathSceneCheck

# furnace.toml: six walls of emission Le = 0.25 and albedo rho = 0.75, max_depth 20 (paths of 0
# to 19 bounces): L = Le (1 - rho^20) / (1 - rho) in every pixel and channel.
RHO, LE, DEPTH = 0.75, 0.25, 20
FURNACE = LE * (1 - RHO**DEPTH) / (1 - RHO)

SCENES = [
    PathSceneCheck(
        "L12",
        "small_light",
        "next-event estimation: a point on the area light",
        "the Cornell box's walls under a light of 0.1 x 0.1, direct light only",
        hint="the light sample's density per solid angle is pdf_area r^2 / cos(theta_l), and "
        "its estimate f Le cos(theta_i) / pdf: a missing r^2 or cosine brightens or darkens "
        "the walls unevenly",
    ),
    PathSceneCheck(
        "L12",
        "colour_bleeding",
        "light bounces many times: the cosine-weighted bounce",
        "the Cornell box, seven bounces: the red and green walls bleed onto the white ones",
        hint="a bounce drawn with density cos / pi carries f cos / pdf = albedo; a density "
        "without its 1/pi, or directions drawn uniformly, change all the indirect light",
    ),
    PathSceneCheck(
        "L12",
        "glossy_mis",
        "multiple importance sampling: the power heuristic",
        "a glossy floor reflecting a small bright and a large dim sphere light",
        visibility=HIDDEN,
        hint="the two strategies' weights of one direction must sum to one: "
        "p^2 / (p_light^2 + p_bsdf^2) for each, the bounce's too when it hits the light",
    ),
    PathSceneCheck(
        "L12",
        "furnace",
        "each bounce attenuates light: Russian roulette",
        "inside a closed box of glowing walls: every pixel is 1 - 0.75^20",
        visibility=HIDDEN,
        closed_form=(
            (FURNACE, FURNACE, FURNACE),
            "Le (1 - rho^20) / (1 - rho), Le = 0.25, rho = 0.75",
        ),
        hint="a path that survives the roulette with probability q must carry 1/q more, or "
        "the paths it ends are missing from the image",
    ),
]
